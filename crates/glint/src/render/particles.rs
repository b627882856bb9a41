//! Core layer: particle layers, drawn as camera-facing billboards at the end
//! of every view's forward pass (after the transparent stages, before the
//! glare), depth-tested against the scene without writing depth. A layer is a
//! buffer of [`ParticleGpu`] records, one instance of a four-vertex strip
//! each: written from the CPU ([`Renderer::write_particles`]) or by a compute
//! shader ([`Renderer::particle_buffer`], `sim/particles`). Alpha-blended
//! layers must be written back to front; additive ones in any order. One draw
//! call a layer, whatever its count.

use super::{RenderError, Renderer};
use crate::asset::Texture;
use crate::gpu::TargetFormat;
use crate::FrameStats;
use std::collections::HashMap;

/// Most records one layer holds: 128 MiB, the storage binding every adapter has.
pub const MAX_LAYER_PARTICLES: u32 = 1 << 22;

/// One billboard (32 bytes): the per-instance vertex data of the particle
/// pipeline (locations 0 and 1) and what `particles.wgsl` writes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ParticleGpu {
    /// xyz: the centre; w: the side, world units (0: not drawn).
    pub center_size: [f32; 4],
    /// Linear RGB and alpha.
    pub color: [f32; 4],
}

/// How a layer's particles blend into the picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ParticleBlend {
    /// Added to what is behind (fire, sparks, glow): no order needed.
    Additive,
    /// Over what is behind by their alpha (smoke, bubbles): written back to front.
    Alpha,
}

/// What a layer's particles look like.
#[derive(Clone, Debug)]
pub struct ParticleLook {
    /// How they blend.
    pub blend: ParticleBlend,
    /// The sprite each billboard shows, times its colour (a soft round spot
    /// without one).
    pub texture: Option<Texture>,
}

/// A particle layer of a [`Renderer`] ([`Renderer::add_particles`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ParticlesId(pub(crate) u32);

/// One layer's records and sprite.
pub(crate) struct ParticleLayer {
    buffer: wgpu::Buffer,
    capacity: u32,
    count: u32,
    blend: ParticleBlend,
    group: wgpu::BindGroup,
}

/// The particle pipelines (one per target format and blend) and their sprite layout.
pub(crate) struct ParticlePipelines {
    texture_layout: wgpu::BindGroupLayout,
    layout: wgpu::PipelineLayout,
    module: Option<wgpu::ShaderModule>,
    cache: HashMap<(TargetFormat, ParticleBlend), wgpu::RenderPipeline>,
}

/// The soft round spot a layer without a texture shows.
fn spot() -> Texture {
    let image = image::RgbaImage::from_fn(64, 64, |x, y| {
        let d = ((x as f32 - 31.5).powi(2) + (y as f32 - 31.5).powi(2)).sqrt() / 32.0;
        let a = (1.0 - d).clamp(0.0, 1.0).powf(1.5);
        image::Rgba([255, 255, 255, (a * 255.0) as u8])
    });
    Texture::new("particle spot", image, true)
}

impl ParticlePipelines {
    pub(crate) fn new(device: &wgpu::Device, scene: &wgpu::BindGroupLayout, camera: &wgpu::BindGroupLayout) -> Self {
        let texture_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("renderer: particle sprite layout (group 2)"),
            entries: &[crate::gpu::texture_entry(0), crate::gpu::sampler_entry(1)],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("renderer: particle pipeline layout"),
            bind_group_layouts: &[Some(scene), Some(camera), Some(&texture_layout)],
            immediate_size: 0,
        });
        Self { texture_layout, layout, module: None, cache: HashMap::new() }
    }

    /// Build the pipeline for `target` and `blend` unless it exists; returns
    /// whether it was built now.
    fn build(
        &mut self,
        device: &wgpu::Device,
        library: &mut crate::shader::ShaderLibrary,
        (target, blend): (TargetFormat, ParticleBlend),
    ) -> Result<bool, RenderError> {
        if self.cache.contains_key(&(target, blend)) {
            return Ok(false);
        }
        if self.module.is_none() {
            let module = library.particles().map_err(RenderError::Shader)?;
            self.module = Some(super::pipelines::shader_module(device, "renderer: particle shader", module));
        }
        let module = self.module.as_ref().expect("built above");
        let color = match blend {
            ParticleBlend::Additive => wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::One,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            },
            // The shader's colour is premultiplied by its alpha.
            ParticleBlend::Alpha => wgpu::BlendComponent::OVER,
        };
        let keep_alpha = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::Zero,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let states = crate::scene::RenderStates {
            depth: crate::scene::DepthState { compare: crate::scene::Compare::LessEqual, write: false },
            ..Default::default()
        };
        let attributes = wgpu::vertex_attr_array![0 => Float32x4, 1 => Float32x4];
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("renderer: particle pipeline"),
            layout: Some(&self.layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some("vs_particle"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<ParticleGpu>() as u64,
                    step_mode: wgpu::VertexStepMode::Instance,
                    attributes: &attributes,
                })],
            },
            primitive: wgpu::PrimitiveState { topology: wgpu::PrimitiveTopology::TriangleStrip, ..Default::default() },
            depth_stencil: Some(super::pipelines::depth_stencil(&states, crate::gpu::DEPTH_FORMAT)),
            multisample: wgpu::MultisampleState { count: target.samples, ..Default::default() },
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some("fs_particle"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: target.color,
                    blend: Some(wgpu::BlendState { color, alpha: keep_alpha }),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        self.cache.insert((target, blend), pipeline);
        Ok(true)
    }
}

