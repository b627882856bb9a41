//! Core layer: the naive baseline `glint bench` measures the optimized frame
//! against ([`FrameMode::Naive`](crate::render::FrameMode::Naive)): the way frames were
//! built before the application stage. Every valid instance of every submitted
//! entity is one draw, in submission order, nothing culled or sorted; each
//! draw's material entry and instance index are written on their own before
//! it, every frame; and the pass binds every state again for every draw, one
//! `draw_indexed` call each. It shares the optimized frame's prepare, blocks
//! and compose stages, and nothing of its batching, upload or encoding.

use crate::gpu::OffscreenTarget;
use crate::render::batch::Batch;
use crate::render::debug::explain::{run_calls, state};
use crate::render::debug::outline::Outline;
use crate::render::debug::stats::{ms_since, FrameStats, Laps, PassStats};
use crate::render::debug::timer::Timed;
use crate::render::error::RenderError;
use crate::render::frame::draw::{draw_glare, draw_sky};
use crate::render::frame::encode::begin_forward_pass;
use crate::render::frame::encode::Part;
use crate::render::frame::forward::upload_view_blocks;
use crate::render::frame::prepared::Prepared;
use crate::render::frame::state::Frame;
use crate::render::frame::visible::visible_instances;
use crate::render::frame::visible::{shown, Submitted};
use crate::render::gpu_driven::commands::Run;
use crate::render::queue::{sort_key, Queue};
use crate::render::resources::Resources;
use crate::render::view::ViewFrame;
use crate::render::views::ViewGpu;
use crate::scene::Lighting;

/// The most draws a naive frame makes: each costs about 5 KB of memory
/// while the frame is built and encoded (7 KB with `glint explain`'s call
/// list), and `glint explain --naive` draws eight such frames: at 250,000 it
/// took 34 s and 1.8 GB on this project's 2-core machine (`docs/limits.md`).
pub const MAX_NAIVE_DRAWS: usize = 150_000;

/// The naive frame's stages between prepare and compose: batch, upload,
/// encode into `encoder` (each stage's CPU time in `stats`, from `lap`).
/// `shadowed` is each light's first shadow view.
pub(crate) fn naive_frame(
    res: &mut Resources,
    frame: &mut Frame,
    (gpu, view): (&mut ViewGpu, &ViewFrame),
    (lighting, shadowed): (&Lighting, &[Option<u32>]),
    (target, prepared): (&OffscreenTarget, &[Prepared]),
    (stats, lap): (&mut FrameStats, &mut Laps),
) -> Result<(), RenderError> {
    naive_batches(res, &frame.submitted, (gpu, view), stats, prepared)?;
    stats.cpu_ms.batch = lap.next();
    naive_upload(res, (gpu, view), (lighting, shadowed), stats)?;
    stats.cpu_ms.upload = lap.next();
    naive_encode(res, (&mut frame.encoder, &frame.outline, frame.index), (gpu, view), (target, lighting), stats);
    stats.cpu_ms.encode = lap.next();
    Ok(())
}

/// One batch per instance the optimized frame draws with culling off
/// (every valid one; of a tiled entity, each tile's share at its
/// density), in submission order, each drawing as `prepared` says.
/// Refuses a frame of more than [`MAX_NAIVE_DRAWS`] draws before building it.
fn naive_batches(
    res: &mut Resources,
    submitted: &[Submitted],
    (gpu, frame): (&mut ViewGpu, &ViewFrame),
    stats: &mut FrameStats,
    prepared: &[Prepared],
) -> Result<(), RenderError> {
    gpu.forward.clear();
    let mut instances = Vec::new();
    let shown = shown(res, frame.hides);
    for (s, &Prepared { pipeline, draw, .. }) in submitted.iter().zip(prepared).filter(|(s, _)| shown.contains(s)) {
        let slot = res.store.slot(s.slot);
        stats.instances_invalid += u64::from(slot.invalid);
        instances.clear();
        visible_instances(&frame.frustum, false, slot, s.share(frame.far_eye), (&res.store, &mut instances));
        let drawn = gpu.forward.batches.len() + instances.len();
        if drawn > MAX_NAIVE_DRAWS {
            let what = "the naive frame (one draw per instance)";
            return Err(RenderError::TooMany { what, count: drawn as u64, limit: MAX_NAIVE_DRAWS as u64 });
        }
        // Keyed as the optimized frame keys it (blended materials far to
        // near), though the naive frame draws in submission order.
        let stage = Queue::Opaque.stage();
        let features = res.registry.pipelines.key_of(pipeline).features;
        let blended = features.contains(crate::shader::ShaderFeatures::ALPHA_BLEND);
        let key = sort_key(stage, blended, pipeline, draw.texture_set, s.material, s.shape, 0.0);
        for &i in &instances {
            let list = &mut gpu.forward;
            // The COMPACT variant draws an instance by its number; the
            // others read it from the draw-index list.
            let first_instance = if slot.compact { i } else { list.draw_indices.len() as u32 };
            let batch = Batch {
                key,
                stage,
                pipeline,
                material: s.material,
                shape: s.shape,
                first_instance,
                instance_count: 1,
                level: 0,
                copies: false,
            };
            list.push_alone(batch, draw, (!slot.compact).then_some(i));
        }
    }
    stats.set_drawn(gpu.forward.cpu_drawn());
    Ok(())
}

