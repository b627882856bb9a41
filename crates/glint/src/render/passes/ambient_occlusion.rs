//! Core layer: screen-space ambient occlusion of a view with
//! [`View::ambient_occlusion`](crate::View::ambient_occlusion) (camera key `ssao`).
//!
//! Three render passes before the view's forward pass, the same on Vulkan, GL,
//! WebGL2 and WebGPU:
//! 1. **depth pre-pass** — the forward list's opaque and alpha-tested runs, each
//!    with its pipeline's pre-pass twin (`fs_prepass`: [`PassKind::Prepass`](crate::render::resources::pipelines::PassKind)),
//!    write the view-space normal and distance into a target of their own
//!    ([`PREPASS_FORMAT`]) and their depth into the view target's, with its
//!    samples ([`PrepassDepth::Shared`]). The forward pass then loads that
//!    depth and tests it for equality (each run's equal-depth twin), drawing
//!    no depth of its own: depth is drawn once, and each pixel is shaded once.
//!    (Where two surfaces land on the same depth value, as far-off grass can
//!    in a 24-bit depth buffer, the last drawn shows rather than the first:
//!    the meadow with ambient occlusion shows two such pixels of 65,536 at its
//!    horizon with its near plane at 0.05, none with it at 1.)
//!    With occlusion culling the pre-pass draws the early phase, the depth
//!    pyramid and late cull are built from its depth, and a second pre-pass
//!    draws the late phase: what comes into view is occluded in the frame it
//!    appears. Into a multisampled target where the next passes are fragment
//!    passes (GL, WebGL2: they cannot read a multisampled texture), the
//!    pre-pass has one sample and a depth of its own ([`PrepassDepth::Own`]),
//!    drawn before the forward pass draws depth as without ambient occlusion.
//! 2. **occlusion** — `shader/ssao.wgsl`'s ground-truth-style pass at half
//!    resolution (reading the pre-pass's first sample where it has several);
//! 3. **blur** — depth-aware, at half resolution, into the texture the forward
//!    shader's `AMBIENT_OCCLUSION` variant reads (group 0, binding 9), which
//!    darkens ambient and environment light only, never the lights'.
//!
//! Passes 2 and 3 are compute passes where the frame's path has compute (views
//! cull on the GPU: [`Gpu::culls_on_gpu`](crate::Gpu::culls_on_gpu)), full-screen
//! fragment passes otherwise (GL, WebGL2); both run the same functions.
//!
//! GPU time: the shared pre-pass is [`GpuTimes::depth_prepass_ms`](crate::render::GpuTimes::depth_prepass_ms)
//! (the view's depth), occlusion and blur (and a pre-pass with a depth of its
//! own) [`GpuTimes::ambient_occlusion_ms`](crate::render::GpuTimes::ambient_occlusion_ms);
//! the draws are [`Passes::ambient_occlusion`](crate::render::Passes::ambient_occlusion)
//! (the pre-pass's, and one each for occlusion and blur as fragment passes).

use crate::gpu::OffscreenTarget;
use crate::render::debug::explain::PassType;
use crate::render::debug::timer::Timed;
use crate::render::frame::encode::{Bound, Twin};
use crate::render::gpu_driven::draw_list::run_stage;
use crate::render::queue::SKY_STAGE;
use crate::render::resources::blocks::UniformBlock;
use crate::render::view::ViewFrame;
use crate::render::views::{ViewBlocks, ViewGpu};
use crate::render::{FrameStats, RenderError, Renderer};
use crate::scene::{AmbientOcclusion, Projection};

/// The pre-pass target: octahedral view-space normal (xy), distance as a half
/// float (z) plus what it rounded away (w); 0 where nothing was drawn.
pub(crate) const PREPASS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// The occlusion textures (half resolution), in red: 1 open, 0 wholly
/// occluded. Four channels, as compute passes store it and one is not a
/// storage format.
const OCCLUSION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// The largest radius searched, in full-resolution pixels (nearer surfaces
/// search no further, so a close-up costs what a distant view does).
const MAX_RADIUS_PIXELS: f32 = 64.0;

/// The occlusion passes' parameters (`Occlusion` in `shader/ssao.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct AmbientOcclusionGpu {
    projection: [f32; 4],
    params: [f32; 4],
}

