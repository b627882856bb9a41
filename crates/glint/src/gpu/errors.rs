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

    /// The error caught, if any: out of memory before internal and validation
    /// errors. Natively (and on WebGL) the scopes answer
    /// at once; the browser's WebGPU answers later, and there the errors are
    /// left to its console rather than block the page's thread.
    pub(crate) fn finish(self) -> Option<wgpu::Error> {
        // Out of memory first: a texture the device could not hold makes every
        // later use of it a validation error too, and the memory is the cause.
        let memory = at_once(self.memory.pop()).flatten();
        let internal = at_once(self.internal.pop()).flatten();
        memory.or(internal).or(at_once(self.validation.pop()).flatten())
    }
}

/// Errors no scope caught: wgpu's default handler panics on them (a device out
/// of memory for a huge target, say); glint keeps the first instead, and the
/// renderer returns it from the frame it happened in (exit code 3), never a panic.
#[derive(Clone, Debug, Default)]
pub(crate) struct UncapturedErrors(std::sync::Arc<std::sync::Mutex<Option<String>>>);

impl UncapturedErrors {
    /// Catch `device`'s uncaptured errors from now on.
    pub(crate) fn install(device: &wgpu::Device) -> Self {
        let errors = Self::default();
        let sink = errors.0.clone();
        device.on_uncaptured_error(std::sync::Arc::new(move |e: wgpu::Error| {
            let mut first = sink.lock().unwrap_or_else(|e| e.into_inner());
            first.get_or_insert_with(|| describe(&e));
        }));
        errors
    }

    /// The first error caught since the last call, if any.
    pub(crate) fn take(&self) -> Option<String> {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).take()
    }
}

/// `e` in one short line: out of memory said plainly, anything else shortened.
pub(crate) fn describe(e: &wgpu::Error) -> String {
    match e {
        wgpu::Error::OutOfMemory { .. } => "the GPU is out of memory".into(),
        other => crate::text::shorten(&other.to_string().replace('\n', " "), crate::text::MAX_MESSAGE_CHARS / 2),
    }
}

/// What `future` gives when polled once, or `None` if it is not ready yet.
fn at_once<F: std::future::Future>(future: F) -> Option<F::Output> {
    let mut future = std::pin::pin!(future);
    let mut context = std::task::Context::from_waker(std::task::Waker::noop());
    match future.as_mut().poll(&mut context) {
        std::task::Poll::Ready(value) => Some(value),
        std::task::Poll::Pending => None,
    }
}
