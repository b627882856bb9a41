//! Core layer: what a frame is given ([`FrameInput`]: entities, keyed views,
//! lighting, simulations, the work after the views) and what it gives back
//! ([`FrameOutput`]), and how it is built ([`FrameMode`]).

use crate::gpu::{AfterViews, GpuSimulation};
use crate::render::debug::stats::FrameStats;
use crate::scene::{Entity, Lighting, View};

/// A view's identity, chosen by the caller: its GPU state (camera records,
/// draw lists, ambient-occlusion textures, post parameters) is kept between
/// frames under it, whatever the view's place in the list. A key not drawn
/// for [`KEEP_VIEW_FRAMES`] frames gives its state back.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ViewKey(pub u32);

/// Frames a view's GPU state is kept while its key is not drawn.
pub const KEEP_VIEW_FRAMES: u64 = 120;

/// Everything one frame draws ([`Renderer::render_frame`](crate::Renderer::render_frame)).
pub struct FrameInput<'a> {
    /// The entities drawn, after any [`submit`](crate::Renderer::submit)ted since the last frame.
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

/// What a frame cost ([`Renderer::render_frame`](crate::Renderer::render_frame)).
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

/// How a frame is built.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FrameMode {
    /// Culled, sorted, batched, uploading only what changed.
    #[default]
    Optimized,
    /// The pre-upgrade way, kept as a baseline for `glint bench`: one draw per
    /// instance in submission order, no culling and no sorting, the material block
    /// and the draw's instance index written before every draw, and every state
    /// bound again for every draw.
    Naive,
}
