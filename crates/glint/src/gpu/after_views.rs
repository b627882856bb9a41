//! Core layer: [`AfterViews`], work a frame records into its own encoder
//! after its views have drawn the picture — an overlay drawn over it, the blit
//! onto a window's surface texture — so that a displayed frame is one
//! submission.

use super::OffscreenTarget;

/// Work recorded after a frame's views ([`FrameInput::then`](crate::FrameInput::then)).
pub trait AfterViews {
    /// Record into `encoder`, after the frame's views have drawn `target`.
    /// Returns command buffers that must run before the frame's (an egui paint
    /// callback's, say): submitted with it, in the same submission.
    fn record(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        target: &OffscreenTarget,
    ) -> Vec<wgpu::CommandBuffer>;
}
