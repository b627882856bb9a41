//! The school drawn in place: [`SchoolDrawing`] says which entity draws which
//! swimmers, and [`Placer`] records the compute pass (`shader/school_place.wgsl`)
//! that writes their instance records and world boxes straight into the
//! renderer's instance store after the frame's steps
//! ([`GpuSimulation::place`](crate::render::GpuSimulation::place)): nothing
//! read back, no instance uploaded from the CPU.

use crate::gpu::{GpuError, PlaceTargets};
use glam::Mat4;

/// Part transforms one drawing multiplies each swimmer by, at most (a model
/// part drawing its mesh several times).
pub const MAX_PART_TRANSFORMS: usize = 4;
/// Bytes between drawings' blocks (the dynamic-offset alignment).
const STRIDE: u64 = 512;
const WORKGROUP: u32 = 256;

/// Which of a school's swimmers an entity draws.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Swimmers {
    /// Every fish, fish `i` at `size` varied ±15 % by its number
    /// ([`SchoolDesc::fish_scale`](crate::asset::SchoolDesc::fish_scale)).
    Fish {
        /// Their scale before the variation.
        size: f32,
    },
    /// The predator, at `size`.
    Predator {
        /// Its scale.
        size: f32,
    },
}

/// One entity drawing a [`GpuSchool`](super::GpuSchool)'s swimmers: made with
/// [`Entity::with_gpu_instances`](crate::Entity::with_gpu_instances), its
/// instance `k` is swimmer `k / parts.len()` (placed by its frame, as
/// [`Swimmer::transform`](super::Swimmer::transform) places it) times
/// `parts[k % parts.len()]`.
#[derive(Clone, Debug, PartialEq)]
pub struct SchoolDrawing {
    /// The entity's [`key`](crate::Entity::key).
    pub entity: u64,
    /// What it draws.
    pub swimmers: Swimmers,
    /// Each swimmer's instances, relative to its frame: 1 to [`MAX_PART_TRANSFORMS`].
    pub parts: Vec<Mat4>,
}

/// The uniform block `Place` of `shader/school_place.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct PlaceGpu {
    first: u32,
    count: u32,
    each: u32,
    material: u32,
    flags: u32,
    size: f32,
    walk: f32,
    pad: u32,
    local_center: [f32; 4],
    local_extent: [f32; 4],
    parts: [[f32; 16]; MAX_PART_TRANSFORMS],
}

/// The placing pass and its drawings.
pub(crate) struct Placer {
    drawings: Vec<SchoolDrawing>,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    /// One block per drawing, `STRIDE` apart.
    blocks: wgpu::Buffer,
    /// What each block holds, so an unchanged one is not written again.
    written: Vec<Option<PlaceGpu>>,
}

impl Placer {
    /// The pass for `drawings`. Errors for a drawing without part transforms
    /// or with more than [`MAX_PART_TRANSFORMS`].
    pub(crate) fn new(device: &wgpu::Device, drawings: Vec<SchoolDrawing>) -> Result<Self, GpuError> {
        if let Some(d) = drawings.iter().find(|d| d.parts.is_empty() || d.parts.len() > MAX_PART_TRANSFORMS) {
            return Err(GpuError::Failed(format!(
                "a school is drawn in place with 1 to {MAX_PART_TRANSFORMS} transforms a swimmer, not {}",
                d.parts.len()
            )));
        }
        let layout = crate::gpu::buffers_layout(device, "school: place", 5, 1, Some(0));
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("school_place.wgsl"),
            source: wgpu::ShaderSource::Wgsl(crate::shader::SCHOOL_PLACE.into()),
        });
        let pipeline = crate::gpu::compute_pipeline(device, &module, "place_swimmers", &[Some(&layout)]);
        let blocks = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("school: place blocks"),
            size: STRIDE * drawings.len().max(1) as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(Self { written: vec![None; drawings.len()], drawings, layout, pipeline, blocks })
    }

    /// Record the pass writing every drawing's instances from `fish` (the
    /// current state of `fish_count` fish) and `hunter` (the predator's
    /// state) into `targets`. A drawing whose entity was not submitted, or
    /// whose instance count is not its swimmers' times its parts', is skipped.
    pub(crate) fn encode(
        &mut self,
        (device, queue): (&wgpu::Device, &wgpu::Queue),
        encoder: &mut wgpu::CommandEncoder,
        (fish, hunter, fish_count): (&wgpu::Buffer, &wgpu::Buffer, u32),
        targets: &PlaceTargets<'_>,
    ) {
        let block = wgpu::BufferBinding {
            buffer: &self.blocks,
            offset: 0,
            size: wgpu::BufferSize::new(std::mem::size_of::<PlaceGpu>() as u64),
        };
        let resources = [
            wgpu::BindingResource::Buffer(block),
            fish.as_entire_binding(),
            hunter.as_entire_binding(),
            targets.records.as_entire_binding(),
            targets.bounds.as_entire_binding(),
        ];
        let group = crate::gpu::bind_buffers(device, "school: place", &self.layout, resources);
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("school: place"), timestamp_writes: None });
        pass.set_pipeline(&self.pipeline);
        for (k, (drawing, written)) in self.drawings.iter().zip(&mut self.written).enumerate() {
            let Some(range) = targets.range(drawing.entity) else { continue };
            let (count, flags, size) = match drawing.swimmers {
                Swimmers::Fish { size } => (fish_count, 4, size),
                Swimmers::Predator { size } => (1, 2, size),
            };
            let each = drawing.parts.len() as u32;
            if range.count != count * each {
                continue;
            }
            let mut parts = [[0.0; 16]; MAX_PART_TRANSFORMS];
            for (slot, m) in parts.iter_mut().zip(&drawing.parts) {
                *slot = m.to_cols_array();
            }
            let (c, e) = (range.local.center(), range.local.half_extent());
            let data = PlaceGpu {
                first: range.first,
                count,
                each,
                material: range.material,
                flags: flags | u32::from(range.receive_shadows),
                size,
                walk: range.walk,
                pad: 0,
                local_center: [c.x, c.y, c.z, 0.0],
                local_extent: [e.x, e.y, e.z, 0.0],
                parts,
            };
            if *written != Some(data) {
                queue.write_buffer(&self.blocks, k as u64 * STRIDE, bytemuck::bytes_of(&data));
                *written = Some(data);
            }
            pass.set_bind_group(0, &group, &[(k as u64 * STRIDE) as u32]);
            pass.dispatch_workgroups((count * each).div_ceil(WORKGROUP), 1, 1);
        }
    }
}

#[cfg(test)]
mod layout_tests {
    use super::*;
    use crate::shader::layout::assert_mirrors;

    #[test]
    fn the_place_block_mirrors_its_wgsl_struct() {
        let wgsl = crate::shader::SCHOOL_PLACE;
        assert_mirrors!(
            PlaceGpu,
            wgsl,
            "Place",
            [first, count, each, material, flags, size, walk, pad, local_center, local_extent, parts]
        );
        // The records and boxes it writes are the store's: `InstanceGpu`'s 64
        // bytes, `BoundsGpu`'s 32 (render/resources).
        let record = [("row_x", 0), ("row_y", 16), ("row_z", 32), ("material", 48), ("joints", 52)];
        let record = [&record[..], &[("joint_count", 56), ("flags", 60)]].concat();
        crate::shader::layout::assert_layout(wgsl, "Instance", 64, &record);
        crate::shader::layout::assert_layout(wgsl, "Bounds", 32, &[("center", 0), ("extent", 16)]);
    }
}