impl AmbientOcclusionGpu {
    fn new(frame: &ViewFrame, settings: AmbientOcclusion) -> Self {
        let p = frame.camera.projection(frame.aspect);
        let orthographic = matches!(frame.camera.projection, Projection::Orthographic { .. });
        Self {
            projection: [p.x_axis.x, p.y_axis.y, f32::from(u8::from(orthographic)), settings.radius],
            params: [settings.intensity, MAX_RADIUS_PIXELS, 0.0, 0.0],
        }
    }
}

/// How the occlusion and blur passes run.
enum Kind {
    Fragment([wgpu::RenderPipeline; 2]),
    Compute([wgpu::ComputePipeline; 2]),
}

/// The occlusion and blur pipelines reading a pre-pass of one sample or of
/// several, made with the first view that needs them.
pub(crate) struct AmbientOcclusionPipelines {
    layouts: [wgpu::BindGroupLayout; 2],
    kind: Kind,
}

impl AmbientOcclusionPipelines {
    /// As compute passes when `compute`, else as fragment passes; reading a
    /// `multisampled` pre-pass or not.
    pub(crate) fn new(device: &wgpu::Device, compute: bool, multisampled: bool) -> Self {
        let visibility = if compute { wgpu::ShaderStages::COMPUTE } else { wgpu::ShaderStages::FRAGMENT };
        let entry = |binding, ty| wgpu::BindGroupLayoutEntry { binding, visibility, ty, count: None };
        let texture = |binding| {
            entry(
                binding,
                wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    // The pre-pass (binding 1).
                    multisampled: multisampled && binding == 1,
                },
            )
        };
        let uniform = entry(
            0,
            wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
        );
        let output = entry(
            3,
            wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format: OCCLUSION_FORMAT,
                view_dimension: wgpu::TextureViewDimension::D2,
            },
        );
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            let entries: Vec<_> = entries.iter().copied().chain(compute.then_some(output)).collect();
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries })
        };
        let layouts = [
            layout("ambient occlusion: occlusion", &[uniform, texture(1)]),
            layout("ambient occlusion: blur", &[uniform, texture(1), texture(2)]),
        ];
        let source = match compute {
            true => format!("{}{}", crate::shader::ssao(multisampled), crate::shader::SSAO_COMPUTE),
            false => crate::shader::ssao(multisampled),
        };
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("ssao.wgsl"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let kind = match compute {
            true => Kind::Compute([0, 1].map(|k| {
                let entry = ["cs_occlusion", "cs_blur"][k];
                crate::gpu::compute_pipeline(device, &module, entry, &[Some(&layouts[k])])
            })),
            false => Kind::Fragment([0, 1].map(|k| {
                let (label, entry) =
                    [("ambient occlusion: occlusion", "fs_occlusion"), ("ambient occlusion: blur", "fs_blur")][k];
                let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some(label),
                    bind_group_layouts: &[Some(&layouts[k])],
                    immediate_size: 0,
                });
                crate::gpu::full_screen_pipeline(
                    device,
                    label,
                    (&layout, &module),
                    ("vs_full", entry),
                    OCCLUSION_FORMAT,
                )
            })),
        };
        Self { layouts, kind }
    }
}

/// Where a view's depth pre-pass writes its depth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PrepassDepth {
    /// Into the view target's depth, with its samples: the forward pass tests
    /// it for equality and draws no depth of its own; with occlusion culling,
    /// the pre-pass draws each phase (the depth pyramid built between them),
    /// so what the late phase reveals is occluded in the frame it appears.
    Shared,
    /// Into a single-sample depth buffer of its own, thrown away: where the
    /// target is multisampled and the occlusion passes are fragment passes
    /// (GL, WebGL2, which cannot read a multisampled texture). With occlusion
    /// culling it draws the early phase only.
    Own,
}

