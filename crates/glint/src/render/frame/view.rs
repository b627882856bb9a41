//! Core layer: one view of the frame ([`Renderer::draw_view`]): the target
//! it is drawn into, then its stages, one a line ([`Renderer::view_stages`]):
//! prepare → shadow views → cull → queue → sort → batch → upload → encode,
//! and compose.

use crate::gpu::{OffscreenTarget, TargetFormat, HDR_FORMAT};
use crate::render::frame::shadow_pass::ViewShadows;
use crate::render::frame::{Frame, ViewKey};
use crate::render::frame_variant::FrameVariant;
use crate::render::passes::post::ChainImages;
use crate::render::view::ViewFrame;
use crate::render::views::ViewGpu;
use crate::render::{ms_since, queue, FrameMode, FrameStats, Laps, RenderError, Renderer};
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
}

impl Renderer {
    /// A view of the frame (in its debug group "view k" where `group` is its
    /// place `k` in a frame of several views), with the GPU state
    /// kept under `key` (made on its first frame): drawn into `output`, or
    /// into its render target, leaving out the entities that show that target.
    pub(crate) fn draw_view(
        &mut self,
        frame: &mut Frame,
        (group, (key, view)): (Option<usize>, (ViewKey, &View)),
        (lighting, shadows): (&Lighting, &ViewShadows),
        output: &OffscreenTarget,
    ) -> Result<FrameStats, RenderError> {
        let start = Instant::now();
        let mut gpu = match self.views.remove(&key) {
            Some((gpu, _)) => gpu,
            None => ViewGpu::new(&self.shared(), self.paths),
        };
        gpu.refresh(&self.shared());
        if let Some(k) = group {
            self.outline.enter(&mut frame.encoder, &format!("view {k}"));
        }
        if let Some(timer) = &mut self.gpu_timer {
            timer.begin_view(group.unwrap_or(0));
        }
        let drawn = match view.output {
            None => self.draw_into(frame, &mut gpu, (view, None), (lighting, shadows), output),
            Some(id) => {
                // The render targets are out of the registry while one is drawn into.
                let targets = std::mem::take(&mut self.registry.render_targets);
                let (own, texture) = &targets[id.0 as usize];
                let drawn = self.draw_into(frame, &mut gpu, (view, Some(*texture)), (lighting, shadows), own);
                self.registry.render_targets = targets;
                drawn
            }
        };
        if group.is_some() {
            self.outline.leave(&mut frame.encoder);
        }
        self.views.insert(key, (gpu, frame.index));
        let mut stats = drawn?;
        stats.cpu_ms.total = ms_since(start);
        Ok(stats)
    }

    /// `view` drawn into `target` itself when it covers it and has no post
    /// chain; else into a view target of the viewport's size (HDR for a post
    /// chain, whose last pass writes the rectangle), copied into the
    /// rectangle. `hides`: the view's own render target.
    fn draw_into(
        &mut self,
        frame: &mut Frame,
        gpu: &mut ViewGpu,
        (view, hides): (&View, Option<TextureId>),
        (lighting, shadows): (&Lighting, &ViewShadows),
        target: &OffscreenTarget,
    ) -> Result<FrameStats, RenderError> {
        let [x, y, width, height] = view.viewport.pixels(target.width(), target.height());
        let occluded = self.occludes(view.ambient_occlusion);
        let variant = FrameVariant::after(shadows.first, shadows.views.len(), lighting.lights, occluded);
        let view_frame = ViewFrame::new(view, (width, height), (self.cull_pipelines.is_some(), hides, variant));
        let format = self.scene_format(view, target);
        if (width, height, format) == (target.width(), target.height(), target.format()) {
            return self.view_stages(frame, gpu, &view_frame, (lighting, shadows), (target, Compose::Direct));
        }
        let read_depth = self.cull_pipelines.as_ref().is_some_and(|p| p.occlusion());
        let own = self.targets.take_view(&self.device, (width, height), (format, read_depth), frame.index);
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
        let drawn = self.view_stages(frame, gpu, &view_frame, (lighting, shadows), (&own, compose));
        self.targets.put_back(own, frame.index);
        drawn
    }

    /// The target a view's scene is drawn into: HDR (with the output's samples
    /// where the adapter can) for a post chain, else the output's own format.
    fn scene_format(&self, view: &View, target: &OffscreenTarget) -> TargetFormat {
        match view.post.is_empty() {
            true => target.format(),
            false => TargetFormat { color: HDR_FORMAT, samples: if self.hdr_msaa { target.samples() } else { 1 } },
        }
    }

