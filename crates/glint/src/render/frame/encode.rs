//! Core layer: stage 7 of the frame, recording the forward pass.
//!
//! Batches come sorted; a run of adjacent batches with the same pipeline, texture
//! set and mesh-pool page needs no state change between them, so in optimized mode
//! the run is one `multi_draw_indexed_indirect` call over its batches' commands
//! (or one `draw_indexed` per batch where the device cannot draw indirect). A
//! list culled on the GPU has its cull pass recorded first, and each run draws
//! the commands that pass left (with their count, where the device has
//! `MULTI_DRAW_INDIRECT_COUNT`). (The naive baseline has its own encoder:
//! `naive.rs`.)

use crate::gpu::OffscreenTarget;
use crate::render::debug::explain::PassType;
use crate::render::debug::outline::Outline;
use crate::render::debug::stats::FrameStats;
use crate::render::debug::timer::Timed;
use crate::render::frame::ambient_occlusion::{encode_ambient_occlusion, prepass_depth};
use crate::render::frame::draw::{draw_glare, draw_sky, draw_stages, Bound, Twin};
use crate::render::frame::state::Frame;
use crate::render::frame::transparency::{draw_composite, encode_transparency};
use crate::render::gpu_driven::draw_list::run_stage;
use crate::render::passes::ambient_occlusion::{PrepassDepth, PrepassPart};
use crate::render::passes::particles::Layers;
use crate::render::queue::SKY_STAGE;
use crate::render::resources::Resources;
use crate::render::view::ViewFrame;
use crate::render::views::{ViewBlocks, ViewGpu};
use crate::scene::{Background, Environment};

/// Which part of a view's forward pass a render pass is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Part {
    /// All of it.
    Whole,
    /// Occlusion culling's early draws.
    First,
    /// Its late draws, the sky and what follows.
    Second,
    /// What comes before the last part, after occlusion culling's early draws.
    Middle,
    /// The part that ends the view, reading the depth it is tested against:
    /// the transparency composite, particles and the glare (after the
    /// transparency pass, or where soft particles read the depth).
    Last,
}

/// Stage 7: record the forward pass, cleared to `background`: opaque →
/// alpha-test → sky → transparent (or as `render_order` stages say) →
/// particles → glare. With ambient occlusion, its depth pre-pass and
/// passes first; where the pre-pass draws the target's depth, the forward
/// pass tests it for equality and draws no depth of its own.
pub(crate) fn encode(
    res: &mut Resources,
    frame: &mut Frame,
    gpu: &mut ViewGpu,
    (view, target): (&ViewFrame, &OffscreenTarget),
    environment: &Environment,
    stats: &mut FrameStats,
) {
    let background = environment.background;
    let list = &gpu.forward;
    let sky_at = list.runs.partition_point(|r| run_stage(list, r) < SKY_STAGE);
    if let Some(pipelines) = &res.cull_pipelines {
        if gpu.forward.culled_on_gpu() {
            frame.outline.pass("cull instances", PassType::Compute, &[]);
        }
        gpu.forward.record_cull(&mut frame.encoder, pipelines, res.queue.submits());
    }
    let depth = target.depth_only_view().filter(|_| gpu.forward.gpu.as_ref().is_some_and(|g| g.occluding));
    let prepass = prepass_depth(res, gpu, view);
    let shared = prepass == Some(PrepassDepth::Shared);
    // The pre-pass draws occlusion culling's phases where it draws the target's depth.
    let phased = shared && depth.is_some() && res.cull_pipelines.is_some();
    if prepass.is_some() {
        let part = PrepassPart { first: true, last: !phased };
        encode_ambient_occlusion(res, frame, gpu, target, (part, false), stats);
    }
    let end = gpu.forward.runs.len();
    // Occlusion culling: the opaque stages of what was seen last frame, then
    // the late phase (depth pyramid, late cull), then what it found, in a
    // second forward pass that goes on with the sky and the later stages;
    // or, where the pre-pass draws the depth, its two phases around the late
    // phase and one forward pass drawing both.
    let (part, before_sky, after_sky) = match (depth, &res.cull_pipelines) {
        (Some(depth), Some(pipelines)) => {
            if !phased {
                let mut bound = Bound::default();
                let mut pass = begin_forward_pass(
                    res,
                    (&mut frame.encoder, &frame.outline),
                    gpu,
                    target,
                    (background, Part::First, false),
                    stats,
                );
                draw_stages(res, &frame.outline, &gpu.forward, &mut pass, (0..sky_at, &[false]), &mut bound, stats);
            }
            if let Some(culled) = &mut gpu.forward.gpu {
                frame.outline.pass("depth pyramid", PassType::Compute, &[]);
                frame.outline.pass("cull instances: late", PassType::Compute, &[]);
                culled.record_late((&res.device, &mut frame.encoder), pipelines, depth, res.queue.submits());
            }
            match phased {
                true => {
                    let part = PrepassPart { first: false, last: true };
                    encode_ambient_occlusion(res, frame, gpu, target, (part, true), stats);
                    (Part::Whole, &[false, true][..], &[false, true][..])
                }
                false => (Part::Second, &[true][..], &[false, true][..]),
            }
        }
        _ => (Part::Whole, &[false][..], &[false][..]),
    };
    // Soft particles read the depth, and order-independent transparency
    // draws between: the last part gets a pass of its own.
    let particle_depth = res.particles.depth(&res.device, target);
    let transparency = gpu.transparency.as_ref().map(|t| t.way());
    let last = particle_depth.is_some() || transparency.is_some();
    let part = match (part, last) {
        (Part::Whole, true) => Part::First,
        (Part::Second, true) => Part::Middle,
        (part, _) => part,
    };
    {
        let mut pass = begin_forward_pass(
            res,
            (&mut frame.encoder, &frame.outline),
            gpu,
            target,
            (background, part, shared),
            stats,
        );
        let mut bound = Bound::twin(if shared { Twin::Equal } else { Twin::Own }, transparency);
        draw_stages(res, &frame.outline, &gpu.forward, &mut pass, (0..sky_at, before_sky), &mut bound, stats);
        // The pre-pass drew only the stages before the sky.
        if draw_sky(res, &frame.outline, gpu, &mut pass, target, environment, stats) || shared {
            bound = bound.after_full_screen();
        }
        draw_stages(res, &frame.outline, &gpu.forward, &mut pass, (sky_at..end, after_sky), &mut bound, stats);
        if !last {
            let layers = (target.format(), view.variant.clustered, Layers::All);
            res.particles.draw((&mut pass, &frame.outline), layers, None, stats);
            draw_glare(res, &frame.outline, &mut pass, target, environment, stats);
        }
    }
    // Every stage's blended runs (a `render_order` may put some before the
    // sky), from both phases where occlusion culling split them.
    let depth = particle_depth.as_ref();
    encode_transparency(res, frame, (gpu, view), target, (0..end, after_sky), depth, stats);
    if last {
        let mut pass = begin_forward_pass(
            res,
            (&mut frame.encoder, &frame.outline),
            gpu,
            target,
            (background, Part::Last, false),
            stats,
        );
        draw_composite(res, &frame.outline, &mut pass, (gpu, target), stats);
        // The alpha-blended layers were drawn with the blended materials.
        let which = if transparency.is_some() { Layers::Additive } else { Layers::All };
        let layers = (target.format(), view.variant.clustered, which);
        res.particles.draw((&mut pass, &frame.outline), layers, depth, stats);
        draw_glare(res, &frame.outline, &mut pass, target, environment, stats);
    }
    if let Some(timer) = &mut res.gpu_timer {
        timer.resolve(&mut frame.encoder, Timed::Forward, frame.index);
    }
}

