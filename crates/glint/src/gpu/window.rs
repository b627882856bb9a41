//! Core layer: a window as one more target. Frames are drawn into an
//! [`OffscreenTarget`] as always and then blitted onto the window's next
//! surface texture, so everything headless works the same in a window.

use super::{AfterViews, Blitter, Gpu, GpuError, OffscreenTarget};

/// A window's surface, configured for its size, showing [`OffscreenTarget`]s.
pub struct WindowSurface {
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    /// sRGB view format the blit draws through (the surface format or its sRGB twin).
    view_format: wgpu::TextureFormat,
    blitter: Blitter,
    pipeline: wgpu::RenderPipeline,
}

impl WindowSurface {
    /// Configure `surface` (from [`Gpu::for_window`]) for a `width` × `height` window.
    /// A zero side is allowed: nothing is shown until [`WindowSurface::resize`]
    /// gives the window an area.
    pub fn new(gpu: &Gpu, surface: wgpu::Surface<'static>, width: u32, height: u32) -> Result<Self, GpuError> {
        let caps = surface.get_capabilities(&gpu.adapter);
        // Frames are sRGB-encoded colour: show them through an sRGB view, so the
        // blit decodes and re-encodes rather than showing encoded values as linear.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(wgpu::TextureFormat::is_srgb)
            .or_else(|| caps.formats.first().copied())
            .ok_or_else(|| GpuError::Surface(format!("'{}' cannot present to this window", gpu.info().name)))?;
        let view_format = format.add_srgb_suffix();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width,
            height,
            desired_maximum_frame_latency: 2,
            present_mode: wgpu::PresentMode::AutoVsync,
            alpha_mode: caps.alpha_modes.first().copied().unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: if view_format == format { Vec::new() } else { vec![view_format] },
        };
        let blitter = Blitter::new(&gpu.device);
        let pipeline = blitter.pipeline(&gpu.device, view_format);
        let mut window = Self { surface, config, view_format, blitter, pipeline };
        window.resize(gpu, width, height);
        Ok(window)
    }

    /// Follow the window to `width` × `height`. Returns whether it has an area to
    /// show frames in (a minimised window has none: frames are skipped until it does).
    pub fn resize(&mut self, gpu: &Gpu, width: u32, height: u32) -> bool {
        self.config.width = width;
        self.config.height = height;
        let shown = width > 0 && height > 0;
        if shown {
            self.surface.configure(&gpu.device, &self.config);
        }
        shown
    }

    /// The window's size in pixels, as last given.
    pub fn size(&self) -> (u32, u32) {
        (self.config.width, self.config.height)
    }

    /// The window's next surface texture, to show a frame on: record it into
    /// the frame ([`SurfaceFrame`] is [`AfterViews`]), then
    /// [`present`](SurfaceFrame::present) it. `None` while the window has no
    /// area or is hidden, or when the surface had to be configured again (the
    /// next frame is shown).
    pub fn acquire(&mut self, gpu: &Gpu) -> Option<SurfaceFrame<'_>> {
        if self.config.width == 0 || self.config.height == 0 {
            return None;
        }
        let texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&gpu.device, &self.config);
                return None;
            }
            wgpu::CurrentSurfaceTexture::Timeout
            | wgpu::CurrentSurfaceTexture::Occluded
            | wgpu::CurrentSurfaceTexture::Validation => return None,
        };
        let view = texture
            .texture
            .create_view(&wgpu::TextureViewDescriptor { format: Some(self.view_format), ..Default::default() });
        Some(SurfaceFrame { window: self, texture, view })
    }
}

/// A window's surface texture for one frame ([`WindowSurface::acquire`]):
/// as [`AfterViews`], it blits the frame's picture onto it, scaled to the
/// window if their sizes differ; once the frame is submitted, present it.
pub struct SurfaceFrame<'w> {
    window: &'w WindowSurface,
    texture: wgpu::SurfaceTexture,
    view: wgpu::TextureView,
}

impl SurfaceFrame<'_> {
    /// Show the texture, after the frame that drew it was submitted.
    pub fn present(self, gpu: &Gpu) {
        gpu.queue.present(self.texture);
    }
}

impl AfterViews for SurfaceFrame<'_> {
    fn record(
        &mut self,
        device: &wgpu::Device,
        _queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        target: &OffscreenTarget,
    ) -> Vec<wgpu::CommandBuffer> {
        let window = self.window;
        window.blitter.blit(device, encoder, &window.pipeline, target.color_view(), &self.view);
        Vec::new()
    }
}
