//! Core layer: the frame. [`Renderer::render_views`] draws each view in turn;
//! [`Renderer::flush`] is one view's frame, whose stages [`Renderer::run_frame`]
//! calls in order (prepare → cull → queue → sort → batch → upload → encode →
//! compose → submit) after [`Renderer::shadow_pass`] has drawn that view's
//! shadow maps. A frame is one command encoder and one submission. Debug groups
//! nest like the outline (`outline.rs`: frame › view k › shadows, forward,
//! post), around passes labelled "light n cascade c", "cull instances",
//! "depth pre-pass", "ambient occlusion", "forward pass: early", "depth
//! pyramid", "post: …".

use super::post::ChainImages;
use super::shadow_pass::{Shadows, ShadowsDrawn};
use super::view::ViewFrame;
use super::{ms_since, queue, FrameMode, FrameStats, FrameVariant, Laps, RenderError, Renderer};
use crate::gpu::{OffscreenTarget, TargetFormat, HDR_FORMAT};
use crate::scene::{Culling, Entity, Lighting, MaterialId, PostEffect, TextureId, View, MAX_LIGHTS, MAX_POST_EFFECTS};
use std::collections::HashMap;
use web_time::Instant;

/// How a view's picture reaches the output (stage 8 of [`Renderer::run_frame`]).
enum Compose<'a> {
    /// It was drawn into the output itself.
    Direct,
    /// Copied from its own target into the output at `origin`.
    Copy { from: &'a OffscreenTarget, to: &'a OffscreenTarget, origin: [u32; 2] },
    /// Its post chain, from its HDR target into its rectangle of the output.
    Post { chain: &'a [PostEffect], images: &'a ChainImages<'a> },
}

impl Renderer {
    /// One whole frame of `entities` seen by `view` (or a camera), the seed's
    /// calls in order: [`submit`](Self::submit) each,
    /// [`shadow_pass`](Self::shadow_pass), then [`flush`](Self::flush). The
    /// statistics include the shadow pass's; the shadow pass's error comes first.
    pub fn render<'e, 'l>(
        &mut self,
        entities: impl IntoIterator<Item = &'e Entity>,
        view: impl Into<View>,
        lighting: impl Into<Lighting<'l>>,
        target: &mut OffscreenTarget,
    ) -> Result<FrameStats, RenderError> {
        self.last_frame_had_views = false;
        let frame = self.record_render(entities, view, lighting, target);
        self.submit_frame(frame)
    }

    /// [`render`](Self::render) without its submission: the view's commands
    /// wait in the frame's encoder for its one submission.
    fn record_render<'e, 'l>(
        &mut self,
        entities: impl IntoIterator<Item = &'e Entity>,
        view: impl Into<View>,
        lighting: impl Into<Lighting<'l>>,
        target: &mut OffscreenTarget,
    ) -> Result<FrameStats, RenderError> {
        let (view, lighting) = (view.into(), lighting.into());
        for entity in entities {
            self.submit(entity);
        }
        // Flush even after a failed shadow pass, so the submitted entities are dropped.
        let shadows = self.shadow_pass(&view, lighting, target);
        let frame = self.record_flush(view, lighting, shadows.as_ref().unwrap_or(&Shadows::none()), target);
        shadows.and(frame)
    }

    /// Submit the frame's commands (new textures' mip levels first: the shadow
    /// passes may sample them) in one submission and count it in `frame`'s
    /// statistics; a failed frame's commands are dropped.
    fn submit_frame(&mut self, frame: Result<FrameStats, RenderError>) -> Result<FrameStats, RenderError> {
        let mut stats = match frame {
            Ok(stats) => stats,
            Err(e) => {
                self.drop_frame();
                return Err(e);
            }
        };
        let t = Instant::now();
        let commands = self.encoder.take().map(|mut encoder| {
            self.outline.finish(&mut encoder);
            encoder.finish()
        });
        self.queue.submit(std::mem::take(&mut self.registry.mip_blits).into_iter().chain(commands));
        if let Some(timer) = &mut self.gpu_timer {
            timer.submitted();
        }
        stats.cpu_ms.submit = ms_since(t);
        stats.cpu_ms.total += stats.cpu_ms.submit;
        stats.submits = (self.queue.submits() - self.submits_counted) as u32;
        self.submits_counted = self.queue.submits();
        self.check_device()?;
        Ok(stats)
    }

