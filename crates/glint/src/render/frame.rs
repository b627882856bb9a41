//! Core layer: the frame. [`Renderer::render_views`] draws each view in turn;
//! [`Renderer::flush`] is one view's frame, whose stages [`Renderer::run_frame`]
//! calls in order (prepare → cull → queue → sort → batch → upload → encode →
//! submit) after [`Renderer::shadow_pass`] has drawn that view's shadow maps.

use super::shadow_pass::{Shadows, ShadowsDrawn};
use super::view::ViewFrame;
use super::{ms_since, queue, FrameMode, FrameStats, FrameVariant, RenderError, Renderer};
use crate::gpu::OffscreenTarget;
use crate::scene::{Entity, Light, View, MAX_LIGHTS};
use std::time::Instant;

impl Renderer {
    /// One whole frame of `entities` seen by `view` (or a camera), the seed's
    /// calls in order: [`submit`](Self::submit) each,
    /// [`shadow_pass`](Self::shadow_pass), then [`flush`](Self::flush). The
    /// statistics include the shadow pass's; the shadow pass's error comes first.
    pub fn render<'e>(
        &mut self,
        entities: impl IntoIterator<Item = &'e Entity>,
        view: impl Into<View>,
        lights: &[Light],
        target: &mut OffscreenTarget,
    ) -> Result<FrameStats, RenderError> {
        let view = view.into();
        for entity in entities {
            self.submit(entity);
        }
        // Flush even after a failed shadow pass, so the submitted entities are dropped.
        let shadows = self.shadow_pass(view, lights, target);
        let frame = self.flush(view, lights, shadows.as_ref().unwrap_or(&Shadows::none()), target);
        shadows.and(frame)
    }

    /// One frame of several `views` of `entities` into `target`, in order, each
    /// culled, shadowed and drawn on its own ([`render`](Self::render) per view);
    /// a later view draws over an earlier one where their viewports overlap.
    /// When the first view does not cover the whole target, the target is
    /// cleared to black first. Returns each view's statistics.
    pub fn render_views<'e, E>(
        &mut self,
        entities: E,
        views: &[View],
        lights: &[Light],
        target: &mut OffscreenTarget,
    ) -> Result<Vec<FrameStats>, RenderError>
    where
        E: IntoIterator<Item = &'e Entity> + Clone,
    {
        if views.first().is_some_and(|v| {
            v.viewport.pixels(target.width(), target.height())[2..] != [target.width(), target.height()]
        }) {
            self.clear(target);
        }
        views.iter().map(|view| self.render(entities.clone(), *view, lights, target)).collect()
    }

    /// Clear `target` to black.
    fn clear(&self, target: &OffscreenTarget) {
        let mut encoder =
            self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("renderer: clear") });
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("clear the target"),
            color_attachments: &[Some(target.color_attachment(wgpu::Color::BLACK))],
            ..Default::default()
        });
        self.queue.submit([encoder.finish()]);
    }

    /// Draw everything submitted since the last flush, seen by `view` (or a
    /// camera, for the whole target), lit by `lights`, into its viewport of
    /// `target`, and return what the frame cost. `shadows` are the maps this
    /// frame's [`shadow_pass`](Self::shadow_pass) drew for the same view and
    /// lights ([`Shadows::none`] draws without shadows).
    ///
    /// The frame of one view, one stage per line ([`Renderer::draw_view`]):
    /// 1. prepare — GPU twins for new shapes, textures, materials and pipelines; edited materials rewritten
    /// 2. cull — each entity's world box, then its instances', against the view's frustum
    /// 3. queue — one draw item with a 64-bit sort key per visible run (per instance when blended)
    /// 4. sort — radix sort by key
    /// 5. batch — equal (stage, pipeline, material, shape) runs merged into instanced draws, one indirect command each
    /// 6. upload — Scene and Camera blocks if changed, changed instances, draw indices and indirect commands if changed
    /// 7. encode — one pass: opaque → alpha-test → sky → transparent (or as `render_order` says);
    ///    batches sharing pipeline, texture set and mesh page go in one multi-draw-indirect call
    /// 8. submit
    ///
    /// A view of part of the target is drawn into a target of its own (kept for
    /// the next frames) and copied into its rectangle.
    ///
    /// Errors (the submitted entities are dropped): more than [`MAX_LIGHTS`]
    /// lights, an id that is not this renderer's, a viewport outside the
    /// target, or shadow maps drawn for another frame, view or lights.
    pub fn flush(
        &mut self,
        view: impl Into<View>,
        lights: &[Light],
        shadows: &Shadows,
        target: &mut OffscreenTarget,
    ) -> Result<FrameStats, RenderError> {
        let start = Instant::now();
        let view = view.into();
        let result = match self.submit_error.take() {
            Some(e) => Err(e),
            None => self.draw_view(&view, lights, shadows, target),
        };
        self.submitted.clear();
        self.instances_submitted = 0;
        self.frame_index += 1;
        result.map(|mut stats| {
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
    /// it, else into a view target of the viewport's size, then copied there.
    fn draw_view(
        &mut self,
        view: &View,
        lights: &[Light],
        shadows: &Shadows,
        target: &OffscreenTarget,
    ) -> Result<FrameStats, RenderError> {
        if !view.viewport.is_valid() {
            return Err(RenderError::BadViewport(view.viewport));
        }
        let drawn = match &shadows.drawn {
            Some(drawn) => drawn.first_views(self.frame_index, view, lights).map(|_| Some(drawn))?,
            None => None,
        };
        let [x, y, width, height] = view.viewport.pixels(target.width(), target.height());
        let frame = ViewFrame::new(view, width, height);
        if (width, height) == (target.width(), target.height()) {
            return self.run_frame(&frame, lights, drawn, target);
        }
        let own = self.take_view_target(width, height, target.samples());
        let stats = self.run_frame(&frame, lights, drawn, &own);
        let mut encoder = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("renderer: view into its viewport"),
        });
        encoder.copy_texture_to_texture(
            own.color_texture().as_image_copy(),
            wgpu::TexelCopyTextureInfo {
                origin: wgpu::Origin3d { x, y, z: 0 },
                ..target.color_texture().as_image_copy()
            },
            wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        );
        self.queue.submit([encoder.finish()]);
        self.view_targets.push((own, self.frame_index));
        stats
    }

    /// A view target of this size and sample count: one kept from an earlier
    /// frame, or a new one. Targets unused for more than a frame are dropped.
    fn take_view_target(&mut self, width: u32, height: u32, samples: u32) -> OffscreenTarget {
        let now = self.frame_index;
        let fits = |t: &OffscreenTarget| (t.width(), t.height(), t.samples()) == (width, height, samples);
        if let Some(k) = self.view_targets.iter().position(|(t, _)| fits(t)) {
            return self.view_targets.swap_remove(k).0;
        }
        // A window being resized asks for a new size every frame: keep only recent ones.
        self.view_targets.retain(|(_, used)| used + 2 >= now);
        OffscreenTarget::on_device(&self.device, width, height, samples)
    }

    fn run_frame(
        &mut self,
        frame: &ViewFrame,
        lights: &[Light],
        drawn: Option<&ShadowsDrawn>,
        target: &OffscreenTarget,
    ) -> Result<FrameStats, RenderError> {
        if lights.len() > MAX_LIGHTS {
            return Err(RenderError::TooManyLights(lights.len()));
        }
        let mut stats = FrameStats {
            entities_submitted: self.submitted.len() as u32,
            instances_submitted: self.instances_submitted,
            ..Default::default()
        };
        let t = Instant::now();
        self.frame_variant = FrameVariant::after(drawn, lights);
        self.prepare(target.samples(), &mut stats)?;
        stats.cpu_ms.prepare = ms_since(t);

        let mut visible = std::mem::take(&mut self.visible);
        if self.mode == FrameMode::Naive {
            let t = Instant::now();
            self.naive_batches(&mut stats);
            stats.cpu_ms.batch = ms_since(t);
        } else {
            let t = Instant::now();
            self.cull(frame, &mut visible, &mut stats);
            stats.cpu_ms.cull = ms_since(t);

            let t = Instant::now();
            self.forward.clear();
            self.build_queue(frame, &visible);
            stats.cpu_ms.queue = ms_since(t);

            let t = Instant::now();
            queue::sort(&mut self.forward.items);
            stats.cpu_ms.sort = ms_since(t);

            let t = Instant::now();
            let shapes = &self.shapes;
            self.forward.build(0, &visible.instances, |b| shapes[b.shape.0 as usize].gpu.expect("prepared"));
            stats.cpu_ms.batch = ms_since(t);
        }
        self.visible = visible;

        let t = Instant::now();
        let shadowed = drawn.map_or(&[][..], |d| d.first_view.as_slice());
        self.upload(frame, lights, shadowed, &mut stats)?;
        stats.cpu_ms.upload = ms_since(t);

        let t = Instant::now();
        let commands = self.encode(target, &mut stats);
        stats.cpu_ms.encode = ms_since(t);

        let t = Instant::now();
        self.queue.submit([commands]);
        stats.cpu_ms.submit = ms_since(t);
        stats.bytes_uploaded.finish();
        Ok(stats)
    }
}
