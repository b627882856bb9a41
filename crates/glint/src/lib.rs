//! # glint
//!
//! A real-time 3D renderer on wgpu, built to be read. A beginner layer over a
//! core layer:
//!
//! - **Beginner layer** ([`scene`]): [`Mesh`], [`Material`], [`Entity`], [`Light`],
//!   [`Camera`] — plain data, no wgpu.
//! - **Core layer**: the [`Gpu`] context and targets ([`gpu`]) and the WGSL
//!   composed when glint is built (`shader`); above them, loaders that never
//!   trust a file ([`asset`]), the simulations ([`sim`]: cloth, schools,
//!   particles) and the [`Renderer`] with its sort keys, batching and shader
//!   data blocks ([`render`]); on top, a [`World`]: a loaded scene placed in a
//!   renderer and run ([`world`]). `DESIGN.md` in the repository keeps the
//!   table of what may import what.
//!
//! A frame is one call, [`Renderer::render_frame`], given a [`FrameInput`]
//! (entities, views, lighting, GPU simulations); the seed's calls, in Tiny
//! Graphics' program structure, are a thin layer over it:
//!
//! ```no_run
//! use glint::{asset::ShapeKind, Camera, Entity, Gpu, Light, Material, OffscreenTarget, Renderer};
//! use glam::{Mat4, Vec3};
//!
//! let gpu = Gpu::headless()?;
//! let mut renderer = Renderer::new(&gpu);
//! let cube = renderer.add_shape(ShapeKind::Cube.mesh());
//! let red = renderer.add_material(Material::color("red", 0.8, 0.1, 0.1));
//! let entity = Entity::new(cube, red, Mat4::IDENTITY);
//! let camera = Camera::perspective(60.0, 0.1, 100.0).looking_at(Vec3::new(2.0, 2.0, 3.0), Vec3::ZERO);
//! let lights = [Light::directional(Vec3::new(-1.0, -2.0, -1.0), Vec3::ONE, 2.0)];
//! let mut target = OffscreenTarget::new(&gpu, 256, 256, 4)?;
//!
//! renderer.submit(&entity);
//! let shadows = renderer.shadow_pass(&camera, &lights, &target)?;
//! let stats = renderer.flush(&camera, &lights, &shadows, &mut target)?;
//! assert_eq!(stats.draw_calls, 1);
//! target.save_png(&gpu, "cube.png")?;
//! # Ok::<(), glint::Error>(())
//! ```

#![warn(missing_docs)]

pub mod asset;
#[cfg(not(target_arch = "wasm32"))]
pub mod compare;
pub mod gpu;
pub mod render;
pub mod scene;
mod shader;
pub mod sim;
pub mod text;
pub mod world;

pub use asset::{Diagnostic, Texture};
pub use gpu::{AfterViews, Gpu, GpuError, OffscreenTarget, SurfaceFrame, WindowSurface};
pub use render::{FrameInput, FrameMode, FrameOutput, FrameStats, RenderError, Renderer, Shadows, SubFrame, ViewKey};
pub use scene::{
    AlphaMode, AmbientOcclusion, Background, Camera, Culling, Entity, Environment, Light, Lighting, Material,
    MaterialId, Mesh, RenderTargetId, ShadowSettings, ShapeId, TextureId, Tiles, View, Viewport,
};
pub use world::World;

/// Any glint error, with the process exit code the CLI uses for it.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Bad input file (exit code 1).
    #[error(transparent)]
    Asset(#[from] Diagnostic),
    /// No adapter or device (exit code 2); other GPU failures (exit code 3).
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// Invalid frame request (exit code 3).
    #[error(transparent)]
    Render(#[from] RenderError),
    /// A simulation step failed (exit code 3).
    #[error(transparent)]
    Sim(#[from] sim::cloth::StepError),
    /// A scene's simulation failed while it was posed (exit code 3): where in
    /// the scene, and why.
    #[error("{place}: {source}")]
    Posing {
        /// The scene, the block's line and what it was doing.
        place: Diagnostic,
        /// Why the step failed.
        source: sim::cloth::StepError,
    },
}

impl Error {
    /// Exit code for the CLI: 1 bad input, 2 no GPU adapter, 3 other failures.
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Asset(_) => 1,
            Error::Gpu(GpuError::NoAdapter(_) | GpuError::Device { .. }) => 2,
            Error::Gpu(_) | Error::Render(_) | Error::Sim(_) | Error::Posing { .. } => 3,
        }
    }
}