    /// One frame of several `views` of `entities` into `target`, each culled,
    /// shadowed and drawn on its own ([`render`](Self::render) per view), all
    /// in one submission (counted in the first view drawn's
    /// [`FrameStats::submits`]); a later view draws over an earlier one where
    /// their viewports overlap.
    ///
    /// A view with an [`output`](View::output) draws into that render target,
    /// before every view that draws a material showing it (the views are taken
    /// in their order otherwise), and without the entities whose materials show
    /// its own target. Views that need each other's targets are an error.
    /// When the first view into `target` does not cover it, it is cleared to
    /// black first. Returns each view's statistics, in the order given.
    pub fn render_views<'e, 'l, E>(
        &mut self,
        entities: E,
        views: &[View],
        lighting: impl Into<Lighting<'l>>,
        target: &mut OffscreenTarget,
    ) -> Result<Vec<FrameStats>, RenderError>
    where
        E: IntoIterator<Item = &'e Entity> + Clone,
    {
        let lighting = lighting.into();
        self.last_frame_had_views = true;
        let drawn: Vec<Vec<&Entity>> = (views.iter())
            .map(|v| {
                let own = v.output.and_then(|id| self.registry.render_targets.get(id.0 as usize)).map(|t| t.1);
                entities
                    .clone()
                    .into_iter()
                    .filter(|e| own.is_none_or(|t| !self.registry.shows(e.material, t)))
                    .collect()
            })
            .collect();
        let order = self.view_order(views, &drawn)?;
        let into_target = order.iter().map(|&k| &views[k]).find(|v| v.output.is_none());
        if into_target.is_some_and(|v| {
            v.viewport.pixels(target.width(), target.height())[2..] != [target.width(), target.height()]
        }) {
            self.clear(target);
        }
        let mut stats = vec![FrameStats::default(); views.len()];
        for &k in &order {
            let (view, entities) = (&views[k], drawn[k].iter().copied());
            let frame = self.in_view_state(k, |r| match view.output {
                None => r.record_render(entities, view, lighting, target),
                Some(id) => {
                    let index = id.0 as usize;
                    let (mut own, texture) = r.registry.render_targets.swap_remove(index);
                    let result = r.record_render(entities, view, lighting, &mut own);
                    r.registry.render_targets.push((own, texture));
                    let last = r.registry.render_targets.len() - 1;
                    r.registry.render_targets.swap(index, last);
                    result
                }
            });
            match frame {
                Ok(frame) => stats[k] = frame,
                Err(e) => {
                    // The earlier views' commands go with the failed frame.
                    self.drop_frame();
                    return Err(e);
                }
            }
        }
        let first = order.first().copied().unwrap_or(0);
        let Some(slot) = stats.get_mut(first) else { return Ok(stats) };
        *slot = self.submit_frame(Ok(std::mem::take(slot)))?;
        Ok(stats)
    }

    /// Fill in the instance counts of the last frame's views (`stats`, its
    /// statistics: [`render_views`](Self::render_views)' list, or the one of
    /// [`render`](Self::render) or [`flush`](Self::flush)) that were culled on
    /// the GPU, waiting for the GPU to count them: for a frame on its own, such
    /// as `glint render --stats` draws (in a running frame loop the counts come
    /// a frame or two late, without waiting).
    pub fn wait_for_counts(&mut self, stats: &mut [FrameStats]) {
        let submits = self.queue.submits();
        for (k, stats) in stats.iter_mut().enumerate().filter(|(_, s)| s.culling == Culling::Gpu) {
            let view = match self.last_frame_had_views {
                true => self.kept_views.get_mut(k).and_then(Option::as_mut),
                false => Some(&mut self.view).filter(|_| k == 0),
            };
            let Some(gpu) = view.and_then(|v| v.forward.gpu.as_mut()) else { continue };
            if let Some(drawn) = gpu.wait_drawn(&self.device, submits) {
                let drawn: u64 = drawn.iter().map(|&n| u64::from(n)).sum();
                let valid = stats.instances_submitted - stats.instances_invalid;
                (stats.instances_drawn, stats.instances_culled) = (drawn, valid.saturating_sub(drawn));
            }
        }
    }

