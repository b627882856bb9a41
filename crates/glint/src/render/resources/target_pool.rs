//! Core layer: [`TargetPool`], the renderer's transient targets from one pool
//! keyed by size and use: a view's own target (a view of part of the output,
//! or its HDR picture for a post chain) and the post chain's intermediate
//! images. A target unused for more than two frames is dropped when the pool
//! makes a new one (a window being resized asks for a new size every frame).

use crate::gpu::{OffscreenTarget, TargetFormat};

/// What a transient target is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum TargetUse {
    /// A view's own target: colour and depth, in this format and sample count.
    View(TargetFormat),
    /// The post chain's intermediate image in this slot: one sample, in
    /// the slot's format (HDR colour, or SMAA's stencil).
    PostImage(usize),
}

/// A pooled target.
enum Transient {
    View(Box<OffscreenTarget>),
    Image(wgpu::TextureView),
}

struct Entry {
    size: (u32, u32),
    usage: TargetUse,
    /// `None` while a view target is taken out.
    target: Option<Transient>,
    last_used: u64,
}

/// Every transient target the renderer keeps between frames.
#[derive(Default)]
pub(crate) struct TargetPool {
    entries: Vec<Entry>,
}

impl TargetPool {
    /// A view target of `size` and `format` to draw into in frame `frame`, kept
    /// from an earlier frame or new; give it back with [`put_back`](Self::put_back).
    pub(crate) fn take_view(
        &mut self,
        device: &wgpu::Device,
        size: (u32, u32),
        (format, read_depth): (TargetFormat, bool),
        frame: u64,
    ) -> OffscreenTarget {
        let usage = TargetUse::View(format);
        let kept = self.entries.iter_mut().find(|e| e.size == size && e.usage == usage && e.target.is_some());
        if let Some(Transient::View(target)) = kept.and_then(|e| e.target.take()) {
            return *target;
        }
        self.drop_stale(frame);
        self.entries.push(Entry { size, usage, target: None, last_used: frame });
        OffscreenTarget::on_device(device, size.0, size.1, format, read_depth)
    }

    /// Give back a view target taken in frame `frame`.
    pub(crate) fn put_back(&mut self, target: OffscreenTarget, frame: u64) {
        let (size, usage) = ((target.width(), target.height()), TargetUse::View(target.format()));
        match self.entries.iter_mut().find(|e| e.size == size && e.usage == usage && e.target.is_none()) {
            Some(entry) => (entry.target, entry.last_used) = (Some(Transient::View(Box::new(target))), frame),
            None => self.entries.push(Entry {
                size,
                usage,
                target: Some(Transient::View(Box::new(target))),
                last_used: frame,
            }),
        }
    }

    /// Make sure post image `slot` of `size` and `format` exists (a slot
    /// keeps one format), used in frame `frame`.
    pub(crate) fn keep_image(
        &mut self,
        device: &wgpu::Device,
        size: (u32, u32),
        (slot, format): (usize, wgpu::TextureFormat),
        frame: u64,
    ) {
        let usage = TargetUse::PostImage(slot);
        if let Some(entry) = self.entries.iter_mut().find(|e| e.size == size && e.usage == usage) {
            entry.last_used = frame;
            return;
        }
        self.drop_stale(frame);
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("post: intermediate"),
            size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let view = Transient::Image(texture.create_view(&Default::default()));
        self.entries.push(Entry { size, usage, target: Some(view), last_used: frame });
    }

    /// Post image `slot` of `size` ([`keep_image`](Self::keep_image) made it).
    pub(crate) fn image(&self, size: (u32, u32), slot: usize) -> Option<&wgpu::TextureView> {
        let usage = TargetUse::PostImage(slot);
        self.entries.iter().find(|e| e.size == size && e.usage == usage).and_then(|e| match &e.target {
            Some(Transient::Image(view)) => Some(view),
            _ => None,
        })
    }

    /// Drop the targets unused since two frames before `frame` (never one taken out).
    fn drop_stale(&mut self, frame: u64) {
        self.entries.retain(|e| e.target.is_none() || e.last_used + 2 >= frame);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::{Gpu, COLOR_FORMAT, HDR_FORMAT};

    #[test]
    fn targets_are_kept_by_size_and_use_and_dropped_when_stale() {
        let gpu = match Gpu::headless() {
            Ok(gpu) => gpu,
            Err(e) if std::env::var("GLINT_REQUIRE_ADAPTER").as_deref() == Ok("1") => panic!("{e}"),
            Err(e) => return eprintln!("skipping GPU test: {e}"),
        };
        let device = &gpu.device;
        let format = TargetFormat { color: COLOR_FORMAT, samples: 1 };
        let mut pool = TargetPool::default();
        // Two views of one size in one frame: two targets.
        let a = pool.take_view(device, (8, 4), (format, false), 0);
        let b = pool.take_view(device, (8, 4), (format, false), 0);
        pool.put_back(a, 0);
        pool.put_back(b, 0);
        assert_eq!(pool.entries.len(), 2);
        // The next frame takes them again rather than making new ones.
        let a = pool.take_view(device, (8, 4), (format, false), 1);
        pool.put_back(a, 1);
        pool.keep_image(device, (8, 4), (0, HDR_FORMAT), 1);
        pool.keep_image(device, (8, 4), (0, HDR_FORMAT), 1);
        assert_eq!(pool.entries.len(), 3, "one post image per size and slot");
        assert!(pool.image((8, 4), 0).is_some() && pool.image((8, 4), 1).is_none());
        // Four frames later a new size drops what was not used since.
        let c = pool.take_view(device, (16, 16), (format, false), 5);
        pool.put_back(c, 5);
        assert_eq!(pool.entries.len(), 1);
    }
}