/// The view's blocks and changed instances as the optimized frame writes
/// them; then every draw's material entry and instance index, one small
/// write each.
fn naive_upload(
    res: &mut Resources,
    (gpu, frame): (&mut ViewGpu, &ViewFrame),
    (lighting, shadowed): (&Lighting, &[Option<u32>]),
    stats: &mut FrameStats,
) -> Result<(), RenderError> {
    let bytes = &mut stats.bytes_uploaded;
    upload_view_blocks(res, gpu, frame, lighting, shadowed, bytes)?;
    for b in &gpu.forward.batches {
        let block = res.registry.materials[b.material.0 as usize].material.to_gpu();
        bytes.material += res.registry.material_table.write(&res.queue, b.material.0, &block);
    }
    let layout = &res.registry.pipelines.instance_layout;
    let list = &mut gpu.forward;
    bytes.draw_indices += list.write_indices_one_by_one(&res.device, &res.queue, (layout, res.instances.array()))?;
    Ok(())
}

/// One pass: the sky first, under everything, then each batch with every
/// state bound again and its own `draw_indexed` call.
fn naive_encode(
    res: &mut Resources,
    (encoder, outline, index): (&mut wgpu::CommandEncoder, &Outline, u64),
    (gpu, view): (&ViewGpu, &ViewFrame),
    (target, lighting): (&OffscreenTarget, &Lighting),
    stats: &mut FrameStats,
) {
    let start = web_time::Instant::now();
    {
        let background = lighting.environment.background;
        let mut pass =
            begin_forward_pass(res, (encoder, outline), gpu, target, (background, Part::Whole, false), stats);
        draw_sky(res, outline, gpu, &mut pass, target, &lighting.environment, stats);
        let list = &gpu.forward;
        pass.push_debug_group("naive: one draw per instance");
        for (b, draw) in list.batches.iter().zip(&list.draws) {
            let pipelines = &res.registry.pipelines;
            pass.set_stencil_reference(pipelines.stencil_reference(b.pipeline));
            pass.set_pipeline(pipelines.forward(b.pipeline));
            pass.set_bind_group(2, &res.registry.texture_sets[draw.texture_set as usize].bind_group, &[]);
            let mesh = draw.mesh;
            let base_vertex = match res.base_vertex {
                true => {
                    res.registry.mesh_pool.bind(&mut pass, mesh.page);
                    mesh.base_vertex
                }
                false => {
                    res.registry.mesh_pool.bind_from(&mut pass, mesh.page, mesh.base_vertex as u64);
                    0
                }
            };
            let indices = mesh.first_index..mesh.first_index + mesh.index_count;
            pass.draw_indexed(indices, base_vertex, b.first_instance..b.first_instance + 1);
        }
        outline.calls(|| {
            let every = state::STENCIL | state::PIPELINE | state::TEXTURES | state::VERTICES;
            let run = |k: usize| Run::new(k, 1, 0);
            (0..list.batches.len())
                .flat_map(|k| {
                    run_calls((&res.registry, res.base_vertex), list, &run(k), ("draw_indexed", false), every)
                })
                .collect()
        });
        pass.pop_debug_group();
        let layers = (target.format(), view.variant.clustered, crate::render::passes::particles::Layers::All);
        res.particles.draw((&mut pass, outline), layers, None, stats);
        draw_glare(res, outline, &mut pass, target, &lighting.environment, stats);
        let n = list.batches.len() as u32;
        (stats.pipelines_bound, stats.bind_groups_set) = (stats.pipelines_bound + n, stats.bind_groups_set + n);
        (stats.draws, stats.draw_calls) = (stats.draws + n, stats.draw_calls + n);
        let instances = u64::from(n);
        stats.passes.opaque = PassStats { draw_calls: n, draws: n, instances, triangles: 0, cpu_ms: ms_since(start) };
    }
    if let Some(timer) = &mut res.gpu_timer {
        timer.resolve(encoder, Timed::Forward, index);
    }
}
