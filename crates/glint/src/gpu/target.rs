//! Core layer: [`OffscreenTarget`], the colour and depth textures a frame is
//! drawn into (with MSAA, resolved), and [`Readback`], a frame copied back to
//! the CPU in bands.

use super::{Gpu, GpuError, COLOR_FORMAT, DEPTH_FORMAT};

/// What pipelines drawing into a target depend on: its colour format and samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct TargetFormat {
    /// Colour format ([`COLOR_FORMAT`] or [`HDR_FORMAT`](super::HDR_FORMAT)).
    pub color: wgpu::TextureFormat,
    /// Samples per pixel (1 or 4).
    pub samples: u32,
}

/// An offscreen render target: sRGB colour plus depth, optionally multisampled,
/// with a resolve texture that can be read back to RGBA8 and saved as PNG.
pub struct OffscreenTarget {
    width: u32,
    height: u32,
    samples: u32,
    format: wgpu::TextureFormat,
    /// Single-sample colour: the resolve target with MSAA, the render target without.
    resolved: wgpu::Texture,
    resolved_view: wgpu::TextureView,
    /// Multisampled colour, present only when `samples > 1`.
    msaa_view: Option<wgpu::TextureView>,
    depth_view: wgpu::TextureView,
    /// The depth aspect alone, for reading depth in a shader (occlusion
    /// culling's pyramid), where the device occlusion-culls.
    depth_only_view: Option<wgpu::TextureView>,
}

/// Bytes per pixel of [`COLOR_FORMAT`].
const BYTES_PER_PIXEL: u32 = 4;

