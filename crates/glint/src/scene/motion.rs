//! Core layer: vertex animation a material gives its instances, computed in
//! the vertex shader from the scene time ([`Environment::time`]), in every
//! view and shadow view; each kind is a shader-variant bit (`WIND`, `FLAP`,
//! `CIRCLE`, `SWIM`). A per-instance phase comes from a hash of the
//! instance's placed position, so instances of one draw do not move in
//! lockstep and no instance data is added; a swimming fish's tail follows the
//! phase its entity gives it ([`Entity::phases`](crate::Entity::phases)). The culler's boxes grow to cover the motion ([`Motion::reach`]).
//!
//! [`Environment::time`]: super::Environment::time

use super::Aabb;
use glam::{Vec2, Vec3};

/// Strongest wind the bounds allow for: [`Wind::strength`] is clamped to it.
pub const MAX_WIND: f32 = 2.0;

/// How far a swaying vertex reaches at most, as a multiple of its sway at
/// wind strength 1: the shader's gust (0.6 + 0.4 + 0.15) at [`MAX_WIND`].
const WIND_REACH: f32 = 1.15 * MAX_WIND;

/// The world's wind, which bends [`Motion::Wind`] materials.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wind {
    /// Direction in the ground plane (x, z), normalised when used.
    pub direction: Vec2,
    /// 0 (still) to [`MAX_WIND`]; 1 is a breeze.
    pub strength: f32,
}

impl Default for Wind {
    fn default() -> Self {
        Self { direction: Vec2::X, strength: 1.0 }
    }
}

impl Wind {
    /// Unit direction times clamped strength, as the Scene block holds it.
    pub(crate) fn to_gpu(self) -> [f32; 3] {
        let d = self.direction.try_normalize().unwrap_or(Vec2::X);
        let s = if self.strength.is_finite() { self.strength.clamp(0.0, MAX_WIND) } else { 0.0 };
        [s, d.x, d.y]
    }
}

/// How a material's vertices move with time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Motion {
    /// Grass in the world's wind: a vertex `h` object units above `base` moves
    /// `sway · h²` (object units, scaled with the instance) along the wind,
    /// times the wind's strength and a gust that varies with time, per-instance
    /// phase and a noise term.
    Wind {
        /// Tip travel per squared unit of height at wind strength 1.
        sway: f32,
        /// Object-space height of the model's base, which stays put.
        base: f32,
    },
    /// Wings: a vertex `d` object units from the model's YZ plane (|x|) swings
    /// up and down by `amplitude · d` (so the body stays and the tips move
    /// most), `rate` times a second, rate and phase varied per instance.
    Flap {
        /// Height change per unit of |x| at the top of a beat.
        amplitude: f32,
        /// Beats per second.
        rate: f32,
    },
    /// Walks a circle around its placed position, facing along its path:
    /// radius from `radius.x` to `radius.y` world units and clockwise or
    /// counter-clockwise per instance, at `speed` world units a second.
    Circle {
        /// Smallest and largest radius.
        radius: Vec2,
        /// World units a second along the circle.
        speed: f32,
    },
    /// A fish's tail: a vertex `d = pivot − z` object units behind the pivot
    /// (the model faces +Z) swings sideways (x) by `amplitude · d²` times a
    /// wave `sin(2π·phase − 2·d)` running down the body, where `phase` is the
    /// instance's own ([`Entity::phases`](crate::Entity::phases)): a school
    /// beats each fish's tail at its own pace.
    Swim {
        /// Sideways travel per squared unit behind the pivot.
        amplitude: f32,
        /// Object-space z in front of which nothing moves.
        pivot: f32,
    },
}

impl Motion {
    /// Its three parameters as the material block holds them.
    pub(crate) fn params(self) -> [f32; 3] {
        match self {
            Self::Wind { sway, base } => [sway, base, 0.0],
            Self::Flap { amplitude, rate } => [amplitude, rate, 0.0],
            Self::Circle { radius, speed } => [radius.x, radius.y, speed],
            Self::Swim { amplitude, pivot } => [amplitude, pivot, 0.0],
        }
    }

    /// How far the motion takes a model whose local box is `local`: that box
    /// grown in object space, and a distance every world box grows in x and z
    /// (a walk's largest radius; its boxes also grow to any heading).
    pub fn reach(self, local: Aabb) -> (Aabb, f32) {
        match self {
            Self::Wind { sway, base } => {
                let h = (local.max.y - base).max(0.0);
                let d = WIND_REACH * sway.abs() * h * h;
                (Aabb { min: local.min - Vec3::new(d, 0.0, d), max: local.max + Vec3::new(d, 0.0, d) }, 0.0)
            }
            Self::Flap { amplitude, .. } => {
                let d = amplitude.abs() * local.min.x.abs().max(local.max.x.abs());
                (Aabb { min: local.min - Vec3::Y * d, max: local.max + Vec3::Y * d }, 0.0)
            }
            Self::Circle { radius, .. } => (local, radius.x.abs().max(radius.y.abs())),
            Self::Swim { amplitude, pivot } => {
                let behind = (pivot - local.min.z).max(0.0);
                let d = amplitude.abs() * behind * behind;
                (Aabb { min: local.min - Vec3::X * d, max: local.max + Vec3::X * d }, 0.0)
            }
        }
    }
}