impl Renderer {
    /// A particle layer of `capacity` billboards (at most [`MAX_LAYER_PARTICLES`]), drawn in
    /// every view from the next frame on; none to draw until written.
    pub fn add_particles(&mut self, capacity: u32, look: ParticleLook) -> ParticlesId {
        let capacity = capacity.clamp(1, MAX_LAYER_PARTICLES);
        let registry = &mut self.registry;
        let buffer = registry.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("renderer: particles"),
            size: capacity as u64 * std::mem::size_of::<ParticleGpu>() as u64,
            usage: match self.cull_pipelines.is_some() {
                true => wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                false => wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            },
            mapped_at_creation: false,
        });
        let sprite = look.texture.unwrap_or_else(spot);
        let (view, _, blits) = registry.uploader.upload(&registry.device, &registry.queue, &sprite);
        registry.mip_blits.extend(blits);
        let group = registry.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("renderer: particle sprite"),
            layout: &self.particle_pipelines.texture_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&registry.sampler) },
            ],
        });
        self.particle_layers.push(ParticleLayer { buffer, capacity, count: 0, blend: look.blend, group });
        ParticlesId(self.particle_layers.len() as u32 - 1)
    }

    /// Draw `records` in layer `id` from the next frame on (as many as fit).
    pub fn write_particles(&mut self, id: ParticlesId, records: &[ParticleGpu]) {
        let Some(layer) = self.particle_layers.get_mut(id.0 as usize) else { return };
        let count = records.len().min(layer.capacity as usize);
        self.queue.write_buffer(&layer.buffer, 0, bytemuck::cast_slice(&records[..count]));
        layer.count = count as u32;
    }

    /// Layer `id`'s record buffer, for a compute shader to write (it allows
    /// storage where the device computes), and its capacity.
    pub fn particle_buffer(&self, id: ParticlesId) -> Option<(&wgpu::Buffer, u32)> {
        self.particle_layers.get(id.0 as usize).map(|l| (&l.buffer, l.capacity))
    }

    /// Draw the first `count` records of layer `id` (as written by a compute shader).
    pub fn set_particle_count(&mut self, id: ParticlesId, count: u32) {
        if let Some(layer) = self.particle_layers.get_mut(id.0 as usize) {
            layer.count = count.min(layer.capacity);
        }
    }

    /// Stage 1 for particles: the pipelines of every layer for `target`.
    pub(super) fn prepare_particles(
        &mut self,
        target: TargetFormat,
        stats: &mut FrameStats,
    ) -> Result<(), RenderError> {
        let registry = &mut self.registry;
        for layer in self.particle_layers.iter().filter(|l| l.count > 0) {
            let built = self.particle_pipelines.build(
                &registry.device,
                &mut registry.pipelines.library,
                (target, layer.blend),
            )?;
            stats.pipelines_compiled += u32::from(built);
        }
        Ok(())
    }

    /// Stage 7's last draws before the glare: every layer with records, one
    /// draw each. Leaves groups 0 and 1 bound.
    pub(super) fn draw_particles(&self, pass: &mut wgpu::RenderPass<'_>, target: TargetFormat, stats: &mut FrameStats) {
        for layer in self.particle_layers.iter().filter(|l| l.count > 0) {
            let Some(pipeline) = self.particle_pipelines.cache.get(&(target, layer.blend)) else { continue };
            pass.set_pipeline(pipeline);
            pass.set_bind_group(2, &layer.group, &[]);
            pass.set_vertex_buffer(0, layer.buffer.slice(..));
            pass.draw(0..4, 0..layer.count);
            stats.draw_calls += 1;
            stats.draws += 1;
            stats.bind_groups_set += 1;
            stats.particles_drawn += layer.count;
        }
    }
}