/// One view's ambient-occlusion textures at its size, and its parameters.
pub(crate) struct OcclusionTargets {
    size: (u32, u32),
    depth_of: PrepassDepth,
    /// With the target's samples where it shares its depth.
    prepass: wgpu::TextureView,
    /// Whether `prepass` has several samples.
    multisampled: bool,
    /// Its own depth ([`PrepassDepth::Own`]).
    depth: Option<wgpu::TextureView>,
    raw: wgpu::TextureView,
    /// What the forward pass reads.
    pub(crate) blurred: wgpu::TextureView,
    block: UniformBlock<AmbientOcclusionGpu>,
    groups: [wgpu::BindGroup; 2],
}

impl OcclusionTargets {
    /// Textures for a view of `size` drawn into a target of `samples`.
    fn new(
        device: &wgpu::Device,
        pipelines: &AmbientOcclusionPipelines,
        ((width, height), samples): ((u32, u32), u32),
        depth_of: PrepassDepth,
    ) -> Self {
        let compute = matches!(pipelines.kind, Kind::Compute(_));
        let texture = |label, (width, height), (format, sample_count), usage| {
            device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
                    mip_level_count: 1,
                    sample_count,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage,
                    view_formats: &[],
                })
                .create_view(&Default::default())
        };
        let read = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let written = match compute {
            true => read | wgpu::TextureUsages::STORAGE_BINDING,
            false => read,
        };
        let full = (width, height);
        let half = (width.div_ceil(2), height.div_ceil(2));
        let samples = if depth_of == PrepassDepth::Shared { samples } else { 1 };
        let prepass = texture("ambient occlusion: pre-pass", full, (PREPASS_FORMAT, samples), read);
        let depth = (depth_of == PrepassDepth::Own).then(|| {
            let format = crate::render::passes::shadow_maps::SHADOW_FORMAT;
            let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
            texture("ambient occlusion: pre-pass depth", full, (format, 1), attachment)
        });
        let raw = texture("ambient occlusion: raw", half, (OCCLUSION_FORMAT, 1), written);
        let blurred = texture("ambient occlusion: blurred", half, (OCCLUSION_FORMAT, 1), written);
        let block = UniformBlock::new(device, "ambient occlusion: parameters");
        // Binding 0 the parameters, 1 the pre-pass, 2 the raw occlusion (the
        // blur's), 3 the output (compute passes').
        let group = |k: usize, inputs: &[&wgpu::TextureView], output: &wgpu::TextureView| {
            let view =
                |binding, view| wgpu::BindGroupEntry { binding, resource: wgpu::BindingResource::TextureView(view) };
            let entries: Vec<_> =
                std::iter::once(wgpu::BindGroupEntry { binding: 0, resource: block.buffer.as_entire_binding() })
                    .chain(inputs.iter().enumerate().map(|(j, v)| view(1 + j as u32, v)))
                    .chain(compute.then(|| view(3, output)))
                    .collect();
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("ambient occlusion: inputs"),
                layout: &pipelines.layouts[k],
                entries: &entries,
            })
        };
        let groups = [group(0, &[&prepass], &raw), group(1, &[&prepass, &raw], &blurred)];
        Self { size: full, depth_of, prepass, multisampled: samples > 1, depth, raw, blurred, block, groups }
    }
}

/// Which of a view's pre-pass passes is recorded: the first clears, the last
/// resolves (several with occlusion culling's phases).
#[derive(Clone, Copy)]
pub(crate) struct PrepassPart {
    pub first: bool,
    pub last: bool,
}

impl Renderer {
    /// Whether a view with these settings gets ambient occlusion: only the
    /// optimized frame draws it (the naive baseline has no pre-pass).
    pub(crate) fn occludes(&self, settings: Option<AmbientOcclusion>) -> bool {
        settings.is_some() && self.mode == crate::render::FrameMode::Optimized
    }

