//! Core layer: the frame being recorded ([`Frame`]), handed `&mut` from stage
//! to stage and consumed by its submission, and what the renderer keeps for
//! the next frame between frames ([`NextFrame`]).

use crate::render::debug::outline::Outline;
use crate::render::debug::timer::GpuTimes;
use crate::render::error::RenderError;
use crate::render::frame::input::SubFrame;
use crate::render::frame::prepared::{PrepareKey, Prepared};
use crate::render::frame::visible::{Submitted, Visible};
use web_time::Instant;

/// What the renderer keeps for its next frame: the number it will have, the
/// entities submitted for it so far (and the first bad id among them), the
/// debug-group outline (which keeps the last frame's), and a visible set kept
/// to reuse its allocations. [`Frame::begin`] takes them; the frame's
/// submission gives them back.
pub(crate) struct NextFrame {
    pub index: u64,
    pub submitted: Vec<Submitted>,
    pub submit_error: Option<RenderError>,
    pub outline: Outline,
    pub visible: Visible,
}

impl NextFrame {
    /// Frame 0, its outline in driver debug groups where `debug_groups`.
    pub(crate) fn new(debug_groups: bool) -> Self {
        let (submitted, visible) = (Vec::new(), Visible::default());
        Self { index: 0, submitted, submit_error: None, outline: Outline::new(debug_groups), visible }
    }
}

/// The frame being recorded: handed `&mut` from stage to stage, consumed by
/// its submission ([`submit_frame`](crate::render::frame::stages::submit_frame));
/// dropped with its commands when a stage fails.
pub(crate) struct Frame {
    /// Its number.
    pub index: u64,
    /// Its one command encoder.
    pub encoder: wgpu::CommandEncoder,
    /// Its debug groups (and `glint explain`'s calls), recorded as it goes.
    pub outline: Outline,
    /// The entities it draws, in submission order.
    pub submitted: Vec<Submitted>,
    /// The first bad id submitted for it, which fails it.
    pub submit_error: Option<RenderError>,
    /// What the view (or shadow view) being drawn sees.
    pub visible: Visible,
    /// The last table the prepare stage made, and what for: the frame's
    /// views that draw into the same format with the same variant share it.
    pub prepared: Option<(PrepareKey, Vec<Prepared>)>,
    /// Prepare stages run anew.
    pub prepares: u32,
    /// Whether it prefiltered the environment.
    pub prefiltered: bool,
    /// The view drawn first, which carries the frame's own costs.
    pub first_view: Option<usize>,
    /// Mesh bytes the simulate stage copied into the mesh pool (shapes GPU
    /// simulations write), counted in the first view's uploads.
    pub mesh_bytes: u64,
    /// Command buffers to submit before the frame's (the after-view work's).
    pub before: Vec<wgpu::CommandBuffer>,
    /// The newest finished earlier frame's GPU times.
    pub gpu: Option<GpuTimes>,
    /// When it began, for its own CPU time.
    pub start: Instant,
    /// Which sub-frame of an accumulated still it is.
    pub sample: SubFrame,
}

impl Frame {
    /// Begin frame `next.index`, begun at `start`, with what `next` kept (its
    /// entities, outline and lists), recording into `encoder` under the debug
    /// group "frame N"; `gpu`: an earlier frame's GPU times.
    pub(crate) fn begin(
        next: &mut NextFrame,
        mut encoder: wgpu::CommandEncoder,
        gpu: Option<GpuTimes>,
        start: Instant,
    ) -> Self {
        let mut outline = std::mem::replace(&mut next.outline, Outline::new(false));
        outline.enter(&mut encoder, &format!("frame {}", next.index));
        Frame {
            index: next.index,
            encoder,
            outline,
            submitted: std::mem::take(&mut next.submitted),
            submit_error: next.submit_error.take(),
            visible: std::mem::take(&mut next.visible),
            prepared: None,
            prepares: 0,
            prefiltered: false,
            first_view: None,
            mesh_bytes: 0,
            before: Vec::new(),
            gpu,
            start,
            sample: SubFrame::ONE,
        }
    }
}