    /// One view's stages into `target`, one a line, each stage's CPU time the
    /// lap that ends on its line:
    /// 1. prepare — GPU twins for new shapes, textures, materials and
    ///    pipelines, edited materials rewritten (once per frame for each target
    ///    format and variant its views draw with)
    /// 2. shadow views — this view's cascades, and (the frame's first view)
    ///    the spot and point lights' views: culled, batched and drawn from every
    ///    submitted caster (`render/shadow_pass.rs`)
    /// 3. cull — each entity's world box, then its instances', against the
    ///    view's frustum; culled on the GPU ([`Culling::Gpu`]), every valid
    ///    instance of each entity not blended becomes a candidate the GPU tests
    ///    (`render/gpu_cull.rs`)
    /// 4. queue — one draw item with a 64-bit sort key per visible run (per instance when blended)
    /// 5. sort — radix sort by key
    /// 6. batch — equal (stage, pipeline, material, shape) runs merged into
    ///    instanced draws, one indirect command each
    /// 7. upload — with ambient occlusion, its pre-pass pipelines, textures and
    ///    parameters (`render/ambient_occlusion.rs`); Scene and Camera blocks
    ///    if changed, changed instances, draw indices and indirect commands if changed
    /// 8. encode — culled on the GPU, the cull pass first; with ambient
    ///    occlusion, its depth pre-pass (the view's depth, which the forward
    ///    pass then tests for equality), occlusion and blur passes; one pass:
    ///    opaque → alpha-test → sky → transparent (or as `render_order` says)
    ///    → particle layers → glare; batches sharing pipeline, texture set and
    ///    mesh page go in one multi-draw-indirect call. Occlusion culling
    ///    splits the pass (or the depth pre-pass) around its depth pyramid and
    ///    late cull (`render/occlusion.rs`)
    /// 9. compose — a view drawn into a target of its own reaches its
    ///    rectangle: copied, or through its post chain (`render/post.rs`)
    fn view_stages(
        &mut self,
        frame: &mut Frame,
        gpu: &mut ViewGpu,
        view: &ViewFrame,
        (lighting, shadows): (&Lighting, &ViewShadows),
        (target, compose): (&OffscreenTarget, Compose),
    ) -> Result<FrameStats, RenderError> {
        let mut stats = self.view_counts(view);
        let mut lap = Laps::start();
        let prepared = self.prepare(frame, target.format(), view.variant, &lighting.environment, &mut stats)?;
        self.prepare_particles(target.format(), &mut stats)?;
        stats.cpu_ms.prepare = lap.next();
        self.draw_shadows(frame, gpu, (view.culling, shadows), (&prepared, &lighting.environment), &mut stats)?;
        lap.next();
        let forward = if self.mode == FrameMode::Naive { "forward (naive)" } else { "forward" };
        self.outline.enter(&mut frame.encoder, forward);
        let encoder = &mut frame.encoder;
        match self.mode {
            FrameMode::Naive => {
                stats.culling = Culling::Off;
                let shadowed = (lighting, shadows.shadowed());
                self.naive_frame(gpu, view, shadowed, (target, &prepared), (encoder, &mut stats), &mut lap)?;
            }
            FrameMode::Optimized => {
                let mut visible = std::mem::take(&mut self.visible);
                self.cull(view, &mut visible, &mut stats);
                stats.cpu_ms.cull = lap.next();
                gpu.forward.clear();
                self.build_queue(gpu, view, &visible, &prepared);
                stats.cpu_ms.queue = lap.next();
                queue::sort(&mut gpu.forward.items);
                stats.cpu_ms.sort = lap.next();
                let placed = |item: &queue::DrawItem| visible.placed[item.entry as usize];
                let draw_of = |item: &queue::DrawItem| prepared[item.entry as usize].draw;
                gpu.forward.build(0, &visible.instances, view.frustum, draw_of, placed);
                stats.cpu_ms.batch = lap.next();
                self.visible = visible;
                self.prepare_ambient_occlusion(gpu, view, target, &mut stats)?;
                self.upload(gpu, view, (lighting, shadows.shadowed()), target, &mut stats)?;
                stats.cpu_ms.upload = lap.next();
                self.encode(gpu, view, (encoder, target), &lighting.environment, &mut stats);
                stats.cpu_ms.encode = lap.next();
            }
        }
        self.outline.leave(&mut frame.encoder);
        self.compose(frame, gpu, compose, &mut stats)?;
        stats.bytes_uploaded.finish();
        Ok(stats)
    }

    /// A view's counts before it is drawn: the entities it may draw (not those
    /// showing its own target), their instances and instance records.
    fn view_counts(&self, view: &ViewFrame) -> FrameStats {
        let (mut entities, mut instances, mut records) = (0, 0, 0);
        let shown = self.shown(view.hides);
        for s in self.submitted.iter().filter(|s| shown.contains(s)) {
            let slot = self.store.slot(s.slot);
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
    fn compose(
        &mut self,
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
                wgpu::TexelCopyTextureInfo {
                    origin: wgpu::Origin3d { x, y, z: 0 },
                    ..to.color_texture().as_image_copy()
                },
                wgpu::Extent3d { width: from.width(), height: from.height(), depth_or_array_layers: 1 },
            ),
            Compose::Post { chain, images } => {
                let t = Instant::now();
                self.outline.enter(encoder, "post");
                let (device, queue, timer) = (&self.device, &self.queue, self.gpu_timer.as_mut());
                let (params, pool) = (&mut gpu.post_params, &mut self.targets);
                let at = (frame.index, timer, &self.outline);
                stats.passes.post = self.post.encode((device, queue), (params, pool), encoder, chain, images, at)?;
                stats.draws += stats.passes.post.draws;
                stats.draw_calls += stats.passes.post.draw_calls;
                self.outline.leave(encoder);
                stats.passes.post.cpu_ms = ms_since(t);
            }
        }
        Ok(())
    }
}
