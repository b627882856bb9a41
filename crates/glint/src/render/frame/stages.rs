//! Core layer: the frame's own stages, before and after its views: its
//! start (the entities submitted into the instance store, its encoder), the
//! checks it makes before drawing, the order of its views, compacting the
//! instance store, the clear of what its views leave uncovered, the work after
//! its views, and its one submission.

use crate::gpu::{AfterViews, OffscreenTarget};
use crate::render::clusters::Clusters;
use crate::render::debug::stats::{ms_since, FrameStats};
use crate::render::error::RenderError;
use crate::render::frame::input::{FrameOutput, ViewKey};
use crate::render::frame::state::{Frame, NextFrame};
use crate::render::frame::visible::{shown, Submitted};
use crate::render::resources::Resources;
use crate::render::views::ViewStates;
use crate::scene::{Entity, Lighting, MaterialId, TextureId, View, MAX_POST_EFFECTS};
use std::collections::HashMap;
use web_time::Instant;

/// Queue `entity` for the next frame: its instances into the store (copied
/// to the GPU again only when its version changed), it into `next`'s list; a
/// shape id that is not `res`'s is kept as the next frame's error.
pub(crate) fn submit(res: &mut Resources, next: &mut NextFrame, entity: &Entity) {
    let Some(reach) = res.registry.reach(entity.shape, entity.material) else {
        next.submit_error.get_or_insert(RenderError::UnknownShape(entity.shape));
        return;
    };
    let far_field = res.registry.material(entity.material).and_then(|m| m.far_field);
    let slot = res.store.submit(entity, reach, next.index);
    next.submitted.push(Submitted {
        slot,
        shape: entity.shape,
        material: entity.material,
        render_order: entity.render_order,
        cast_shadows: entity.cast_shadows,
        instances: entity.transforms().len() as u64,
        density: entity.density * res.density,
        far_field,
    });
}

/// The frame's start: `entities` submitted after any submitted already, its
/// encoder begun with its "frame N" debug group, and the GPU times of an
/// earlier frame collected.
pub(crate) fn begin_frame(res: &mut Resources, next: &mut NextFrame, entities: &[Entity]) -> Frame {
    let start = Instant::now();
    for entity in entities {
        submit(res, next, entity);
    }
    let label = Some("renderer: frame");
    let encoder = res.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label });
    let gpu = res.gpu_timer.as_mut().and_then(|t| t.collect(&res.device));
    Frame::begin(next, encoder, gpu, start)
}

/// The errors a frame finds before drawing: a bad id submitted, a sub-frame
/// outside its still, too many lights, a viewport outside its target or a
/// post chain too long.
pub(crate) fn check_frame(
    frame: &mut Frame,
    views: &[(ViewKey, &View)],
    (lighting, clusters): (&Lighting, Clusters),
) -> Result<(), RenderError> {
    if let Some(e) = frame.submit_error.take() {
        return Err(e);
    }
    let sample = frame.sample;
    if !sample.is_valid() {
        let most = crate::render::frame::input::MAX_SUB_FRAMES;
        let why = format!("expected an index below the count, and 1 to {most} sub-frames");
        return Err(RenderError::SubFrameOutOfOrder { index: sample.index, count: sample.count, why });
    }
    clusters.check(lighting.lights)?;
    for (_, view) in views {
        if !view.viewport.is_valid() {
            return Err(RenderError::BadViewport(view.viewport));
        }
        if view.post.len() > MAX_POST_EFFECTS {
            return Err(RenderError::PostChainTooLong(view.post.len()));
        }
    }
    Ok(())
}

/// Compact the instance store when it holds more garbage than data, and make
/// room for every record in its GPU buffer (all written again when the
/// buffer was replaced): before any command recorded writes or draws
/// instances where they are. Errors past the adapter's limits.
pub(crate) fn compact_store(res: &mut Resources, frame: &mut Frame) -> Result<(), RenderError> {
    if let Some(remap) = res.store.compact_if_wasteful(frame.index) {
        for s in &mut frame.submitted {
            s.slot = remap[s.slot];
        }
    }
    if res.instances.reserve(&res.device, res.store.len())? {
        res.store.mark_all_dirty();
    }
    Ok(())
}

