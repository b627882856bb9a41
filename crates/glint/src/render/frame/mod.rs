//! Core layer: the frame. [`Renderer::render_frame`] is a whole frame, one
//! stage a line, as DESIGN.md's data flow draws it; each stage is a free
//! function of this folder whose inputs are its arguments — the renderer's
//! [`Resources`](crate::render::resources::Resources) first, then the frame
//! being recorded ([`Frame`](state::Frame): its encoder, debug outline,
//! submitted entities and visible set), then a view's GPU state
//! ([`ViewGpu`](crate::render::views::ViewGpu)) — and whose outputs are its
//! return values:
//!
//! | file | stages |
//! | --- | --- |
//! | `stages.rs` | the frame's start (entities into the instance store, its encoder), its checks, the order of its views, compacting the store, the clear of uncovered pixels, the work after the views, the one submission |
//! | `simulate.rs` | GPU simulations' compute passes (their steps, then the instances they draw), before any view |
//! | `shadow_pass.rs` | shadow views planned once a frame; per view, culled, batched, uploaded and drawn |
//! | `view.rs` | one view: its target, then prepare → shadows → cull → queue → sort → batch → upload → encode → compose |
//! | `prepare.rs`, `prepared.rs` | GPU twins and pipelines for what the entities use; the table of what each draws with |
//! | `lights.rs` | the view's light clusters: binned (by `gpu_driven/light_binning.rs`'s passes where it culls on the GPU, else on the CPU) and uploaded |
//! | `visible.rs` | which instances a view sees (stage 3, cull) |
//! | `forward.rs` | the draw queue (stage 4) and the upload (stage 7) |
//! | `encode.rs`, `draw.rs`, `ambient_occlusion.rs` | the forward pass and its depth pre-pass, occlusion culling's phases, ambient occlusion (stage 8) |
//! | `naive.rs` | the naive baseline's batch, upload and encode |
//! | `input.rs`, `state.rs` | what a frame is given and gives back; the frame being recorded and what the renderer keeps for the next |
//! | `beginner.rs` | the seed's calls (`submit`, `shadow_pass`, `flush`, `render`, `render_views`): a thin layer that builds a `FrameInput` |
//!
//! A frame is one command encoder, carried from stage to stage in the
//! per-frame `Frame` value, and one submission, which consumes it. Debug
//! groups nest like the outline (`debug/outline.rs`): frame N › simulate,
//! then per view (in a group "view k" where the frame has several): shadows,
//! lights (where the GPU bins them), forward, post; around passes labelled
//! "light n cascade c", "bin lights", "cull instances", "depth pre-pass",
//! "ambient occlusion", "forward pass: early", "depth pyramid", "post: …".

pub(crate) mod ambient_occlusion;
mod beginner;
pub(crate) mod draw;
pub(crate) mod encode;
pub(crate) mod forward;
pub(crate) mod input;
pub(crate) mod lights;
pub(crate) mod naive;
pub(crate) mod prepare;
pub(crate) mod prepared;
pub(crate) mod shadow_pass;
pub(crate) mod simulate;
pub(crate) mod stages;
pub(crate) mod state;
pub(crate) mod transparency;
mod view;
pub(crate) mod visible;

pub use beginner::Shadows;

use crate::gpu::OffscreenTarget;
use crate::render::debug::stats::FrameStats;
use crate::render::frame::input::{FrameInput, FrameOutput};
use crate::render::frame::prepare::prepare_environment;
use crate::render::frame::shadow_pass::plan_shadows;
use crate::render::frame::simulate::simulate;
use crate::render::frame::stages::{after_views, begin_frame, check_frame, clear_uncovered, compact_store};
use crate::render::frame::stages::{submit_frame, view_order};
use crate::render::frame::view::draw_view;
use crate::render::{RenderError, Renderer};

