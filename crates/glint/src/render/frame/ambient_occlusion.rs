//! Core layer: a view's ambient occlusion stages (the passes and their
//! targets are `passes/ambient_occlusion.rs`): whether a view gets it, its
//! pre-pass twins, targets and parameters before the upload, and the depth
//! pre-pass, occlusion and blur passes recorded before the forward pass.

use crate::gpu::OffscreenTarget;
use crate::render::debug::explain::{DrawCall, PassType};
use crate::render::debug::outline::Outline;
use crate::render::debug::stats::{ms_since, FrameStats};
use crate::render::debug::timer::{GpuTimer, Timed};
use crate::render::error::RenderError;
use crate::render::frame::draw::{draw_stages, Bound, Twin};
use crate::render::frame::input::FrameMode;
use crate::render::frame::state::Frame;
use crate::render::gpu_driven::draw_list::run_stage;
use crate::render::passes::ambient_occlusion::{AmbientOcclusionGpu, AmbientOcclusionPipelines, Kind};
use crate::render::passes::ambient_occlusion::{OcclusionTargets, PrepassDepth, PrepassPart};
use crate::render::queue::SKY_STAGE;
use crate::render::resources::Resources;
use crate::render::view::ViewFrame;
use crate::render::views::{ViewBlocks, ViewGpu};
use crate::scene::AmbientOcclusion;

/// Whether a view with these settings gets ambient occlusion: only the
/// optimized frame draws it (the naive baseline has no pre-pass).
pub(crate) fn occludes(res: &Resources, settings: Option<AmbientOcclusion>) -> bool {
    settings.is_some() && res.mode == FrameMode::Optimized
}

/// The start of stage 6 for a view with ambient occlusion (after batching,
/// which says what the pre-pass draws) drawn into `target`: the occlusion
/// pipelines, each forward pipeline's pre-pass twin (and its twin testing
/// the shared depth), the view's textures (the Scene bind group pointed at
/// them) and its parameters.
pub(crate) fn prepare_ambient_occlusion(
    res: &mut Resources,
    gpu: &mut ViewGpu,
    frame: &ViewFrame,
    target: &OffscreenTarget,
    stats: &mut FrameStats,
) -> Result<(), RenderError> {
    let Some(settings) = frame.ambient_occlusion.filter(|_| frame.variant.ambient_occlusion) else {
        return Ok(());
    };
    let compute = res.cull_pipelines.is_some();
    let depth_of = match target.samples() == 1 || compute {
        true => PrepassDepth::Shared,
        false => PrepassDepth::Own,
    };
    let multisampled = depth_of == PrepassDepth::Shared && target.samples() > 1;
    let pipelines = res.ambient_occlusion_pipelines[usize::from(multisampled)]
        .get_or_insert_with(|| AmbientOcclusionPipelines::new(&res.device, compute, multisampled));
    // A run's batches share one pipeline (what `draw_run` binds).
    let list = &gpu.forward;
    for run in &list.runs {
        let forward = list.batches[run.first as usize].pipeline;
        let (_, built) = res.registry.pipelines.prepass_id(&res.device, forward, depth_of == PrepassDepth::Shared)?;
        stats.pipelines_compiled += built;
    }
    let size = (target.width(), target.height());
    if gpu.occlusion.as_ref().is_none_or(|t| (t.size, t.depth_of, t.multisampled) != (size, depth_of, multisampled)) {
        let targets = OcclusionTargets::new(&res.device, pipelines, (size, target.samples()), depth_of);
        gpu.set_occlusion(&res.shared(), targets);
    }
    let targets = gpu.occlusion.as_mut().expect("made above");
    stats.bytes_uploaded.camera += targets.block.update(&res.queue, AmbientOcclusionGpu::new(frame, settings));
    Ok(())
}

/// Where the pre-pass of `view` writes its depth; `None` when it has no
/// ambient occlusion this frame.
pub(crate) fn prepass_depth(res: &Resources, gpu: &ViewGpu, view: &ViewFrame) -> Option<PrepassDepth> {
    let targets = gpu.occlusion.as_ref().filter(|_| view.variant.ambient_occlusion)?;
    res.ambient_occlusion_pipelines[usize::from(targets.multisampled)].as_ref().map(|_| targets.depth_of)
}

