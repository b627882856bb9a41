//! Core layer: a view's post-processing chain. The view was drawn into an HDR
//! target; each [`PostEffect`] runs in order on full-screen triangles
//! (`shader/post.wgsl`; SMAA's three passes `shader/smaa.wgsl`), between two
//! full-size intermediate targets (bloom also uses two at half size, SMAA two
//! more at full size for its edges and blending weights), and the last pass
//! writes the view's rectangle of the output. Intermediates are kept between
//! frames by size, never made per frame; each effect's parameters are written
//! only when they change. SMAA's area texture is computed and uploaded the
//! first time a chain holds SMAA (`smaa_area.rs`).

use super::smaa_area;
use crate::gpu::{sampler_entry, texture_entry, DEPTH_FORMAT, HDR_FORMAT};
use crate::render::debug::stats::PassStats;
use crate::render::debug::timer::{GpuTimer, Timed};
use crate::render::error::RenderError;
use crate::render::resources::target_pool::TargetPool;
use crate::scene::{PostEffect, Tonemap, MAX_POST_EFFECTS};
use std::collections::HashMap;

/// Full-screen passes one chain may take (bloom takes four, SMAA three).
const MAX_PASSES: usize = 4 * MAX_POST_EFFECTS;
/// Bytes between pass parameter records: the dynamic-offset alignment every device accepts.
const PARAMS_STRIDE: u64 = 256;

/// A full-screen pass: one fragment entry point of `post.wgsl`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Pass {
    Bright,
    Blur,
    BloomAdd,
    Tonemap,
    Fxaa,
    Edges,
    Vignette,
    SmaaEdges,
    SmaaWeights,
    SmaaBlend,
}

/// The shader module a pass's entry point is in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Module {
    Post,
    Smaa,
}

/// The intermediate SMAA marks the pixels on edges in (a stencil of
/// [`DEPTH_FORMAT`]), so that its costly weights pass shades only those.
const SMAA_STENCIL: usize = 6;

impl Pass {
    /// How the pass uses SMAA's stencil: the edges pass marks the pixels on
    /// an edge, the weights pass runs only on them (on GPUs that shade in
    /// lockstep, as CPU rasterizers do, a branch around the weights'
    /// searches would not save their cost).
    fn stencil(self) -> Option<wgpu::StencilFaceState> {
        let (compare, pass_op) = match self {
            Pass::SmaaEdges => (wgpu::CompareFunction::Always, wgpu::StencilOperation::Replace),
            Pass::SmaaWeights => (wgpu::CompareFunction::Equal, wgpu::StencilOperation::Keep),
            _ => return None,
        };
        Some(wgpu::StencilFaceState { compare, pass_op, ..wgpu::StencilFaceState::IGNORE })
    }

    fn module(self) -> Module {
        match self {
            Pass::SmaaEdges | Pass::SmaaWeights | Pass::SmaaBlend => Module::Smaa,
            _ => Module::Post,
        }
    }

    fn entry_point(self) -> &'static str {
        match self {
            Pass::Bright => "fs_bright",
            Pass::Blur => "fs_blur",
            Pass::BloomAdd => "fs_bloom_add",
            Pass::Tonemap => "fs_tonemap",
            Pass::Fxaa => "fs_fxaa",
            Pass::Edges => "fs_edges",
            Pass::Vignette => "fs_vignette",
            Pass::SmaaEdges => "fs_smaa_edges",
            Pass::SmaaWeights => "fs_smaa_weights",
            Pass::SmaaBlend => "fs_smaa_blend",
        }
    }
}

/// The parameters block of `post.wgsl` and `smaa.wgsl`: `a`, then the
/// input's texel size and its size in pixels.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    a: [f32; 4],
    texel: [f32; 4],
}

/// Where a pass reads or writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Image {
    /// The view as drawn (HDR).
    Scene,
    /// Intermediate `k`: 0 and 1 full size, 2 and 3 half size, 4 and 5 full
    /// size (SMAA's edges and blending weights; [`SMAA_STENCIL`] its stencil).
    Pooled(usize),
    /// The view's rectangle of the output.
    Output,
}

/// One full-screen pass of a chain.
struct Step {
    pass: Pass,
    a: [f32; 4],
    source: Image,
    extra: Option<Image>,
    target: Image,
}

