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
use crate::render::debug::explain::{queue_name, state, DrawCall, PassType};
use crate::render::debug::timer::Timed;
use crate::render::gpu_driven::draw_list::{run_stage, DrawList};
use crate::render::gpu_driven::gpu_cull::{Run, COMMAND_BYTES};
use crate::render::passes::ambient_occlusion::{PrepassDepth, PrepassPart};
use crate::render::queue::{Queue, SKY_STAGE};
use crate::render::resources::pipelines::SkyPass;
use crate::render::view::ViewFrame;
use crate::render::views::{ViewBlocks, ViewGpu};
use crate::render::{FrameStats, Renderer};
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
    /// What comes before soft particles, after occlusion culling's early draws.
    Middle,
    /// Soft particles and the glare, reading the depth they are tested against.
    Particles,
}

/// Which pipeline draws a run: its own, or one of its twins
/// ([`Pipelines::prepass_id`](crate::render::resources::pipelines::Pipelines::prepass_id)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum Twin {
    /// Its own.
    #[default]
    Own,
    /// Its depth pre-pass twin (runs without one are skipped), drawing into
    /// the view target's depth when `shared`.
    Prepass { shared: bool },
    /// Its twin testing the shared pre-pass's depth for equality (runs
    /// without one draw with their own).
    Equal,
}

/// What the pass has bound, to skip redundant state changes.
#[derive(Default)]
pub(crate) struct Bound {
    pipeline: Option<u16>,
    texture_set: Option<u16>,
    page: Option<u16>,
    stencil_reference: u32,
    /// Which of each run's pipelines draws it.
    twin: Twin,
}

impl Bound {
    /// Nothing bound yet, drawing each run with `twin`.
    pub(crate) fn twin(twin: Twin) -> Self {
        Self { twin, ..Self::default() }
    }
}

