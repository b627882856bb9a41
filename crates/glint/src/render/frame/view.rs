//! Core layer: one view of the frame ([`draw_view`]): the target
//! it is drawn into, then its stages, one a line ([`view_stages`]):
//! prepare → shadow views → cull → queue → sort → batch → upload → encode,
//! and compose.

use crate::gpu::{OffscreenTarget, TargetFormat, HDR_FORMAT};
use crate::render::debug::stats::{ms_since, FrameStats, Laps};
use crate::render::error::RenderError;
use crate::render::frame::ambient_occlusion::{occludes, prepare_ambient_occlusion};
use crate::render::frame::encode::encode;
use crate::render::frame::forward::{build_queue, upload};
use crate::render::frame::input::FrameMode;
use crate::render::frame::input::SubFrame;
use crate::render::frame::lights::cluster_lights;
use crate::render::frame::naive::naive_frame;
use crate::render::frame::prepare::prepare;
use crate::render::frame::shadow_pass::draw_shadows;
use crate::render::frame::shadow_pass::ViewShadows;
use crate::render::frame::state::Frame;
use crate::render::frame::transparency::prepare_transparency;
use crate::render::frame::visible::{cull, shown};
use crate::render::frame_variant::FrameVariant;
use crate::render::passes::accumulate::{AccumulatePipelines, Accumulation};
use crate::render::passes::post::ChainImages;
use crate::render::queue;
use crate::render::resources::Resources;
use crate::render::view::ViewFrame;
use crate::render::views::ViewGpu;
use crate::scene::{Culling, Lighting, PostEffect, TextureId, View};
use web_time::Instant;

