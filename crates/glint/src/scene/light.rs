//! Beginner layer: [`Light`], a directional, point or spot light, and its
//! [`ShadowSettings`] (at most [`MAX_LIGHTS`] a frame, or
//! [`MAX_CLUSTERED_LIGHTS`] with light clusters).

use glam::Vec3;

/// Most lights one frame without light clusters can use, and most
/// directional lights with them: they live in one uniform block
/// (`@group(0)`); [`Renderer::flush`](crate::Renderer::flush) returns an error past this.
pub const MAX_LIGHTS: usize = 64;

/// Most lights a frame with light clusters may have (`render/clusters.rs`):
/// its point and spot lights are in each view's light table, its directional
/// lights (at most [`MAX_LIGHTS`]) in the Scene block.
pub const MAX_CLUSTERED_LIGHTS: usize = 4096;

/// What kind of light, with its geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Parallel light travelling along `direction` (like the sun).
    Directional {
        /// Direction the light travels (normalised when uploaded).
        direction: Vec3,
    },
    /// Light radiating from `position`, fading smoothly to zero at `range`.
    Point {
        /// World position.
        position: Vec3,
        /// Distance at which the light reaches zero.
        range: f32,
    },
    /// A point light limited to a cone: full inside `inner_angle` of `direction`,
    /// fading smoothly to nothing at `outer_angle` (half-angles, radians).
    Spot {
        /// World position.
        position: Vec3,
        /// Direction the cone points (normalised when uploaded).
        direction: Vec3,
        /// Distance at which the light reaches zero.
        range: f32,
        /// Half-angle of the fully lit cone.
        inner_angle: f32,
        /// Half-angle where the light reaches zero (at most π/2).
        outer_angle: f32,
    },
}

/// How a light casts shadows (see [`Light::with_shadows`]).
///
/// A directional light gets [`CASCADES`] cascaded maps of `map_size`² texels
/// covering the camera's view out to `distance`; a spot light one map; a point
/// light a cube of six faces storing distance. Biases are in shadow-map texels,
/// so the defaults hold at any map size and scene scale: the receiving point is
/// moved `normal_bias` texels along its normal before the lookup, and the stored
/// depth is pushed away by `depth_bias` texels of depth slope (plus a fixed
/// slope-scaled bias in the shadow pipelines).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowSettings {
    /// Width and height of each shadow map, in texels (16..=8192).
    pub map_size: u32,
    /// Depth bias, in texels (default 1).
    pub depth_bias: f32,
    /// Normal offset, in texels (default 1.5).
    pub normal_bias: f32,
    /// Directional lights: how far from the camera the cascades reach; `None`
    /// uses the camera's far plane.
    pub distance: Option<f32>,
    /// The light's size, for soft shadows (percentage-closer soft shadows:
    /// penumbrae that widen with the distance from caster to receiver): a
    /// directional light's angular diameter in degrees (the sun's is about
    /// 0.53), a spot light's radius in world units. 0, the default, keeps the
    /// 3×3 filter; point lights keep it whatever their size.
    pub light_size: f32,
}

impl Default for ShadowSettings {
    fn default() -> Self {
        Self { map_size: 1024, depth_bias: 1.0, normal_bias: 1.5, distance: None, light_size: 0.0 }
    }
}

impl ShadowSettings {
    /// Whether `kind`'s shadows are soft with these settings: a directional
    /// or spot light with a size.
    pub fn soft(&self, kind: &LightKind) -> bool {
        self.light_size > 0.0 && !matches!(kind, LightKind::Point { .. })
    }
}

/// Cascades of a directional light's shadow.
pub const CASCADES: usize = 4;

/// A light: kind, linear colour and intensity, and whether it casts shadows.
///
/// Point lights fall off as `intensity / d² · (1 − (d/range)⁴)²` (clamped), which
/// reaches exactly zero at `range`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Directional or point, with its geometry.
    pub kind: LightKind,
    /// Linear RGB colour.
    pub color: Vec3,
    /// Scale of the colour.
    pub intensity: f32,
    /// Shadow maps, when the light casts shadows (drawn by
    /// [`Renderer::shadow_pass`](crate::Renderer::shadow_pass)).
    pub shadows: Option<ShadowSettings>,
}

impl Light {
    /// A white-ish directional light travelling along `direction`.
    pub fn directional(direction: Vec3, color: Vec3, intensity: f32) -> Self {
        Self { kind: LightKind::Directional { direction }, color, intensity, shadows: None }
    }

    /// The same light casting shadows with `settings`.
    pub fn with_shadows(mut self, settings: ShadowSettings) -> Self {
        self.shadows = Some(settings);
        self
    }

    /// A spot light at `position` pointing along `direction`, full within
    /// `inner_angle` and reaching zero at `outer_angle` (half-angles, radians) and at `range`.
    pub fn spot(
        position: Vec3,
        direction: Vec3,
        color: Vec3,
        intensity: f32,
        range: f32,
        (inner_angle, outer_angle): (f32, f32),
    ) -> Self {
        Self {
            kind: LightKind::Spot { position, direction, range, inner_angle, outer_angle },
            color,
            intensity,
            shadows: None,
        }
    }

    /// A point light at `position` reaching zero at `range`.
    pub fn point(position: Vec3, color: Vec3, intensity: f32, range: f32) -> Self {
        Self { kind: LightKind::Point { position, range }, color, intensity, shadows: None }
    }
}
