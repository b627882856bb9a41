//! Core layer: GPU time of the shadow pass, the forward pass and each post effect
//! from timestamp queries, where the device supports them (`Features::TIMESTAMP_QUERY`).
//!
//! Each timed frame's timestamps are copied into one of [`SLOTS`] readback
//! buffers and mapped after its submission; a later frame picks up the ones the
//! GPU has finished without waiting ([`GpuTimer::collect`]), so
//! [`FrameStats::gpu`](crate::render::FrameStats::gpu) trails the frame by a frame or two.
//! A frame that finds every buffer still in flight is not timed.

use crate::scene::MAX_POST_EFFECTS;
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;

/// A pass the timer brackets with a pair of timestamps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Timed {
    /// From the first shadow view's pass to the last one's end.
    Shadow,
    /// The forward pass.
    Forward,
    /// Ambient occlusion: from its occlusion pass (or its depth pre-pass, where
    /// that has a depth of its own) to its blur's end.
    AmbientOcclusion,
    /// The depth pre-pass a view with ambient occlusion shares with its forward
    /// pass: from its first pass to its last's end (with occlusion culling,
    /// the depth pyramid and late cull between its phases).
    DepthPrepass,
    /// Binning the view's lights into its clusters on the GPU.
    Lights,
    /// Order-independent transparency's pass: the blended draws into the
    /// view's sums or lists (inside the forward pass's span).
    Transparency,
    /// Post effect k of the view's chain (all its passes).
    Post(u8),
}

/// Timestamp pairs of a view: shadow, forward, ambient occlusion, depth
/// pre-pass, light binning, transparency, then one per post effect.
const PAIRS: usize = 6 + MAX_POST_EFFECTS;

/// The views of a frame timed, each with pairs of its own (a frame's later
/// views are not timed).
const TIMED_VIEWS: usize = 8;

/// Timestamp pairs in all: each timed view's.
const ALL_PAIRS: usize = PAIRS * TIMED_VIEWS;

impl Timed {
    fn pair(self) -> usize {
        match self {
            Timed::Shadow => 0,
            Timed::Forward => 1,
            Timed::AmbientOcclusion => 2,
            Timed::DepthPrepass => 3,
            Timed::Lights => 4,
            Timed::Transparency => 5,
            Timed::Post(k) => 6 + usize::from(k),
        }
    }
}

/// GPU time of one frame's passes, each summed over the frame's views (the
/// first 8 of them).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct GpuTimes {
    /// The frame timed: its [`FrameStats::frame`](crate::render::FrameStats::frame).
    pub frame: u64,
    /// Every shadow view of the frame's shadow pass; `None` when it drew none.
    pub shadow_ms: Option<f64>,
    /// The forward pass: opaque, alpha-test, sky and transparent.
    pub forward_ms: f64,
    /// Ambient occlusion's passes (occlusion and blur, and its depth pre-pass
    /// where that has a depth of its own); `None` for a view without it.
    pub ambient_occlusion_ms: Option<f64>,
    /// The depth pre-pass a view with ambient occlusion shares with its forward
    /// pass (which then draws no depth); `None` without one.
    pub depth_prepass_ms: Option<f64>,
    /// Binning the view's lights into its clusters, where the GPU binned
    /// them (`render/gpu_driven/light_binning.rs`); `None` elsewhere.
    pub lights_ms: Option<f64>,
    /// Order-independent transparency's pass (weighted sums or exact lists:
    /// [`Transparency`](crate::scene::Transparency)), which the forward pass's
    /// time includes; `None` for a view drawing its transparency sorted.
    pub transparency_ms: Option<f64>,
    /// Each post effect of the views' chains, in order: effect k summed over
    /// the views that have a k-th (empty without one).
    pub post_ms: Vec<f64>,
}

/// Readback buffers in the ring: frames in flight that can be timed at once.
const SLOTS: usize = 3;

/// A readback buffer's state, shared with its map callback.
const FREE: u8 = 0;
const MAPPING: u8 = 1;
const MAPPED: u8 = 2;
const FAILED: u8 = 3;
/// Copies recorded into it, not yet submitted (several frames' views may share a submission).
const RECORDED: u8 = 4;

