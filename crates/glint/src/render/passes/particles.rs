//! Core layer: particle layers, drawn as camera-facing billboards at the end
//! of every view's forward pass (after the transparent stages, before the
//! glare), depth-tested against the scene without writing depth; a soft
//! layer fades in front of geometry where the target's depth is readable (a
//! pass of their own then: `encode.rs`). A layer is a
//! buffer of [`ParticleGpu`] records, one instance of a four-vertex strip
//! each: written from the CPU ([`Renderer::write_particles`](crate::Renderer::write_particles)) or by a compute
//! shader ([`Renderer::particle_buffer`](crate::Renderer::particle_buffer), `sim/particles`). Alpha-blended
//! layers must be written back to front; additive ones in any order. One draw
//! call a layer, whatever its count.

use crate::gpu::TargetFormat;
use crate::gpu::{ParticleGpu, MAX_LAYER_PARTICLES};
use crate::render::debug::explain::DrawCall;
use crate::render::debug::outline::Outline;
use crate::render::debug::stats::FrameStats;
use crate::render::error::RenderError;
use crate::render::resources::registry::Registry;
use crate::render::resources::transparency_twins::{WEIGHTED_BLEND, WEIGHTED_FORMATS};
pub use crate::scene::ParticleBlend;
use crate::scene::Transparency;
use crate::scene::{Texture, TextureId};
use crate::shader::ParticleShading;
use std::collections::HashMap;

/// What a layer's particles look like.
#[derive(Clone, Debug)]
pub struct ParticleLook {
    /// How they blend.
    pub blend: ParticleBlend,
    /// The sprite each billboard shows, times its colour (a soft round spot
    /// without one): a texture of this renderer's registry, uploaded once
    /// however many layers and materials show it.
    pub texture: Option<TextureId>,
    /// World units over which a particle fades out in front of geometry
    /// (0: none). Soft where the target's depth is readable (the devices that
    /// occlusion-cull: [`Gpu::occlusion_culls`](crate::Gpu::occlusion_culls));
    /// elsewhere (GL, WebGL2) particles meet geometry hard.
    pub soft: f32,
    /// Lit by the frame's lights, as a medium with no normal: the sprite
    /// times the colour times the ambient light and every light arriving at
    /// the particle's fragment, unshadowed (point and spot lights from the
    /// view's light clusters where it has them). Else (the default) the
    /// colour is shown as it is, as a light of its own.
    pub lit: bool,
}

/// A particle layer of a [`Renderer`](crate::Renderer) ([`Renderer::add_particles`](crate::Renderer::add_particles)).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ParticlesId(pub(crate) u32);

/// One layer's records and sprite.
pub(crate) struct ParticleLayer {
    buffer: wgpu::Buffer,
    capacity: u32,
    count: u32,
    blend: ParticleBlend,
    soft: f32,
    lit: bool,
    /// The registry texture it shows, uploaded on its first frame.
    sprite: TextureId,
    look_block: wgpu::Buffer,
    /// Its sprite group (group 2), made on its first frame.
    group: Option<wgpu::BindGroup>,
}

/// A particle pipeline: for a target, a blend, whether it reads depth,
/// whether it is lit (and from light clusters), and for alpha-blended
/// layers the transparency it draws for (sorted: blended over the target;
/// weighted or exact: into the view's sums or lists, `passes/transparency.rs`).
type PipelineKey = (TargetFormat, ParticleBlend, bool, Option<bool>, Transparency);

/// Which of a frame's layers a pass draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Layers {
    /// All of them, over the target (a view drawing transparency sorted).
    All,
    /// The additive ones (the alpha-blended went into the transparency pass).
    Additive,
    /// The alpha-blended ones, into the view's sums or lists.
    Alpha(Transparency),
}