impl Renderer {
    /// Stage 7: record the forward pass, cleared to `background`: opaque →
    /// alpha-test → sky → transparent (or as `render_order` stages say) →
    /// particles → glare. With ambient occlusion, its depth pre-pass and
    /// passes first; where the pre-pass draws the target's depth, the forward
    /// pass tests it for equality and draws no depth of its own.
    pub(crate) fn encode(
        &mut self,
        gpu: &mut ViewGpu,
        view: &ViewFrame,
        (encoder, target): (&mut wgpu::CommandEncoder, &OffscreenTarget),
        environment: &Environment,
        stats: &mut FrameStats,
    ) {
        let background = environment.background;
        let list = &gpu.forward;
        let sky_at = list.runs.partition_point(|r| run_stage(list, r) < SKY_STAGE);
        if let Some(pipelines) = &self.cull_pipelines {
            if gpu.forward.culled_on_gpu() {
                self.outline.pass("cull instances", PassType::Compute, &[]);
            }
            gpu.forward.record_cull(encoder, pipelines, self.queue.submits());
        }
        let depth = target.depth_only_view().filter(|_| gpu.forward.gpu.as_ref().is_some_and(|g| g.occluding));
        let prepass = self.prepass_depth(gpu, view);
        let shared = prepass == Some(PrepassDepth::Shared);
        // The pre-pass draws occlusion culling's phases where it draws the target's depth.
        let phased = shared && depth.is_some() && self.cull_pipelines.is_some();
        if prepass.is_some() {
            let part = PrepassPart { first: true, last: !phased };
            self.encode_ambient_occlusion(gpu, (encoder, target), (part, false), stats);
        }
        let end = gpu.forward.runs.len();
        // Occlusion culling: the opaque stages of what was seen last frame, then
        // the late phase (depth pyramid, late cull), then what it found, in a
        // second forward pass that goes on with the sky and the later stages;
        // or, where the pre-pass draws the depth, its two phases around the late
        // phase and one forward pass drawing both.
        let (part, before_sky, after_sky) = match (depth, &self.cull_pipelines) {
            (Some(depth), Some(pipelines)) => {
                if !phased {
                    let mut bound = Bound::default();
                    let mut pass =
                        self.begin_forward_pass(gpu, encoder, target, (background, Part::First, false), stats);
                    self.draw_stages(&gpu.forward, &mut pass, (0..sky_at, &[false]), &mut bound, stats);
                }
                if let Some(culled) = &mut gpu.forward.gpu {
                    self.outline.pass("depth pyramid", PassType::Compute, &[]);
                    self.outline.pass("cull instances: late", PassType::Compute, &[]);
                    culled.record_late((&self.device, encoder), pipelines, depth, self.queue.submits());
                }
                match phased {
                    true => {
                        let part = PrepassPart { first: false, last: true };
                        self.encode_ambient_occlusion(gpu, (encoder, target), (part, true), stats);
                        (Part::Whole, &[false, true][..], &[false, true][..])
                    }
                    false => (Part::Second, &[true][..], &[false, true][..]),
                }
            }
            _ => (Part::Whole, &[false][..], &[false][..]),
        };
        // Soft particles read the depth: they and the glare get a pass of their own.
        let particle_depth = self.particle_depth(target);
        let part = match (part, &particle_depth) {
            (Part::Whole, Some(_)) => Part::First,
            (Part::Second, Some(_)) => Part::Middle,
            (part, _) => part,
        };
        {
            let mut pass = self.begin_forward_pass(gpu, encoder, target, (background, part, shared), stats);
            let mut bound = Bound::twin(if shared { Twin::Equal } else { Twin::Own });
            self.draw_stages(&gpu.forward, &mut pass, (0..sky_at, before_sky), &mut bound, stats);
            // The pre-pass drew only the stages before the sky.
            if self.draw_sky(gpu, &mut pass, target, environment, stats) || shared {
                bound = Bound { stencil_reference: bound.stencil_reference, ..Bound::default() };
            }
            self.draw_stages(&gpu.forward, &mut pass, (sky_at..end, after_sky), &mut bound, stats);
            if particle_depth.is_none() {
                self.draw_particles(&mut pass, target.format(), None, stats);
                self.draw_glare(&mut pass, target, environment, stats);
            }
        }
        if let Some(depth) = &particle_depth {
            let mut pass = self.begin_forward_pass(gpu, encoder, target, (background, Part::Particles, false), stats);
            self.draw_particles(&mut pass, target.format(), Some(depth), stats);
            self.draw_glare(&mut pass, target, environment, stats);
        }
        if let Some(timer) = &mut self.gpu_timer {
            timer.resolve(encoder, Timed::Forward, self.frame_index);
        }
    }

