//! A [`GpuCloth`](super::gpu::GpuCloth) drawn in place: [`SurfacePlacer`]
//! records the compute pass (`shader/cloth_place.wgsl`) that writes the
//! cloth's positions and area-weighted normals into its surface shape's
//! vertices in the renderer's mesh pool after the frame's steps
//! ([`GpuSimulation::place`](crate::render::GpuSimulation::place)): nothing
//! read back, no vertex uploaded from the CPU.

use crate::gpu::{PlaceTargets, VertexTarget};
use crate::scene::ShapeId;
use crate::sim::cloth::Cloth;

const WORKGROUP: u32 = 64;
/// Words of a [`Vertex`](crate::scene::Vertex).
const VERTEX_WORDS: u64 = 12;

/// The uniform block `Place` of `shader/cloth_place.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct PlaceGpu {
    first_word: u32,
    nodes: u32,
    pad: [u32; 2],
}

/// The pass writing one cloth's surface shape, and what it reads besides
/// the positions: each node's triangles.
pub(crate) struct SurfacePlacer {
    shape: ShapeId,
    nodes: u32,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    block: wgpu::Buffer,
    written: Option<PlaceGpu>,
    /// Node i's triangles are `around[around_start[i]..around_start[i + 1]]`.
    around_start: wgpu::Buffer,
    around: wgpu::Buffer,
    triangles: wgpu::Buffer,
}

impl SurfacePlacer {
    /// The pass writing `cloth`'s surface into `shape`, a mesh of one vertex
    /// per node (as [`ClothView`](crate::sim::cloth::ClothView) makes it).
    pub(crate) fn new(device: &wgpu::Device, queue: &wgpu::Queue, cloth: &Cloth, shape: ShapeId) -> Self {
        let triangles = &cloth.mesh().triangles;
        let n = cloth.positions.len();
        let mut counts = vec![0u32; n];
        for t in triangles.iter().flatten() {
            counts[*t as usize] += 1;
        }
        let starts: Vec<u32> = std::iter::once(0)
            .chain(counts.iter().scan(0, |sum, c| {
                *sum += c;
                Some(*sum)
            }))
            .collect();
        let mut fill = starts.clone();
        let mut around = vec![0u32; triangles.len() * 3];
        for (k, t) in triangles.iter().enumerate() {
            for &i in t {
                around[fill[i as usize] as usize] = k as u32;
                fill[i as usize] += 1;
            }
        }
        let storage = |label: &str, words: &[u32]| {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: (words.len() as u64 * 4).max(16),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            queue.write_buffer(&buffer, 0, bytemuck::cast_slice(words));
            buffer
        };
        let flat: Vec<u32> = triangles.iter().flatten().copied().collect();
        let block = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("cloth: place"),
            size: std::mem::size_of::<PlaceGpu>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = crate::gpu::buffers_layout(device, "cloth: place", 6, 1, None);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("cloth_place.wgsl"),
            source: wgpu::ShaderSource::Wgsl(crate::shader::CLOTH_PLACE.into()),
        });
        Self {
            shape,
            nodes: n as u32,
            pipeline: crate::gpu::compute_pipeline(device, &module, "place_surface", &[Some(&layout)]),
            layout,
            block,
            written: None,
            around_start: storage("cloth: triangles around starts", &starts),
            around: storage("cloth: triangles around", &around),
            triangles: storage("cloth: triangles", &flat),
        }
    }

    /// The shape it writes.
    pub(crate) fn shape(&self) -> ShapeId {
        self.shape
    }

    /// Record the pass writing the surface from `positions` into `targets`'
    /// vertices of its shape; nothing where the shape is not in the mesh
    /// pool or has another vertex count.
    pub(crate) fn encode(
        &mut self,
        (device, queue): (&wgpu::Device, &wgpu::Queue),
        encoder: &mut wgpu::CommandEncoder,
        positions: &wgpu::Buffer,
        targets: &PlaceTargets<'_>,
    ) {
        let Some(target) = targets.vertices(self.shape).filter(|t| t.count == self.nodes) else { return };
        let (window, first_word) = window(device, &target);
        let data = PlaceGpu { first_word, nodes: self.nodes, pad: [0; 2] };
        if self.written != Some(data) {
            queue.write_buffer(&self.block, 0, bytemuck::bytes_of(&data));
            self.written = Some(data);
        }
        let resources = [
            self.block.as_entire_binding(),
            positions.as_entire_binding(),
            self.around_start.as_entire_binding(),
            self.around.as_entire_binding(),
            self.triangles.as_entire_binding(),
            wgpu::BindingResource::Buffer(window),
        ];
        let group = crate::gpu::bind_buffers(device, "cloth: place", &self.layout, resources);
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("cloth: place"), timestamp_writes: None });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(self.nodes.div_ceil(WORKGROUP), 1, 1);
    }
}

/// The part of `target`'s buffer to bind (from an offset the device allows
/// storage bindings at, through the shape's last vertex), and the shape's
/// first word in it.
fn window<'a>(device: &wgpu::Device, target: &VertexTarget<'a>) -> (wgpu::BufferBinding<'a>, u32) {
    let align = u64::from(device.limits().min_storage_buffer_offset_alignment);
    let start = u64::from(target.first) * VERTEX_WORDS * 4;
    let offset = start / align * align;
    let end = start + u64::from(target.count) * VERTEX_WORDS * 4;
    let binding = wgpu::BufferBinding { buffer: target.buffer, offset, size: wgpu::BufferSize::new(end - offset) };
    (binding, ((start - offset) / 4) as u32)
}

#[cfg(test)]
mod layout_tests {
    use super::*;
    use crate::shader::layout::assert_mirrors;

    #[test]
    fn the_place_block_mirrors_its_wgsl_struct() {
        assert_mirrors!(PlaceGpu, crate::shader::CLOTH_PLACE, "Place", [first_word, nodes, pad]);
    }
}
