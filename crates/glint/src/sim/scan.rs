//! [`GpuScan`]: an exclusive running sum on the GPU (`shader/scan.wgsl`), the middle
//! of the counting sorts that rebuild the school's grid and order particles
//! by depth: count into buckets, sum, scatter.

/// Most entries a scan covers: 256 blocks of 256, 16 block totals a thread.
pub const MAX_SCAN: u32 = 256 * 256 * 16;

// A school's grid, counted by cell, is scanned one past its last cell.
const _: () = assert!(crate::scene::school::MAX_GRID_CELLS < MAX_SCAN);
const WORKGROUP: u32 = 256;

/// The scan's three pipelines and their bind group layout.
pub(crate) struct GpuScan {
    layout: wgpu::BindGroupLayout,
    pipelines: [wgpu::ComputePipeline; 3],
}

/// One scan's buffers: `n` counts in, their running sum out.
pub(crate) struct ScanGroup {
    group: wgpu::BindGroup,
    n: u32,
}

impl GpuScan {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let layout = crate::gpu::buffers_layout(device, "scan", 4, 1, None);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("scan.wgsl"),
            source: wgpu::ShaderSource::Wgsl(crate::shader::SCAN.into()),
        });
        let pipeline = |entry| crate::gpu::compute_pipeline(device, &module, entry, &[Some(&layout)]);
        let pipelines = [pipeline("scan_blocks"), pipeline("scan_sums"), pipeline("scan_add")];
        Self { layout, pipelines }
    }

    /// The buffers of a scan of the first `n` (at most [`MAX_SCAN`]) words of
    /// `counts` into `starts`; makes its own uniform and block totals.
    pub(crate) fn group(
        &self,
        (device, queue): (&wgpu::Device, &wgpu::Queue),
        counts: &wgpu::Buffer,
        starts: &wgpu::Buffer,
        n: u32,
    ) -> ScanGroup {
        assert!(n <= MAX_SCAN, "a scan covers at most {MAX_SCAN} entries");
        // Written, not mapped at creation: a device out of memory makes an
        // invalid buffer, which an error scope reports, where mapping one panics.
        let size = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("scan: size"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        queue.write_buffer(&size, 0, bytemuck::cast_slice(&[n, 0, 0, 0]));
        let sums = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("scan: block totals"),
            size: 4 * u64::from(n.div_ceil(WORKGROUP).max(4)),
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let buffers = [&size, counts, starts, &sums];
        let group =
            crate::gpu::bind_buffers(device, "scan", &self.layout, buffers.iter().map(|b| b.as_entire_binding()));
        ScanGroup { group, n }
    }

    /// Record the scan of `group` into `pass` (which the caller's own bind
    /// group must be set on again afterwards).
    pub(crate) fn encode(&self, pass: &mut wgpu::ComputePass<'_>, group: &ScanGroup) {
        let blocks = group.n.div_ceil(WORKGROUP);
        pass.set_bind_group(0, &group.group, &[]);
        for (pipeline, groups) in self.pipelines.iter().zip([blocks, 1, blocks]) {
            pass.set_pipeline(pipeline);
            pass.dispatch_workgroups(groups, 1, 1);
        }
    }
}