impl OffscreenTarget {
    /// Create a `width` x `height` target with `samples` (1 or 4) samples per pixel.
    ///
    /// Errors when a side is 0 or above the device's 2D texture limit, when the
    /// adapter cannot multisample the colour format, or when the device cannot
    /// hold the textures ([`GpuError::Failed`]: out of memory).
    pub fn new(gpu: &Gpu, width: u32, height: u32, samples: u32) -> Result<Self, GpuError> {
        let max = gpu.device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(GpuError::TargetSize { width, height, max });
        }
        if !(samples == 1 || samples == 4) || !gpu.supports_msaa(samples) {
            return Err(GpuError::SampleCount(samples));
        }
        let scope = super::DriverErrors::watch(&gpu.device);
        let format = TargetFormat { color: COLOR_FORMAT, samples };
        let target = Self::on_device(&gpu.device, width, height, format, gpu.occlusion_culls());
        match scope.finish() {
            None => Ok(target),
            Some(e) => Err(GpuError::Failed(format!(
                "cannot make a {width}x{height} target with {samples} samples: {}",
                super::errors::describe(&e)
            ))),
        }
    }

    /// [`OffscreenTarget::new`] without its checks, for a target no larger and
    /// with no more samples than one that passed them, its depth readable in
    /// shaders when `read_depth` (occlusion culling: only where the device
    /// does it, as GL's backend draws point-light shadows wrong beside a
    /// readable depth buffer).
    /// The colour format may be [`HDR_FORMAT`](super::HDR_FORMAT) (not readable back).
    pub(crate) fn on_device(
        device: &wgpu::Device,
        width: u32,
        height: u32,
        format: TargetFormat,
        read_depth: bool,
    ) -> Self {
        let TargetFormat { color: color_format, samples } = format;
        let size = wgpu::Extent3d { width, height, depth_or_array_layers: 1 };
        let texture = |label: &str, format, samples, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size,
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let resolved = texture(
            "offscreen target: colour",
            color_format,
            1,
            wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::COPY_DST
                | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let msaa_view = (samples > 1).then(|| {
            texture("offscreen target: msaa colour", color_format, samples, wgpu::TextureUsages::RENDER_ATTACHMENT)
                .create_view(&Default::default())
        });
        let depth_usage = match read_depth {
            true => wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            false => wgpu::TextureUsages::RENDER_ATTACHMENT,
        };
        let depth = texture("offscreen target: depth", DEPTH_FORMAT, samples, depth_usage);
        let depth_only_view = read_depth.then(|| {
            depth.create_view(&wgpu::TextureViewDescriptor {
                aspect: wgpu::TextureAspect::DepthOnly,
                ..Default::default()
            })
        });
        Self {
            width,
            height,
            samples,
            format: color_format,
            resolved_view: resolved.create_view(&Default::default()),
            resolved,
            msaa_view,
            depth_view: depth.create_view(&Default::default()),
            depth_only_view,
        }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Samples per pixel (1 or 4).
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Its colour format and samples.
    pub fn format(&self) -> TargetFormat {
        TargetFormat { color: self.format, samples: self.samples }
    }

    /// The single-sample colour texture holding the last frame (for copies).
    pub(crate) fn color_texture(&self) -> &wgpu::Texture {
        &self.resolved
    }

    /// The single-sample colour texture holding the last frame (its format is
    /// [`format`](Self::format)'s colour): for blits, and for drawing over the
    /// frame (a user interface) before it is shown or read back.
    pub fn color_view(&self) -> &wgpu::TextureView {
        &self.resolved_view
    }

    /// The colour attachment for a pass that clears with `clear`: renders into the
    /// MSAA texture and resolves into the readable one, or renders straight into it.
    pub(crate) fn color_attachment(&self, clear: wgpu::Color) -> wgpu::RenderPassColorAttachment<'_> {
        let ops = wgpu::Operations {
            load: wgpu::LoadOp::Clear(clear),
            // The multisampled texture is only an intermediate: resolving is enough.
            store: if self.msaa_view.is_some() { wgpu::StoreOp::Discard } else { wgpu::StoreOp::Store },
        };
        match &self.msaa_view {
            Some(msaa) => wgpu::RenderPassColorAttachment {
                view: msaa,
                depth_slice: None,
                resolve_target: Some(&self.resolved_view),
                ops,
            },
            None => wgpu::RenderPassColorAttachment {
                view: &self.resolved_view,
                depth_slice: None,
                resolve_target: None,
                ops,
            },
        }
    }

    /// The attachments of the first of two passes that draw one picture: colour
    /// cleared to `clear` and kept (not resolved yet), depth and stencil
    /// cleared and kept.
    pub(crate) fn first_of_two(
        &self,
        clear: wgpu::Color,
    ) -> (wgpu::RenderPassColorAttachment<'_>, wgpu::RenderPassDepthStencilAttachment<'_>) {
        let color = wgpu::RenderPassColorAttachment {
            view: self.msaa_view.as_ref().unwrap_or(&self.resolved_view),
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load: wgpu::LoadOp::Clear(clear), store: wgpu::StoreOp::Store },
        };
        (color, self.depth_stencil(true, true))
    }

    /// The attachments of the second: colour, depth and stencil loaded; the
    /// colour resolved (with MSAA) and depth and stencil discarded at the end.
    pub(crate) fn second_of_two(
        &self,
    ) -> (wgpu::RenderPassColorAttachment<'_>, wgpu::RenderPassDepthStencilAttachment<'_>) {
        let (color, _) = self.first_of_two(wgpu::Color::BLACK);
        let color = wgpu::RenderPassColorAttachment {
            resolve_target: self.msaa_view.as_ref().map(|_| &self.resolved_view),
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: if self.msaa_view.is_some() { wgpu::StoreOp::Discard } else { wgpu::StoreOp::Store },
            },
            ..color
        };
        (color, self.depth_stencil(false, false))
    }

    /// The attachments of a pass between two others: colour, depth and
    /// stencil loaded and kept (not resolved yet).
    pub(crate) fn middle_of_three(
        &self,
    ) -> (wgpu::RenderPassColorAttachment<'_>, wgpu::RenderPassDepthStencilAttachment<'_>) {
        let (color, _) = self.first_of_two(wgpu::Color::BLACK);
        let color = wgpu::RenderPassColorAttachment {
            ops: wgpu::Operations { load: wgpu::LoadOp::Load, ..color.ops },
            ..color
        };
        (color, self.depth_stencil(false, true))
    }

    /// The attachments of a last pass that reads the depth it is tested
    /// against ([`depth_only_view`](Self::depth_only_view)): as
    /// [`second_of_two`](Self::second_of_two), depth and stencil read-only.
    pub(crate) fn last_reading_depth(
        &self,
    ) -> (wgpu::RenderPassColorAttachment<'_>, wgpu::RenderPassDepthStencilAttachment<'_>) {
        let (color, depth) = self.second_of_two();
        (color, wgpu::RenderPassDepthStencilAttachment { depth_ops: None, stencil_ops: None, ..depth })
    }

    /// The depth aspect alone, to read in a shader; `None` unless the target
    /// was made for occlusion culling.
    pub(crate) fn depth_only_view(&self) -> Option<&wgpu::TextureView> {
        self.depth_only_view.as_ref()
    }

    /// The depth-stencil attachment, cleared to the far plane (1.0) and stencil 0.
    pub(crate) fn depth_attachment(&self) -> wgpu::RenderPassDepthStencilAttachment<'_> {
        self.depth_stencil(true, false)
    }

    /// The depth-stencil attachment: cleared (to the far plane, 1.0, and
    /// stencil 0) when `cleared`, else loaded; kept after the pass when
    /// `kept`, else discarded.
    pub(crate) fn depth_stencil(&self, cleared: bool, kept: bool) -> wgpu::RenderPassDepthStencilAttachment<'_> {
        use wgpu::{LoadOp, Operations, StoreOp};
        let store = if kept { StoreOp::Store } else { StoreOp::Discard };
        let (depth, stencil) =
            if cleared { (LoadOp::Clear(1.0), LoadOp::Clear(0)) } else { (LoadOp::Load, LoadOp::Load) };
        wgpu::RenderPassDepthStencilAttachment {
            view: &self.depth_view,
            depth_ops: Some(Operations { load: depth, store }),
            stencil_ops: Some(Operations { load: stencil, store }),
        }
    }

    /// Copy the last rendered frame back to the CPU as an RGBA8 (sRGB) image.
    ///
    /// Blocks until the GPU has finished the frame. Errors when the device
    /// cannot hold the copy or the map fails.
    pub fn read_rgba8(&self, gpu: &Gpu) -> Result<image::RgbaImage, GpuError> {
        let readback = self.start_readback(gpu);
        gpu.device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| GpuError::Readback(e.to_string()))?;
        // Another thread polling the same device may run the map's callback
        // just after this thread's wait returns.
        while !readback.poll(gpu) {
            std::thread::yield_now();
        }
        readback.finish()
    }

    /// Start copying the last rendered frame back to the CPU without waiting:
    /// poll the [`Readback`] until it is ready (the browser's way, where nothing
    /// may block), then finish it. The frame comes back in bands of rows, each
    /// buffer within the device's `max_buffer_size` (a 16384² frame is 1 GiB;
    /// the limit is usually 256 MiB).
    pub fn start_readback(&self, gpu: &Gpu) -> Readback {
        // Rows of a texture-to-buffer copy must be 256-byte aligned: pad, then strip.
        let unpadded = self.width * BYTES_PER_PIXEL;
        let padded = unpadded.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let band_rows =
            (gpu.device.limits().max_buffer_size / u64::from(padded)).clamp(1, u64::from(self.height)) as u32;
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("offscreen target: readback") });
        let scope = super::DriverErrors::watch(&gpu.device);
        let bands: Vec<(wgpu::Buffer, u32)> = (0..self.height)
            .step_by(band_rows as usize)
            .map(|first| {
                let rows = band_rows.min(self.height - first);
                let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("offscreen target: readback band"),
                    size: u64::from(padded) * u64::from(rows),
                    usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                    mapped_at_creation: false,
                });
                encoder.copy_texture_to_buffer(
                    wgpu::TexelCopyTextureInfo {
                        texture: &self.resolved,
                        mip_level: 0,
                        origin: wgpu::Origin3d { x: 0, y: first, z: 0 },
                        aspect: wgpu::TextureAspect::All,
                    },
                    wgpu::TexelCopyBufferInfo {
                        buffer: &buffer,
                        layout: wgpu::TexelCopyBufferLayout {
                            offset: 0,
                            bytes_per_row: Some(padded),
                            rows_per_image: Some(rows),
                        },
                    },
                    wgpu::Extent3d { width: self.width, height: rows, depth_or_array_layers: 1 },
                );
                (buffer, rows)
            })
            .collect();
        let failed =
            scope.finish().map(|e| format!("cannot make the readback buffers: {}", super::errors::describe(&e)));
        let mapped = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
        if failed.is_none() {
            gpu.queue.submit([encoder.finish()]);
            for (buffer, _) in &bands {
                let answer = mapped.clone();
                buffer.map_async(wgpu::MapMode::Read, .., move |r| {
                    answer.lock().unwrap_or_else(|e| e.into_inner()).push(r.map_err(|e| e.to_string()));
                });
            }
        }
        Readback { bands, width: self.width, height: self.height, padded, mapped, failed }
    }

    /// Read the frame back and write it to `path` as PNG. A write that fails
    /// (a full disk, `/dev/full`) is an error: the PNG is encoded in memory and
    /// written whole, so no buffered bytes are dropped unchecked.
    pub fn save_png(&self, gpu: &Gpu, path: impl AsRef<std::path::Path>) -> Result<(), GpuError> {
        let path = path.as_ref();
        let fail = |source| GpuError::Png { path: path.display().to_string(), source };
        let mut png = std::io::Cursor::new(Vec::new());
        self.read_rgba8(gpu)?.write_to(&mut png, image::ImageFormat::Png).map_err(fail)?;
        std::fs::write(path, png.into_inner()).map_err(|e| fail(image::ImageError::IoError(e)))
    }
}

