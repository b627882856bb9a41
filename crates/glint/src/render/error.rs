//! Core layer: [`RenderError`], what a frame can fail with.

use crate::scene::MAX_POST_EFFECTS;
use crate::scene::{MaterialId, RenderTargetId, ShapeId, TextureId, Viewport};

/// Errors from [`Renderer::flush`](crate::Renderer::flush).
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// More lights than a frame can use: the Scene block's
    /// [`MAX_LIGHTS`](crate::scene::MAX_LIGHTS) directional lights, or lights in
    /// all without light clusters; [`MAX_CLUSTERED_LIGHTS`](crate::render::clusters::MAX_CLUSTERED_LIGHTS) with them.
    #[error("{given} {what} given, but a frame can use at most {most}")]
    TooManyLights {
        /// How many were given.
        given: usize,
        /// What they are: "lights", "directional lights" or "lights with light clusters off".
        what: &'static str,
        /// The most a frame can use.
        most: usize,
    },
    /// An entity names a shape this renderer never created.
    #[error("unknown shape id {0:?}: shapes come from this renderer's add_shape")]
    UnknownShape(ShapeId),
    /// The environment names an image this renderer was never given.
    #[error("unknown environment {0:?}: environment images come from this renderer's add_environment")]
    UnknownEnvironment(crate::scene::EnvironmentId),
    /// An entity names a material this renderer never created.
    #[error("unknown material id {0:?}: materials come from this renderer's add_material")]
    UnknownMaterial(MaterialId),
    /// One of glint's own shaders failed to compose (a bug in glint).
    #[error(transparent)]
    Shader(#[from] crate::shader::ShaderError),
    /// A shape too large for one GPU buffer.
    #[error("shape {shape:?}: {source}")]
    MeshTooLarge {
        /// The shape.
        shape: ShapeId,
        /// Its size and the limit.
        source: MeshTooLarge,
    },
    /// A GPU resource the frame needs is larger than glint or the adapter allows.
    #[error("{what} needs {bytes} bytes, more than the {limit}-byte limit ({limit_name})")]
    TooLarge {
        /// The resource.
        what: &'static str,
        /// What it needs.
        bytes: u64,
        /// The most allowed.
        limit: u64,
        /// Which limit that is.
        limit_name: &'static str,
    },
    /// A view asks for something this adapter cannot draw.
    #[error("{what} is not available on this adapter: {why}")]
    Unavailable {
        /// What was asked for.
        what: &'static str,
        /// Why not, and what to use instead.
        why: &'static str,
    },
    /// A frame would make more of something than glint allows.
    #[error("{what} would make {count}, more than the {limit} glint allows (docs/limits.md)")]
    TooMany {
        /// What is counted.
        what: &'static str,
        /// How many the frame would make.
        count: u64,
        /// The most allowed.
        limit: u64,
    },
    /// A texture wider or taller than the adapter allows.
    #[error("texture '{name}' is {width} x {height}, larger than this adapter's {side} texels a side (max_texture_dimension_2d)")]
    TextureTooLarge {
        /// The texture's name.
        name: String,
        /// Its size.
        width: u32,
        /// Its size.
        height: u32,
        /// The adapter's largest side.
        side: u32,
    },
    /// The device refused to create a resource (out of memory, or a limit). The
    /// renderer may hold a broken resource afterwards: make a new one.
    #[error("the GPU could not create {what}: {message}")]
    Device {
        /// The resource.
        what: &'static str,
        /// What wgpu said.
        message: String,
    },
    /// A flush was given shadow maps drawn for an earlier frame.
    #[error("the shadow maps given to flush were drawn for an earlier frame: call shadow_pass again each frame")]
    StaleShadows,
    /// A flush was given shadow maps drawn for another view or other lights.
    #[error("the shadow maps given to flush were drawn for another view or other lights")]
    ShadowsForOtherView,
    /// A view's viewport is empty or reaches outside the target.
    #[error("viewport {0:?} is not a non-empty rectangle inside 0..1")]
    BadViewport(Viewport),
    /// A sub-frame of an accumulated still that does not follow the one before
    /// it for the same view ([`SubFrame`](crate::render::SubFrame)).
    #[error("sub-frame {index} of {count}: {why}")]
    SubFrameOutOfOrder {
        /// Its index.
        index: u32,
        /// The still's sub-frames.
        count: u32,
        /// What was expected.
        why: String,
    },
    /// A view draws into a render target this renderer never created.
    #[error("unknown render target {0:?}: render targets come from this renderer's add_render_target")]
    UnknownRenderTarget(RenderTargetId),
    /// Views that each show another's render target, round in a circle.
    #[error("views draw render targets that each need another's first: a cycle")]
    RenderTargetCycle,
    /// A view's post chain has more effects than glint runs.
    #[error("a post chain of {0} effects; at most {MAX_POST_EFFECTS}")]
    PostChainTooLong(usize),
    /// A material names a texture this renderer never created.
    #[error("material '{material}' uses unknown texture id {texture:?}")]
    UnknownTexture {
        /// The material's name.
        material: String,
        /// The bad id.
        texture: TextureId,
    },
}

/// Why a mesh could not be placed.
#[derive(Debug, thiserror::Error)]
#[error("mesh of {bytes} bytes is larger than the device's largest buffer ({max} bytes)")]
pub struct MeshTooLarge {
    /// The largest stream of the mesh, in bytes.
    pub bytes: u64,
    /// The device limit.
    pub max: u64,
}
