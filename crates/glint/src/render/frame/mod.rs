//! Core layer: the frame. [`Renderer::render_frame`] is a whole frame, one
//! stage a line, as DESIGN.md's data flow draws it; each view's stages are in
//! `view.rs` ([`Renderer::draw_view`]), and the seed's calls (`submit`,
//! `shadow_pass`, `flush`, `render`, `render_views`) are a thin layer over
//! it in `beginner.rs`.
//!
//! A frame is one command encoder, carried from stage to stage in the
//! per-frame [`Frame`] value, and one submission, which consumes it. Debug
//! groups nest like the outline (`outline.rs`): frame N › simulate, then per
//! view (in a group "view k" where the frame has several): shadows, forward, post; around passes labelled "light n
//! cascade c", "cull instances", "depth pre-pass", "ambient occlusion",
//! "forward pass: early", "depth pyramid", "post: …".

mod beginner;
pub(crate) mod encode;
pub(crate) mod forward;
pub(crate) mod naive;
pub(crate) mod prepare;
pub(crate) mod shadow_pass;
pub(crate) mod simulate;
mod view;
pub(crate) mod visible;

pub use beginner::Shadows;

use crate::gpu::{AfterViews, GpuSimulation, OffscreenTarget};
use crate::render::{ms_since, FrameStats, GpuTimes, RenderError, Renderer};
use crate::scene::{Entity, Lighting, MaterialId, TextureId, View, MAX_LIGHTS, MAX_POST_EFFECTS};
use std::collections::HashMap;
use web_time::Instant;

/// A view's identity, chosen by the caller: its GPU state (camera records,
/// draw lists, ambient-occlusion textures, post parameters) is kept between
/// frames under it, whatever the view's place in the list. A key not drawn
/// for [`KEEP_VIEW_FRAMES`] frames gives its state back.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ViewKey(pub u32);

/// Frames a view's GPU state is kept while its key is not drawn.
pub const KEEP_VIEW_FRAMES: u64 = 120;

/// Everything one frame draws ([`Renderer::render_frame`]).
pub struct FrameInput<'a> {
    /// The entities drawn, after any [`submit`](Renderer::submit)ted since the last frame.
    pub entities: &'a [Entity],
    /// The views, each with its key, drawn in this order, except that a view
    /// into a render target comes before every view whose entities show it.
    pub views: Vec<(ViewKey, &'a View)>,
    /// The lights and the environment.
    pub lighting: Lighting<'a>,
    /// Whether the lights that ask for shadows get them (true unless
    /// [`without_shadows`](Self::without_shadows)).
    pub shadows: bool,
    /// GPU simulations stepped in the frame's simulate stage, before any view,
    /// so that what they write is drawn in the same submission.
    pub simulations: Vec<&'a mut dyn GpuSimulation>,
    /// Work recorded after the views, in this order (an overlay, the blit
    /// onto a window), so that a displayed frame is one submission.
    pub after: Vec<&'a mut dyn AfterViews>,
}

impl<'a> FrameInput<'a> {
    /// A frame of `entities` under `lighting`, with no view yet.
    pub fn new(entities: &'a [Entity], lighting: impl Into<Lighting<'a>>) -> Self {
        let (views, simulations, after) = (Vec::new(), Vec::new(), Vec::new());
        Self { entities, views, lighting: lighting.into(), shadows: true, simulations, after }
    }

    /// Add `view`, its GPU state kept under `key`.
    pub fn view(mut self, key: ViewKey, view: &'a View) -> Self {
        self.views.push((key, view));
        self
    }

    /// Add `views`, each keyed by its place in the list.
    pub fn views(mut self, views: &'a [View]) -> Self {
        self.views.extend(views.iter().enumerate().map(|(k, v)| (ViewKey(k as u32), v)));
        self
    }

    /// Step `simulation` in the frame's simulate stage.
    pub fn simulate(mut self, simulation: &'a mut dyn GpuSimulation) -> Self {
        self.simulations.push(simulation);
        self
    }

    /// Record `work` after the views (and after the work given before it).
    pub fn then(mut self, work: &'a mut dyn AfterViews) -> Self {
        self.after.push(work);
        self
    }

    /// Draw every light without shadows.
    pub fn without_shadows(mut self) -> Self {
        self.shadows = false;
        self
    }
}

/// What a frame cost ([`Renderer::render_frame`]).
#[derive(Clone, Debug, Default)]
pub struct FrameOutput {
    /// The frame's number: frames rendered before it.
    pub frame: u64,
    /// Each view's statistics, in the order given. The frame's own costs (its
    /// submission, the time of the stages before its views) are counted in the
    /// first view drawn's; every view reports the frame's number.
    pub views: Vec<FrameStats>,
    /// Command submissions the frame made (1: everything in one).
    pub submits: u32,
    /// Times the prepare stage ran (not reused within the frame): once per
    /// target format and shader variant its views draw with.
    pub prepares: u32,
}

