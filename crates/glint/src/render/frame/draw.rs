//! Core layer: drawing a draw list's runs into a render pass, setting only
//! the state that changes ([`draw_stages`]): the forward pass, the shadow
//! views and the depth pre-pass all draw this way; and the full-screen sky
//! and glare.

use crate::gpu::OffscreenTarget;
use crate::render::debug::explain::{queue_name, run_calls, state, DrawCall};
use crate::render::debug::outline::Outline;
use crate::render::debug::stats::{ms_since, FrameStats, PassStats};
use crate::render::frame::prepared::sky_pass;
use crate::render::gpu_driven::commands::{Placed, Run, COMMAND_BYTES};
use crate::render::gpu_driven::draw_list::{run_stage, DrawList};
use crate::render::queue::{Queue, SKY_STAGE};
use crate::render::resources::pipelines::{Pipelines, SkyPass};
use crate::render::resources::Resources;
use crate::render::views::ViewGpu;
use crate::scene::{Environment, Transparency};

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
    /// Its twin for the order-independent transparency [`Bound::leaves`]
    /// names (runs without one are skipped).
    Transparent,
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
    /// The order-independent transparency whose twins draw blended runs in a
    /// pass of their own: other passes leave those runs out.
    leaves: Option<Transparency>,
}

impl Bound {
    /// Nothing bound yet, drawing each run with `twin`, and leaving the runs
    /// that have a twin for `transparency` to its pass (drawing only those
    /// with [`Twin::Transparent`]).
    pub(crate) fn twin(twin: Twin, transparency: Option<Transparency>) -> Self {
        Self { twin, leaves: transparency, ..Self::default() }
    }

    /// The pipeline that draws a run of forward pipeline `own` in this pass:
    /// its twin, or its own; `None` where the pass leaves the run out (to the
    /// transparency pass, or without a pre-pass or transparency twin).
    fn pipeline_of(&self, pipelines: &Pipelines, own: u16) -> Option<u16> {
        let transparent = self.leaves.and_then(|way| pipelines.transparency_of(own, way));
        match (self.twin, transparent) {
            (Twin::Transparent, twin) => twin,
            (_, Some(_)) => None,
            (Twin::Own, None) => Some(own),
            (Twin::Prepass { shared }, None) => pipelines.prepass_of(own, shared),
            (Twin::Equal, None) => Some(pipelines.equal_of(own).unwrap_or(own)),
        }
    }

    /// What stays bound after a full-screen draw (the sky) between runs: the
    /// stencil reference only; each run draws with its own pipeline again
    /// (still leaving what it left).
    pub(crate) fn after_full_screen(&self) -> Self {
        Self { stencil_reference: self.stencil_reference, leaves: self.leaves, ..Self::default() }
    }
}

/// Draw the sun glare of `environment` over everything (none at glare 0),
/// the pass's last draw.
pub(crate) fn draw_glare(
    res: &Resources,
    outline: &Outline,
    pass: &mut wgpu::RenderPass<'_>,
    target: &OffscreenTarget,
    environment: &Environment,
    stats: &mut FrameStats,
) {
    let glare = res.registry.pipelines.sky_built(target.format(), SkyPass::Glare);
    if let Some(glare) = glare.filter(|_| environment.glare > 0.0) {
        full_screen(pass, glare, "glare", stats);
        outline.call(|| DrawCall::single("glare", "draw", (1, 1), &["pipeline"]));
    }
}

/// Draw the sky of `environment` (its image, or its gradient; none for a
/// plain colour: [`sky_pass`]); returns
/// whether it drew, after which only groups 0, 1 and 3 are bound.
pub(crate) fn draw_sky(
    res: &Resources,
    outline: &Outline,
    gpu: &ViewGpu,
    pass: &mut wgpu::RenderPass<'_>,
    target: &OffscreenTarget,
    environment: &Environment,
    stats: &mut FrameStats,
) -> bool {
    let sky = sky_pass(environment).and_then(|p| res.registry.pipelines.sky_built(target.format(), p));
    let Some(sky) = sky else { return false };
    full_screen(pass, sky, "sky", stats);
    outline.call(|| DrawCall::single("sky", "draw", (1, 1), &["pipeline"]));
    stats.passes.sky = PassStats { draw_calls: 1, draws: 1, instances: 1, triangles: 0, cpu_ms: 0.0 };
    // The sky's layout has groups 0–1 only: bind the forward groups again.
    pass.set_bind_group(3, &gpu.forward.bind_group, &[]);
    stats.bind_groups_set += 1;
    true
}

/// Draw `list`'s runs in `range`, one debug group per stage, each stage
/// from the commands of each of `phases` in turn (occlusion culling's late
/// phase when true, else the early or only one).
pub(crate) fn draw_stages(
    res: &Resources,
    outline: &Outline,
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
                draw_run((res, outline), list, pass, (at + k, late), run, bound, stats);
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
        // A GPU-culled batch counts its candidates, once for all its levels.
        let pipelines = &res.registry.pipelines;
        let batches = (stage.iter())
            .filter(|r| bound.pipeline_of(pipelines, list.batches[r.first as usize].pipeline).is_some())
            .flat_map(|r| r.batches())
            .filter(|&k| list.placed[k] != Placed::OnGpu || list.batches[k].level == 0);
        cost.instances += batches.map(|k| u64::from(list.batches[k].instance_count)).sum::<u64>();
        cost.cpu_ms += ms_since(start);
    }
}

/// Draw run `k` of `list` (`run`), from the late phase's commands when
/// `late`, setting only the state that changes (nothing for a run this pass
/// leaves out: [`Bound::pipeline_of`]).
fn draw_run(
    (res, outline): (&Resources, &Outline),
    list: &DrawList,
    pass: &mut wgpu::RenderPass<'_>,
    (k, late): (usize, bool),
    run: &Run,
    bound: &mut Bound,
    stats: &mut FrameStats,
) {
    let (first, draw) = (&list.batches[run.first as usize], &list.draws[run.first as usize]);
    let pipelines = &res.registry.pipelines;
    let Some(pipeline) = bound.pipeline_of(pipelines, first.pipeline) else { return };
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
        pass.set_bind_group(2, &res.registry.texture_sets[draw.texture_set as usize].bind_group, &[]);
        bound.texture_set = Some(draw.texture_set);
        stats.bind_groups_set += 1;
        changed |= state::TEXTURES;
    }
    let page = draw.mesh.page;
    if bound.page != Some(page) && res.base_vertex {
        res.registry.mesh_pool.bind(pass, page);
        bound.page = Some(page);
        changed |= state::VERTICES;
    }
    let command = match (&list.indirect, &list.gpu, &res.cull_pipelines) {
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
                let base_vertex = match res.base_vertex {
                    true => mesh.base_vertex,
                    false => {
                        res.registry.mesh_pool.bind_from(pass, page, mesh.base_vertex as u64);
                        0
                    }
                };
                pass.draw_indexed(indices, base_vertex, b.first_instance..b.first_instance + b.instance_count);
            }
            (stats.draws, stats.draw_calls) = (stats.draws + run.len, stats.draw_calls + run.len);
            "draw_indexed"
        }
    };
    outline.calls(|| run_calls((&res.registry, res.base_vertex), list, run, (command, late), changed));
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
