//! Core layer: GPU twins of scene data — textures (with mipmaps made on the GPU),
//! the material table — and the Renderer block's instance records.

use crate::gpu::Blitter;
use crate::render::cull::Boxes;
use crate::render::error::RenderError;
use crate::render::resources::blocks::{InstanceGpu, MaterialGpu};
use crate::render::resources::gpu_array::{GpuArray, GrowBuffer};
use crate::scene::Texture;

/// One instance's world box as the cull pass reads it (`w` unused).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct BoundsGpu {
    center: [f32; 4],
    extent: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<BoundsGpu>() == 32);

impl BoundsGpu {
    /// Boxes `range` of `boxes`, as the cull pass reads them.
    pub(crate) fn of(boxes: &Boxes, range: std::ops::Range<usize>) -> Vec<Self> {
        (range)
            .map(|i| {
                let (c, e) = (boxes.center(i), boxes.extent(i));
                Self { center: [c.x, c.y, c.z, 0.0], extent: [e.x, e.y, e.z, 0.0] }
            })
            .collect()
    }
}

/// Builds textures and fills their mip chains by repeated half-size blits.
pub(crate) struct TextureUploader {
    blitter: Blitter,
    srgb: wgpu::RenderPipeline,
    linear: wgpu::RenderPipeline,
}

impl TextureUploader {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let blitter = Blitter::new(device);
        Self {
            srgb: blitter.pipeline(device, wgpu::TextureFormat::Rgba8UnormSrgb),
            linear: blitter.pipeline(device, wgpu::TextureFormat::Rgba8Unorm),
            blitter,
        }
    }

    /// Create the GPU texture for `texture` and write level 0; record the blits
    /// of the rest of the mip chain for the next submission (`None` for a
    /// texture of one level). Returns the view, the bytes written from the CPU
    /// and the blits.
    pub(crate) fn upload(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        texture: &Texture,
    ) -> (wgpu::TextureView, u64, Option<wgpu::CommandBuffer>) {
        let (width, height) = texture.image.dimensions();
        let format = if texture.srgb { wgpu::TextureFormat::Rgba8UnormSrgb } else { wgpu::TextureFormat::Rgba8Unorm };
        let levels = texture.mip_levels();
        let size = wgpu::Extent3d { width, height, depth_or_array_layers: 1 };
        let gpu_texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(&format!("texture '{}'", texture.name)),
            size,
            mip_level_count: levels,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_DST
                | wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        // Only level 0 comes from the CPU; the blits below fill the rest.
        queue.write_texture(
            gpu_texture.as_image_copy(),
            texture.image.as_raw(),
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(4 * width), rows_per_image: Some(height) },
            size,
        );
        let pipeline = if texture.srgb { &self.srgb } else { &self.linear };
        let mut encoder =
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("texture uploader: mips") });
        let level_view = |level| {
            gpu_texture.create_view(&wgpu::TextureViewDescriptor {
                base_mip_level: level,
                mip_level_count: Some(1),
                ..Default::default()
            })
        };
        for level in 1..levels {
            self.blitter.blit(device, &mut encoder, pipeline, &level_view(level - 1), &level_view(level));
        }
        let blits = (levels > 1).then(|| encoder.finish());
        (gpu_texture.create_view(&Default::default()), texture.image.as_raw().len() as u64, blits)
    }
}

/// Bytes of one record of `T` (records are small: a few dozen bytes).
fn record_bytes<T>() -> u32 {
    std::mem::size_of::<T>() as u32
}

/// The material table of the Material block (`@group(2) @binding(0)`): one
/// [`MaterialGpu`] per material id.
pub(crate) struct MaterialTable(GpuArray);

impl MaterialTable {
    /// A table with room for 64 materials: a storage buffer when `storage`, else a data texture.
    pub(crate) fn new(device: &wgpu::Device, storage: bool) -> Self {
        let label = "material block: material table";
        Self(GpuArray::new(device, label, record_bytes::<MaterialGpu>(), 64, storage))
    }

    /// Make room for `materials`; returns whether the table was replaced (every
    /// material must be written again and every material bind group rebuilt).
    pub(crate) fn reserve(&mut self, device: &wgpu::Device, materials: usize) -> Result<bool, RenderError> {
        self.0.reserve(device, record_bytes::<MaterialGpu>(), materials)
    }

    /// Write material `id`'s entry; returns bytes written.
    pub(crate) fn write(&self, queue: &wgpu::Queue, id: u32, block: &MaterialGpu) -> u64 {
        self.0.write(queue, id.into(), std::slice::from_ref(block))
    }

    pub(crate) fn binding(&self) -> wgpu::BindingResource<'_> {
        self.0.binding()
    }
}

/// The instances of the Renderer block (`@group(3) @binding(0)`): every stored
/// instance record, persistent between frames (each [`DrawList`](crate::render::gpu_driven::draw_list::DrawList)
/// binds it beside its own draw indices).
pub(crate) struct InstanceBuffer {
    array: GpuArray,
    /// Each instance's world box, where views cull on the GPU.
    bounds: Option<GrowBuffer>,
    /// How many times the buffer was replaced: bind groups made for an older
    /// generation point at a dropped buffer.
    generation: u64,
}

impl InstanceBuffer {
    /// Room for 1,024 records: a storage buffer when `storage`, else a data
    /// texture; with their world boxes when `bounds` (GPU culling).
    pub(crate) fn new(device: &wgpu::Device, storage: bool, bounds: bool) -> Self {
        let array = GpuArray::new(device, "renderer block: instances", record_bytes::<InstanceGpu>(), 1024, storage);
        let size = 1024 * u64::from(record_bytes::<BoundsGpu>());
        // Copied from only to read it back for inspection.
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let bounds = bounds.then(|| GrowBuffer::new(device, "gpu culling: instance bounds", usage, size));
        Self { array, bounds, generation: 0 }
    }

    /// Make room for `instances` records. Returns whether the buffer was replaced
    /// (its contents must be written again and its bind groups rebuilt).
    pub(crate) fn reserve(&mut self, device: &wgpu::Device, instances: usize) -> Result<bool, RenderError> {
        let mut replaced = self.array.reserve(device, record_bytes::<InstanceGpu>(), instances)?;
        if let Some(bounds) = &mut self.bounds {
            replaced |= bounds.reserve(device, u64::from(record_bytes::<BoundsGpu>()) * instances as u64)?;
        }
        self.generation += u64::from(replaced);
        Ok(replaced)
    }

    /// Write `data` at record `first`, and their world boxes where views cull
    /// on the GPU; returns bytes written: instances, boxes.
    pub(crate) fn write(&self, queue: &wgpu::Queue, first: u32, data: &[InstanceGpu], boxes: &Boxes) -> (u64, u64) {
        let written = self.array.write(queue, first.into(), data);
        let Some(bounds) = &self.bounds else { return (written, 0) };
        let range = first as usize..first as usize + data.len();
        (written, bounds.write(queue, first.into(), &BoundsGpu::of(boxes, range)))
    }

    /// The world boxes, where views cull on the GPU.
    pub(crate) fn bounds(&self) -> Option<&wgpu::Buffer> {
        self.bounds.as_ref().map(|b| &b.buffer)
    }

    pub(crate) fn array(&self) -> &GpuArray {
        &self.array
    }

    /// How many times the buffer was replaced.
    pub(crate) fn generation(&self) -> u64 {
        self.generation
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shader::layout::assert_mirrors;

    #[test]
    fn an_instances_bounds_record_mirrors_its_wgsl_struct() {
        assert_mirrors!(BoundsGpu, crate::shader::CULL, "Bounds", [center, extent]);
    }
}
