//! Core layer: GPU time of the shadow pass, the forward pass and each post effect
//! from timestamp queries, where the device supports them (`Features::TIMESTAMP_QUERY`).

use super::post::MAX_POST_EFFECTS;

/// A pass the timer brackets with a pair of timestamps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Timed {
    /// From the first shadow view's pass to the last one's end.
    Shadow,
    /// The forward pass.
    Forward,
    /// Post effect k of the view's chain (all its passes).
    Post(u8),
}

/// Timestamp pairs: shadow, forward, then one per post effect.
const PAIRS: usize = 2 + MAX_POST_EFFECTS;

impl Timed {
    fn pair(self) -> usize {
        match self {
            Timed::Shadow => 0,
            Timed::Forward => 1,
            Timed::Post(k) => 2 + usize::from(k),
        }
    }
}

/// GPU time of the last frame's passes, from [`Renderer::read_gpu_times`](crate::Renderer::read_gpu_times).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct GpuTimes {
    /// Every shadow view of the frame's shadow pass; `None` when it drew none.
    pub shadow_ms: Option<f64>,
    /// The forward pass: opaque, alpha-test, sky and transparent.
    pub forward_ms: f64,
    /// Each post effect of the view's chain, in order (empty without one).
    pub post_ms: Vec<f64>,
}

/// Two timestamps per [`Timed`] pass, each pair resolved into a buffer and copied
/// to one the CPU can map. Reading waits for the GPU, so only benchmarks ask.
pub(crate) struct GpuTimer {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    readback: wgpu::Buffer,
    period_ns: f64,
    /// Which pairs the last frame wrote.
    written: [bool; PAIRS],
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
        Some(Self {
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("gpu timer: shadow, forward and post pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * PAIRS as u32,
            }),
            resolved: buffer(
                "gpu timer: resolved",
                (PAIRS as u64 - 1) * RESOLVE_STRIDE + PAIR_BYTES,
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            ),
            readback: buffer(
                "gpu timer: readback",
                PAIRS as u64 * PAIR_BYTES,
                wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            ),
            period_ns: f64::from(queue.get_timestamp_period()),
            written: [false; PAIRS],
        })
    }

    /// Timestamp writes for a pass of `which`: at its beginning when `begin`,
    /// at its end when `end`, none when neither (a timed span may cover several passes).
    pub(crate) fn pass_writes(
        &self,
        which: Timed,
        begin: bool,
        end: bool,
    ) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        let first = 2 * which.pair() as u32;
        (begin || end).then_some(wgpu::RenderPassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: begin.then_some(first),
            end_of_pass_write_index: end.then_some(first + 1),
        })
    }

    /// After the last pass of `which`: resolve its timestamps and copy them where
    /// the CPU can read them.
    pub(crate) fn resolve(&mut self, encoder: &mut wgpu::CommandEncoder, which: Timed) {
        let pair = which.pair();
        let first = 2 * pair as u32;
        let at = pair as u64 * RESOLVE_STRIDE;
        encoder.resolve_query_set(&self.queries, first..first + 2, &self.resolved, at);
        encoder.copy_buffer_to_buffer(&self.resolved, at, &self.readback, pair as u64 * PAIR_BYTES, PAIR_BYTES);
        self.written[pair] = true;
    }

    /// The last frame's pass times, waiting for it; `None` when it drew no
    /// timed forward pass since the last read.
    pub(crate) fn read(&mut self, device: &wgpu::Device) -> Option<GpuTimes> {
        let written = std::mem::take(&mut self.written);
        if !written[Timed::Forward.pair()] {
            return None;
        }
        let (tx, rx) = std::sync::mpsc::channel();
        self.readback.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        device.poll(wgpu::PollType::wait_indefinitely()).ok()?;
        rx.recv().ok()?.ok()?;
        let ticks: [u64; 2 * PAIRS] = {
            let view = self.readback.get_mapped_range(..).ok()?;
            bytemuck::pod_read_unaligned(&view[..PAIRS * PAIR_BYTES as usize])
        };
        self.readback.unmap();
        let ms = |pair: usize| ticks[2 * pair + 1].saturating_sub(ticks[2 * pair]) as f64 * self.period_ns / 1e6;
        // Post effects are timed in order: the chain is the written pairs after the forward pass.
        let post = (0..MAX_POST_EFFECTS as u8).map(Timed::Post).take_while(|t| written[t.pair()]);
        Some(GpuTimes {
            shadow_ms: written[Timed::Shadow.pair()].then(|| ms(Timed::Shadow.pair())),
            forward_ms: ms(Timed::Forward.pair()),
            post_ms: post.map(|t| ms(t.pair())).collect(),
        })
    }
}
