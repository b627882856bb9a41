//! Core layer: the seed's calls, a thin layer over [`Renderer::render_frame`].
//! Tiny Graphics' program submits each entity, draws the shadow maps, then
//! flushes: [`Renderer::submit`] queues an entity for the next frame,
//! [`Renderer::shadow_pass`] asks for the lights' shadows (and checks them),
//! and [`Renderer::flush`] is the frame of one view. [`Renderer::render`] is
//! those calls in order, [`Renderer::render_views`] the frame of several views.

use crate::gpu::OffscreenTarget;
use crate::render::frame::input::{FrameInput, ViewKey};
use crate::render::{FrameStats, RenderError, Renderer};
use crate::scene::{Entity, Light, Lighting, View};

/// The shadows a frame's [`shadow_pass`](Renderer::shadow_pass) asked for:
/// what the [`flush`](Renderer::flush) of the same frame, view and lights draws
/// with. [`Shadows::none`] draws without shadows.
#[derive(Clone, Debug, Default)]
pub struct Shadows {
    asked: Option<Asked>,
}

/// What a shadow pass was asked for.
#[derive(Clone, Debug)]
struct Asked {
    /// The renderer's frame (the maps are drawn anew every frame).
    frame_index: u64,
    /// The view (cascades follow the camera and its aspect).
    view: View,
    /// The lights.
    lights: Vec<Light>,
}

impl Shadows {
    /// No shadow maps: every light is drawn without shadows.
    pub fn none() -> Self {
        Self::default()
    }

    /// Whether a flush of `view` and `lights` in frame `frame_index` draws
    /// with these: an error when they were asked for another frame, view or lights.
    fn drawn_for(&self, frame_index: u64, view: &View, lights: &[Light]) -> Result<bool, RenderError> {
        let Some(asked) = &self.asked else { return Ok(false) };
        if asked.frame_index != frame_index {
            return Err(RenderError::StaleShadows);
        }
        // The maps follow the camera and the rectangle's shape, not the post chain.
        let same = asked.view.camera == view.camera && asked.view.viewport == view.viewport;
        if !same || asked.lights != lights {
            return Err(RenderError::ShadowsForOtherView);
        }
        Ok(true)
    }
}

impl Renderer {
    /// One whole frame of `entities` seen by `view` (or a camera), the seed's
    /// calls in order: [`submit`](Self::submit) each,
    /// [`shadow_pass`](Self::shadow_pass), then [`flush`](Self::flush).
    pub fn render<'e, 'l>(
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
        let shadows = self.shadow_pass(&view, lighting, target);
        // Flush even after a failed shadow pass, so the submitted entities are dropped.
        let frame = self.flush(view, lighting, shadows.as_ref().unwrap_or(&Shadows::none()), target);
        shadows.and(frame)
    }

    /// One frame of several `views` of `entities` into `target`
    /// ([`render_frame`](Self::render_frame), each view keyed by its place in
    /// the list), all in one submission (counted in the first view drawn's
    /// [`FrameStats::submits`]); a later view draws over an earlier one where
    /// their viewports overlap.
    ///
    /// A view with an [`output`](View::output) draws into that render target,
    /// before every view that draws a material showing it (the views are taken
    /// in their order otherwise), and without the entities whose materials show
    /// its own target. Views that need each other's targets are an error.
    /// When the first view into `target` does not cover it, it is cleared to
    /// black first. Returns each view's statistics, in the order given.
    pub fn render_views<'e, 'l>(
        &mut self,
        entities: impl IntoIterator<Item = &'e Entity>,
        views: &[View],
        lighting: impl Into<Lighting<'l>>,
        target: &mut OffscreenTarget,
    ) -> Result<Vec<FrameStats>, RenderError> {
        for entity in entities {
            self.submit(entity);
        }
        let lighting: Lighting = lighting.into();
        let input = FrameInput::new(&[], lighting).views(views);
        Ok(self.render_frame(input, target)?.views)
    }

    /// Draw the shadow maps of every light in `lighting` that casts shadows (see
    /// [`Light::with_shadows`]) in this frame's [`flush`](Self::flush), which
    /// must be of the same `view` and lights: it darkens what they cannot
    /// reach. The maps are drawn with the flush, from every entity submitted
    /// by then.
    ///
    /// Lights past the shadow maps' room (16 two-dimensional views: four per
    /// directional light, one per spot light; 4 point lights) are drawn without
    /// shadows, with a warning in the log. A bad id submitted this frame is
    /// reported by `flush`.
    pub fn shadow_pass<'l>(
        &mut self,
        view: impl Into<View>,
        lighting: impl Into<Lighting<'l>>,
        _target: &OffscreenTarget,
    ) -> Result<Shadows, RenderError> {
        let (view, lighting) = (view.into(), lighting.into());
        self.res.clusters.check(lighting.lights)?;
        let asked = Asked { frame_index: self.next.index, view, lights: lighting.lights.to_vec() };
        Ok(Shadows { asked: Some(asked) })
    }

    /// Draw everything submitted since the last frame, seen by `view` (or a
    /// camera, for the whole target), under `lighting` (or a list of lights),
    /// into its viewport of `target`, and return what the frame cost: the
    /// frame of one view ([`render_frame`](Self::render_frame), under
    /// [`ViewKey`] 0). `shadows` is this frame's
    /// [`shadow_pass`](Self::shadow_pass) for the same view and lights
    /// ([`Shadows::none`] draws without shadows).
    ///
    /// Errors (the submitted entities are dropped): more lights than
    /// [`Clusters::check`](crate::render::Clusters::check) allows, an id that is not this renderer's, a viewport
    /// outside the target, or shadows asked for another frame, view or lights.
    pub fn flush<'l>(
        &mut self,
        view: impl Into<View>,
        lighting: impl Into<Lighting<'l>>,
        shadows: &Shadows,
        target: &mut OffscreenTarget,
    ) -> Result<FrameStats, RenderError> {
        let (view, lighting) = (view.into(), lighting.into());
        let mut input = FrameInput::new(&[], lighting).view(ViewKey(0), &view);
        match shadows.drawn_for(self.next.index, &view, lighting.lights) {
            Ok(drawn) => input.shadows = drawn,
            // The frame is drawn to drop what was submitted, and the error returned.
            Err(e) => {
                self.next.submit_error.get_or_insert(e);
            }
        }
        let mut output = self.render_frame(input, target)?;
        Ok(output.views.remove(0))
    }
}
