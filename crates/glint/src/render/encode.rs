//! Core layer: stage 7 of the frame, recording the forward pass, and the render
//! bundles that let an unchanged frame skip it.

use super::batch::Batch;
use super::queue::{Queue, SKY_STAGE};
use super::{FrameMode, FrameStats, Renderer};
use crate::gpu::OffscreenTarget;
use crate::scene::{Background, MaterialId, ShapeId};

impl Renderer {
    /// Stage 7: record the forward pass. In optimized mode the draws are replayed from
    /// render bundles recorded when the batch list last changed (a static scene is
    /// encoded once); the naive baseline, and frames that need a stencil reference
    /// (pass state a bundle cannot set), are encoded draw by draw.
    pub(super) fn encode(&mut self, target: &OffscreenTarget, stats: &mut FrameStats) -> wgpu::CommandBuffer {
        let samples = target.samples();
        let sky_at = match self.mode {
            // Naive frames are in submission order: the sky goes first, under everything.
            FrameMode::Naive => 0,
            FrameMode::Optimized => self.batches.partition_point(|b| b.stage < SKY_STAGE),
        };
        let bundled = self.mode == FrameMode::Optimized
            && self.batches.iter().all(|b| self.pipelines.stencil_reference(b.pipeline) == 0);
        let draws_before = stats.draw_calls;
        if bundled
            && !self.bundles.as_ref().is_some_and(|r| r.matches(&self.batches, self.resources_generation, samples))
        {
            let recorded = self.record_bundles(sky_at, samples);
            stats.draws_encoded += recorded.before_sky_counts.draw_calls + recorded.after_sky_counts.draw_calls;
            self.bundles = Some(recorded);
        }
        let clear = match self.environment.background {
            Background::Color(c) | Background::Gradient { bottom: c, .. } => {
                wgpu::Color { r: c.x.into(), g: c.y.into(), b: c.z.into(), a: 1.0 }
            }
        };
        let mut encoder =
            self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("renderer: frame") });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("forward pass"),
                color_attachments: &[Some(target.color_attachment(clear))],
                depth_stencil_attachment: Some(target.depth_attachment()),
                timestamp_writes: self.gpu_timer.as_ref().map(|t| t.pass_writes()),
                ..Default::default()
            });
            let sky = match self.environment.background {
                Background::Gradient { .. } => self.pipelines.sky_built(samples),
                Background::Color(_) => None,
            };
            match (&self.bundles, bundled) {
                (Some(recorded), true) => {
                    pass.push_debug_group("before the sky (render bundle)");
                    pass.execute_bundles([&recorded.before_sky]);
                    pass.pop_debug_group();
                    stats.add(recorded.before_sky_counts);
                    if let Some(sky) = sky {
                        // Executing a bundle clears the pass state: the sky binds its own.
                        pass.set_bind_group(0, &self.scene_group, &[]);
                        pass.set_bind_group(1, &self.camera_group, &[]);
                        self.draw_sky(&mut pass, sky, stats);
                    }
                    pass.push_debug_group("after the sky (render bundle)");
                    pass.execute_bundles([&recorded.after_sky]);
                    pass.pop_debug_group();
                    stats.add(recorded.after_sky_counts);
                    stats.draws_encoded += u32::from(sky.is_some());
                }
                _ => {
                    self.bind_frame_groups(&mut pass, stats);
                    let mut bound = Bound::default();
                    self.draw_stages(&mut pass, &self.batches[..sky_at], &mut bound, stats);
                    if let Some(sky) = sky {
                        self.draw_sky(&mut pass, sky, stats);
                        // The sky's layout has groups 0–1 only: bind the forward groups again.
                        pass.set_bind_group(3, &self.instance_buffers.bind_group, &[]);
                        stats.bind_groups_set += 1;
                        bound = Bound::default();
                    }
                    self.draw_stages(&mut pass, &self.batches[sky_at..], &mut bound, stats);
                    stats.draws_encoded += stats.draw_calls - draws_before;
                }
            }
        }
        if let Some(timer) = &mut self.gpu_timer {
            timer.resolve(&mut encoder);
        }
        encoder.finish()
    }

    /// Bind the groups that stay the same for every draw of a frame: Scene, Camera, Renderer.
    fn bind_frame_groups<'e>(&'e self, enc: &mut impl wgpu::util::RenderEncoder<'e>, stats: &mut FrameStats) {
        enc.set_bind_group(0, Some(&self.scene_group), &[]);
        enc.set_bind_group(1, Some(&self.camera_group), &[]);
        enc.set_bind_group(3, Some(&self.instance_buffers.bind_group), &[]);
        stats.bind_groups_set += 3;
    }

    fn draw_sky(&self, pass: &mut wgpu::RenderPass<'_>, sky: &wgpu::RenderPipeline, stats: &mut FrameStats) {
        pass.push_debug_group("sky");
        pass.set_pipeline(sky);
        pass.draw(0..3, 0..1);
        pass.pop_debug_group();
        stats.pipelines_bound += 1;
        stats.draw_calls += 1;
    }

    /// Record the batches before and after the sky into two render bundles.
    fn record_bundles(&self, sky_at: usize, samples: u32) -> RecordedDraws {
        let record = |label: &str, batches: &[Batch]| {
            let mut enc = self.device.create_render_bundle_encoder(&wgpu::RenderBundleEncoderDescriptor {
                label: Some(label),
                color_formats: &[Some(crate::gpu::COLOR_FORMAT)],
                depth_stencil: Some(wgpu::RenderBundleDepthStencil {
                    format: crate::gpu::DEPTH_FORMAT,
                    depth_read_only: false,
                    stencil_read_only: false,
                }),
                sample_count: samples,
                multiview: None,
            });
            let mut counts = FrameStats::default();
            if !batches.is_empty() {
                self.bind_frame_groups(&mut enc, &mut counts);
                self.draw_batches(&mut enc, batches, &mut Bound::default(), &mut counts);
            }
            (enc.finish(&wgpu::RenderBundleDescriptor { label: Some(label) }), counts)
        };
        let (before_sky, before_sky_counts) = record("renderer: draws before the sky", &self.batches[..sky_at]);
        let (after_sky, after_sky_counts) = record("renderer: draws after the sky", &self.batches[sky_at..]);
        RecordedDraws {
            batches: self.batches.clone(),
            generation: self.resources_generation,
            samples,
            before_sky,
            before_sky_counts,
            after_sky,
            after_sky_counts,
        }
    }

    /// Draw batches directly into the pass, one debug group per stage.
    fn draw_stages<'e>(
        &'e self,
        pass: &mut wgpu::RenderPass<'e>,
        batches: &[Batch],
        bound: &mut Bound,
        stats: &mut FrameStats,
    ) {
        for run in batches.chunk_by(|a, b| a.stage == b.stage) {
            pass.push_debug_group(&stage_name(run[0].stage));
            for b in run {
                let reference = self.pipelines.stencil_reference(b.pipeline);
                if bound.stencil_reference != reference || self.mode == FrameMode::Naive {
                    pass.set_stencil_reference(reference);
                    bound.stencil_reference = reference;
                }
                self.draw_batches(pass, std::slice::from_ref(b), bound, stats);
            }
            pass.pop_debug_group();
        }
    }

    /// Draw batches in order, setting only the state that changes (naive frames:
    /// all of it, every draw).
    fn draw_batches<'e>(
        &'e self,
        enc: &mut impl wgpu::util::RenderEncoder<'e>,
        batches: &[Batch],
        bound: &mut Bound,
        stats: &mut FrameStats,
    ) {
        for b in batches {
            if self.mode == FrameMode::Naive {
                *bound = Bound::default();
            }
            if bound.pipeline != Some(b.pipeline) {
                enc.set_pipeline(self.pipelines.forward(b.pipeline));
                bound.pipeline = Some(b.pipeline);
                stats.pipelines_bound += 1;
            }
            if bound.material != Some(b.material) {
                let twin = self.materials[b.material.0 as usize].gpu.as_ref().expect("prepared");
                enc.set_bind_group(2, Some(&twin.bind_group), &[]);
                bound.material = Some(b.material);
                stats.bind_groups_set += 1;
            }
            let mesh = self.shapes[b.shape.0 as usize].gpu.as_ref().expect("prepared");
            if bound.shape != Some(b.shape) {
                enc.set_vertex_buffer(0, Some(mesh.vertices.slice(..)));
                enc.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
                bound.shape = Some(b.shape);
            }
            enc.draw_indexed(0..mesh.index_count, 0, b.first_instance..b.first_instance + b.instance_count);
            stats.draw_calls += 1;
        }
    }
}

/// Draws recorded into render bundles, and what they were recorded from.
pub(super) struct RecordedDraws {
    batches: Vec<Batch>,
    generation: u64,
    samples: u32,
    before_sky: wgpu::RenderBundle,
    before_sky_counts: FrameStats,
    after_sky: wgpu::RenderBundle,
    after_sky_counts: FrameStats,
}

impl RecordedDraws {
    /// Whether replaying these draws gives what recording `batches` now would.
    fn matches(&self, batches: &[Batch], generation: u64, samples: u32) -> bool {
        self.generation == generation && self.samples == samples && self.batches == batches
    }
}

/// Debug-group name of a stage: its queue, or the render order that put it there.
fn stage_name(stage: u8) -> String {
    match stage {
        s if s == Queue::Opaque.stage() => "opaque".into(),
        s if s == Queue::AlphaTest.stage() => "alpha-test".into(),
        s if s == Queue::Transparent.stage() => "transparent".into(),
        s => format!("render_order {s}"),
    }
}

/// What the pass has bound, to skip redundant state changes.
#[derive(Default)]
struct Bound {
    pipeline: Option<u16>,
    material: Option<MaterialId>,
    shape: Option<ShapeId>,
    stencil_reference: u32,
}