/// A frame being copied back to the CPU ([`OffscreenTarget::start_readback`]).
pub struct Readback {
    /// Each band's buffer and rows, top to bottom.
    bands: Vec<(wgpu::Buffer, u32)>,
    width: u32,
    height: u32,
    /// Bytes per row in the buffers (rows are 256-byte aligned).
    padded: u32,
    /// Each band's map outcome, as the GPU answers.
    mapped: std::sync::Arc<std::sync::Mutex<Vec<Result<(), String>>>>,
    /// Why the copy could not start, if it could not.
    failed: Option<String>,
}

impl Readback {
    /// Let the device make progress without waiting; returns whether the copy
    /// has arrived (or failed to start).
    pub fn poll(&self, gpu: &Gpu) -> bool {
        let _ = gpu.device.poll(wgpu::PollType::Poll);
        self.failed.is_some() || self.mapped.lock().unwrap_or_else(|e| e.into_inner()).len() == self.bands.len()
    }

    /// The image, once [`Readback::poll`] says it has arrived (an error before).
    pub fn finish(self) -> Result<image::RgbaImage, GpuError> {
        if let Some(message) = self.failed {
            return Err(GpuError::Failed(message));
        }
        let answers = std::mem::take(&mut *self.mapped.lock().unwrap_or_else(|e| e.into_inner()));
        if answers.len() < self.bands.len() {
            return Err(GpuError::Readback("the copy has not arrived yet".into()));
        }
        answers.into_iter().collect::<Result<Vec<()>, _>>().map_err(GpuError::Readback)?;
        let unpadded = (self.width * BYTES_PER_PIXEL) as usize;
        let mut pixels = Vec::new();
        pixels.try_reserve_exact(unpadded * self.height as usize).map_err(|e| GpuError::Readback(e.to_string()))?;
        for (buffer, _) in &self.bands {
            let view = buffer.get_mapped_range(..).map_err(|e| GpuError::Readback(e.to_string()))?;
            for row in view.chunks_exact(self.padded as usize) {
                pixels.extend_from_slice(&row[..unpadded]);
            }
            drop(view);
            buffer.unmap();
        }
        image::RgbaImage::from_raw(self.width, self.height, pixels)
            .ok_or_else(|| GpuError::Readback("pixel count does not match the size".into()))
    }
}
