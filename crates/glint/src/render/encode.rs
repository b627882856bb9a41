//! Core layer: stage 7 of the frame, recording the forward pass.
//!
//! Batches come sorted; a run of adjacent batches with the same pipeline, texture
//! set and mesh-pool page needs no state change between them, so in optimized mode
//! the run is one `multi_draw_indexed_indirect` call over its batches' commands
//! (or one `draw_indexed` per batch where the device cannot draw indirect). The
//! naive baseline draws batch by batch and binds everything again for each.

use super::batch::Batch;
use super::draw_list::DrawList;
use super::queue::{Queue, SKY_STAGE};
use super::timer::Timed;
use super::views::ViewBlocks;
use super::{FrameMode, FrameStats, Renderer};
use crate::gpu::OffscreenTarget;
use crate::scene::Background;

/// Bytes of one indexed indirect command.
const INDIRECT_STRIDE: u64 = std::mem::size_of::<wgpu::util::DrawIndexedIndirectArgs>() as u64;

/// What the pass has bound, to skip redundant state changes.
#[derive(Default)]
pub(super) struct Bound {
    pipeline: Option<u16>,
    texture_set: Option<u16>,
    page: Option<u16>,
    stencil_reference: u32,
}

/// The state a batch draws with: runs of equal keys share one call.
#[derive(Clone, Copy, PartialEq, Eq)]
struct RunKey {
    pipeline: u16,
    texture_set: u16,
    page: u16,
}

