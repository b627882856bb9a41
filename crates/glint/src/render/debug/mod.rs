//! Core layer: what a frame tells about itself: its statistics, GPU times,
//! debug-group outline, the calls `glint explain` lists, and read-backs of
//! what the GPU drew.

pub(crate) mod explain;
pub(crate) mod inspect;
pub(crate) mod outline;
pub(crate) mod readback;
pub(crate) mod stats;
pub(crate) mod timer;