/// The particle pipelines and their layouts: the sprite group, and for soft
/// layers the scene's depth (single-sampled or multisampled).
pub(crate) struct ParticlePipelines {
    /// The Scene block's (group 0), for the exact layouts.
    scene_layout: wgpu::BindGroupLayout,
    texture_layout: wgpu::BindGroupLayout,
    depth_layouts: [wgpu::BindGroupLayout; 2],
    /// Hard; soft on one sample; soft on several.
    layouts: [wgpu::PipelineLayout; 3],
    /// Those with exact transparency's lists in group 1, made with the first
    /// exact pipeline.
    exact_layouts: Option<[wgpu::PipelineLayout; 3]>,
    modules: HashMap<ParticleShading, wgpu::ShaderModule>,
    cache: HashMap<PipelineKey, wgpu::RenderPipeline>,
    /// Whether targets' depth is readable here (the devices that
    /// occlusion-cull; GL's shaders cannot load from depth textures).
    soft: bool,
    /// Whether the light clusters are a data texture (the Scene layout's binding 10).
    data_textures: bool,
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
    pub(crate) fn new(
        device: &wgpu::Device,
        (scene, camera): (&wgpu::BindGroupLayout, &wgpu::BindGroupLayout),
        (soft, data_textures): (bool, bool),
    ) -> Self {
        let look = wgpu::BindGroupLayoutEntry {
            binding: 2,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let texture_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("renderer: particle sprite layout (group 2)"),
            entries: &[crate::gpu::texture_entry(0), crate::gpu::sampler_entry(1), look],
        });
        let depth_layout = |multisampled: bool| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("renderer: particle scene depth layout (group 3)"),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Depth,
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled,
                    },
                    count: None,
                }],
            })
        };
        let depth_layouts = [depth_layout(false), depth_layout(true)];
        let layouts = pipeline_layouts(device, [scene, camera, &texture_layout], &depth_layouts);
        let (modules, cache) = (HashMap::new(), HashMap::new());
        let exact_layouts = None;
        let scene_layout = scene.clone();
        Self {
            scene_layout,
            texture_layout,
            depth_layouts,
            layouts,
            exact_layouts,
            modules,
            cache,
            soft,
            data_textures,
        }
    }

    /// Build the pipeline of `key` unless it exists; returns whether it was
    /// built now.
    fn build(&mut self, device: &wgpu::Device, key: PipelineKey) -> bool {
        if self.cache.contains_key(&key) {
            return false;
        }
        let (target, blend, soft, lit, transparency) = key;
        let variant = soft.then_some(target.samples > 1);
        let lists = transparency == Transparency::Exact;
        let shading = ParticleShading { soft: variant, lit, data_textures: self.data_textures, lists };
        let module = match self.modules.entry(shading) {
            std::collections::hash_map::Entry::Occupied(built) => built.into_mut(),
            std::collections::hash_map::Entry::Vacant(slot) => {
                let wgsl = crate::shader::particles(shading);
                slot.insert(crate::render::resources::pipelines::shader_module(
                    device,
                    "renderer: particle shader",
                    wgsl,
                ))
            }
        };
        let layouts = match lists {
            true => self.exact_layouts.as_ref().unwrap_or(&self.layouts),
            false => &self.layouts,
        };
        let layout = &layouts[match variant {
            None => 0,
            Some(false) => 1,
            Some(true) => 2,
        }];
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
        let over = [Some(wgpu::ColorTargetState {
            format: target.color,
            blend: Some(wgpu::BlendState { color, alpha: keep_alpha }),
            write_mask: wgpu::ColorWrites::ALL,
        })];
        let weighted = WEIGHTED_FORMATS.map(|format| {
            Some(wgpu::ColorTargetState { format, blend: Some(WEIGHTED_BLEND), write_mask: wgpu::ColorWrites::ALL })
        });
        let (entry, targets): (_, &[_]) = match transparency {
            Transparency::Sorted => ("fs_particle", &over),
            Transparency::Weighted => ("fs_particle_weighted", &weighted),
            Transparency::Exact => ("fs_particle_exact", &[]),
        };
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("renderer: particle pipeline"),
            layout: Some(layout),
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
            depth_stencil: Some(crate::render::resources::pipelines::depth_stencil(&states, crate::gpu::DEPTH_FORMAT)),
            multisample: wgpu::MultisampleState { count: target.samples, ..Default::default() },
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                targets,
            }),
            multiview_mask: None,
            cache: None,
        });
        self.cache.insert(key, pipeline);
        true
    }
}

/// The particle layers a renderer draws in every view, their pipelines, and
/// the soft round spot the layers without a sprite show (added once).
pub(crate) struct Particles {
    layers: Vec<ParticleLayer>,
    spot: Option<TextureId>,
    pipelines: ParticlePipelines,
}

impl Particles {
    /// No layers yet; pipelines over the Scene and Camera layouts, soft layers
    /// reading depth where `soft`, lit ones reading the light clusters from a
    /// data texture where `data_textures`.
    pub(crate) fn new(
        device: &wgpu::Device,
        layouts: (&wgpu::BindGroupLayout, &wgpu::BindGroupLayout),
        (soft, data_textures): (bool, bool),
    ) -> Self {
        let pipelines = ParticlePipelines::new(device, layouts, (soft, data_textures));
        Self { layers: Vec::new(), spot: None, pipelines }
    }