    /// Begin the view's forward pass (or `part` of it) into `target`, cleared
    /// to `background`, with the Scene, Camera and Renderer blocks bound; its
    /// depth loaded, not cleared, where a pre-pass drew it (`drawn`).
    pub(crate) fn begin_forward_pass<'e>(
        &self,
        gpu: &ViewGpu,
        encoder: &'e mut wgpu::CommandEncoder,
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
            Part::Particles => target.last_reading_depth(),
        };
        let depth = match (drawn, part) {
            (true, Part::Whole) => target.depth_stencil(false, false),
            (true, Part::First) => target.depth_stencil(false, true),
            _ => depth,
        };
        let (begins, ends) =
            (matches!(part, Part::Whole | Part::First), matches!(part, Part::Whole | Part::Second | Part::Particles));
        let label = match part {
            Part::Whole => "forward pass",
            Part::First => "forward pass: early",
            Part::Second => "forward pass: late",
            Part::Middle => "forward pass: before soft particles",
            Part::Particles => "forward pass: soft particles",
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[Some(color)],
            depth_stencil_attachment: Some(depth),
            timestamp_writes: self.gpu_timer.as_ref().and_then(|t| t.pass_writes(Timed::Forward, begins, ends)),
            ..Default::default()
        });
        pass.set_bind_group(0, &gpu.scene_group, &[]);
        pass.set_bind_group(1, &gpu.blocks.bind_group, &[ViewBlocks::offset(0)]);
        pass.set_bind_group(3, &gpu.forward.bind_group, &[]);
        stats.bind_groups_set += 3;
        let bound = ["bind group 0 (scene)", "bind group 1 (camera)", "bind group 3 (instances, draw indices)"];
        self.outline.pass(label, PassType::Render, &bound);
        pass
    }

    /// Draw the sun glare of `environment` over everything (none at glare 0),
    /// the pass's last draw.
    pub(crate) fn draw_glare(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        target: &OffscreenTarget,
        environment: &Environment,
        stats: &mut FrameStats,
    ) {
        let glare = self.registry.pipelines.sky_built(target.format(), SkyPass::Glare);
        if let Some(glare) = glare.filter(|_| environment.glare > 0.0) {
            full_screen(pass, glare, "glare", stats);
            self.outline.call(|| DrawCall::single("glare", "draw", (1, 1), &["pipeline"]));
        }
    }

    /// Draw the sky of `environment` (its image, or its gradient; none for a
    /// plain colour: [`sky_pass`](crate::render::frame::prepare::sky_pass)); returns
    /// whether it drew, after which only groups 0, 1 and 3 are bound.
    pub(crate) fn draw_sky(
        &self,
        gpu: &ViewGpu,
        pass: &mut wgpu::RenderPass<'_>,
        target: &OffscreenTarget,
        environment: &Environment,
        stats: &mut FrameStats,
    ) -> bool {
        let sky = crate::render::frame::prepare::sky_pass(environment)
            .and_then(|p| self.registry.pipelines.sky_built(target.format(), p));
        let Some(sky) = sky else { return false };
        full_screen(pass, sky, "sky", stats);
        self.outline.call(|| DrawCall::single("sky", "draw", (1, 1), &["pipeline"]));
        stats.passes.sky = crate::render::PassStats { draw_calls: 1, draws: 1, instances: 1, cpu_ms: 0.0 };
        // The sky's layout has groups 0–1 only: bind the forward groups again.
        pass.set_bind_group(3, &gpu.forward.bind_group, &[]);
        stats.bind_groups_set += 1;
        true
    }

    /// Draw `list`'s runs in `range`, one debug group per stage, each stage
    /// from the commands of each of `phases` in turn (occlusion culling's late
    /// phase when true, else the early or only one).
    pub(crate) fn draw_stages(
        &self,
        list: &DrawList,
        pass: &mut wgpu::RenderPass<'_>,
        (range, phases): (std::ops::Range<usize>, &[bool]),
        bound: &mut Bound,
        stats: &mut FrameStats,
    ) {
        let mut at = range.start;
        for stage in list.runs[range].chunk_by(|a, b| run_stage(list, a) == run_stage(list, b)) {
            let (start, calls, draws) = (web_time::Instant::now(), stats.draw_calls, stats.draws);
            let name = run_stage(list, &stage[0]);
            pass.push_debug_group(&queue_name(name));
            for &late in phases {
                for (k, run) in stage.iter().enumerate() {
                    self.draw_run(list, pass, (at + k, late), run, bound, stats);
                }
            }
            at += stage.len();
            pass.pop_debug_group();
            let named = &mut stats.passes;
            let cost = match name {
                s if s < SKY_STAGE && s != Queue::AlphaTest.stage() => &mut named.opaque,
                s if s == Queue::AlphaTest.stage() => &mut named.alpha_test,
                _ => &mut named.transparent,
            };
            cost.draw_calls += stats.draw_calls - calls;
            cost.draws += stats.draws - draws;
            let batches = stage.iter().flat_map(|r| &list.batches[r.batches()]);
            cost.instances += batches.map(|b| u64::from(b.instance_count)).sum::<u64>();
            cost.cpu_ms += crate::render::ms_since(start);
        }
    }

    /// Draw run `k` of `list` (`run`), from the late phase's commands when
    /// `late`, setting only the state that changes.
    fn draw_run(
        &self,
        list: &DrawList,
        pass: &mut wgpu::RenderPass<'_>,
        (k, late): (usize, bool),
        run: &Run,
        bound: &mut Bound,
        stats: &mut FrameStats,
    ) {
        let (first, draw) = (&list.batches[run.first as usize], &list.draws[run.first as usize]);
        let pipelines = &self.registry.pipelines;
        let pipeline = match bound.twin {
            Twin::Own => first.pipeline,
            Twin::Prepass { shared } => match pipelines.prepass_of(first.pipeline, shared) {
                Some(twin) => twin,
                None => return,
            },
            Twin::Equal => pipelines.equal_of(first.pipeline).unwrap_or(first.pipeline),
        };
        let mut changed = 0;
        let reference = pipelines.stencil_reference(pipeline);
        if bound.stencil_reference != reference {
            pass.set_stencil_reference(reference);
            bound.stencil_reference = reference;
            changed |= state::STENCIL;
        }
        if bound.pipeline != Some(pipeline) {
            pass.set_pipeline(pipelines.forward(pipeline));
            bound.pipeline = Some(pipeline);
            stats.pipelines_bound += 1;
            changed |= state::PIPELINE;
        }
        if bound.texture_set != Some(draw.texture_set) {
            pass.set_bind_group(2, &self.registry.texture_sets[draw.texture_set as usize].bind_group, &[]);
            bound.texture_set = Some(draw.texture_set);
            stats.bind_groups_set += 1;
            changed |= state::TEXTURES;
        }
        let page = draw.mesh.page;
        if bound.page != Some(page) && self.base_vertex {
            self.registry.mesh_pool.bind(pass, page);
            bound.page = Some(page);
            changed |= state::VERTICES;
        }
        let command = match (&list.indirect, &list.gpu, &self.cull_pipelines) {
            (_, Some(gpu), Some(pipelines)) if list.culled_on_gpu() => {
                gpu.draw_run(pipelines, pass, (k, late), run);
                // A batch is one draw, in one phase or both; the late calls apart.
                match late {
                    true => stats.late_draw_calls += 1,
                    false => (stats.draws, stats.draw_calls) = (stats.draws + run.len, stats.draw_calls + 1),
                }
                match pipelines.draw_count {
                    true => "multi_draw_indexed_indirect_count",
                    false => "multi_draw_indexed_indirect",
                }
            }
            (Some(indirect), ..) => {
                pass.multi_draw_indexed_indirect(&indirect.buffer, u64::from(run.first) * COMMAND_BYTES, run.len);
                (stats.draws, stats.draw_calls) = (stats.draws + run.len, stats.draw_calls + 1);
                "multi_draw_indexed_indirect"
            }
            _ => {
                for (b, draw) in list.batches[run.batches()].iter().zip(&list.draws[run.batches()]) {
                    let mesh = draw.mesh;
                    let indices = mesh.first_index..mesh.first_index + mesh.index_count;
                    let base_vertex = match self.base_vertex {
                        true => mesh.base_vertex,
                        false => {
                            self.registry.mesh_pool.bind_from(pass, page, mesh.base_vertex as u64);
                            0
                        }
                    };
                    pass.draw_indexed(indices, base_vertex, b.first_instance..b.first_instance + b.instance_count);
                }
                (stats.draws, stats.draw_calls) = (stats.draws + run.len, stats.draw_calls + run.len);
                "draw_indexed"
            }
        };
        self.outline.calls(|| self.run_calls(list, run, (command, late), changed));
    }
}

/// Draw one full-screen triangle with `pipeline` (the sky shader's passes),
/// in a debug group `name`.
fn full_screen(pass: &mut wgpu::RenderPass<'_>, pipeline: &wgpu::RenderPipeline, name: &str, stats: &mut FrameStats) {
    pass.push_debug_group(name);
    pass.set_pipeline(pipeline);
    pass.draw(0..3, 0..1);
    pass.pop_debug_group();
    stats.pipelines_bound += 1;
    stats.draw_calls += 1;
    stats.draws += 1;
}