/// The passes `chain` takes, in order.
fn steps(chain: &[PostEffect]) -> Vec<(usize, Step)> {
    let mut out = Vec::new();
    let mut current = Image::Scene;
    for (k, effect) in chain.iter().enumerate() {
        let target = if k + 1 == chain.len() {
            Image::Output
        } else if current == Image::Pooled(0) {
            Image::Pooled(1)
        } else {
            Image::Pooled(0)
        };
        let step = |pass, a, source, extra, target| (k, Step { pass, a, source, extra, target });
        match *effect {
            PostEffect::Bloom { threshold, intensity } => {
                let (half, other) = (Image::Pooled(2), Image::Pooled(3));
                out.push(step(Pass::Bright, [threshold, 0.0, 0.0, 0.0], current, None, half));
                out.push(step(Pass::Blur, [1.0, 0.0, 0.0, 0.0], half, None, other));
                out.push(step(Pass::Blur, [0.0, 1.0, 0.0, 0.0], other, None, half));
                out.push(step(Pass::BloomAdd, [intensity, 0.0, 0.0, 0.0], current, Some(half), target));
            }
            PostEffect::Tonemap { operator, exposure } => {
                let op = match operator {
                    Tonemap::None => 0.0,
                    Tonemap::Reinhard => 1.0,
                    Tonemap::Aces => 2.0,
                    Tonemap::Agx => 3.0,
                };
                out.push(step(Pass::Tonemap, [exposure, op, 0.0, 0.0], current, None, target));
            }
            PostEffect::Fxaa => out.push(step(Pass::Fxaa, [0.0; 4], current, None, target)),
            PostEffect::Smaa { preset } => {
                let (a, edges, weights) = (preset.settings(), Image::Pooled(4), Image::Pooled(5));
                out.push(step(Pass::SmaaEdges, a, current, None, edges));
                out.push(step(Pass::SmaaWeights, a, edges, None, weights));
                out.push(step(Pass::SmaaBlend, a, current, Some(weights), target));
            }
            PostEffect::Edges { color, threshold } => {
                out.push(step(Pass::Edges, [color.x, color.y, color.z, threshold], current, None, target))
            }
            PostEffect::Vignette { strength } => {
                out.push(step(Pass::Vignette, [strength, 0.0, 0.0, 0.0], current, None, target))
            }
        }
        current = target;
    }
    out
}

/// The size of intermediate `slot` in a chain of `size`: 2 and 3 are half size.
fn slot_size(slot: usize, (width, height): (u32, u32)) -> (u32, u32) {
    match slot {
        2 | 3 => ((width / 2).max(1), (height / 2).max(1)),
        _ => (width, height),
    }
}

/// What a chain draws from and into.
pub(crate) struct ChainImages<'a> {
    /// The view drawn in HDR, and its size.
    pub scene: &'a wgpu::TextureView,
    /// Its size in pixels (the rectangle's).
    pub size: (u32, u32),
    /// The output and its colour format.
    pub output: &'a wgpu::TextureView,
    /// The output's colour format.
    pub output_format: wgpu::TextureFormat,
    /// The rectangle of the output the chain's last pass fills: x, y, width, height.
    pub rect: [u32; 4],
}

/// A view's post-pass parameter records, one per pass of its chain, each
/// written only when it changes.
pub(crate) struct PostParams {
    buffer: wgpu::Buffer,
    last: Vec<Option<Params>>,
}

impl PostParams {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("post: pass parameters"),
            size: PARAMS_STRIDE * MAX_PASSES as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self { buffer, last: vec![None; MAX_PASSES] }
    }
}

/// The post shader, its pipelines and intermediate targets.
pub(crate) struct PostChain {
    layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    modules: HashMap<Module, wgpu::ShaderModule>,
    sampler: wgpu::Sampler,
    pipelines: HashMap<(Pass, wgpu::TextureFormat), wgpu::RenderPipeline>,
    /// Bound as the second input where a pass has none, and as SMAA's area
    /// texture until a chain holds SMAA.
    black: wgpu::TextureView,
    /// SMAA's area texture, once a chain has held SMAA.
    smaa_area: Option<wgpu::TextureView>,
}

