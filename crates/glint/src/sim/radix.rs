//! [`GpuRadixSort`]: a stable sort of (key, value) `u32` pairs by key on the
//! GPU (`shader/radix.wgsl`), four bits a pass, each pass a count, a
//! [`GpuScan`] and a scatter. Deterministic: it uses no atomics, so the same
//! pairs give the same bits whatever order threads ran in. The school sorts
//! its fish by cell with it (pairs of cell and fish number), so a cell's fish
//! come in the order the CPU's counting sort gives them.

use crate::sim::scan::{GpuScan, ScanGroup, MAX_SCAN};

const WORKGROUP: u32 = 256;
/// Key bits a pass sorts by (`DIGITS` = 16 in the shader).
const BITS: u32 = 4;
const DIGITS: u32 = 1 << BITS;

/// Most pairs a sort takes: its counts (16 a workgroup) must fit one scan.
pub(crate) const MAX_PAIRS: u32 = MAX_SCAN / DIGITS * WORKGROUP;

/// The sort's two pipelines and their bind group layout.
pub(crate) struct GpuRadixSort {
    layout: wgpu::BindGroupLayout,
    count: wgpu::ComputePipeline,
    scatter: wgpu::ComputePipeline,
}

/// One sort's buffers: a bind group a pass (they alternate between the
/// pairs and the spare buffer, an even number of them, so the sorted pairs
/// end where they began), and the scan of its counts.
pub(crate) struct RadixGroup {
    passes: Vec<wgpu::BindGroup>,
    scan: ScanGroup,
    groups: u32,
}

impl GpuRadixSort {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let layout = crate::gpu::buffers_layout(device, "radix sort", 5, 1, None);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("radix.wgsl"),
            source: wgpu::ShaderSource::Wgsl(crate::shader::RADIX.into()),
        });
        let pipeline = |entry| crate::gpu::compute_pipeline(device, &module, entry, &[Some(&layout)]);
        Self { count: pipeline("radix_count"), scatter: pipeline("radix_scatter"), layout }
    }

    /// The buffers of a sort of the first `n` (at most [`MAX_PAIRS`]) pairs of
    /// `pairs` (`vec2<u32>`, key first) by the low `bits` bits of their keys;
    /// `spare` holds as many pairs. Makes its own counts and uniforms.
    pub(crate) fn group(
        &self,
        (device, queue): (&wgpu::Device, &wgpu::Queue),
        scan: &GpuScan,
        (pairs, spare): (&wgpu::Buffer, &wgpu::Buffer),
        (n, bits): (u32, u32),
    ) -> RadixGroup {
        assert!(n <= MAX_PAIRS, "a radix sort takes at most {MAX_PAIRS} pairs");
        let groups = n.div_ceil(WORKGROUP).max(1);
        let storage = |label: &str| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 4 * u64::from(DIGITS * groups),
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        let (counts, starts) = (storage("radix sort: counts"), storage("radix sort: starts"));
        // An even number of passes, so the pairs end in `pairs`.
        let passes = bits.div_ceil(BITS).max(1).next_multiple_of(2);
        let passes = (0..passes)
            .map(|p| {
                let info = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("radix sort: pass"),
                    size: 16,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                queue.write_buffer(&info, 0, bytemuck::cast_slice(&[n, p * BITS, groups, 0]));
                let (from, to) = if p % 2 == 0 { (pairs, spare) } else { (spare, pairs) };
                let buffers = [&info, from, to, &counts, &starts];
                crate::gpu::bind_buffers(
                    device,
                    "radix sort",
                    &self.layout,
                    buffers.iter().map(|b| b.as_entire_binding()),
                )
            })
            .collect();
        let scan = scan.group((device, queue), &counts, &starts, DIGITS * groups);
        RadixGroup { passes, scan, groups }
    }

    /// Record the sort of `group` into `pass` (which the caller's own bind
    /// group must be set on again afterwards).
    pub(crate) fn encode(&self, pass: &mut wgpu::ComputePass<'_>, scan: &GpuScan, group: &RadixGroup) {
        for bind in &group.passes {
            pass.set_bind_group(0, bind, &[]);
            pass.set_pipeline(&self.count);
            pass.dispatch_workgroups(group.groups, 1, 1);
            scan.encode(pass, &group.scan);
            pass.set_bind_group(0, bind, &[]);
            pass.set_pipeline(&self.scatter);
            pass.dispatch_workgroups(group.groups, 1, 1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `pairs` sorted on the GPU by the low `bits` bits of their keys.
    fn sorted_on_gpu(gpu: &crate::Gpu, pairs: &[[u32; 2]], bits: u32) -> Vec<[u32; 2]> {
        let device = &gpu.device;
        let buffer = |label: &str| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 8 * pairs.len() as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let (data, spare) = (buffer("pairs"), buffer("spare"));
        gpu.queue.write_buffer(&data, 0, bytemuck::cast_slice(pairs));
        let (scan, sort) = (GpuScan::new(device), GpuRadixSort::new(device));
        let group = sort.group((device, &gpu.queue), &scan, (&data, &spare), (pairs.len() as u32, bits));
        let mut encoder = device.create_command_encoder(&Default::default());
        let mut pass = encoder.begin_compute_pass(&Default::default());
        sort.encode(&mut pass, &scan, &group);
        drop(pass);
        gpu.queue.submit([encoder.finish()]);
        bytemuck::pod_collect_to_vec(&gpu.read_buffer(&data).expect("read back"))
    }

    #[test]
    fn pairs_sort_by_key_keeping_the_order_of_equal_keys() {
        let Some(gpu) = crate::gpu::test_gpu() else { return };
        // 5,000 pairs (20 workgroups, the last part full) over 20 key bits,
        // many keys repeated; values number the pairs, so stability shows.
        let key = |i: u32| (i.wrapping_mul(2_654_435_761) >> 7) % 700 * 1_409;
        let pairs: Vec<[u32; 2]> = (0..5000).map(|i| [key(i), i]).collect();
        assert!(pairs.iter().all(|p| p[0] < 1 << 20));
        let mut expected = pairs.clone();
        expected.sort_by_key(|p| p[0]);
        let sorted = sorted_on_gpu(&gpu, &pairs, 20);
        assert_eq!(sorted, expected);
        // Equal keys throughout: nothing moves. One pair: itself.
        let same: Vec<[u32; 2]> = (0..600).map(|i| [7, i]).collect();
        assert_eq!(sorted_on_gpu(&gpu, &same, 3), same);
        assert_eq!(sorted_on_gpu(&gpu, &[[5, 9]], 3), [[5, 9]]);
    }
}
