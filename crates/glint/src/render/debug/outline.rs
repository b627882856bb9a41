//! The frame's debug groups, nested like its outline: "frame N" › "simulate"
//! (with GPU simulations), then per view — in a group "view k" (its place in
//! the frame's list) where the frame has several — "shadows" (a pass per
//! "light n cascade c", "light n" or "light n face f"), "forward" (the cull
//! pass, then the forward passes), "post".
//! Capture tools show them where the driver takes them
//! ([`Gpu::debug_groups`](crate::Gpu::debug_groups));
//! [`Renderer::frame_outline`](crate::render::Renderer::frame_outline) lists them everywhere.

use crate::render::debug::explain::{DrawCall, FrameCalls, PassType, Tape};

/// The groups open in the frame's encoder and those it has opened so far,
/// each as its path ("frame 3 › view 1 › shadows"); while explaining, the
/// passes and draw calls recorded in them too.
pub(crate) struct Outline {
    /// Whether the groups go to the driver.
    driver: bool,
    open: Vec<String>,
    opened: Vec<String>,
    /// The groups of the last frame submitted.
    last: Vec<String>,
    /// The passes and calls of the frame being recorded, while explaining.
    tape: Option<Tape>,
    /// The last submitted frame's, while explaining.
    last_calls: Option<FrameCalls>,
}

impl Outline {
    pub(crate) fn new(driver: bool) -> Self {
        Self { driver, open: Vec::new(), opened: Vec::new(), last: Vec::new(), tape: None, last_calls: None }
    }

    /// Start (with a tape) or stop explaining frames.
    pub(crate) fn set_tape(&mut self, tape: Option<Tape>) {
        self.last_calls = None;
        self.tape = tape;
    }

    /// Write down the call `call` builds in the pass begun last, while explaining.
    pub(crate) fn call(&self, call: impl FnOnce() -> DrawCall) {
        self.calls(|| vec![call()]);
    }

    /// Write down the calls `calls` builds, while explaining.
    pub(crate) fn calls(&self, calls: impl FnOnce() -> Vec<DrawCall>) {
        if let Some(tape) = &self.tape {
            calls().into_iter().for_each(|c| tape.call(c));
        }
    }

    /// The last submitted frame's passes and calls, while explaining.
    pub(crate) fn last_calls(&self) -> Option<&FrameCalls> {
        self.last_calls.as_ref()
    }

    /// Write down a pass begun in the innermost open group, while explaining.
    pub(crate) fn pass(&self, name: &str, kind: PassType, bound: &[&str]) {
        if let Some(tape) = &self.tape {
            tape.pass(name, kind, self.open.last().map_or("", String::as_str), bound);
        }
    }

    /// Open the group `name` inside the open ones.
    pub(crate) fn enter(&mut self, encoder: &mut wgpu::CommandEncoder, name: &str) {
        if self.driver {
            encoder.push_debug_group(name);
        }
        let path = match self.open.last() {
            Some(outer) => format!("{outer} › {name}"),
            None => name.to_owned(),
        };
        self.opened.push(path.clone());
        self.open.push(path);
    }

    /// Close the innermost open group.
    pub(crate) fn leave(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if self.open.pop().is_some() && self.driver {
            encoder.pop_debug_group();
        }
    }

    /// Close every open group before the frame's encoder is finished, and keep
    /// its outline as the last frame's.
    pub(crate) fn finish(&mut self, encoder: &mut wgpu::CommandEncoder) {
        while !self.open.is_empty() {
            self.leave(encoder);
        }
        self.last = std::mem::take(&mut self.opened);
        if let Some(tape) = &self.tape {
            self.last_calls = Some(tape.take());
        }
    }

    /// Forget a frame whose encoder was dropped.
    pub(crate) fn drop_frame(&mut self) {
        self.open.clear();
        self.opened.clear();
        if let Some(tape) = &self.tape {
            tape.take();
        }
    }

    /// Every group the last submitted frame opened, in order.
    pub(crate) fn last(&self) -> &[String] {
        &self.last
    }
}