    /// Run `draw` with view `slot`'s GPU state (made on first use, pointed at
    /// the current instance buffer) in place of the single view's, then keep it
    /// for the next frame.
    fn in_view_state<T>(&mut self, slot: usize, draw: impl FnOnce(&mut Self) -> T) -> T {
        if self.kept_views.len() <= slot {
            self.kept_views.resize_with(slot + 1, || None);
        }
        let kept = self.kept_views[slot].take().unwrap_or_else(|| self.view.sibling(&self.shared()));
        let single = std::mem::replace(&mut self.view, kept);
        self.refresh_view();
        self.enter_group(&format!("view {slot}"));
        let result = draw(self);
        self.leave_group();
        self.kept_views[slot] = Some(std::mem::replace(&mut self.view, single));
        self.refresh_view();
        result
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
    /// view whose entities (`drawn`) show that target, the given order otherwise
    /// ([`draw_order`](crate::scene::draw_order): linear in views and entities).
    fn view_order(&self, views: &[View], drawn: &[Vec<&Entity>]) -> Result<Vec<usize>, RenderError> {
        let targets = &self.registry.render_targets;
        let outputs = (views.iter())
            .map(|v| match v.output {
                None => Ok(None),
                Some(id) => {
                    targets.get(id.0 as usize).map(|_| Some(id.0 as usize)).ok_or(RenderError::UnknownRenderTarget(id))
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        let target_of: HashMap<TextureId, usize> = targets.iter().enumerate().map(|(k, t)| (t.1, k)).collect();
        // The targets each material drawn shows, found once per material.
        let mut shows: HashMap<MaterialId, Vec<usize>> = HashMap::new();
        let shown: Vec<Vec<usize>> = (drawn.iter())
            .map(|entities| {
                let mut all: Vec<usize> = Vec::new();
                for e in entities {
                    let of = shows.entry(e.material).or_insert_with(|| {
                        let maps = self.registry.material(e.material).map(|m| m.maps()).unwrap_or_default();
                        maps.iter().flatten().filter_map(|t| target_of.get(t).copied()).collect()
                    });
                    all.extend_from_slice(of);
                }
                all.sort_unstable();
                all.dedup();
                all
            })
            .collect();
        crate::scene::draw_order(&outputs, &shown, targets.len()).map_err(|_| RenderError::RenderTargetCycle)
    }

    /// Clear `target` to black, in the frame's encoder.
    fn clear(&mut self, target: &OffscreenTarget) {
        let mut encoder = self.take_encoder();
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("clear the target"),
            color_attachments: &[Some(target.color_attachment(wgpu::Color::BLACK))],
            ..Default::default()
        });
        self.encoder = Some(encoder);
    }

    /// The frame's command encoder, begun (with its "frame N" debug group)
    /// when this is the frame's first command; put it back in `self.encoder`.
    pub(super) fn take_encoder(&mut self) -> wgpu::CommandEncoder {
        self.encoder.take().unwrap_or_else(|| {
            let label = Some("renderer: frame");
            let mut encoder = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label });
            self.outline.enter(&mut encoder, &format!("frame {}", self.frame_index));
            encoder
        })
    }

    /// Open the debug group `name` in the frame's encoder.
    pub(super) fn enter_group(&mut self, name: &str) {
        let mut encoder = self.take_encoder();
        self.outline.enter(&mut encoder, name);
        self.encoder = Some(encoder);
    }

