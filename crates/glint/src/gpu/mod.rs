//! Core layer: the GPU device, its capabilities, and render targets.
//!
//! `gpu::` owns every wgpu handle that is not tied to one renderer: the
//! [`Gpu`] context (instance, adapter, device, queue) and the
//! [`OffscreenTarget`] a frame is drawn into and read back from, and the
//! [`WindowSurface`] that shows it in a window; and what GPU simulations and
//! the renderer share ([`GpuSimulation`], [`ParticleGpu`], compute helpers).

mod after_views;
mod blit;
mod context;
mod errors;
mod heap;
mod simulation;
mod submit;
mod target;
mod window;

pub use after_views::AfterViews;
pub(crate) use context::{read_buffer, read_buffers, refill};
pub use context::{Gpu, GpuError, WindowHandles};
pub use heap::keep_freed_heap_memory;
pub(crate) use simulation::{bind_buffers, buffers_layout, compute_pipeline};
pub use simulation::{GpuSimulation, InstanceRange, ParticleGpu, PlaceTargets, VertexTarget, MAX_LAYER_PARTICLES};
pub use target::{OffscreenTarget, Readback, TargetFormat};
pub use window::{SurfaceFrame, WindowSurface};

/// A headless GPU for unit tests; none (with a message) where no adapter
/// exists, unless `GLINT_REQUIRE_ADAPTER=1`.
#[cfg(test)]
pub(crate) fn test_gpu() -> Option<Gpu> {
    match Gpu::headless() {
        Ok(gpu) => Some(gpu),
        Err(e) if std::env::var("GLINT_REQUIRE_ADAPTER").as_deref() == Ok("1") => panic!("{e}"),
        Err(e) => {
            eprintln!("skipping GPU test: {e}");
            None
        }
    }
}

pub(crate) use blit::{full_screen_pipeline, full_screen_pipeline_with, Blitter};
pub(crate) use blit::{sampler_entry, storage_entry, texture_entry};
pub(crate) use errors::{DriverErrors, UncapturedErrors};
pub(crate) use submit::SubmitQueue;

/// Colour format of every glint target: 8-bit sRGB, so shaders write linear values
/// and the hardware encodes them.
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// Colour format of a view drawn for a post-processing chain: linear half floats,
/// so light brighter than 1 survives until tonemapping.
pub const HDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Depth-stencil format of every glint target (stencil for materials' `StencilState`).
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth24PlusStencil8;