/// The order to draw `views` in: a view into a render target before every
/// view whose entities show that target, the given order otherwise
/// ([`draw_order`](crate::scene::draw_order): linear in views and entities).
/// A view leaves out the entities whose materials show its own target.
pub(crate) fn view_order(
    res: &Resources,
    frame: &Frame,
    views: &[(ViewKey, &View)],
) -> Result<Vec<usize>, RenderError> {
    let targets = &res.registry.render_targets;
    if targets.is_empty() {
        // No render target: no view draws into one, nothing shows one.
        return match views.iter().find_map(|(_, v)| v.output) {
            Some(id) => Err(RenderError::UnknownRenderTarget(id)),
            None => Ok((0..views.len()).collect()),
        };
    }
    let outputs = (views.iter())
        .map(|(_, v)| match v.output {
            None => Ok(None),
            Some(id) => {
                targets.get(id.0 as usize).map(|_| Some(id.0 as usize)).ok_or(RenderError::UnknownRenderTarget(id))
            }
        })
        .collect::<Result<Vec<_>, _>>()?;
    let target_of: HashMap<TextureId, usize> = targets.iter().enumerate().map(|(k, t)| (t.1, k)).collect();
    // The targets each material drawn shows, found once per material.
    let mut shows: HashMap<MaterialId, Vec<usize>> = HashMap::new();
    for s in &frame.submitted {
        shows.entry(s.material).or_insert_with(|| {
            let maps = res.registry.material(s.material).map(|m| m.maps()).unwrap_or_default();
            maps.iter().flatten().filter_map(|t| target_of.get(t).copied()).collect()
        });
    }
    let shown: Vec<Vec<usize>> = (views.iter())
        .map(|(_, view)| {
            let shown = shown(res, res.registry.render_target_of(view).map(|t| t.1));
            let drawn = frame.submitted.iter().filter(|s| shown.contains(s));
            let mut all: Vec<usize> = drawn.flat_map(|s| shows[&s.material].iter().copied()).collect();
            all.sort_unstable();
            all.dedup();
            all
        })
        .collect();
    crate::scene::draw_order(&outputs, &shown, targets.len()).map_err(|_| RenderError::RenderTargetCycle)
}

/// Clear `target` to black when the first view drawn into it does not cover it.
pub(crate) fn clear_uncovered(
    frame: &mut Frame,
    views: &[(ViewKey, &View)],
    order: &[usize],
    target: &OffscreenTarget,
) {
    let into_target = order.iter().map(|&k| views[k].1).find(|v| v.output.is_none());
    let size = [target.width(), target.height()];
    if into_target.is_none_or(|v| v.viewport.pixels(size[0], size[1])[2..] == size) {
        return;
    }
    frame.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("clear the target"),
        color_attachments: &[Some(target.color_attachment(wgpu::Color::BLACK))],
        ..Default::default()
    });
}

/// Record `after`'s work into the frame, in order, after its views have
/// drawn `target`.
pub(crate) fn after_views(
    res: &Resources,
    frame: &mut Frame,
    after: &mut [&mut dyn AfterViews],
    target: &OffscreenTarget,
) {
    for work in after {
        let before = work.record(&res.device, &res.queue, &mut frame.encoder, target);
        frame.before.extend(before);
    }
}

/// Submit `frame`'s commands (new textures' mip levels first: the shadow
/// passes may sample them; then what its after-view work must run first) in
/// one submission, and fill in `drawn`, its views' statistics, with the
/// frame's number and costs; a failed frame's commands are dropped. Either
/// way its entities are dropped and what it borrowed goes back to `next`,
/// numbered for the frame after; views not drawn for a while give their
/// state back.
pub(crate) fn submit_frame(
    (res, states, next): (&mut Resources, &mut ViewStates, &mut NextFrame),
    mut frame: Frame,
    drawn: Result<Vec<FrameStats>, RenderError>,
) -> Result<FrameOutput, RenderError> {
    // The submission's time: closing the debug groups, finishing and submitting the commands.
    let t = Instant::now();
    match drawn {
        Ok(_) => frame.outline.finish(&mut frame.encoder),
        Err(_) => {
            frame.outline.drop_frame();
            states.forget_stills();
        }
    }
    let Frame {
        index,
        encoder,
        outline,
        mut submitted,
        visible,
        prepares,
        prefiltered,
        first_view,
        mesh_bytes,
        before,
        gpu,
        start,
        ..
    } = frame;
    submitted.clear();
    (next.index, next.submitted, next.visible, next.outline) = (index + 1, submitted, visible, outline);
    let mut views = drawn?;
    let mip_blits = std::mem::take(&mut res.registry.mip_blits);
    res.queue.submit(mip_blits.into_iter().chain(before).chain([encoder.finish()]));
    if let Some(timer) = &mut res.gpu_timer {
        timer.submitted();
    }
    let submits = (res.queue.submits() - res.submits_counted) as u32;
    res.submits_counted = res.queue.submits();
    let in_views: f64 = views.iter().map(|s| s.cpu_ms.total).sum();
    for stats in &mut views {
        (stats.frame, stats.gpu, stats.environment_prefiltered) = (index, gpu.clone(), prefiltered);
    }
    if let Some(first) = first_view.and_then(|k| views.get_mut(k)) {
        first.cpu_ms.submit = ms_since(t);
        first.cpu_ms.total += ms_since(start) - in_views;
        first.submits = submits;
        first.bytes_uploaded.meshes += mesh_bytes;
    }
    states.drop_unused(index);
    check_device(res)?;
    Ok(FrameOutput { frame: index, views, submits, prepares })
}

/// The first error the device reported outside glint's scopes (out of
/// memory while drawing, say), as [`RenderError::Device`].
fn check_device(res: &Resources) -> Result<(), RenderError> {
    match res.uncaptured.take() {
        None => Ok(()),
        Some(message) => Err(RenderError::Device { what: "the frame", message }),
    }
}