    /// Close the innermost debug group, unless the frame was dropped.
    pub(super) fn leave_group(&mut self) {
        if let Some(encoder) = &mut self.encoder {
            self.outline.leave(encoder);
        }
    }

    /// Drop the frame's commands (a stage failed) and its debug groups.
    fn drop_frame(&mut self) {
        self.encoder = None;
        self.outline.drop_frame();
    }

    /// Every debug group the last submitted frame opened, in order, each as its
    /// path: "frame 3", "frame 3 › view 1", "frame 3 › view 1 › shadows", …
    /// (the outline a capture tool shows, where the driver takes debug groups:
    /// [`Gpu::debug_groups`](crate::Gpu::debug_groups)).
    pub fn frame_outline(&self) -> &[String] {
        self.outline.last()
    }

    /// Draw everything submitted since the last flush, seen by `view` (or a
    /// camera, for the whole target), under `lighting` (or a list of lights), into its viewport of
    /// `target`, and return what the frame cost. `shadows` are the maps this
    /// frame's [`shadow_pass`](Self::shadow_pass) drew for the same view and
    /// lights ([`Shadows::none`] draws without shadows).
    ///
    /// The frame of one view, one stage per line (`Renderer::draw_view`):
    /// 0. simulate — before any view, GPU simulations' compute passes
    ///    ([`simulate`](Self::simulate): particles stepping and sorting into their layers)
    /// 1. prepare — GPU twins for new shapes, textures, materials and pipelines; edited materials rewritten
    /// 2. cull — each entity's world box, then its instances', against the view's frustum;
    ///    culled on the GPU ([`Culling::Gpu`]), every valid instance of each entity not blended
    ///    becomes a candidate the GPU tests (`render/gpu_cull.rs`)
    /// 3. queue — one draw item with a 64-bit sort key per visible run (per instance when blended)
    /// 4. sort — radix sort by key
    /// 5. batch — equal (stage, pipeline, material, shape) runs merged into instanced draws, one indirect command each
    /// 6. upload — with ambient occlusion, its pre-pass pipelines, textures and parameters
    ///    (`render/ambient_occlusion.rs`); Scene and Camera blocks if changed, changed instances,
    ///    draw indices and indirect commands if changed
    /// 7. encode — culled on the GPU, the cull pass first; with ambient occlusion, its depth
    ///    pre-pass, occlusion and blur passes; one pass: opaque → alpha-test → sky →
    ///    transparent (or as `render_order` says) → particle layers → glare; batches sharing pipeline, texture set and
    ///    mesh page go in one multi-draw-indirect call. Occlusion culling splits the pass
    ///    around its depth pyramid and late cull (`render/occlusion.rs`)
    /// 8. compose — a view drawn into a target of its own (a view of part of the
    ///    target, or one with a post chain: HDR) reaches its rectangle: copied, or
    ///    through its post chain's full-screen passes (`render/post.rs`)
    /// 9. submit — the frame's one command encoder in one submission (with `render_views`, every view's)
    ///
    /// Errors (the submitted entities are dropped): more than [`MAX_LIGHTS`]
    /// lights, an id that is not this renderer's, a viewport outside the
    /// target, or shadow maps drawn for another frame, view or lights.
    pub fn flush<'l>(
        &mut self,
        view: impl Into<View>,
        lighting: impl Into<Lighting<'l>>,
        shadows: &Shadows,
        target: &mut OffscreenTarget,
    ) -> Result<FrameStats, RenderError> {
        self.last_frame_had_views = false;
        let frame = self.record_flush(view, lighting, shadows, target);
        self.submit_frame(frame)
    }

    /// [`flush`](Self::flush) without its submission: the view's commands wait
    /// in the frame's encoder for its one submission.
    fn record_flush<'l>(
        &mut self,
        view: impl Into<View>,
        lighting: impl Into<Lighting<'l>>,
        shadows: &Shadows,
        target: &mut OffscreenTarget,
    ) -> Result<FrameStats, RenderError> {
        let start = Instant::now();
        let (view, lighting) = (view.into(), lighting.into());
        let gpu = self.gpu_timer.as_mut().and_then(|t| t.collect(&self.device));
        let frame = self.frame_index;
        let result = match self.submit_error.take() {
            Some(e) => Err(e),
            None => self.draw_view(&view, &lighting, shadows, target),
        };
        self.submitted.clear();
        self.instances_submitted = 0;
        self.frame_index += 1;
        result.map(|mut stats| {
            (stats.frame, stats.gpu) = (frame, gpu);
            stats.cpu_ms.total = ms_since(start);
            if let Some(shadow) = &shadows.drawn {
                stats.shadow_views = shadow.views;
                stats.passes.shadow = shadow.cost;
                stats.pipelines_compiled += shadow.prepared.pipelines_compiled;
                stats.bytes_uploaded.add(&shadow.prepared.bytes_uploaded);
            }
            stats
        })
    }

    /// [`flush`](Self::flush)'s frame: into `target` itself when `view` covers
    /// it and has no post chain; else into a view target of the viewport's size
    /// (HDR for a post chain, whose last pass writes the rectangle), or copied
    /// into the rectangle.
    fn draw_view(
        &mut self,
        view: &View,
        lighting: &Lighting,
        shadows: &Shadows,
        target: &OffscreenTarget,
    ) -> Result<FrameStats, RenderError> {
        if !view.viewport.is_valid() {
            return Err(RenderError::BadViewport(view.viewport));
        }
        if view.post.len() > MAX_POST_EFFECTS {
            return Err(RenderError::PostChainTooLong(view.post.len()));
        }
        let drawn = match &shadows.drawn {
            Some(drawn) => drawn.first_views(self.frame_index, view, lighting.lights).map(|_| Some(drawn))?,
            None => None,
        };
        let [x, y, width, height] = view.viewport.pixels(target.width(), target.height());
        let frame = ViewFrame::new(view, width, height, self.cull_pipelines.is_some());
        let format = self.scene_format(view, target);
        if (width, height, format) == (target.width(), target.height(), target.format()) {
            return self.run_frame(&frame, lighting, drawn, target, Compose::Direct);
        }
        let read_depth = self.cull_pipelines.as_ref().is_some_and(|p| p.occlusion());
        let own = self.targets.take_view(&self.device, (width, height), (format, read_depth), self.frame_index);
        let images = ChainImages {
            scene: own.color_view(),
            size: (width, height),
            output: target.color_view(),
            output_format: target.format().color,
            rect: [x, y, width, height],
        };
        let compose = match view.post.is_empty() {
            true => Compose::Copy { from: &own, to: target, origin: [x, y] },
            false => Compose::Post { chain: &view.post, images: &images },
        };
        let result = self.run_frame(&frame, lighting, drawn, &own, compose);
        self.targets.put_back(own, self.frame_index);
        result
    }

    /// Stage 8 of a view not drawn straight into the output: its picture copied,
    /// or its post chain run, into its rectangle of the output.
    fn compose(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        compose: Compose,
        stats: &mut FrameStats,
    ) -> Result<(), RenderError> {
        match compose {
            Compose::Direct => {}
            Compose::Copy { from, to, origin: [x, y] } => encoder.copy_texture_to_texture(
                from.color_texture().as_image_copy(),
                wgpu::TexelCopyTextureInfo {
                    origin: wgpu::Origin3d { x, y, z: 0 },
                    ..to.color_texture().as_image_copy()
                },
                wgpu::Extent3d { width: from.width(), height: from.height(), depth_or_array_layers: 1 },
            ),
            Compose::Post { chain, images } => {
                let t = Instant::now();
                self.outline.enter(encoder, "post");
                let (device, queue, index, timer) =
                    (&self.device, &self.queue, self.frame_index, self.gpu_timer.as_mut());
                let (params, pool) = (&mut self.view.post_params, &mut self.targets);
                let frame = (index, timer, &self.outline);
                stats.passes.post = self.post.encode((device, queue), (params, pool), encoder, chain, images, frame)?;
                stats.draws += stats.passes.post.draws;
                stats.draw_calls += stats.passes.post.draw_calls;
                self.outline.leave(encoder);
                stats.passes.post.cpu_ms = ms_since(t);
            }
        }
        Ok(())
    }

    /// The target a view's scene is drawn into: HDR (with the output's samples
    /// where the adapter can) for a post chain, else the output's own format.
    pub(super) fn scene_format(&self, view: &View, target: &OffscreenTarget) -> TargetFormat {
        match view.post.is_empty() {
            true => target.format(),
            false => TargetFormat { color: HDR_FORMAT, samples: if self.hdr_msaa { target.samples() } else { 1 } },
        }
    }

    /// One view's frame into `target`, stage by stage (the list at [`flush`](Self::flush)).
    fn run_frame(
        &mut self,
        frame: &ViewFrame,
        lighting: &Lighting,
        drawn: Option<&ShadowsDrawn>,
        target: &OffscreenTarget,
        compose: Compose,
    ) -> Result<FrameStats, RenderError> {
        if lighting.lights.len() > MAX_LIGHTS {
            return Err(RenderError::TooManyLights(lighting.lights.len()));
        }
        let records: usize = self.submitted.iter().map(|s| self.store.slot(s.slot).len()).sum();
        let mut stats = FrameStats {
            entities_submitted: self.submitted.len() as u32,
            instances_submitted: self.instances_submitted,
            instance_bytes: (records * std::mem::size_of::<super::blocks::InstanceGpu>()) as u64,
            ..Default::default()
        };
        // Each stage's CPU time is the lap that ends on its line.
        let mut lap = Laps::start();
        let occluded = self.occludes(frame.ambient_occlusion);
        self.frame_variant = FrameVariant::after(drawn, lighting.lights, occluded);
        stats.environment_prefiltered = self.prepare_environment(lighting)?;
        let prepared = self.prepare(target.format(), &lighting.environment, &mut stats)?;
        self.prepare_particles(target.format(), &mut stats)?;
        stats.cpu_ms.prepare = lap.next();
        let shadowed = drawn.map_or(&[][..], |d| d.first_view.as_slice());
        // The frame's encoder, given back once this view's commands are in it
        // (a failed view drops it, and the frame).
        let mut encoder = self.take_encoder();
        let forward = if self.mode == FrameMode::Naive { "forward (naive)" } else { "forward" };
        self.outline.enter(&mut encoder, forward);
        match self.mode {
            FrameMode::Naive => {
                stats.culling = Culling::Off;
                self.naive_frame(
                    frame,
                    (lighting, shadowed),
                    (target, &prepared),
                    (&mut encoder, &mut stats),
                    &mut lap,
                )?;
            }
            FrameMode::Optimized => {
                let mut visible = std::mem::take(&mut self.visible);
                self.cull(frame, &mut visible, &mut stats);
                stats.cpu_ms.cull = lap.next();
                self.view.forward.clear();
                self.build_queue(frame, &visible, &prepared);
                stats.cpu_ms.queue = lap.next();
                queue::sort(&mut self.view.forward.items);
                stats.cpu_ms.sort = lap.next();
                let placed = |item: &queue::DrawItem| visible.placed[item.entry as usize];
                let draw_of = |item: &queue::DrawItem| prepared[item.entry as usize].draw;
                self.view.forward.build(0, &visible.instances, frame.frustum, draw_of, placed);
                stats.cpu_ms.batch = lap.next();
                self.visible = visible;
                self.prepare_ambient_occlusion(frame, (target.width(), target.height()), &mut stats)?;
                self.upload(frame, (lighting, shadowed), target, &mut stats)?;
                stats.cpu_ms.upload = lap.next();
                self.encode(&mut encoder, target, &lighting.environment, &mut stats);
                stats.cpu_ms.encode = lap.next();
            }
        }
        self.outline.leave(&mut encoder);
        self.compose(&mut encoder, compose, &mut stats)?;
        self.encoder = Some(encoder);
        stats.bytes_uploaded.finish();
        Ok(stats)
    }
}