impl Renderer {
    /// Stage 7: record the forward pass, cleared to `background`: opaque →
    /// alpha-test → sky → transparent (or as `render_order` stages say).
    pub(super) fn encode(
        &mut self,
        target: &OffscreenTarget,
        background: Background,
        stats: &mut FrameStats,
    ) -> wgpu::CommandBuffer {
        let sky_at = match self.mode {
            // Naive frames are in submission order: the sky goes first, under everything.
            FrameMode::Naive => 0,
            FrameMode::Optimized => self.view.forward.batches.partition_point(|b| b.stage < SKY_STAGE),
        };
        let clear = match background {
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
                timestamp_writes: self.gpu_timer.as_ref().and_then(|t| t.pass_writes(Timed::Forward, true, true)),
                ..Default::default()
            });
            pass.set_bind_group(0, &self.view.scene_group, &[]);
            pass.set_bind_group(1, &self.view.blocks.bind_group, &[ViewBlocks::offset(0)]);
            pass.set_bind_group(3, &self.view.forward.bind_group, &[]);
            stats.bind_groups_set += 3;
            let mut bound = Bound::default();
            self.draw_stages(&self.view.forward, &mut pass, 0..sky_at, &mut bound, stats);
            let sky = match background {
                Background::Gradient { .. } => self.registry.pipelines.sky_built(target.format()),
                Background::Color(_) => None,
            };
            if let Some(sky) = sky {
                pass.push_debug_group("sky");
                pass.set_pipeline(sky);
                pass.draw(0..3, 0..1);
                pass.pop_debug_group();
                stats.pipelines_bound += 1;
                stats.draw_calls += 1;
                stats.draws += 1;
                stats.passes.sky = super::PassStats { draw_calls: 1, draws: 1, instances: 1, cpu_ms: 0.0 };
                // The sky's layout has groups 0–1 only: bind the forward groups again.
                pass.set_bind_group(3, &self.view.forward.bind_group, &[]);
                stats.bind_groups_set += 1;
                bound = Bound { stencil_reference: bound.stencil_reference, ..Bound::default() };
            }
            self.draw_stages(&self.view.forward, &mut pass, sky_at..self.view.forward.batches.len(), &mut bound, stats);
        }
        if let Some(timer) = &mut self.gpu_timer {
            timer.resolve(&mut encoder, Timed::Forward, self.frame_index);
        }
        encoder.finish()
    }

    /// Draw `list`'s batches in `range`, one debug group per stage.
    pub(super) fn draw_stages(
        &self,
        list: &DrawList,
        pass: &mut wgpu::RenderPass<'_>,
        range: std::ops::Range<usize>,
        bound: &mut Bound,
        stats: &mut FrameStats,
    ) {
        let mut at = range.start;
        for stage in list.batches[range].chunk_by(|a, b| a.stage == b.stage) {
            let (start, calls, draws) = (web_time::Instant::now(), stats.draw_calls, stats.draws);
            pass.push_debug_group(&stage_name(stage[0].stage));
            let naive = self.mode == FrameMode::Naive;
            for run in stage.chunk_by(|a, b| !naive && self.run_key(a) == self.run_key(b)) {
                self.draw_run(list, pass, at, run, bound, stats);
                at += run.len();
            }
            pass.pop_debug_group();
            let named = &mut stats.passes;
            let cost = match stage[0].stage {
                s if s < SKY_STAGE && s != Queue::AlphaTest.stage() => &mut named.opaque,
                s if s == Queue::AlphaTest.stage() => &mut named.alpha_test,
                _ => &mut named.transparent,
            };
            cost.draw_calls += stats.draw_calls - calls;
            cost.draws += stats.draws - draws;
            cost.instances += stage.iter().map(|b| u64::from(b.instance_count)).sum::<u64>();
            cost.cpu_ms += super::ms_since(start);
        }
    }

    /// Draw `run` (batches from index `at`), which share one [`RunKey`], setting
    /// only the state that changes (naive frames: all of it).
    fn draw_run(
        &self,
        list: &DrawList,
        pass: &mut wgpu::RenderPass<'_>,
        at: usize,
        run: &[Batch],
        bound: &mut Bound,
        stats: &mut FrameStats,
    ) {
        if self.mode == FrameMode::Naive {
            *bound = Bound::default();
        }
        let key = self.run_key(&run[0]);
        let reference = self.registry.pipelines.stencil_reference(key.pipeline);
        if bound.stencil_reference != reference || self.mode == FrameMode::Naive {
            pass.set_stencil_reference(reference);
            bound.stencil_reference = reference;
        }
        if bound.pipeline != Some(key.pipeline) {
            pass.set_pipeline(self.registry.pipelines.forward(key.pipeline));
            bound.pipeline = Some(key.pipeline);
            stats.pipelines_bound += 1;
        }
        if bound.texture_set != Some(key.texture_set) {
            pass.set_bind_group(2, &self.registry.texture_sets[key.texture_set as usize].bind_group, &[]);
            bound.texture_set = Some(key.texture_set);
            stats.bind_groups_set += 1;
        }
        if bound.page != Some(key.page) && self.base_vertex {
            self.registry.mesh_pool.bind(pass, key.page);
            bound.page = Some(key.page);
        }
        stats.draws += run.len() as u32;
        match &list.indirect {
            Some(indirect) if self.mode == FrameMode::Optimized => {
                pass.multi_draw_indexed_indirect(&indirect.buffer, at as u64 * INDIRECT_STRIDE, run.len() as u32);
                stats.draw_calls += 1;
            }
            _ => {
                for b in run {
                    let mesh = self.registry.shapes[b.shape.0 as usize].gpu.expect("prepared");
                    let indices = mesh.first_index..mesh.first_index + mesh.index_count;
                    let base_vertex = match self.base_vertex {
                        true => mesh.base_vertex,
                        false => {
                            self.registry.mesh_pool.bind_from(pass, key.page, mesh.base_vertex as u64);
                            0
                        }
                    };
                    pass.draw_indexed(indices, base_vertex, b.first_instance..b.first_instance + b.instance_count);
                }
                stats.draw_calls += run.len() as u32;
            }
        }
    }

    fn run_key(&self, b: &Batch) -> RunKey {
        let material = self.registry.materials[b.material.0 as usize].gpu.as_ref().expect("prepared");
        let mesh = self.registry.shapes[b.shape.0 as usize].gpu.expect("prepared");
        RunKey { pipeline: b.pipeline, texture_set: material.texture_set, page: mesh.page }
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