/// How a view's picture reaches the output (the compose stage).
enum Compose<'a> {
    /// It was drawn into the output itself.
    Direct,
    /// Copied from its own target into the output at `origin`.
    Copy { from: &'a OffscreenTarget, to: &'a OffscreenTarget, origin: [u32; 2] },
    /// Its post chain, from its HDR target into its rectangle of the output.
    Post { chain: &'a [PostEffect], images: &'a ChainImages<'a> },
    /// Folded into its running mean as a sub-frame of an accumulated still;
    /// at the last, the mean through its post chain (clamped without one).
    Accumulate { chain: &'a [PostEffect], images: &'a ChainImages<'a> },
}

/// The chain of a view without post effects whose sub-frames were
/// accumulated in HDR: clamped into the output's 0..1, as drawing into it does.
const CLAMP: [PostEffect; 1] = [PostEffect::Tonemap { operator: crate::scene::Tonemap::None, exposure: 0.0 }];

/// A view of the frame (in its debug group "view k" where `group` is its
/// place `k` in a frame of several views), with its GPU state `gpu`: drawn
/// into `output`, or into its render target, leaving out the entities that
/// show that target.
pub(crate) fn draw_view(
    res: &mut Resources,
    frame: &mut Frame,
    gpu: &mut ViewGpu,
    (group, view): (Option<usize>, &View),
    (lighting, shadows): (&Lighting, &ViewShadows),
    output: &OffscreenTarget,
) -> Result<FrameStats, RenderError> {
    let start = Instant::now();
    if let Some(k) = group {
        frame.outline.enter(&mut frame.encoder, &format!("view {k}"));
    }
    if let Some(timer) = &mut res.gpu_timer {
        timer.begin_view(group.unwrap_or(0));
    }
    let drawn = match view.output {
        None => draw_into(res, frame, gpu, (view, None), (lighting, shadows), output),
        Some(id) => {
            // The render targets are out of the registry while one is drawn into.
            let targets = std::mem::take(&mut res.registry.render_targets);
            let (own, texture) = &targets[id.0 as usize];
            let drawn = draw_into(res, frame, gpu, (view, Some(*texture)), (lighting, shadows), own);
            res.registry.render_targets = targets;
            drawn
        }
    };
    if group.is_some() {
        frame.outline.leave(&mut frame.encoder);
    }
    let mut stats = drawn?;
    stats.cpu_ms.total = ms_since(start);
    Ok(stats)
}

/// `view` drawn into `target` itself when it covers it and has no post
/// chain; else into a view target of the viewport's size (HDR for a post
/// chain, whose last pass writes the rectangle, or for a sub-frame of an
/// accumulated still), copied into the rectangle. `hides`: the view's own
/// render target (a view into one is not accumulated).
fn draw_into(
    res: &mut Resources,
    frame: &mut Frame,
    gpu: &mut ViewGpu,
    (view, hides): (&View, Option<TextureId>),
    (lighting, shadows): (&Lighting, &ViewShadows),
    target: &OffscreenTarget,
) -> Result<FrameStats, RenderError> {
    let [x, y, width, height] = view.viewport.pixels(target.width(), target.height());
    let occluded = occludes(res, view.ambient_occlusion);
    let variant = FrameVariant::after(shadows.first, shadows.views.len(), lighting.lights, occluded)
        .with_clusters(res.clusters.applies(lighting.lights));
    let renderer = (res.cull_pipelines.is_some(), res.levels_of_detail, hides, variant);
    let sample = if hides.is_none() { frame.sample } else { SubFrame::ONE };
    if !sample.accumulates() {
        gpu.accumulation = None; // a frame of its own: no still to keep (40 bytes a pixel)
    }
    let view_frame = ViewFrame::new(view, (width, height), renderer, sample);
    let format = scene_format(res, (view, sample), target);
    if (width, height, format) == (target.width(), target.height(), target.format()) {
        return view_stages(res, frame, gpu, &view_frame, (lighting, shadows), (target, Compose::Direct));
    }
    let read_depth = res.cull_pipelines.as_ref().is_some_and(|p| p.occlusion());
    let own = res.targets.take_view(&res.device, (width, height), (format, read_depth), frame.index);
    let images = ChainImages {
        scene: own.color_view(),
        size: (width, height),
        output: target.color_view(),
        output_format: target.format().color,
        rect: [x, y, width, height],
    };
    let compose = match (sample.accumulates(), view.post.is_empty()) {
        (true, _) => Compose::Accumulate { chain: &view.post, images: &images },
        (false, true) => Compose::Copy { from: &own, to: target, origin: [x, y] },
        (false, false) => Compose::Post { chain: &view.post, images: &images },
    };
    let drawn = view_stages(res, frame, gpu, &view_frame, (lighting, shadows), (&own, compose));
    res.targets.put_back(own, frame.index);
    drawn
}

/// The target a view's scene is drawn into: HDR (with the output's samples
/// where the adapter can) for a post chain or a sub-frame of a still of
/// several, else the output's own format.
fn scene_format(res: &Resources, (view, sample): (&View, SubFrame), target: &OffscreenTarget) -> TargetFormat {
    match view.post.is_empty() && !sample.accumulates() {
        true => target.format(),
        false => TargetFormat { color: HDR_FORMAT, samples: if res.hdr_msaa { target.samples() } else { 1 } },
    }
}

/// One view's stages into `target`, one a line, each stage's CPU time the
/// lap that ends on its line:
/// 1. prepare — GPU twins for new shapes, textures, materials and
///    pipelines, edited materials rewritten (once per frame for each target
///    format and variant its views draw with)
/// 2. shadow views — this view's cascades, and (the frame's first view)
///    the spot and point lights' views: culled, batched and drawn from every
///    submitted caster (`render/frame/shadow_pass.rs`)
/// 3. lights — where the view clusters, its point and spot lights binned
///    into its cluster grid, by a compute pass where it culls on the GPU,
///    else on the CPU (`render/frame/lights.rs`)
/// 4. cull — each entity's world box, then its instances', against the
///    view's frustum; culled on the GPU ([`Culling::Gpu`]), every valid
///    instance of each entity not blended becomes a candidate the GPU tests
///    (`render/gpu_driven/gpu_cull.rs`)
/// 5. queue — one draw item with a 64-bit sort key per visible run (per instance when blended)
/// 6. sort — radix sort by key
/// 7. batch — equal (stage, pipeline, material, shape) runs merged into
///    instanced draws, one indirect command each
/// 8. upload — with ambient occlusion, its pre-pass pipelines, textures and
///    parameters (`render/passes/ambient_occlusion.rs`); Scene and Camera blocks
///    if changed, changed instances, draw indices and indirect commands if changed
/// 9. encode — culled on the GPU, the cull pass first; with ambient
///    occlusion, its depth pre-pass (the view's depth, which the forward
///    pass then tests for equality), occlusion and blur passes; one pass:
///    opaque → alpha-test → sky → transparent (or as `render_order` says)
///    → particle layers → glare; batches sharing pipeline, texture set and
///    mesh page go in one multi-draw-indirect call. Occlusion culling
///    splits the pass (or the depth pre-pass) around its depth pyramid and
///    late cull (`render/gpu_driven/occlusion.rs`)
/// 10. compose — a view drawn into a target of its own reaches its
///     rectangle: copied, or through its post chain (`render/passes/post.rs`)
fn view_stages(
    res: &mut Resources,
    frame: &mut Frame,
    gpu: &mut ViewGpu,
    view: &ViewFrame,
    (lighting, shadows): (&Lighting, &ViewShadows),
    (target, compose): (&OffscreenTarget, Compose),
) -> Result<FrameStats, RenderError> {
    let mut stats = view_counts(res, frame, view);
    let mut lap = Laps::start();
    let prepared = prepare(res, frame, target.format(), view.variant, &lighting.environment, &mut stats)?;
    res.particles.prepare(&mut res.registry, (target.format(), view.variant.clustered), &mut stats)?;
    stats.cpu_ms.prepare = lap.next();
    draw_shadows(res, frame, gpu, (view, shadows), (&prepared, &lighting.environment), &mut stats)?;
    lap.next();
    cluster_lights(res, frame, (gpu, view), lighting.lights, &mut stats)?;
    stats.cpu_ms.lights = lap.next();
    let forward = if res.mode == FrameMode::Naive { "forward (naive)" } else { "forward" };
    frame.outline.enter(&mut frame.encoder, forward);
    match res.mode {
        FrameMode::Naive => {
            stats.culling = Culling::Off;
            let shadowed = (lighting, shadows.shadowed());
            naive_frame(res, frame, (gpu, view), shadowed, (target, &prepared), (&mut stats, &mut lap))?;
        }
        FrameMode::Optimized => {
            cull(res, (&frame.submitted, &mut frame.visible), view, &mut stats);
            stats.cpu_ms.cull = lap.next();
            gpu.forward.clear();
            build_queue(res, frame, gpu, view, &prepared);
            stats.cpu_ms.queue = lap.next();
            queue::sort(&mut gpu.forward.items);
            stats.cpu_ms.sort = lap.next();
            let visible = &frame.visible;
            let placed = |item: &queue::DrawItem| visible.placed[item.entry as usize];
            let draw_of = |item: &queue::DrawItem| prepared[item.entry as usize].draw;
            gpu.forward.build(0, &visible.instances, (view.frustum, view.lod), draw_of, placed);
            stats.cpu_ms.batch = lap.next();
            prepare_ambient_occlusion(res, gpu, view, target, &mut stats)?;
            prepare_transparency(res, gpu, view, target, &mut stats)?;
            upload(res, gpu, view, (lighting, shadows.shadowed()), target, &mut stats)?;
            stats.cpu_ms.upload = lap.next();
            encode(res, frame, gpu, (view, target), &lighting.environment, &mut stats);
            stats.cpu_ms.encode = lap.next();
        }
    }
    frame.outline.leave(&mut frame.encoder);
    compose_view(res, frame, gpu, compose, &mut stats)?;
    stats.bytes_uploaded.finish();
    Ok(stats)
}

/// A view's counts before it is drawn: the entities it may draw (not those
/// showing its own target), their instances and instance records.
fn view_counts(res: &Resources, frame: &Frame, view: &ViewFrame) -> FrameStats {
    let (mut entities, mut instances, mut records) = (0, 0, 0);
    let shown = shown(res, view.hides);
    for s in frame.submitted.iter().filter(|s| shown.contains(s)) {
        let slot = res.store.slot(s.slot);
        (entities, instances, records) = (entities + 1, instances + s.instances, records + slot.len());
    }
    FrameStats {
        entities_submitted: entities,
        instances_submitted: instances,
        instance_bytes: (records * std::mem::size_of::<crate::render::resources::blocks::InstanceGpu>()) as u64,
        ..Default::default()
    }
}

/// Stage 9 of a view not drawn straight into the output: its picture copied,
/// or its post chain run, into its rectangle of the output.
fn compose_view(
    res: &mut Resources,
    frame: &mut Frame,
    gpu: &mut ViewGpu,
    compose: Compose,
    stats: &mut FrameStats,
) -> Result<(), RenderError> {
    let encoder = &mut frame.encoder;
    match compose {
        Compose::Direct => {}
        Compose::Copy { from, to, origin: [x, y] } => encoder.copy_texture_to_texture(
            from.color_texture().as_image_copy(),
            wgpu::TexelCopyTextureInfo { origin: wgpu::Origin3d { x, y, z: 0 }, ..to.color_texture().as_image_copy() },
            wgpu::Extent3d { width: from.width(), height: from.height(), depth_or_array_layers: 1 },
        ),
        Compose::Post { chain, images } => post(res, frame, gpu, (chain, images), stats)?,
        Compose::Accumulate { chain, images } => {
            let sample = frame.sample;
            let size = images.size;
            // Out of the view's state while the chain, which takes that state, reads its mean.
            let mut accumulation = Accumulation::for_sample(&res.device, gpu.accumulation.take(), sample, size)?;
            let pipelines = match &res.accumulate {
                Some(pipelines) => pipelines,
                None => res.accumulate.insert(AccumulatePipelines::new(&res.device)?),
            };
            frame.outline.enter(encoder, "accumulate");
            let passes = (&res.device, &*res.queue, pipelines);
            let last = accumulation.fold(passes, (encoder, &frame.outline), images.scene, sample);
            frame.outline.leave(encoder);
            let drawn = match last {
                true => {
                    let chain = if chain.is_empty() { &CLAMP[..] } else { chain };
                    let images = ChainImages { scene: accumulation.mean(), ..*images };
                    post(res, frame, gpu, (chain, &images), stats)
                }
                false => Ok(()),
            };
            gpu.accumulation = Some(accumulation);
            drawn?;
        }
    }
    Ok(())
}

/// A view's post chain from `images.scene` into its rectangle of the output.
fn post(
    res: &mut Resources,
    frame: &mut Frame,
    gpu: &mut ViewGpu,
    (chain, images): (&[PostEffect], &ChainImages),
    stats: &mut FrameStats,
) -> Result<(), RenderError> {
    let t = Instant::now();
    let encoder = &mut frame.encoder;
    frame.outline.enter(encoder, "post");
    let (device, queue, timer) = (&res.device, &res.queue, res.gpu_timer.as_mut());
    let (params, pool) = (&mut gpu.post_params, &mut res.targets);
    let at = (frame.index, timer, &frame.outline);
    stats.passes.post = res.post.encode((device, queue), (params, pool), encoder, chain, images, at)?;
    stats.draws += stats.passes.post.draws;
    stats.draw_calls += stats.passes.post.draw_calls;
    frame.outline.leave(encoder);
    stats.passes.post.cpu_ms = ms_since(t);
    Ok(())
}