impl PostChain {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let params_entry = wgpu::BindGroupLayoutEntry {
            binding: 3,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: true,
                min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<Params>() as u64),
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("post: layout"),
            entries: &[texture_entry(0), texture_entry(1), sampler_entry(2), params_entry, texture_entry(4)],
        });
        let black = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("post: black"),
            size: wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: HDR_FORMAT,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        Self {
            pipeline_layout: device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("post: pipeline layout"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            }),
            layout,
            modules: HashMap::new(),
            sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("post: linear clamp"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..Default::default()
            }),
            pipelines: HashMap::new(),
            black: black.create_view(&Default::default()),
            smaa_area: None,
        }
    }

    /// Record `chain` from `images.scene` into `images.output`, its passes'
    /// parameters in `params` (the view's own: views' chains share one
    /// submission), its intermediate images from `pool`. Returns the chain's draws; the GPU time of effect k is timed
    /// as `Timed::Post(k)` by `timer`, for frame `frame_index`.
    pub(crate) fn encode(
        &mut self,
        (device, queue): (&wgpu::Device, &wgpu::Queue),
        (params, pool): (&mut PostParams, &mut TargetPool),
        encoder: &mut wgpu::CommandEncoder,
        chain: &[PostEffect],
        images: &ChainImages,
        (frame_index, mut timer, outline): (u64, Option<&mut GpuTimer>, &crate::render::debug::outline::Outline),
    ) -> Result<PassStats, RenderError> {
        if chain.len() > MAX_POST_EFFECTS {
            return Err(RenderError::PostChainTooLong(chain.len()));
        }
        let steps = steps(chain);
        self.prepare((device, queue), &steps, images, (pool, frame_index))?;
        let pool = &*pool;
        let size_of = |image: Image| match image {
            Image::Pooled(slot) => slot_size(slot, images.size),
            _ => images.size,
        };
        let mut stats = PassStats::default();
        for (k, (effect, step)) in steps.iter().enumerate() {
            let (sw, sh) = size_of(step.source);
            let (w, h) = (sw as f32, sh as f32);
            let record = Params { a: step.a, texel: [1.0 / w, 1.0 / h, w, h] };
            if params.last[k] != Some(record) {
                queue.write_buffer(&params.buffer, PARAMS_STRIDE * k as u64, bytemuck::bytes_of(&record));
                params.last[k] = Some(record);
            }
            let source = self.view(step.source, images, pool)?;
            let extra = match step.extra {
                Some(e) => self.view(e, images, pool)?,
                None => &self.black,
            };
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("post: pass inputs"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(source) },
                    wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(extra) },
                    wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::Sampler(&self.sampler) },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer: &params.buffer,
                            offset: 0,
                            size: wgpu::BufferSize::new(std::mem::size_of::<Params>() as u64),
                        }),
                    },
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: wgpu::BindingResource::TextureView(self.smaa_area.as_ref().unwrap_or(&self.black)),
                    },
                ],
            });
            let first = k == 0 || steps[k - 1].0 != *effect;
            let last = steps.get(k + 1).is_none_or(|(next, _)| next != effect);
            let writes = timer.as_ref().and_then(|t| t.pass_writes(Timed::Post(*effect as u8), first, last));
            let format = if step.target == Image::Output { images.output_format } else { HDR_FORMAT };
            let label = format!("post: {} ({})", chain[*effect].name(), step.pass.entry_point());
            // SMAA's passes write only the pixels on edges: the rest is cleared.
            let stencil = step.pass.stencil().map(|_| self.stencil_attachment(step, images, pool)).transpose()?;
            let stencil_marks = stencil.is_some();
            let load = if stencil_marks { wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT) } else { wgpu::LoadOp::Load };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(&label),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: self.view(step.target, images, pool)?,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations { load, store: wgpu::StoreOp::Store },
                })],
                depth_stencil_attachment: stencil,
                timestamp_writes: writes,
                ..Default::default()
            });
            if stencil_marks {
                pass.set_stencil_reference(1);
            }
            if step.target == Image::Output {
                let [x, y, w, h] = images.rect;
                pass.set_viewport(x as f32, y as f32, w as f32, h as f32, 0.0, 1.0);
            }
            pass.set_pipeline(&self.pipelines[&(step.pass, format)]);
            pass.set_bind_group(0, &bind_group, &[(PARAMS_STRIDE * k as u64) as u32]);
            pass.draw(0..3, 0..1);
            drop(pass);
            outline.pass(&label, crate::render::debug::explain::PassType::Render, &[]);
            let changed = ["pipeline", "bind group 0 (the step's images and parameters)", "stencil reference"];
            let changed = &changed[..if stencil_marks { 3 } else { 2 }];
            outline.call(|| crate::render::debug::explain::DrawCall::single(&label, "draw", (1, 1), changed));
            if last {
                if let Some(timer) = timer.as_deref_mut() {
                    timer.resolve(encoder, Timed::Post(*effect as u8), frame_index);
                }
            }
            stats.draw_calls += 1;
            stats.draws += 1;
        }
        Ok(stats)
    }

    /// Build the pipelines, intermediate targets and lookup textures `steps` need.
    fn prepare(
        &mut self,
        (device, queue): (&wgpu::Device, &wgpu::Queue),
        steps: &[(usize, Step)],
        images: &ChainImages,
        (pool, frame_index): (&mut TargetPool, u64),
    ) -> Result<(), RenderError> {
        let scope = crate::gpu::DriverErrors::watch(device);
        for (_, step) in steps {
            let module = step.pass.module();
            let module = self.modules.entry(module).or_insert_with(|| {
                let (label, source) = match module {
                    Module::Post => ("post: shader", crate::shader::POST),
                    Module::Smaa => ("post: SMAA shader", crate::shader::SMAA),
                };
                let source = wgpu::ShaderSource::Wgsl(source.into());
                device.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some(label), source })
            });
            let format = if step.target == Image::Output { images.output_format } else { HDR_FORMAT };
            self.pipelines.entry((step.pass, format)).or_insert_with(|| {
                let label = format!("post: {} ({format:?})", step.pass.entry_point());
                let shader = (&self.pipeline_layout, &*module);
                let stencil = step.pass.stencil().map(|face| wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(false),
                    depth_compare: Some(wgpu::CompareFunction::Always),
                    stencil: wgpu::StencilState { front: face, back: face, read_mask: 1, write_mask: 1 },
                    bias: Default::default(),
                });
                let entries = ("vs_post", step.pass.entry_point());
                crate::gpu::full_screen_pipeline_with(device, &label, shader, entries, format, stencil)
            });
        }
        if self.smaa_area.is_none() && steps.iter().any(|(_, s)| s.pass.module() == Module::Smaa) {
            self.smaa_area = Some(smaa_area_texture(device, queue));
        }
        let used = |image: &Image| matches!(image, Image::Pooled(_)).then_some(*image);
        for image in steps.iter().flat_map(|(_, s)| [used(&s.source), s.extra, used(&s.target)]).flatten() {
            let Image::Pooled(slot) = image else { continue };
            pool.keep_image(device, slot_size(slot, images.size), (slot, HDR_FORMAT), frame_index);
        }
        if steps.iter().any(|(_, s)| s.pass.stencil().is_some()) {
            pool.keep_image(device, images.size, (SMAA_STENCIL, DEPTH_FORMAT), frame_index);
        }
        match scope.finish() {
            Some(error) => {
                self.modules.clear();
                self.pipelines.clear();
                Err(RenderError::Device { what: "the post-processing passes", message: error.to_string() })
            }
            None => Ok(()),
        }
    }

    /// SMAA's stencil for `step`: cleared by the edges pass, which marks the
    /// pixels on edges; kept for the weights pass, which tests it.
    fn stencil_attachment<'a>(
        &self,
        step: &Step,
        images: &ChainImages,
        pool: &'a TargetPool,
    ) -> Result<wgpu::RenderPassDepthStencilAttachment<'a>, RenderError> {
        let missing = || RenderError::Device {
            what: "the post-processing passes",
            message: format!("no SMAA stencil of {}x{}", images.size.0, images.size.1),
        };
        let view = pool.image(images.size, SMAA_STENCIL).ok_or_else(missing)?;
        let (load, store) = match step.pass {
            Pass::SmaaEdges => (wgpu::LoadOp::Clear(0), wgpu::StoreOp::Store),
            _ => (wgpu::LoadOp::Load, wgpu::StoreOp::Discard),
        };
        Ok(wgpu::RenderPassDepthStencilAttachment {
            view,
            depth_ops: None,
            stencil_ops: Some(wgpu::Operations { load, store }),
        })
    }

    /// The texture view of `image` (a pooled image as `prepare` made it).
    fn view<'a>(
        &'a self,
        image: Image,
        images: &'a ChainImages,
        pool: &'a TargetPool,
    ) -> Result<&'a wgpu::TextureView, RenderError> {
        match image {
            Image::Scene => Ok(images.scene),
            Image::Output => Ok(images.output),
            Image::Pooled(slot) => {
                let size = slot_size(slot, images.size);
                let missing = || RenderError::Device {
                    what: "the post-processing passes",
                    message: format!("no intermediate image {slot} of {}x{}", size.0, size.1),
                };
                pool.image(size, slot).ok_or_else(missing)
            }
        }
    }
}

