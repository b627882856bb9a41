//! Core layer: the device's queue as glint's renderer uses it, counting every
//! submission, so [`FrameStats::submits`](crate::FrameStats::submits) shows how
//! many a frame made (the frame's outline aims at one).

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// A queue that counts its submissions; everything else is the queue's own
/// (it dereferences to [`wgpu::Queue`]).
#[derive(Clone, Debug)]
pub(crate) struct SubmitQueue {
    queue: wgpu::Queue,
    submits: Arc<AtomicU64>,
}

impl SubmitQueue {
    /// Count `queue`'s submissions from now on (clones share the count).
    pub(crate) fn new(queue: wgpu::Queue) -> Self {
        Self { queue, submits: Arc::default() }
    }

    /// Submit `buffers` in one submission, and count it.
    pub(crate) fn submit<I: IntoIterator<Item = wgpu::CommandBuffer>>(&self, buffers: I) -> wgpu::SubmissionIndex {
        self.submits.fetch_add(1, Ordering::Relaxed);
        self.queue.submit(buffers)
    }

    /// Submissions so far, by this queue and its clones.
    pub(crate) fn submits(&self) -> u64 {
        self.submits.load(Ordering::Relaxed)
    }
}

impl std::ops::Deref for SubmitQueue {
    type Target = wgpu::Queue;

    fn deref(&self) -> &wgpu::Queue {
        &self.queue
    }
}