    /// The start of stage 6 for a view with ambient occlusion (after batching,
    /// which says what the pre-pass draws) drawn into `target`: the occlusion
    /// pipelines, each forward pipeline's pre-pass twin (and its twin testing
    /// the shared depth), the view's textures (the Scene bind group pointed at
    /// them) and its parameters.
    pub(crate) fn prepare_ambient_occlusion(
        &mut self,
        gpu: &mut ViewGpu,
        frame: &ViewFrame,
        target: &OffscreenTarget,
        stats: &mut FrameStats,
    ) -> Result<(), RenderError> {
        let Some(settings) = frame.ambient_occlusion.filter(|_| frame.variant.ambient_occlusion) else {
            return Ok(());
        };
        let compute = self.cull_pipelines.is_some();
        let depth_of = match target.samples() == 1 || compute {
            true => PrepassDepth::Shared,
            false => PrepassDepth::Own,
        };
        let multisampled = depth_of == PrepassDepth::Shared && target.samples() > 1;
        let pipelines = self.ambient_occlusion_pipelines[usize::from(multisampled)]
            .get_or_insert_with(|| AmbientOcclusionPipelines::new(&self.device, compute, multisampled));
        // A run's batches share one pipeline (what `draw_run` binds).
        let list = &gpu.forward;
        for run in &list.runs {
            let forward = list.batches[run.first as usize].pipeline;
            let (_, built) =
                self.registry.pipelines.prepass_id(&self.device, forward, depth_of == PrepassDepth::Shared)?;
            stats.pipelines_compiled += built;
        }
        let size = (target.width(), target.height());
        if gpu.occlusion.as_ref().is_none_or(|t| (t.size, t.depth_of, t.multisampled) != (size, depth_of, multisampled))
        {
            let targets = OcclusionTargets::new(&self.device, pipelines, (size, target.samples()), depth_of);
            gpu.set_occlusion(&self.shared(), targets);
        }
        let targets = gpu.occlusion.as_mut().expect("made above");
        stats.bytes_uploaded.camera += targets.block.update(&self.queue, AmbientOcclusionGpu::new(frame, settings));
        Ok(())
    }

    /// Where the pre-pass of `view` writes its depth; `None` when it has no
    /// ambient occlusion this frame.
    pub(crate) fn prepass_depth(&self, gpu: &ViewGpu, view: &ViewFrame) -> Option<PrepassDepth> {
        let targets = gpu.occlusion.as_ref().filter(|_| view.variant.ambient_occlusion)?;
        self.ambient_occlusion_pipelines[usize::from(targets.multisampled)].as_ref().map(|_| targets.depth_of)
    }