    /// A particle layer of `capacity` billboards (at most [`MAX_LAYER_PARTICLES`]), drawn in
    /// every view from the next frame on; none to draw until written.
    pub(crate) fn add(
        &mut self,
        registry: &mut Registry,
        storage: bool,
        (capacity, look): (u32, ParticleLook),
    ) -> Result<ParticlesId, RenderError> {
        let capacity = capacity.clamp(1, MAX_LAYER_PARTICLES);
        let sprite = match look.texture {
            Some(id) => id,
            None => *self.spot.get_or_insert_with(|| registry.add_texture(spot())),
        };
        let device = &registry.device;
        let scope = crate::gpu::DriverErrors::watch(device);
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("renderer: particles"),
            size: capacity as u64 * std::mem::size_of::<ParticleGpu>() as u64,
            usage: match storage {
                true => wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                false => wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            },
            mapped_at_creation: false,
        });
        let soft = if look.soft.is_finite() { look.soft.max(0.0) } else { 0.0 };
        let look_block = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("renderer: particle look"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        registry.queue.write_buffer(&look_block, 0, bytemuck::cast_slice(&[soft, 0.0, 0.0, 0.0]));
        if let Some(error) = scope.finish() {
            return Err(RenderError::Device { what: "a particle layer", message: error.to_string() });
        }
        let (blend, lit) = (look.blend, look.lit);
        let layer = ParticleLayer { buffer, capacity, count: 0, blend, soft, lit, sprite, look_block, group: None };
        self.layers.push(layer);
        Ok(ParticlesId(self.layers.len() as u32 - 1))
    }

    /// Draw `records` in layer `id` from the next frame on (as many as fit).
    pub(crate) fn write(&mut self, queue: &wgpu::Queue, id: ParticlesId, records: &[ParticleGpu]) {
        let Some(layer) = self.layers.get_mut(id.0 as usize) else { return };
        let count = records.len().min(layer.capacity as usize);
        queue.write_buffer(&layer.buffer, 0, bytemuck::cast_slice(&records[..count]));
        layer.count = count as u32;
    }

    /// Layer `id`'s record buffer, for a compute shader to write (it allows
    /// storage where the device computes), and its capacity.
    pub(crate) fn buffer(&self, id: ParticlesId) -> Option<(&wgpu::Buffer, u32)> {
        self.layers.get(id.0 as usize).map(|l| (&l.buffer, l.capacity))
    }

    /// Draw the first `count` records of layer `id` (as written by a compute shader).
    pub(crate) fn set_count(&mut self, id: ParticlesId, count: u32) {
        if let Some(layer) = self.layers.get_mut(id.0 as usize) {
            layer.count = count.min(layer.capacity);
        }
    }

    /// Stage 1 for particles: every layer to draw gets its sprite (uploaded
    /// once however many layers and materials show it, counted in `stats`)
    /// and its pipelines for `target` (a soft layer's both ways where depth is
    /// readable: a view's target may not be), a lit one's for a view whose
    /// lights are `clustered` or not.
    pub(crate) fn prepare(
        &mut self,
        registry: &mut Registry,
        (target, clustered): (TargetFormat, bool),
        stats: &mut FrameStats,
    ) -> Result<(), RenderError> {
        for layer in self.layers.iter_mut().filter(|l| l.count > 0) {
            if layer.group.is_none() {
                stats.bytes_uploaded.textures += registry.upload_texture(layer.sprite, "particle layer")?;
                // A sprite that could not be uploaded shows white, as a material's map does.
                let uploaded = registry.textures[layer.sprite.0 as usize].view.as_ref();
                let view = uploaded.unwrap_or(&registry.defaults.white_srgb);
                layer.group = Some(registry.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("renderer: particle sprite"),
                    layout: &self.pipelines.texture_layout,
                    entries: &[
                        wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(view) },
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: wgpu::BindingResource::Sampler(&registry.sampler),
                        },
                        wgpu::BindGroupEntry { binding: 2, resource: layer.look_block.as_entire_binding() },
                    ],
                }));
            }
            for soft in [false, layer.soft > 0.0 && self.pipelines.soft] {
                let lit = layer.lit.then_some(clustered);
                let built =
                    self.pipelines.build(&registry.device, (target, layer.blend, soft, lit, Transparency::Sorted));
                stats.pipelines_compiled += u32::from(built);
            }
        }
        Ok(())
    }

    /// A view's order-independent transparency `way` (not sorted) for
    /// particles: the alpha-blended layers with records get their pipelines
    /// into its sums or lists (exact ones' group 1 `lists`, the Camera block
    /// and the lists). Returns whether it has any such layer.
    pub(crate) fn prepare_transparency(
        &mut self,
        device: &wgpu::Device,
        (target, clustered): (TargetFormat, bool),
        (way, lists): (Transparency, Option<&wgpu::BindGroupLayout>),
        stats: &mut FrameStats,
    ) -> bool {
        let pipelines = &mut self.pipelines;
        if let (Some(lists), None) = (lists, &pipelines.exact_layouts) {
            let groups = [&pipelines.scene_layout, lists, &pipelines.texture_layout];
            pipelines.exact_layouts = Some(pipeline_layouts(device, groups, &pipelines.depth_layouts));
        }
        let mut any = false;
        for layer in self.layers.iter().filter(|l| l.count > 0 && l.blend == ParticleBlend::Alpha) {
            for soft in [false, layer.soft > 0.0 && pipelines.soft] {
                let built = pipelines.build(device, (target, layer.blend, soft, layer.lit.then_some(clustered), way));
                stats.pipelines_compiled += u32::from(built);
            }
            any = true;
        }
        any
    }

    /// The scene depth a frame's soft layers read from `target`, when some
    /// layer to draw is soft and the depth is readable; the frame then draws
    /// its particles in a pass of their own.
    pub(crate) fn depth(&self, device: &wgpu::Device, target: &crate::OffscreenTarget) -> Option<wgpu::BindGroup> {
        let depth = target.depth_only_view().filter(|_| self.pipelines.soft)?;
        self.layers.iter().any(|l| l.count > 0 && l.soft > 0.0).then(|| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("renderer: particle scene depth"),
                layout: &self.pipelines.depth_layouts[usize::from(target.samples() > 1)],
                entries: &[wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(depth) }],
            })
        })
    }

    /// Stage 7's last draws before the glare (or, for `Layers::Alpha`, the
    /// transparency pass's): every layer of `layers` with records, one
    /// draw each, soft ones reading `depth` when given (group 3), lit ones
    /// from the view's light clusters where `clustered`. Leaves groups 0 and 1 bound.
    pub(crate) fn draw(
        &self,
        (pass, outline): (&mut wgpu::RenderPass<'_>, &Outline),
        (target, clustered, layers): (TargetFormat, bool, Layers),
        depth: Option<&wgpu::BindGroup>,
        stats: &mut FrameStats,
    ) {
        let (drawn, way) = match layers {
            Layers::All => (None, Transparency::Sorted),
            Layers::Additive => (Some(ParticleBlend::Additive), Transparency::Sorted),
            Layers::Alpha(way) => (Some(ParticleBlend::Alpha), way),
        };
        for layer in self.layers.iter().filter(|l| l.count > 0 && drawn.is_none_or(|b| b == l.blend)) {
            let soft = depth.filter(|_| layer.soft > 0.0);
            let lit = layer.lit.then_some(clustered);
            let pipeline = self.pipelines.cache.get(&(target, layer.blend, soft.is_some(), lit, way));
            let (Some(pipeline), Some(group)) = (pipeline, &layer.group) else { continue };
            pass.set_pipeline(pipeline);
            pass.set_bind_group(2, group, &[]);
            if let Some(depth) = soft {
                pass.set_bind_group(3, depth, &[]);
            }
            pass.set_vertex_buffer(0, layer.buffer.slice(..));
            pass.draw(0..4, 0..layer.count);
            outline.call(|| {
                let what = format!(
                    "particles ({}{}{})",
                    format!("{:?}", layer.blend).to_lowercase(),
                    if soft.is_some() { ", soft" } else { "" },
                    match lit {
                        Some(true) => ", lit from the light clusters",
                        Some(false) => ", lit",
                        None => "",
                    }
                );
                let mut changed = vec!["pipeline", "bind group 2 (particle layer)", "vertex buffer 0 (records)"];
                changed.extend(soft.map(|_| "bind group 3 (scene depth)"));
                let count = u64::from(layer.count);
                DrawCall::single(&what, "draw", (count, 2 * count), &changed)
            });
            stats.draw_calls += 1;
            stats.draws += 1;
            stats.bind_groups_set += 1 + u32::from(soft.is_some());
            stats.particles_drawn += layer.count;
        }
    }
}

/// The particle pipeline layouts over `[scene, camera, sprite]` (group 1
/// the Camera block, or exact transparency's lists beside it): hard, and
/// soft reading a single-sampled or a multisampled depth (group 3).
fn pipeline_layouts(
    device: &wgpu::Device,
    [scene, camera, sprite]: [&wgpu::BindGroupLayout; 3],
    depth: &[wgpu::BindGroupLayout; 2],
) -> [wgpu::PipelineLayout; 3] {
    [None, Some(&depth[0]), Some(&depth[1])].map(|depth| {
        device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("renderer: particle pipeline layout"),
            bind_group_layouts: &[Some(scene), Some(camera), Some(sprite), depth],
            immediate_size: 0,
        })
    })
}
