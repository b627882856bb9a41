//! Beginner layer: render-state objects. Plain values describing how a material's
//! fragments meet the target: blending, depth, stencil and rasterization. They are
//! part of the pipeline key, so two materials with equal states share pipelines.

/// How a fragment's colour combines with the target.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BlendState {
    /// Overwrite (opaque).
    #[default]
    Replace,
    /// `src·α + dst·(1−α)`: ordinary transparency.
    Alpha,
    /// `src·α + dst`: glows, fire, light shafts.
    Additive,
    /// `src · dst`: tinting what is behind.
    Multiply,
}

/// Comparison used by depth and stencil tests.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Compare {
    /// Never passes.
    Never,
    /// New < stored.
    Less,
    /// New ≤ stored.
    LessEqual,
    /// New == stored.
    Equal,
    /// New ≥ stored.
    GreaterEqual,
    /// New > stored.
    Greater,
    /// New != stored.
    NotEqual,
    /// Always passes.
    Always,
}

/// Depth testing and writing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DepthState {
    /// Test against the depth buffer with this comparison (`Always` turns testing off).
    pub compare: Compare,
    /// Write the fragment's depth.
    pub write: bool,
}

impl Default for DepthState {
    fn default() -> Self {
        Self { compare: Compare::Less, write: true }
    }
}

/// What a stencil test does to the stored value.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum StencilOp {
    /// Leave it.
    #[default]
    Keep,
    /// Set it to 0.
    Zero,
    /// Set it to the reference value.
    Replace,
    /// Add 1, stopping at 255.
    IncrementClamp,
    /// Subtract 1, stopping at 0.
    DecrementClamp,
    /// Flip its bits.
    Invert,
}

/// Stencil testing (both faces alike). The default always passes and writes nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct StencilState {
    /// Test: `reference (compare) stored`, both masked by `read_mask`.
    pub compare: Compare,
    /// On pass (stencil and depth).
    pub pass: StencilOp,
    /// On stencil failure.
    pub fail: StencilOp,
    /// On stencil pass but depth failure.
    pub depth_fail: StencilOp,
    /// Bits read by the test.
    pub read_mask: u8,
    /// Bits written.
    pub write_mask: u8,
    /// The reference value, set per draw.
    pub reference: u8,
}

impl Default for StencilState {
    fn default() -> Self {
        Self {
            compare: Compare::Always,
            pass: StencilOp::Keep,
            fail: StencilOp::Keep,
            depth_fail: StencilOp::Keep,
            read_mask: 0xff,
            write_mask: 0,
            reference: 0,
        }
    }
}

/// Which faces are dropped before shading.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Cull {
    /// Drop faces seen from behind (counter-clockwise faces are the front).
    #[default]
    Back,
    /// Drop faces seen from the front.
    Front,
    /// Draw both sides.
    None,
}

/// Rasterization: face culling and depth bias.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct RasterState {
    /// Faces to drop.
    pub cull: Cull,
    /// Constant depth bias, in depth-buffer units.
    pub depth_bias: i32,
    /// Depth bias scaled by the polygon's slope, as `f32::to_bits` (so the state stays hashable).
    pub slope_bias_bits: u32,
}

/// All four state objects of a material.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct RenderStates {
    /// Blending.
    pub blend: BlendState,
    /// Depth test and write.
    pub depth: DepthState,
    /// Stencil test.
    pub stencil: StencilState,
    /// Culling and depth bias.
    pub raster: RasterState,
}

/// How a particle layer's billboards blend into the picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ParticleBlend {
    /// Added to what is behind (fire, sparks, glow): no order needed.
    Additive,
    /// Over what is behind by their alpha (smoke, bubbles): written back to front.
    Alpha,
}