/// SMAA's area texture on the GPU (RG8, filtered between distances).
fn smaa_area_texture(device: &wgpu::Device, queue: &wgpu::Queue) -> wgpu::TextureView {
    use wgpu::util::DeviceExt;
    let size = wgpu::Extent3d { width: smaa_area::WIDTH, height: smaa_area::HEIGHT, depth_or_array_layers: 1 };
    let texture = device.create_texture_with_data(
        queue,
        &wgpu::TextureDescriptor {
            label: Some("post: SMAA area texture"),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rg8Unorm,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        smaa_area::bytes(),
    );
    texture.create_view(&Default::default())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_post_parameters_mirror_their_wgsl_struct() {
        crate::shader::layout::assert_mirrors!(Params, crate::shader::POST, "Params", [a, texel]);
        crate::shader::layout::assert_mirrors!(Params, crate::shader::SMAA, "Params", [a, texel]);
    }

    #[test]
    fn a_chain_ping_pongs_between_two_targets_and_ends_in_the_output() {
        let chain = [PostEffect::BLOOM, PostEffect::TONEMAP, PostEffect::Fxaa];
        let steps = steps(&chain);
        let shape: Vec<(usize, Pass, Image, Image)> =
            steps.iter().map(|(k, s)| (*k, s.pass, s.source, s.target)).collect();
        assert_eq!(
            shape,
            vec![
                (0, Pass::Bright, Image::Scene, Image::Pooled(2)),
                (0, Pass::Blur, Image::Pooled(2), Image::Pooled(3)),
                (0, Pass::Blur, Image::Pooled(3), Image::Pooled(2)),
                (0, Pass::BloomAdd, Image::Scene, Image::Pooled(0)),
                (1, Pass::Tonemap, Image::Pooled(0), Image::Pooled(1)),
                (2, Pass::Fxaa, Image::Pooled(1), Image::Output),
            ]
        );
        assert_eq!(steps[3].1.extra, Some(Image::Pooled(2)), "the blurred light is added back");
        assert!(super::steps(&[]).is_empty(), "no chain, no passes");
        let one = super::steps(&[PostEffect::Fxaa]);
        assert_eq!((one.len(), one[0].1.source, one[0].1.target), (1, Image::Scene, Image::Output));
    }

    #[test]
    fn smaa_finds_edges_then_weights_then_blends_the_input() {
        let steps = steps(&[PostEffect::TONEMAP, PostEffect::SMAA]);
        let shape: Vec<(usize, Pass, Image, Option<Image>, Image)> =
            steps.iter().map(|(k, s)| (*k, s.pass, s.source, s.extra, s.target)).collect();
        assert_eq!(
            shape,
            vec![
                (0, Pass::Tonemap, Image::Scene, None, Image::Pooled(0)),
                (1, Pass::SmaaEdges, Image::Pooled(0), None, Image::Pooled(4)),
                (1, Pass::SmaaWeights, Image::Pooled(4), None, Image::Pooled(5)),
                (1, Pass::SmaaBlend, Image::Pooled(0), Some(Image::Pooled(5)), Image::Output),
            ]
        );
        assert_eq!(steps[1].1.a, crate::scene::SmaaPreset::High.settings(), "the preset's settings");
        assert_eq!((slot_size(4, (9, 5)), slot_size(3, (9, 5))), ((9, 5), (4, 2)));
    }
}
