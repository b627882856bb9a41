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
    /// Which sub-frame of an accumulated still this frame is
    /// ([`SubFrame::ONE`]: a frame of its own).
    pub sample: SubFrame,
}

/// Most sub-frames one accumulated still averages.
pub const MAX_SUB_FRAMES: u32 = 4096;

/// Sub-frame `index` of `count` of an accumulated still (`glint render
/// --spp`): the frame's views into the output are drawn with their cameras
/// jittered by a fraction of a pixel ([`jitter`](Self::jitter)) and their
/// ambient occlusion's noise turned, and folded into a running mean in 32-bit
/// float; only the last sub-frame writes the output, the mean through the
/// view's post chain (clamped where it has none), so the average is taken in
/// HDR before tonemapping. A still's sub-frames are consecutive frames of the
/// same scene at the same time, each view under the same key. Views into
/// render targets are drawn as in any frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SubFrame {
    /// Its place, from 0.
    pub index: u32,
    /// Sub-frames in the still, 1 to [`MAX_SUB_FRAMES`].
    pub count: u32,
}

impl SubFrame {
    /// A frame of its own: no jitter, nothing accumulated.
    pub const ONE: Self = Self { index: 0, count: 1 };

    /// Whether it is a sub-frame of a still of several.
    pub fn accumulates(self) -> bool {
        self.count > 1
    }

    /// Whether it is the still's last, which writes the output.
    pub fn is_last(self) -> bool {
        self.index.saturating_add(1) == self.count
    }

    /// Whether it can be drawn: an index below its count, and 1 to
    /// [`MAX_SUB_FRAMES`] sub-frames.
    pub fn is_valid(self) -> bool {
        self.index < self.count && self.count <= MAX_SUB_FRAMES
    }

    /// Its camera offset in pixels (x right, y down), each within ±0.5: the
    /// Halton sequence in bases 2 and 3 at `index + 1`, so that any number of
    /// sub-frames covers the pixel evenly; none for a frame of its own.
    pub fn jitter(self) -> glam::Vec2 {
        self.offset((2, 3))
    }

    /// Its offset of the soft-shadow filter's grid, in taps, each within
    /// ±0.5: the Halton sequence in bases 5 and 7 (apart from the camera's);
    /// none for a frame of its own.
    pub fn shadow_offset(self) -> glam::Vec2 {
        self.offset((5, 7))
    }

    /// The Halton sequence in `bases` at `index + 1`, less 0.5; 0 for a frame of its own.
    fn offset(self, (a, b): (u32, u32)) -> glam::Vec2 {
        if !self.accumulates() {
            return glam::Vec2::ZERO;
        }
        let halton = |mut i: u32, base: u32| {
            let (mut f, mut r) = (1.0, 0.0);
            while i > 0 {
                f /= base as f32;
                r += f * (i % base) as f32;
                i /= base;
            }
            r
        };
        let i = self.index.saturating_add(1);
        glam::Vec2::new(halton(i, a), halton(i, b)) - 0.5
    }
}

impl<'a> FrameInput<'a> {
    /// A frame of `entities` under `lighting`, with no view yet.
    pub fn new(entities: &'a [Entity], lighting: impl Into<Lighting<'a>>) -> Self {
        let (views, simulations, after) = (Vec::new(), Vec::new(), Vec::new());
        Self { entities, views, lighting: lighting.into(), shadows: true, simulations, after, sample: SubFrame::ONE }
    }

    /// Draw it as `sample` of an accumulated still.
    pub fn sample(mut self, sample: SubFrame) -> Self {
        self.sample = sample;
        self
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