/// One frame's timestamps on their way back to the CPU.
struct Slot {
    buffer: wgpu::Buffer,
    state: Arc<AtomicU8>,
    /// Which pairs its frame wrote (each view's, in turn).
    written: [bool; ALL_PAIRS],
    frame: u64,
}

/// Two timestamps per [`Timed`] pass, each pair resolved into a buffer and
/// copied into the frame's readback slot.
pub(crate) struct GpuTimer {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    slots: Vec<Slot>,
    /// The slot this frame's timestamps go to, once its first pass resolved.
    current: Option<usize>,
    /// The view whose passes are being recorded: its place in the frame
    /// ([`begin_view`](Self::begin_view)).
    view: usize,
    period_ns: f64,
    /// The newest frame's times collected so far, and whether `read` returned them.
    latest: Option<(GpuTimes, bool)>,
}

const PAIR_BYTES: u64 = 2 * std::mem::size_of::<u64>() as u64;
/// Where each pair is resolved: resolves must start on this alignment.
const RESOLVE_STRIDE: u64 = wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT;

impl GpuTimer {
    /// A timer, or `None` when the device has no timestamp queries.
    pub(crate) fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Option<Self> {
        if !device.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
            return None;
        }
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
        };
        let slot = |_| Slot {
            buffer: buffer(
                "gpu timer: readback",
                ALL_PAIRS as u64 * PAIR_BYTES,
                wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            ),
            state: Arc::new(AtomicU8::new(FREE)),
            written: [false; ALL_PAIRS],
            frame: 0,
        };
        Some(Self {
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("gpu timer: shadow, forward, ambient occlusion, depth pre-pass and post pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * ALL_PAIRS as u32,
            }),
            resolved: buffer(
                "gpu timer: resolved",
                (ALL_PAIRS as u64 - 1) * RESOLVE_STRIDE + PAIR_BYTES,
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            ),
            slots: (0..SLOTS).map(slot).collect(),
            current: None,
            view: 0,
            period_ns: f64::from(queue.get_timestamp_period()),
            latest: None,
        })
    }

    /// The passes recorded from now on are the view at place `k` of the frame's.
    pub(crate) fn begin_view(&mut self, k: usize) {
        self.view = k;
    }

    /// The pair of `which` of the view being recorded; `None` past the views timed.
    fn pair(&self, which: Timed) -> Option<usize> {
        (self.view < TIMED_VIEWS).then(|| self.view * PAIRS + which.pair())
    }

    /// Timestamp writes for a pass of `which`: at its beginning when `begin`,
    /// at its end when `end`, none when neither (a timed span may cover several passes).
    pub(crate) fn pass_writes(
        &self,
        which: Timed,
        begin: bool,
        end: bool,
    ) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        let first = 2 * self.pair(which)? as u32;
        (begin || end).then_some(wgpu::RenderPassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: begin.then_some(first),
            end_of_pass_write_index: end.then_some(first + 1),
        })
    }

    /// [`pass_writes`](Self::pass_writes) for a compute pass.
    pub(crate) fn compute_pass_writes(
        &self,
        which: Timed,
        begin: bool,
        end: bool,
    ) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.pass_writes(which, begin, end).map(|w| wgpu::ComputePassTimestampWrites {
            query_set: w.query_set,
            beginning_of_pass_write_index: w.beginning_of_pass_write_index,
            end_of_pass_write_index: w.end_of_pass_write_index,
        })
    }

    /// After the last pass of `which` in frame `frame`: resolve its timestamps
    /// and copy them into the frame's readback slot (none free: not timed).
    pub(crate) fn resolve(&mut self, encoder: &mut wgpu::CommandEncoder, which: Timed, frame: u64) {
        let Some(pair) = self.pair(which) else { return };
        if self.current.is_none_or(|k| self.slots[k].frame != frame) {
            self.current = self.slots.iter().position(|s| s.state.load(Ordering::Acquire) == FREE);
            let Some(k) = self.current else { return };
            (self.slots[k].frame, self.slots[k].written) = (frame, [false; ALL_PAIRS]);
            self.slots[k].state.store(RECORDED, Ordering::Release);
        }
        let Some(k) = self.current else { return };
        let first = 2 * pair as u32;
        let at = pair as u64 * RESOLVE_STRIDE;
        encoder.resolve_query_set(&self.queries, first..first + 2, &self.resolved, at);
        let slot = &mut self.slots[k];
        encoder.copy_buffer_to_buffer(&self.resolved, at, &slot.buffer, pair as u64 * PAIR_BYTES, PAIR_BYTES);
        slot.written[pair] = true;
    }

    /// After the submission holding the frames' forward passes: map every slot
    /// recorded into since the last submission, to be read once the GPU has
    /// finished them (a slot whose frame drew no timed forward pass is freed).
    pub(crate) fn submitted(&mut self) {
        self.current = None;
        for slot in self.slots.iter().filter(|s| s.state.load(Ordering::Acquire) == RECORDED) {
            if !(0..TIMED_VIEWS).any(|v| slot.written[v * PAIRS + Timed::Forward.pair()]) {
                slot.state.store(FREE, Ordering::Release);
                continue;
            }
            slot.state.store(MAPPING, Ordering::Release);
            let state = Arc::clone(&slot.state);
            slot.buffer.map_async(wgpu::MapMode::Read, .., move |r| {
                state.store(if r.is_ok() { MAPPED } else { FAILED }, Ordering::Release);
            });
        }
    }

    /// The newest frame's times that have come back, without waiting for the GPU.
    pub(crate) fn collect(&mut self, device: &wgpu::Device) -> Option<GpuTimes> {
        let _ = device.poll(wgpu::PollType::Poll);
        for k in 0..SLOTS {
            let times = match self.slots[k].state.load(Ordering::Acquire) {
                MAPPED => self.take(k),
                FAILED => None,
                _ => continue,
            };
            self.slots[k].state.store(FREE, Ordering::Release);
            if let Some(t) = times.filter(|t| self.latest.as_ref().is_none_or(|(l, _)| t.frame > l.frame)) {
                self.latest = Some((t, false));
            }
        }
        self.latest.as_ref().map(|(t, _)| t.clone())
    }

    /// The times of the newest frame timed, waiting for the GPU to finish it;
    /// `None` when it drew no timed forward pass or `read` already returned it.
    pub(crate) fn read(&mut self, device: &wgpu::Device) -> Option<GpuTimes> {
        // Another thread polling the same device may be the one that runs a map
        // callback, just after this thread's wait returns: wait for the callbacks too.
        let start = web_time::Instant::now();
        while self.slots.iter().any(|s| s.state.load(Ordering::Acquire) == MAPPING) {
            device.poll(wgpu::PollType::wait_indefinitely()).ok()?;
            if start.elapsed() > std::time::Duration::from_secs(10) {
                return None;
            }
            std::thread::yield_now();
        }
        self.collect(device);
        let (times, read) = self.latest.as_mut()?;
        (!std::mem::replace(read, true)).then(|| times.clone())
    }

    /// Slot `k`'s times, read from its mapped buffer (then unmapped).
    fn take(&self, k: usize) -> Option<GpuTimes> {
        let slot = &self.slots[k];
        let ticks: Option<Vec<u64>> = slot.buffer.get_mapped_range(..).ok().map(|view| {
            view[..ALL_PAIRS * PAIR_BYTES as usize].chunks_exact(8).map(bytemuck::pod_read_unaligned).collect()
        });
        slot.buffer.unmap();
        let ticks = ticks?;
        let ms = |pair: usize| ticks[2 * pair + 1].saturating_sub(ticks[2 * pair]) as f64 * self.period_ns / 1e6;
        // Each pass summed over the views that wrote it; `None` where none did.
        let sum = |which: Timed| {
            let pairs = (0..TIMED_VIEWS).map(|v| v * PAIRS + which.pair()).filter(|&p| slot.written[p]);
            pairs.map(ms).reduce(|a, b| a + b)
        };
        // Post effects are timed in order: a chain is the written pairs after the forward pass.
        let post = (0..MAX_POST_EFFECTS as u8).map(Timed::Post).map_while(sum);
        Some(GpuTimes {
            frame: slot.frame,
            shadow_ms: sum(Timed::Shadow),
            forward_ms: sum(Timed::Forward).unwrap_or(0.0),
            ambient_occlusion_ms: sum(Timed::AmbientOcclusion),
            depth_prepass_ms: sum(Timed::DepthPrepass),
            lights_ms: sum(Timed::Lights),
            transparency_ms: sum(Timed::Transparency),
            post_ms: post.collect(),
        })
    }
}