/// The frame being recorded: handed `&mut` from stage to stage, consumed by
/// its submission ([`Renderer::submit_frame`]); dropped with its commands when
/// a stage fails.
pub(crate) struct Frame {
    /// Its number.
    pub index: u64,
    /// Its one command encoder.
    pub encoder: wgpu::CommandEncoder,
    /// Prepare stages run anew.
    pub prepares: u32,
    /// Whether it prefiltered the environment.
    pub prefiltered: bool,
    /// The view drawn first, which carries the frame's own costs.
    pub first_view: Option<usize>,
    /// Command buffers to submit before the frame's (the after-view work's).
    pub before: Vec<wgpu::CommandBuffer>,
    /// The newest finished earlier frame's GPU times.
    pub gpu: Option<GpuTimes>,
    /// When it began, for its own CPU time.
    pub start: Instant,
}

impl Renderer {
    /// Draw one frame of `input` into `target`: simulate → plan shadows →
    /// per view (prepare, shadow views, cull, queue, sort, batch, upload,
    /// encode, compose) → the work after the views → one submission. Errors
    /// (the frame's commands and entities are dropped): more than
    /// [`MAX_LIGHTS`] lights, an id that is not this renderer's, a viewport
    /// outside its target, views that need each other's render targets.
    pub fn render_frame(
        &mut self,
        input: FrameInput,
        target: &mut OffscreenTarget,
    ) -> Result<FrameOutput, RenderError> {
        let FrameInput { entities, views, lighting, shadows, mut simulations, mut after } = input;
        let mut frame = self.begin_frame(entities, &views); // its number and encoder; entities into the store
        let mut stages = || {
            self.check_frame(&views, &lighting)?; // lights, ids, viewports, post chains
            self.simulate(&mut frame, &mut simulations); // GPU simulations' compute passes
            let order = self.view_order(&views)?; // render targets before the views that show them
            self.compact_store(); // before any command draws from the instance store
            frame.prefiltered = self.prepare_environment(&lighting)?; // image-based lighting's maps
            let plan = self.plan_shadows(&views, &lighting, shadows, target)?; // spot and point lights once, cascades per view
            self.clear_uncovered(&mut frame, &views, &order, target); // black where the views leave gaps
            let mut stats = vec![FrameStats::default(); views.len()];
            for (n, &k) in order.iter().enumerate() {
                let shadows = plan.of_view(k, n == 0);
                let group = (views.len() > 1).then_some(k); // "view k" when there are several
                stats[k] = self.draw_view(&mut frame, (group, views[k]), (&lighting, &shadows), target)?;
            }
            frame.first_view = order.first().copied();
            self.after_views(&mut frame, &mut after, target); // an overlay, the blit onto a window
            Ok(stats)
        };
        let drawn = stages();
        self.submit_frame(frame, drawn) // one submission
    }

