//! Core layer: GPU time of the forward pass from timestamp queries, where the
//! device supports them (`Features::TIMESTAMP_QUERY`).

/// Two timestamps around the forward pass, resolved into a buffer and copied to
/// one the CPU can map. Reading waits for the GPU, so only benchmarks ask.
pub(crate) struct GpuTimer {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    readback: wgpu::Buffer,
    period_ns: f64,
    /// Whether the last frame wrote the timestamps.
    written: bool,
}

const BYTES: u64 = 2 * std::mem::size_of::<u64>() as u64;

impl GpuTimer {
    /// A timer, or `None` when the device has no timestamp queries.
    pub(crate) fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Option<Self> {
        if !device.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
            return None;
        }
        let buffer = |label, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: BYTES,
                usage,
                mapped_at_creation: false,
            })
        };
        Some(Self {
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("gpu timer: forward pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            }),
            resolved: buffer("gpu timer: resolved", wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC),
            readback: buffer("gpu timer: readback", wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ),
            period_ns: f64::from(queue.get_timestamp_period()),
            written: false,
        })
    }

    /// Timestamp writes for the forward pass.
    pub(crate) fn pass_writes(&self) -> wgpu::RenderPassTimestampWrites<'_> {
        wgpu::RenderPassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(0),
            end_of_pass_write_index: Some(1),
        }
    }

    /// After the pass: resolve the timestamps and copy them where the CPU can read.
    pub(crate) fn resolve(&mut self, encoder: &mut wgpu::CommandEncoder) {
        encoder.resolve_query_set(&self.queries, 0..2, &self.resolved, 0);
        encoder.copy_buffer_to_buffer(&self.resolved, 0, &self.readback, 0, BYTES);
        self.written = true;
    }

    /// Milliseconds between the two timestamps of the last frame, waiting for it.
    pub(crate) fn read_ms(&mut self, device: &wgpu::Device) -> Option<f64> {
        if !std::mem::take(&mut self.written) {
            return None;
        }
        let (tx, rx) = std::sync::mpsc::channel();
        self.readback.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        device.poll(wgpu::PollType::wait_indefinitely()).ok()?;
        rx.recv().ok()?.ok()?;
        let ticks: [u64; 2] = {
            let view = self.readback.get_mapped_range(..).ok()?;
            bytemuck::pod_read_unaligned(&view[..BYTES as usize])
        };
        self.readback.unmap();
        Some(ticks[1].saturating_sub(ticks[0]) as f64 * self.period_ns / 1e6)
    }
}
