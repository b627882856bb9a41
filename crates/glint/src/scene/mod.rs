//! Beginner layer: the nouns a scene is made of.
//!
//! Everything here is plain data with no wgpu handles: a [`Mesh`] is vertices and
//! indices, a [`Material`] is numbers and texture ids, an [`Entity`] is a shape,
//! a material and a list of instance transforms. The [`Renderer`](crate::Renderer)
//! owns the GPU twins and turns submitted entities into draws.

mod camera;
pub mod cloth;
mod daylight;
pub mod emitter;
mod entity;
mod environment;
mod environment_image;
pub mod far_field;
mod fly;
pub mod level_cache;
pub mod levels;
mod light;
mod lighting;
mod material;
mod mesh;
mod motion;
mod post;
pub mod procedural;
pub mod school;
pub(crate) mod shadow_layout;
mod simulation;
mod states;
mod texture;
mod tiles;
mod view;
mod view_order;

pub use camera::{Camera, Projection};
pub use daylight::Daylight;
pub use entity::{Entity, MAX_COMPACT_HALF};
pub use environment::{Background, Environment, EnvironmentLight, EnvironmentSource, Fog};
pub use environment_image::{equirect_direction, equirect_uv, EnvironmentImage, MAX_RADIANCE};
pub use far_field::FarField;
pub use fly::{FlyCamera, FlyInput};
pub use light::{Light, LightKind, ShadowSettings, CASCADES, MAX_CLUSTERED_LIGHTS, MAX_LIGHTS};
pub use lighting::Lighting;
pub use material::{AlphaMode, MapSlots, Material, ShadingModel};
pub use mesh::{smooth_normals, smooth_normals_in_groups, Aabb, BoundingSphere, Mesh, MeshError, SkinVertex, Vertex};
pub use motion::{Motion, Wind, MAX_WIND};
pub use post::{PostEffect, SmaaPreset, Tonemap, MAX_POST_EFFECTS};
pub use procedural::ShapeKind;
pub use shadow_layout::{ShadowLayout, MAX_CUBES, MAX_SHADOW_MAP_BYTES};
pub use simulation::{PathCounts, SimPath, SimulationPaths};
pub use states::{
    BlendState, Compare, Cull, DepthState, ParticleBlend, RasterState, RenderStates, StencilOp, StencilState,
};
pub use texture::Texture;
pub use tiles::Tiles;

/// Most steps one pose may take for one simulation (a cloth, a school, an
/// emitter: `--time` over its `dt`): a later time is an error rather than
/// hours of stepping.
pub const MAX_POSE_STEPS: u64 = 100_000;
pub use view::{AmbientOcclusion, Culling, Transparency, View, Viewport, DEFAULT_LOD_ERROR};
pub use view_order::draw_order;

/// Handle to a shape (a mesh uploaded by the renderer), returned by
/// [`Renderer::add_shape`](crate::Renderer::add_shape). The number is its index
/// in the renderer (public for tools and benchmarks that build draw lists).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ShapeId(pub u32);

/// Handle to a material, returned by [`Renderer::add_material`](crate::Renderer::add_material).
/// The number is its index in the renderer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct MaterialId(pub u32);

/// Handle to a texture, returned by [`Renderer::add_texture`](crate::Renderer::add_texture).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TextureId(pub(crate) u32);

/// Handle to an environment image ([`EnvironmentImage`]):
/// unique in the process from the image's creation, so a scene's
/// [`Environment`] can name it before a renderer has it
/// ([`Registry::add_environment`](crate::render::Registry::add_environment)).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct EnvironmentId(pub(crate) u32);

/// Handle to a render target, returned by [`Renderer::add_render_target`](crate::Renderer::add_render_target):
/// a view can draw into it ([`View::output`]) and a material map can show it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct RenderTargetId(pub u32);
