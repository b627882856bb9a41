//! Core layer: GPU twins of scene data — meshes, textures (with mipmaps made on
//! the GPU), material bind groups — and the per-frame instance buffer.

use super::blocks::InstanceGpu;
use super::pipelines::{sampler_entry, texture_entry};
use crate::asset::Texture;
use crate::scene::Mesh;
use wgpu::util::DeviceExt;

/// A shape's vertex and index buffers.
pub(crate) struct GpuMesh {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub index_count: u32,
}

impl GpuMesh {
    pub(crate) fn new(device: &wgpu::Device, mesh: &Mesh, id: u32) -> Self {
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(&format!("shape {id}: vertices")),
            contents: bytemuck::cast_slice(mesh.vertices()),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(&format!("shape {id}: indices")),
            contents: bytemuck::cast_slice(mesh.indices()),
            usage: wgpu::BufferUsages::INDEX,
        });
        Self { vertices, indices, index_count: mesh.indices().len() as u32 }
    }
}

/// Builds textures and fills their mip chains by repeated half-size blits.
pub(crate) struct TextureUploader {
    layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    srgb: wgpu::RenderPipeline,
    linear: wgpu::RenderPipeline,
}

impl TextureUploader {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("texture uploader: mip source layout"),
            entries: &[texture_entry(0), sampler_entry(1)],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("texture uploader: mip pipeline layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("texture uploader: mip shader"),
            source: wgpu::ShaderSource::Wgsl(crate::shader::MIPMAP.into()),
        });
        let pipeline = |format: wgpu::TextureFormat| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(&format!("texture uploader: mip pipeline ({format:?})")),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_blit"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: Default::default(),
                depth_stencil: None,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_blit"),
                    compilation_options: Default::default(),
                    targets: &[Some(format.into())],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        Self {
            sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("texture uploader: mip sampler"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..Default::default()
            }),
            srgb: pipeline(wgpu::TextureFormat::Rgba8UnormSrgb),
            linear: pipeline(wgpu::TextureFormat::Rgba8Unorm),
            layout,
        }
    }

    /// Create the GPU texture for `texture`, write level 0 and blit the rest of the
    /// mip chain. Returns the view and the bytes written from the CPU.
    pub(crate) fn upload(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        texture: &Texture,
    ) -> (wgpu::TextureView, u64) {
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
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("texture uploader: mip source"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(&level_view(level - 1)),
                    },
                    wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&self.sampler) },
                ],
            });
            let target = level_view(level);
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(&format!("texture '{}': mip {level}", texture.name)),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.draw(0..3, 0..1);
        }
        queue.submit([encoder.finish()]);
        (gpu_texture.create_view(&Default::default()), texture.image.as_raw().len() as u64)
    }
}

/// A storage buffer that grows by doubling (its contents are lost when it grows).
struct GrowBuffer {
    buffer: wgpu::Buffer,
    label: &'static str,
}

impl GrowBuffer {
    fn new(device: &wgpu::Device, label: &'static str, bytes: u64) -> Self {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes.max(256).next_power_of_two(),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self { buffer, label }
    }

    /// Make room for `bytes`; returns whether the buffer was replaced.
    fn reserve(&mut self, device: &wgpu::Device, bytes: u64) -> bool {
        if bytes <= self.buffer.size() {
            return false;
        }
        *self = Self::new(device, self.label, bytes);
        true
    }
}

/// The Renderer block (`@group(3)`): persistent instance transforms (binding 0) and
/// this frame's instance indices in draw order (binding 1).
pub(crate) struct InstanceBuffers {
    transforms: GrowBuffer,
    draw_indices: GrowBuffer,
    pub bind_group: wgpu::BindGroup,
}

impl InstanceBuffers {
    pub(crate) fn new(device: &wgpu::Device, layout: &wgpu::BindGroupLayout) -> Self {
        let transforms = GrowBuffer::new(device, "renderer block: instance transforms", 1024 * 64);
        let draw_indices = GrowBuffer::new(device, "renderer block: draw indices", 1024 * 4);
        let bind_group = Self::bind(device, layout, &transforms, &draw_indices);
        Self { transforms, draw_indices, bind_group }
    }

    fn bind(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        transforms: &GrowBuffer,
        indices: &GrowBuffer,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("renderer block (group 3)"),
            layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: transforms.buffer.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: indices.buffer.as_entire_binding() },
            ],
        })
    }

    /// Make room for `transforms` instances and `indices` draw indices. Returns
    /// whether the transform buffer was replaced (its contents must be written again).
    pub(crate) fn reserve(
        &mut self,
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        transforms: usize,
        indices: usize,
    ) -> (bool, bool) {
        let grew_transforms = self.transforms.reserve(device, (transforms * std::mem::size_of::<InstanceGpu>()) as u64);
        let grew_indices = self.draw_indices.reserve(device, (indices * 4) as u64);
        if grew_transforms || grew_indices {
            self.bind_group = Self::bind(device, layout, &self.transforms, &self.draw_indices);
        }
        (grew_transforms, grew_transforms || grew_indices)
    }

    /// Write `data` at instance `first` of the transform buffer; returns bytes written.
    pub(crate) fn write_transforms(&self, queue: &wgpu::Queue, first: u32, data: &[InstanceGpu]) -> u64 {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        if !bytes.is_empty() {
            queue.write_buffer(
                &self.transforms.buffer,
                u64::from(first) * std::mem::size_of::<InstanceGpu>() as u64,
                bytes,
            );
        }
        bytes.len() as u64
    }

    /// Write one draw index at position `at` (the naive baseline's per-draw upload).
    pub(crate) fn write_draw_index(&self, queue: &wgpu::Queue, at: u32, index: u32) -> u64 {
        queue.write_buffer(&self.draw_indices.buffer, u64::from(at) * 4, bytemuck::bytes_of(&index));
        4
    }

    /// Write this frame's draw indices in one upload; returns bytes written.
    pub(crate) fn write_draw_indices(&self, queue: &wgpu::Queue, indices: &[u32]) -> u64 {
        let bytes: &[u8] = bytemuck::cast_slice(indices);
        if !bytes.is_empty() {
            queue.write_buffer(&self.draw_indices.buffer, 0, bytes);
        }
        bytes.len() as u64
    }
}
