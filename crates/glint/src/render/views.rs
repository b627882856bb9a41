//! Core layer: the Camera block (`@group(1)`) of every view a frame draws — the
//! camera at record 0, then each shadow view — in one uniform buffer bound with a
//! dynamic offset. A record is written only when its bytes change.

use super::blocks::CameraGpu;

/// Records the buffer holds: the camera and up to this many shadow views.
pub(crate) const MAX_SHADOW_VIEWS: usize = 64;
const RECORDS: usize = 1 + MAX_SHADOW_VIEWS;
/// Bytes between records: the dynamic-offset alignment every device accepts.
pub(crate) const RECORD_STRIDE: u64 = 256;

/// The view records and the bind group over them.
pub(crate) struct ViewBlocks {
    buffer: wgpu::Buffer,
    pub bind_group: wgpu::BindGroup,
    last: Vec<Option<CameraGpu>>,
}

impl ViewBlocks {
    pub(crate) fn new(device: &wgpu::Device, layout: &wgpu::BindGroupLayout) -> Self {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("camera block: view records"),
            size: RECORD_STRIDE * RECORDS as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("camera block (group 1)"),
            layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &buffer,
                    offset: 0,
                    size: std::num::NonZeroU64::new(std::mem::size_of::<CameraGpu>() as u64),
                }),
            }],
        });
        Self { buffer, bind_group, last: vec![None; RECORDS] }
    }

    /// Write record `index` (0: the camera, 1 + k: shadow view k) if it changed;
    /// returns bytes written.
    pub(crate) fn update(&mut self, queue: &wgpu::Queue, index: usize, value: CameraGpu) -> u64 {
        if self.last[index] == Some(value) {
            return 0;
        }
        queue.write_buffer(&self.buffer, RECORD_STRIDE * index as u64, bytemuck::bytes_of(&value));
        self.last[index] = Some(value);
        std::mem::size_of::<CameraGpu>() as u64
    }

    /// The dynamic offset that selects record `index`.
    pub(crate) fn offset(index: usize) -> u32 {
        (RECORD_STRIDE * index as u64) as u32
    }
}