impl Renderer {
    /// Draw one frame of `input` into `target`: the instance store compacted →
    /// simulate → plan shadows →
    /// per view (prepare, shadow views, lights, cull, queue, sort, batch, upload,
    /// encode, compose) → the work after the views → one submission. Errors
    /// (the frame's commands and entities are dropped): more lights than
    /// [`Clusters::check`](crate::render::Clusters::check) allows, an id that is not this
    /// renderer's, a viewport outside its target, views that need each
    /// other's render targets.
    pub fn render_frame(
        &mut self,
        input: FrameInput,
        target: &mut OffscreenTarget,
    ) -> Result<FrameOutput, RenderError> {
        let FrameInput { entities, views, lighting, shadows, mut simulations, mut after, sample } = input;
        self.views.begin_frame(views.iter().map(|&(key, _)| key)); // the keys `wait_for_counts` reads
        let (res, states) = (&mut self.res, &mut self.views);
        let mut frame = begin_frame(res, &mut self.next, entities); // its number and encoder; entities into the store
        frame.sample = sample; // a sub-frame of an accumulated still, or a frame of its own
        let mut stages = || {
            check_frame(&mut frame, &views, (&lighting, res.clusters))?; // lights, ids, viewports, post chains
            let order = view_order(res, &frame, &views)?; // render targets before the views that show them
            compact_store(res, &mut frame)?; // and its GPU buffer sized, before any command uses the instance store
            simulate(res, &mut frame, &mut simulations)?; // GPU simulations' steps, and the instances they draw
            frame.prefiltered = prepare_environment(res, &lighting)?; // image-based lighting's maps
            let plan = plan_shadows(res, &frame, (&views, target), &lighting, shadows)?; // spot and point lights once, cascades per view
            clear_uncovered(&mut frame, &views, &order, target); // black where the views leave gaps
            let mut stats = vec![FrameStats::default(); views.len()];
            for (n, &k) in order.iter().enumerate() {
                let (key, view) = views[k];
                let mut gpu = states.take(key, &res.shared(), res.paths); // the view's GPU state, by its key
                let place = (views.len() > 1).then_some(k); // its debug group "view k" when there are several
                let drawn =
                    draw_view(res, &mut frame, &mut gpu, (place, view), (&lighting, &plan.of_view(k, n == 0)), target);
                states.put_back(key, gpu, frame.index);
                stats[k] = drawn?;
            }
            frame.first_view = order.first().copied();
            after_views(res, &mut frame, &mut after, target); // an overlay, the blit onto a window
            Ok(stats)
        };
        let drawn = stages();
        // One submission; what the frame borrowed goes back for the next.
        submit_frame((&mut self.res, &mut self.views, &mut self.next), frame, drawn)
    }

    /// Every debug group the last submitted frame opened, in order, each as its
    /// path: "frame 3", "frame 3 › view 1", "frame 3 › view 1 › shadows", …
    /// (the outline a capture tool shows, where the driver takes debug groups:
    /// [`Gpu::debug_groups`](crate::Gpu::debug_groups)).
    pub fn frame_outline(&self) -> &[String] {
        self.next.outline.last()
    }

    /// The light clusters the GPU binned for the last frame's first view,
    /// read back from its cluster array (waiting for the GPU); `None` where
    /// it did not bin on the GPU. Their `overflow` and `visible` are left 0
    /// (the frame's [`ClusterStats`](crate::render::ClusterStats) count them).
    #[doc(hidden)]
    pub fn gpu_light_clusters(&self) -> Result<Option<crate::render::clusters::LightClusters>, RenderError> {
        let view = self.views.last(0);
        let (Some(grid), Some(buffer)) =
            (view.and_then(|v| v.clusters.gpu_grid()), view.and_then(|v| v.clusters.data.buffer()))
        else {
            return Ok(None);
        };
        let bytes = crate::gpu::read_buffer(&self.res.device, &self.res.queue, buffer)
            .map_err(|e| RenderError::Device { what: "light clusters", message: e.to_string() })?;
        Ok(Some(crate::render::gpu_driven::light_binning::read_clusters(&grid, bytemuck::cast_slice(&bytes))))
    }

    /// Fill in the instance counts (and light clusters' counts, where the GPU
    /// binned them; and exact transparency's fragments) of the last frame's views (`stats`, in the
    /// order given) that were culled on the GPU, waiting for the GPU to count
    /// them: for a frame on its own, such as `glint render --stats` draws (in
    /// a running frame loop the counts come a frame or two late, without waiting).
    pub fn wait_for_counts(&mut self, stats: &mut [FrameStats]) {
        for (k, stats) in stats.iter_mut().enumerate() {
            let lists = self.views.last(k).and_then(|v| match &v.transparency {
                Some(crate::render::passes::transparency::TransparencyTargets::Exact(lists)) => Some(lists),
                _ => None,
            });
            let Some(lists) = lists else { continue };
            let Ok(heads) = crate::gpu::read_buffer(&self.res.device, &self.res.queue, lists.heads()) else { continue };
            let appended = heads.get(..4).map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
            stats.transparent_fragments =
                Some(crate::render::debug::stats::ListCounts { appended: u64::from(appended), held: lists.nodes - 1 });
        }
        let submits = self.res.queue.submits();
        for (k, stats) in stats.iter_mut().enumerate().filter(|(_, s)| s.culling == crate::scene::Culling::Gpu) {
            let Some(view) = self.views.last_mut(k) else { continue };
            if let Some(drawn) = view.forward.gpu_drawn(&self.res.device, submits, true) {
                let valid = stats.instances_submitted - stats.instances_invalid;
                stats.set_drawn(drawn);
                stats.instances_culled = valid.saturating_sub(drawn.instances);
            }
            let bins = view.clusters.bins.as_mut().filter(|_| stats.light_clusters.is_some_and(|c| c.on_gpu));
            if let Some(counted) = bins.and_then(|b| b.stats(&self.res.device, submits, true)) {
                stats.light_clusters = Some(counted);
            }
        }
    }
}
