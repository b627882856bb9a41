//! Core layer: errors wgpu reports while resources, shaders and pipelines are
//! made, caught as values instead of left to wgpu's default handler, which
//! panics. A driver that cannot translate a shader reports one (NVIDIA's GLES
//! through EGL: "the selected version doesn't support BUFFER_STORAGE"), and so
//! does a device out of memory for a shadow map or an instance buffer.

/// Error scopes around a stretch of resource creation; [`DriverErrors::finish`]
/// says whether anything in it failed.
pub(crate) struct DriverErrors {
    // Dropped (popped) in this order, the reverse of pushing.
    memory: wgpu::ErrorScopeGuard,
    internal: wgpu::ErrorScopeGuard,
    validation: wgpu::ErrorScopeGuard,
}

impl DriverErrors {
    /// Start catching validation, internal and out-of-memory errors on `device`.
    pub(crate) fn watch(device: &wgpu::Device) -> Self {
        let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let internal = device.push_error_scope(wgpu::ErrorFilter::Internal);
        Self { memory: device.push_error_scope(wgpu::ErrorFilter::OutOfMemory), internal, validation }
    }

    /// The first error caught, if any.
    pub(crate) fn finish(self) -> Option<wgpu::Error> {
        let memory = pollster::block_on(self.memory.pop());
        let internal = pollster::block_on(self.internal.pop());
        pollster::block_on(self.validation.pop()).or(internal).or(memory)
    }
}
