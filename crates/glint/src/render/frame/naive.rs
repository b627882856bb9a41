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
use crate::render::debug::explain::state;
use crate::render::debug::timer::Timed;
use crate::render::frame::encode::Part;
use crate::render::frame::prepare::Prepared;
use crate::render::frame::visible::visible_instances;
use crate::render::gpu_driven::gpu_cull::Run;
use crate::render::queue::{sort_key, Queue};
use crate::render::view::ViewFrame;
use crate::render::views::ViewGpu;
use crate::render::{FrameStats, Laps, RenderError, Renderer};
use crate::scene::Lighting;

/// The most draws a naive frame makes: each costs about 5 KB of memory
/// while the frame is built and encoded (7 KB with `glint explain`'s call
/// list), and `glint explain --naive` draws eight such frames: at 250,000 it
/// took 34 s and 1.8 GB on this project's 2-core machine (`docs/limits.md`).
pub const MAX_NAIVE_DRAWS: usize = 150_000;

impl Renderer {
    /// The naive frame's stages between prepare and compose: batch, upload,
    /// encode into `encoder` (each stage's CPU time in `stats`, from `lap`).
    /// `shadowed` is each light's first shadow view.
    pub(crate) fn naive_frame(
        &mut self,
        gpu: &mut ViewGpu,
        frame: &ViewFrame,
        (lighting, shadowed): (&Lighting, &[Option<u32>]),
        (target, prepared): (&OffscreenTarget, &[Prepared]),
        (encoder, stats): (&mut wgpu::CommandEncoder, &mut FrameStats),
        lap: &mut Laps,
    ) -> Result<(), RenderError> {
        self.naive_batches(gpu, frame, stats, prepared)?;
        stats.cpu_ms.batch = lap.next();
        self.naive_upload(gpu, frame, (lighting, shadowed), stats)?;
        stats.cpu_ms.upload = lap.next();
        self.naive_encode(gpu, encoder, target, lighting, stats);
        stats.cpu_ms.encode = lap.next();
        Ok(())
    }

    /// One batch per instance the optimized frame draws with culling off
    /// (every valid one; of a tiled entity, each tile's share at its
    /// density), in submission order, each drawing as `prepared` says.
    /// Refuses a frame of more than [`MAX_NAIVE_DRAWS`] draws before building it.
    fn naive_batches(
        &mut self,
        gpu: &mut ViewGpu,
        frame: &ViewFrame,
        stats: &mut FrameStats,
        prepared: &[Prepared],
    ) -> Result<(), RenderError> {
        gpu.forward.clear();
        let mut instances = Vec::new();
        let shown = self.shown(frame.hides);
        for (s, &Prepared { pipeline, draw, .. }) in
            self.submitted.iter().zip(prepared).filter(|(s, _)| shown.contains(s))
        {
            let slot = self.store.slot(s.slot);
            stats.instances_invalid += u64::from(slot.invalid);
            instances.clear();
            visible_instances(&frame.frustum, false, slot, s.density, (&self.store, &mut instances));
            let drawn = gpu.forward.batches.len() + instances.len();
            if drawn > MAX_NAIVE_DRAWS {
                let what = "the naive frame (one draw per instance)";
                return Err(RenderError::TooMany { what, count: drawn as u64, limit: MAX_NAIVE_DRAWS as u64 });
            }
            // Keyed as the optimized frame keys it (blended materials far to
            // near), though the naive frame draws in submission order.
            let stage = Queue::Opaque.stage();
            let features = self.registry.pipelines.key_of(pipeline).features;
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
                };
                list.push_alone(batch, draw, (!slot.compact).then_some(i));
            }
        }
        stats.instances_drawn = gpu.forward.batches.len() as u64;
        Ok(())
    }

    /// The view's blocks and changed instances as the optimized frame writes
    /// them; then every draw's material entry and instance index, one small
    /// write each.
    fn naive_upload(
        &mut self,
        gpu: &mut ViewGpu,
        frame: &ViewFrame,
        (lighting, shadowed): (&Lighting, &[Option<u32>]),
        stats: &mut FrameStats,
    ) -> Result<(), RenderError> {
        let bytes = &mut stats.bytes_uploaded;
        self.upload_view_blocks(gpu, frame, lighting, shadowed, bytes)?;
        for b in &gpu.forward.batches {
            let block = self.registry.materials[b.material.0 as usize].material.to_gpu();
            bytes.material += self.registry.material_table.write(&self.queue, b.material.0, &block);
        }
        let layout = &self.registry.pipelines.instance_layout;
        let list = &mut gpu.forward;
        bytes.draw_indices +=
            list.write_indices_one_by_one(&self.device, &self.queue, (layout, self.instances.array()))?;
        Ok(())
    }

    /// One pass: the sky first, under everything, then each batch with every
    /// state bound again and its own `draw_indexed` call.
    fn naive_encode(
        &mut self,
        gpu: &ViewGpu,
        encoder: &mut wgpu::CommandEncoder,
        target: &OffscreenTarget,
        lighting: &Lighting,
        stats: &mut FrameStats,
    ) {
        let start = web_time::Instant::now();
        {
            let background = lighting.environment.background;
            let mut pass = self.begin_forward_pass(gpu, encoder, target, (background, Part::Whole, false), stats);
            self.draw_sky(gpu, &mut pass, target, &lighting.environment, stats);
            let list = &gpu.forward;
            pass.push_debug_group("naive: one draw per instance");
            for (b, draw) in list.batches.iter().zip(&list.draws) {
                let pipelines = &self.registry.pipelines;
                pass.set_stencil_reference(pipelines.stencil_reference(b.pipeline));
                pass.set_pipeline(pipelines.forward(b.pipeline));
                pass.set_bind_group(2, &self.registry.texture_sets[draw.texture_set as usize].bind_group, &[]);
                let mesh = draw.mesh;
                let base_vertex = match self.base_vertex {
                    true => {
                        self.registry.mesh_pool.bind(&mut pass, mesh.page);
                        mesh.base_vertex
                    }
                    false => {
                        self.registry.mesh_pool.bind_from(&mut pass, mesh.page, mesh.base_vertex as u64);
                        0
                    }
                };
                let indices = mesh.first_index..mesh.first_index + mesh.index_count;
                pass.draw_indexed(indices, base_vertex, b.first_instance..b.first_instance + 1);
            }
            self.outline.calls(|| {
                let every = state::STENCIL | state::PIPELINE | state::TEXTURES | state::VERTICES;
                let run = |k: usize| Run::new(k, 1, 0);
                (0..list.batches.len())
                    .flat_map(|k| self.run_calls(list, &run(k), ("draw_indexed", false), every))
                    .collect()
            });
            pass.pop_debug_group();
            self.draw_particles(&mut pass, target.format(), None, stats);
            self.draw_glare(&mut pass, target, &lighting.environment, stats);
            let n = list.batches.len() as u32;
            (stats.pipelines_bound, stats.bind_groups_set) = (stats.pipelines_bound + n, stats.bind_groups_set + n);
            (stats.draws, stats.draw_calls) = (stats.draws + n, stats.draw_calls + n);
            let instances = u64::from(n);
            stats.passes.opaque =
                crate::render::PassStats { draw_calls: n, draws: n, instances, cpu_ms: crate::render::ms_since(start) };
        }
        if let Some(timer) = &mut self.gpu_timer {
            timer.resolve(encoder, Timed::Forward, self.frame_index);
        }
    }
}