    /// The frame's start: `entities` submitted after any submitted already,
    /// its encoder begun with its "frame N" debug group, the GPU times of an
    /// earlier frame collected, and `views`' keys kept as the last frame's.
    fn begin_frame(&mut self, entities: &[Entity], views: &[(ViewKey, &View)]) -> Frame {
        let start = Instant::now();
        for entity in entities {
            self.submit(entity);
        }
        self.last_keys.clear();
        self.last_keys.extend(views.iter().map(|&(key, _)| key));
        let label = Some("renderer: frame");
        let mut encoder = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label });
        self.outline.enter(&mut encoder, &format!("frame {}", self.frame_index));
        let gpu = self.gpu_timer.as_mut().and_then(|t| t.collect(&self.device));
        let (prepares, prefiltered, first_view, before) = (0, false, None, Vec::new());
        Frame { index: self.frame_index, encoder, prepares, prefiltered, first_view, before, gpu, start }
    }

    /// The errors a frame finds before drawing: a bad id submitted, too many
    /// lights, a viewport outside its target or a post chain too long.
    fn check_frame(&mut self, views: &[(ViewKey, &View)], lighting: &Lighting) -> Result<(), RenderError> {
        if let Some(e) = self.submit_error.take() {
            return Err(e);
        }
        if lighting.lights.len() > MAX_LIGHTS {
            return Err(RenderError::TooManyLights(lighting.lights.len()));
        }
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

    /// Record `after`'s work into the frame, in order, after its views have
    /// drawn `target`.
    fn after_views(&self, frame: &mut Frame, after: &mut [&mut dyn AfterViews], target: &OffscreenTarget) {
        for work in after {
            let before = work.record(&self.device, &self.queue, &mut frame.encoder, target);
            frame.before.extend(before);
        }
    }

    /// Compact the instance store when it holds more garbage than data: at the
    /// frame's start, before any command recorded draws from where instances are.
    fn compact_store(&mut self) {
        if let Some(remap) = self.store.compact_if_wasteful(self.frame_index) {
            for s in &mut self.submitted {
                s.slot = remap[s.slot];
            }
        }
    }

    /// Submit `frame`'s commands (new textures' mip levels first: the shadow
    /// passes may sample them; then what its after-view work must run first)
    /// in one submission, and fill in `drawn`, its
    /// views' statistics, with the frame's number and costs; a failed frame's
    /// commands are dropped. The frame's entities are dropped either way.
    fn submit_frame(
        &mut self,
        frame: Frame,
        drawn: Result<Vec<FrameStats>, RenderError>,
    ) -> Result<FrameOutput, RenderError> {
        self.submitted.clear();
        self.frame_index += 1;
        let Frame { index, mut encoder, prepares, prefiltered, first_view, before, gpu, start } = frame;
        let mut views = match drawn {
            Ok(views) => views,
            Err(e) => {
                self.outline.drop_frame();
                return Err(e);
            }
        };
        let t = Instant::now();
        self.outline.finish(&mut encoder);
        let mip_blits = std::mem::take(&mut self.registry.mip_blits);
        let commands = mip_blits.into_iter().chain(before).chain([encoder.finish()]);
        self.queue.submit(commands);
        if let Some(timer) = &mut self.gpu_timer {
            timer.submitted();
        }
        let submits = (self.queue.submits() - self.submits_counted) as u32;
        self.submits_counted = self.queue.submits();
        let in_views: f64 = views.iter().map(|s| s.cpu_ms.total).sum();
        for stats in &mut views {
            (stats.frame, stats.gpu, stats.environment_prefiltered) = (index, gpu.clone(), prefiltered);
        }
        if let Some(first) = first_view.and_then(|k| views.get_mut(k)) {
            first.cpu_ms.submit = ms_since(t);
            first.cpu_ms.total += ms_since(start) - in_views;
            first.submits = submits;
        }
        self.views.retain(|_, (_, drawn)| *drawn + KEEP_VIEW_FRAMES >= index);
        self.check_device()?;
        Ok(FrameOutput { frame: index, views, submits, prepares })
    }

    /// The first error the device reported outside glint's scopes (out of
    /// memory while drawing, say), as [`RenderError::Device`].
    fn check_device(&self) -> Result<(), RenderError> {
        match self.uncaptured.take() {
            None => Ok(()),
            Some(message) => Err(RenderError::Device { what: "the frame", message }),
        }
    }

    /// The order to draw `views` in: a view into a render target before every
    /// view whose entities show that target, the given order otherwise
    /// ([`draw_order`](crate::scene::draw_order): linear in views and entities).
    /// A view leaves out the entities whose materials show its own target.
    fn view_order(&self, views: &[(ViewKey, &View)]) -> Result<Vec<usize>, RenderError> {
        let targets = &self.registry.render_targets;
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
        for s in &self.submitted {
            shows.entry(s.material).or_insert_with(|| {
                let maps = self.registry.material(s.material).map(|m| m.maps()).unwrap_or_default();
                maps.iter().flatten().filter_map(|t| target_of.get(t).copied()).collect()
            });
        }
        let shown: Vec<Vec<usize>> = (views.iter())
            .map(|(_, view)| {
                let shown = self.shown(self.registry.render_target_of(view).map(|t| t.1));
                let drawn = self.submitted.iter().filter(|s| shown.contains(s));
                let mut all: Vec<usize> = drawn.flat_map(|s| shows[&s.material].iter().copied()).collect();
                all.sort_unstable();
                all.dedup();
                all
            })
            .collect();
        crate::scene::draw_order(&outputs, &shown, targets.len()).map_err(|_| RenderError::RenderTargetCycle)
    }

    /// Clear `target` to black when the first view drawn into it does not cover it.
    fn clear_uncovered(
        &self,
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

    /// Every debug group the last submitted frame opened, in order, each as its
    /// path: "frame 3", "frame 3 › view 1", "frame 3 › view 1 › shadows", …
    /// (the outline a capture tool shows, where the driver takes debug groups:
    /// [`Gpu::debug_groups`](crate::Gpu::debug_groups)).
    pub fn frame_outline(&self) -> &[String] {
        self.outline.last()
    }

    /// Fill in the instance counts of the last frame's views (`stats`, in the
    /// order given) that were culled on the GPU, waiting for the GPU to count
    /// them: for a frame on its own, such as `glint render --stats` draws (in
    /// a running frame loop the counts come a frame or two late, without waiting).
    pub fn wait_for_counts(&mut self, stats: &mut [FrameStats]) {
        let submits = self.queue.submits();
        for (k, stats) in stats.iter_mut().enumerate().filter(|(_, s)| s.culling == crate::scene::Culling::Gpu) {
            let view = self.last_keys.get(k).and_then(|key| self.views.get_mut(key));
            let Some(gpu) = view.and_then(|(v, _)| v.forward.gpu.as_mut()) else { continue };
            if let Some(drawn) = gpu.wait_drawn(&self.device, submits) {
                let drawn: u64 = drawn.iter().map(|&n| u64::from(n)).sum();
                let valid = stats.instances_submitted - stats.instances_invalid;
                (stats.instances_drawn, stats.instances_culled) = (drawn, valid.saturating_sub(drawn));
            }
        }
    }
}