/// Stage 7's ambient occlusion for a view with it (prepared by
/// [`prepare_ambient_occlusion`]): `part`
/// of the depth pre-pass of the forward list's runs before the sky, from
/// occlusion culling's late phase when `late`; after the last, the
/// occlusion and blur passes.
pub(crate) fn encode_ambient_occlusion(
    res: &mut Resources,
    frame: &mut Frame,
    gpu: &ViewGpu,
    target: &OffscreenTarget,
    (part, late): (PrepassPart, bool),
    stats: &mut FrameStats,
) {
    let Some(targets) = &gpu.occlusion else { return };
    let Some(pipelines) = &res.ambient_occlusion_pipelines[usize::from(targets.multisampled)] else { return };
    let start = web_time::Instant::now();
    let shared = targets.depth_of == PrepassDepth::Shared;
    // The shared pre-pass is the view's depth, timed as such; its own is ambient occlusion's alone.
    let timed = if shared { Timed::DepthPrepass } else { Timed::AmbientOcclusion };
    let list = &gpu.forward;
    let sky_at = list.runs.partition_point(|r| run_stage(list, r) < SKY_STAGE);
    let timer = res.gpu_timer.as_ref();
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
        let mut pass = frame.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
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
        frame.outline.pass(label, PassType::Render, &bound);
        let mut bound = Bound::twin(Twin::Prepass { shared }, None);
        draw_stages(res, &frame.outline, list, &mut pass, (0..sky_at, &[late]), &mut bound, &mut drawn);
    }
    let ambient = &mut stats.passes.ambient_occlusion;
    ambient.draw_calls += drawn.draw_calls;
    ambient.draws += drawn.draws;
    if part.first {
        // Both phases draw from the same batches: their instances once.
        ambient.instances += drawn.passes.opaque.instances + drawn.passes.alpha_test.instances;
    }
    if part.last {
        encode_occlusion(
            targets,
            pipelines,
            (&mut frame.encoder, &frame.outline),
            res.gpu_timer.as_ref(),
            shared,
            stats,
        );
    }
    stats.passes.ambient_occlusion.cpu_ms += ms_since(start);
    if let Some(timer) = res.gpu_timer.as_mut().filter(|_| part.last) {
        if shared {
            timer.resolve(&mut frame.encoder, Timed::DepthPrepass, frame.index);
        }
        timer.resolve(&mut frame.encoder, Timed::AmbientOcclusion, frame.index);
    }
}

/// The occlusion and blur passes, from the pre-pass's target into the
/// texture the forward pass reads; timed from the first when
/// `begins` (else from the pre-pass).
fn encode_occlusion(
    targets: &OcclusionTargets,
    pipelines: &AmbientOcclusionPipelines,
    (encoder, outline): (&mut wgpu::CommandEncoder, &Outline),
    timer: Option<&GpuTimer>,
    begins: bool,
    stats: &mut FrameStats,
) {
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
                outline.pass(label, PassType::Render, &["bind group 0 (pre-pass, occlusion)"]);
                pass.set_pipeline(&pipelines[k]);
                pass.set_bind_group(0, &targets.groups[k], &[]);
                pass.draw(0..3, 0..1);
                let changed = ["pipeline", "bind group 0"];
                outline.call(|| DrawCall::single(label, "draw", (1, 1), &changed));
                (ambient.draw_calls, ambient.draws) = (ambient.draw_calls + 1, ambient.draws + 1);
            }
            Kind::Compute(pipelines) => {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some(label),
                    timestamp_writes: timer.and_then(|t| t.compute_pass_writes(Timed::AmbientOcclusion, begin, end)),
                });
                outline.pass(label, PassType::Compute, &[]);
                pass.set_pipeline(&pipelines[k]);
                pass.set_bind_group(0, &targets.groups[k], &[]);
                let (width, height) = (targets.size.0.div_ceil(2), targets.size.1.div_ceil(2));
                pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
            }
        }
    }
}
