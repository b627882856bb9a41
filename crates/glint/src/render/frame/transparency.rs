//! Core layer: a view's order-independent transparency stages (the targets
//! and composites are `passes/transparency.rs`): its way and twins before
//! the upload, the pass that draws its blended runs after the forward
//! pass's stages, and the composite that ends it.

use crate::gpu::OffscreenTarget;
use crate::render::debug::explain::{DrawCall, PassType};
use crate::render::debug::outline::Outline;
use crate::render::debug::stats::FrameStats;
use crate::render::debug::timer::Timed;
use crate::render::error::RenderError;
use crate::render::frame::draw::{draw_stages, Bound, Twin};
use crate::render::frame::state::Frame;
use crate::render::passes::particles::Layers;
use crate::render::passes::transparency::TransparencyTargets;
use crate::render::resources::Resources;
use crate::render::view::ViewFrame;
use crate::render::views::{ViewBlocks, ViewGpu};
use crate::scene::Transparency;

/// The end of stage 6 for a view (after batching, which says what it
/// draws): how it draws transparency here (an error for exact where the
/// device cannot), each blended run's twin, the composite and the view's
/// targets. A view that draws sorted, or has nothing its twins draw, keeps
/// no targets and draws as before.
pub(crate) fn prepare_transparency(
    res: &mut Resources,
    gpu: &mut ViewGpu,
    view: &ViewFrame,
    target: &OffscreenTarget,
    stats: &mut FrameStats,
) -> Result<(), RenderError> {
    let way = res.transparency.way(view.transparency, target.samples())?;
    let mut twins = false;
    if way != Transparency::Sorted {
        let list = &gpu.forward;
        for run in &list.runs {
            let forward = list.batches[run.first as usize].pipeline;
            let (twin, built) = res.registry.pipelines.transparency_id(&res.device, forward, way)?;
            stats.pipelines_compiled += built;
            twins |= twin.is_some();
        }
        let lists = (way == Transparency::Exact).then(|| res.registry.pipelines.lists_layout(&res.device));
        let layers = (target.format(), view.variant.clustered);
        twins |= res.particles.prepare_transparency(&res.device, layers, (way, lists), stats);
    }
    stats.transparency = if twins { way } else { Transparency::Sorted };
    if !twins {
        gpu.transparency = None;
        return Ok(());
    }
    stats.pipelines_compiled += res.transparency.prepare(&res.device, target.format(), way)?;
    let (size, samples) = ((target.width(), target.height()), target.samples());
    if !gpu.transparency.as_ref().is_some_and(|t| t.fits(way, size, samples)) {
        gpu.transparency = None; // the old targets' memory first
        let lists = (way == Transparency::Exact).then(|| res.registry.pipelines.lists_layout(&res.device));
        let targets = res.transparency.targets(&res.device, (way, size, samples), (lists, gpu.blocks.camera()))?;
        gpu.transparency = Some(targets);
    }
    Ok(())
}

/// The view's blended runs in `runs`, each from the commands of each of
/// `phases`, and its alpha-blended particle
/// layers (soft ones reading `particle_depth`), drawn by their twins into
/// its weighted sums or fragment lists, depth-tested against what the
/// forward pass drew.
pub(crate) fn encode_transparency(
    res: &mut Resources,
    frame: &mut Frame,
    (gpu, view): (&ViewGpu, &ViewFrame),
    target: &OffscreenTarget,
    (runs, phases): (std::ops::Range<usize>, &[bool]),
    particle_depth: Option<&wgpu::BindGroup>,
    stats: &mut FrameStats,
) {
    let Some(targets) = &gpu.transparency else { return };
    let way = targets.way();
    let (colors, label, camera): (&[_], _, _) = match targets {
        TransparencyTargets::Weighted(weighted) => {
            (&weighted.attachments(), "transparency: weighted sums", &gpu.blocks.bind_group)
        }
        TransparencyTargets::Exact(lists) => {
            lists.clear(&mut frame.encoder);
            (&[], "transparency: fragment lists", &lists.group)
        }
    };
    let mut pass = frame.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: colors,
        // Read-only: the twins test the forward pass's depth and write none.
        depth_stencil_attachment: Some(target.last_reading_depth().1),
        timestamp_writes: res.gpu_timer.as_ref().and_then(|t| t.pass_writes(Timed::Transparency, true, true)),
        ..Default::default()
    });
    pass.set_bind_group(0, &gpu.scene_group, &[]);
    pass.set_bind_group(1, camera, &[ViewBlocks::offset(0)]);
    pass.set_bind_group(3, &gpu.forward.bind_group, &[]);
    stats.bind_groups_set += 3;
    let bound_groups = match way {
        Transparency::Exact => "bind group 1 (camera, fragment lists)",
        _ => "bind group 1 (camera)",
    };
    let bound = ["bind group 0 (scene)", bound_groups, "bind group 3 (instances, draw indices)"];
    frame.outline.pass(label, PassType::Render, &bound);
    let mut bound = Bound::twin(Twin::Transparent, Some(way));
    draw_stages(res, &frame.outline, &gpu.forward, &mut pass, (runs, phases), &mut bound, stats);
    let layers = (target.format(), view.variant.clustered, Layers::Alpha(way));
    res.particles.draw((&mut pass, &frame.outline), layers, particle_depth, stats);
    drop(pass);
    if let Some(timer) = &mut res.gpu_timer {
        timer.resolve(&mut frame.encoder, Timed::Transparency, frame.index);
    }
}

/// The view's weighted sums or sorted lists blended over `pass` (the one
/// that ends the view), where it drew transparency so this frame.
pub(crate) fn draw_composite(
    res: &Resources,
    outline: &Outline,
    pass: &mut wgpu::RenderPass<'_>,
    (gpu, target): (&ViewGpu, &OffscreenTarget),
    stats: &mut FrameStats,
) {
    let Some(targets) = &gpu.transparency else { return };
    let Some(pipeline) = res.transparency.composite(target.format(), targets.way()) else { return };
    pass.push_debug_group("transparency: composite");
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, targets.composite_group(), &[]);
    pass.draw(0..3, 0..1);
    // The particles' and the glare's layouts share the Scene group.
    pass.set_bind_group(0, &gpu.scene_group, &[]);
    pass.pop_debug_group();
    stats.pipelines_bound += 1;
    stats.bind_groups_set += 2;
    stats.draw_calls += 1;
    stats.draws += 1;
    let name = format!("transparency: {} composite", targets.way().name());
    outline.call(|| DrawCall::single(&name, "draw", (1, 0), &["pipeline", "bind group 0"]));
}
