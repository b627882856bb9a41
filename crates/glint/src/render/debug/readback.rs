//! Core layer: [`CountReadback`], small counts from the GPU (GPU culling's
//! instances and triangles drawn per frustum) read back a frame or two late without a stall:
//! a few buffers copied into, mapped once their submission has gone, and read
//! when the map is done.

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;

const FREE: u8 = 0;
const MAPPING: u8 = 1;
const MAPPED: u8 = 2;
const FAILED: u8 = 3;
const COPIED: u8 = 4;
/// Its slots: a frame's counts are read two or three frames later.
const SLOTS: usize = 3;

/// A few small buffers the per-frustum totals are copied into and mapped from
/// (`copy` is given their length in words).
pub(crate) struct CountReadback {
    slots: Vec<(wgpu::Buffer, Arc<AtomicU8>, u64, u32)>,
    latest: Option<Vec<u32>>,
    /// Words each slot holds.
    max_words: u32,
    /// Whether `latest` came back since [`take_fresh`](CountReadback::take_fresh).
    fresh: bool,
}

impl CountReadback {
    /// Slots of `max_words` words each.
    pub(crate) fn new(device: &wgpu::Device, max_words: u32) -> Self {
        let slot = |_| {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("gpu culling: instances drawn, read back"),
                size: 4 * u64::from(max_words),
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            });
            (buffer, Arc::new(AtomicU8::new(FREE)), 0, 0)
        };
        Self { slots: (0..SLOTS).map(slot).collect(), latest: None, max_words, fresh: false }
    }

    /// Copy `words` words of totals from `at` in `counts` into a free slot
    /// (none free: skipped).
    pub(crate) fn copy(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        counts: &wgpu::Buffer,
        at: u64,
        words: u32,
        submits: u64,
    ) {
        let words = words.min(self.max_words);
        let Some(slot) = self.slots.iter_mut().find(|s| s.1.load(Ordering::Acquire) == FREE) else { return };
        if words > 0 {
            encoder.copy_buffer_to_buffer(counts, at, &slot.0, 0, 4 * u64::from(words));
            slot.1.store(COPIED, Ordering::Release);
            (slot.2, slot.3) = (submits, words);
        }
    }

    /// Map the slots whose copies were submitted (the queue has made more than
    /// `submits` submissions since), and take the newest mapped one's totals.
    pub(crate) fn collect(&mut self, device: &wgpu::Device, submits: u64) -> Option<&[u32]> {
        let _ = device.poll(wgpu::PollType::Poll);
        let mut newest: Option<(u64, Vec<u32>)> = None;
        for (buffer, state, copied_at, words) in &self.slots {
            match state.load(Ordering::Acquire) {
                COPIED if submits > *copied_at => {
                    state.store(MAPPING, Ordering::Release);
                    let state = Arc::clone(state);
                    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
                        state.store(if r.is_ok() { MAPPED } else { FAILED }, Ordering::Release);
                    });
                }
                MAPPED => {
                    let totals = buffer
                        .get_mapped_range(..)
                        .ok()
                        .map(|view| bytemuck::cast_slice::<u8, u32>(&view[..4 * *words as usize]).to_vec());
                    buffer.unmap();
                    state.store(FREE, Ordering::Release);
                    if let Some(totals) = totals.filter(|_| newest.as_ref().is_none_or(|n| n.0 < *copied_at)) {
                        newest = Some((*copied_at, totals));
                    }
                }
                FAILED => state.store(FREE, Ordering::Release),
                _ => {}
            }
        }
        if let Some((_, totals)) = newest {
            (self.latest, self.fresh) = (Some(totals), true);
        }
        self.latest.as_deref()
    }

    /// The newest values that came back.
    pub(crate) fn latest(&self) -> Option<&[u32]> {
        self.latest.as_deref()
    }

    /// Whether new values came back since the last call.
    pub(crate) fn take_fresh(&mut self) -> bool {
        std::mem::take(&mut self.fresh)
    }

    /// Wait until every copy made so far has come back (the queue has made
    /// `submits` submissions), then give the newest values; gives up after
    /// 10 s of waiting.
    pub(crate) fn wait_all(&mut self, device: &wgpu::Device, submits: u64) -> Option<&[u32]> {
        let start = web_time::Instant::now();
        loop {
            self.collect(device, submits);
            let waiting = self.slots.iter().any(|s| matches!(s.1.load(Ordering::Acquire), COPIED | MAPPING | MAPPED));
            if !waiting || start.elapsed() > std::time::Duration::from_secs(10) {
                return self.latest.as_deref();
            }
            device.poll(wgpu::PollType::wait_indefinitely()).ok()?;
        }
    }
}