    /// Stage 7's ambient occlusion for a view with it (prepared by
    /// [`prepare_ambient_occlusion`](Self::prepare_ambient_occlusion)): `part`
    /// of the depth pre-pass of the forward list's runs before the sky, from
    /// occlusion culling's late phase when `late`; after the last, the
    /// occlusion and blur passes.
    pub(crate) fn encode_ambient_occlusion(
        &mut self,
        gpu: &ViewGpu,
        (encoder, target): (&mut wgpu::CommandEncoder, &OffscreenTarget),
        (part, late): (PrepassPart, bool),
        stats: &mut FrameStats,
    ) {
        let Some(targets) = &gpu.occlusion else { return };
        let Some(pipelines) = &self.ambient_occlusion_pipelines[usize::from(targets.multisampled)] else { return };
        let start = web_time::Instant::now();
        let shared = targets.depth_of == PrepassDepth::Shared;
        // The shared pre-pass is the view's depth, timed as such; its own is ambient occlusion's alone.
        let timed = if shared { Timed::DepthPrepass } else { Timed::AmbientOcclusion };
        let list = &gpu.forward;
        let sky_at = list.runs.partition_point(|r| run_stage(list, r) < SKY_STAGE);
        let timer = self.gpu_timer.as_ref();
        let mut drawn = FrameStats::default();
        {
            let label = match (part.first, part.last) {
                (true, false) => "depth pre-pass: early",
                (false, _) => "depth pre-pass: late",
                (true, true) => "depth pre-pass",
            };
            let load = if part.first { wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT) } else { wgpu::LoadOp::Load };
            let color = wgpu::RenderPassColorAttachment {
                view: &targets.prepass,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load, store: wgpu::StoreOp::Store },
            };
            let depth = match &targets.depth {
                Some(own) => wgpu::RenderPassDepthStencilAttachment {
                    view: own,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Discard }),
                    stencil_ops: None,
                },
                // Kept for the forward pass (and the depth pyramid between the phases).
                None => target.depth_stencil(part.first, true),
            };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(label),
                color_attachments: &[Some(color)],
                depth_stencil_attachment: Some(depth),
                timestamp_writes: timer.and_then(|t| t.pass_writes(timed, part.first, shared && part.last)),
                ..Default::default()
            });
            pass.set_bind_group(1, &gpu.blocks.bind_group, &[ViewBlocks::offset(0)]);
            pass.set_bind_group(3, &list.bind_group, &[]);
            drawn.bind_groups_set += 2;
            let bound = ["bind group 1 (camera)", "bind group 3 (instances, draw indices)"];
            self.outline.pass(label, PassType::Render, &bound);
            let mut bound = Bound::twin(Twin::Prepass { shared });
            self.draw_stages(list, &mut pass, (0..sky_at, &[late]), &mut bound, &mut drawn);
        }
        let ambient = &mut stats.passes.ambient_occlusion;
        ambient.draw_calls += drawn.draw_calls;
        ambient.draws += drawn.draws;
        if part.first {
            // Both phases draw from the same batches: their instances once.
            ambient.instances += drawn.passes.opaque.instances + drawn.passes.alpha_test.instances;
        }
        if part.last {
            self.encode_occlusion(targets, pipelines, encoder, shared, stats);
        }
        stats.passes.ambient_occlusion.cpu_ms += crate::render::ms_since(start);
        if let Some(timer) = self.gpu_timer.as_mut().filter(|_| part.last) {
            if shared {
                timer.resolve(encoder, Timed::DepthPrepass, self.frame_index);
            }
            timer.resolve(encoder, Timed::AmbientOcclusion, self.frame_index);
        }
    }

    /// The occlusion and blur passes, from the pre-pass's target into the
    /// texture the forward pass reads; timed from the first when
    /// `begins` (else from the pre-pass).
    fn encode_occlusion(
        &self,
        targets: &OcclusionTargets,
        pipelines: &AmbientOcclusionPipelines,
        encoder: &mut wgpu::CommandEncoder,
        begins: bool,
        stats: &mut FrameStats,
    ) {
        let timer = self.gpu_timer.as_ref();
        let ambient = &mut stats.passes.ambient_occlusion;
        let outputs = [&targets.raw, &targets.blurred];
        for (k, label) in ["ambient occlusion", "ambient occlusion: blur"].into_iter().enumerate() {
            let (begin, end) = (k == 0 && begins, k == 1);
            match &pipelines.kind {
                Kind::Fragment(pipelines) => {
                    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some(label),
                        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                            view: outputs[k],
                            depth_slice: None,
                            resolve_target: None,
                            ops: wgpu::Operations {
                                load: wgpu::LoadOp::Clear(wgpu::Color::WHITE),
                                store: wgpu::StoreOp::Store,
                            },
                        })],
                        timestamp_writes: timer.and_then(|t| t.pass_writes(Timed::AmbientOcclusion, begin, end)),
                        ..Default::default()
                    });
                    self.outline.pass(label, PassType::Render, &["bind group 0 (pre-pass, occlusion)"]);
                    pass.set_pipeline(&pipelines[k]);
                    pass.set_bind_group(0, &targets.groups[k], &[]);
                    pass.draw(0..3, 0..1);
                    let changed = ["pipeline", "bind group 0"];
                    self.outline
                        .call(|| crate::render::debug::explain::DrawCall::single(label, "draw", (1, 1), &changed));
                    (ambient.draw_calls, ambient.draws) = (ambient.draw_calls + 1, ambient.draws + 1);
                }
                Kind::Compute(pipelines) => {
                    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some(label),
                        timestamp_writes: timer
                            .and_then(|t| t.compute_pass_writes(Timed::AmbientOcclusion, begin, end)),
                    });
                    self.outline.pass(label, PassType::Compute, &[]);
                    pass.set_pipeline(&pipelines[k]);
                    pass.set_bind_group(0, &targets.groups[k], &[]);
                    let (width, height) = (targets.size.0.div_ceil(2), targets.size.1.div_ceil(2));
                    pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_occlusion_parameters_mirror_their_wgsl_struct() {
        crate::shader::layout::assert_mirrors!(
            AmbientOcclusionGpu,
            &crate::shader::ssao(false),
            "AmbientOcclusion",
            [projection, params]
        );
    }
}