/// Begin the view's forward pass (or `part` of it) into `target`, cleared
/// to `background`, with the Scene, Camera and Renderer blocks bound; its
/// depth loaded, not cleared, where a pre-pass drew it (`drawn`).
pub(crate) fn begin_forward_pass<'e>(
    res: &Resources,
    (encoder, outline): (&'e mut wgpu::CommandEncoder, &Outline),
    gpu: &ViewGpu,
    target: &OffscreenTarget,
    (background, part, drawn): (Background, Part, bool),
    stats: &mut FrameStats,
) -> wgpu::RenderPass<'e> {
    let clear = match background {
        Background::Color(c) | Background::Gradient { bottom: c, .. } => {
            wgpu::Color { r: c.x.into(), g: c.y.into(), b: c.z.into(), a: 1.0 }
        }
    };
    let (color, depth) = match part {
        Part::Whole => (target.color_attachment(clear), target.depth_attachment()),
        Part::First => target.first_of_two(clear),
        Part::Second => target.second_of_two(),
        Part::Middle => target.middle_of_three(),
        Part::Last => target.last_reading_depth(),
    };
    let depth = match (drawn, part) {
        (true, Part::Whole) => target.depth_stencil(false, false),
        (true, Part::First) => target.depth_stencil(false, true),
        _ => depth,
    };
    let (begins, ends) =
        (matches!(part, Part::Whole | Part::First), matches!(part, Part::Whole | Part::Second | Part::Last));
    let label = match part {
        Part::Whole => "forward pass",
        Part::First => "forward pass: early",
        Part::Second => "forward pass: late",
        Part::Middle => "forward pass: middle",
        Part::Last => "forward pass: last (transparency composite, particles, glare)",
    };
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(color)],
        depth_stencil_attachment: Some(depth),
        timestamp_writes: res.gpu_timer.as_ref().and_then(|t| t.pass_writes(Timed::Forward, begins, ends)),
        ..Default::default()
    });
    pass.set_bind_group(0, &gpu.scene_group, &[]);
    pass.set_bind_group(1, &gpu.blocks.bind_group, &[ViewBlocks::offset(0)]);
    pass.set_bind_group(3, &gpu.forward.bind_group, &[]);
    stats.bind_groups_set += 3;
    let bound = ["bind group 0 (scene)", "bind group 1 (camera)", "bind group 3 (instances, draw indices)"];
    outline.pass(label, PassType::Render, &bound);
    pass
}
