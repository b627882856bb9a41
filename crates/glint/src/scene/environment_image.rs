//! Beginner layer: [`EnvironmentImage`], an equirectangular environment for
//! image-based lighting: decoded from Radiance `.hdr` or OpenEXR files by
//! `asset`, or made here (glint's sky, a studio, a uniform colour).
//!
//! ## The equirectangular convention (written once, here)
//! Texel coordinates (u, v) in 0..1, v down the image. The azimuth is
//! φ = 2π (u − ½), the angle from straight up is θ = π v, and the direction is
//! (sin θ sin φ, cos θ, −sin θ cos φ): the image's middle column looks along −Z
//! (a default camera's forward), its right quarter along +X, its top row up.
//! `shader/equirect.wgsl` holds the same mapping for the shaders.

use crate::scene::EnvironmentId;
use glam::Vec3;
use image::Rgb32FImage;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

/// The largest value an environment texel keeps: the largest half float (the
/// GPU copy's format), so a hot sun cannot overflow to infinity.
pub const MAX_RADIANCE: f32 = 65504.0;

/// An equirectangular environment in linear RGB (module doc: the convention),
/// every texel finite and in 0..=[`MAX_RADIANCE`]. Cloning shares the pixels.
#[derive(Clone, Debug)]
pub struct EnvironmentImage {
    id: EnvironmentId,
    /// What it is called in messages (the file name).
    pub name: String,
    pixels: Arc<Rgb32FImage>,
}

impl EnvironmentImage {
    /// An environment of `pixels` (non-finite and negative values become 0,
    /// values past [`MAX_RADIANCE`] are clamped), with a new id.
    pub fn new(name: impl Into<String>, mut pixels: Rgb32FImage) -> Self {
        for v in pixels.iter_mut() {
            *v = if v.is_finite() { v.clamp(0.0, MAX_RADIANCE) } else { 0.0 };
        }
        static NEXT: AtomicU32 = AtomicU32::new(0);
        let id = EnvironmentId(NEXT.fetch_add(1, Ordering::Relaxed));
        Self { id, name: name.into(), pixels: Arc::new(pixels) }
    }

    /// A `width` × `height` environment whose radiance in each texel's
    /// direction is `radiance(direction)`.
    pub fn from_fn(name: &str, width: u32, height: u32, radiance: impl Fn(Vec3) -> Vec3) -> Self {
        let pixels = Rgb32FImage::from_fn(width.max(1), height.max(1), |x, y| {
            let uv = [(x as f32 + 0.5) / width as f32, (y as f32 + 0.5) / height as f32];
            image::Rgb(radiance(equirect_direction(uv)).to_array())
        });
        Self::new(name, pixels)
    }

    /// The same radiance from every direction (the white furnace).
    pub fn uniform(radiance: Vec3) -> Self {
        Self::from_fn("uniform", 8, 4, |_| radiance)
    }

    /// A sky: the gradient glint's sky draws (`top` straight up, `bottom` at
    /// the horizon and below), with a soft glow of `sun` (direction the light
    /// travels, and its colour × intensity) around the sun. The sun itself
    /// stays a light, so it is not lit twice.
    pub fn sky(top: Vec3, bottom: Vec3, sun: Option<(Vec3, Vec3)>) -> Self {
        Self::from_fn("sky", 128, 64, |d| {
            let t = smoothstep(0.0, 0.6, d.y);
            let glow = sun.map_or(Vec3::ZERO, |(dir, color)| {
                let c = d.dot(-dir.normalize_or_zero()).max(0.0);
                color * (0.25 * c.powi(12)) * smoothstep(-0.1, 0.05, d.y)
            });
            bottom.lerp(top, t) + glow
        })
    }

    /// A neutral studio like glTF viewers light models with: a soft grey dome
    /// over a darker floor, a large key light and a dimmer fill.
    pub fn studio() -> Self {
        let key = Vec3::new(-0.5, 0.6, 0.62).normalize();
        let fill = Vec3::new(0.7, 0.3, -0.65).normalize();
        Self::from_fn("studio", 256, 128, |d| {
            let dome = Vec3::splat(0.35).lerp(Vec3::splat(0.8), smoothstep(-0.2, 0.8, d.y));
            let floor = Vec3::splat(0.18) * (1.0 - smoothstep(-0.05, 0.0, d.y));
            let dome = dome * smoothstep(-0.05, 0.0, d.y) + floor;
            let lamp =
                |axis: Vec3, size: f32, power: f32| power * smoothstep(1.0 - size, 1.0 - 0.6 * size, d.dot(axis));
            dome + Vec3::splat(lamp(key, 0.08, 6.0) + lamp(fill, 0.12, 1.5))
        })
    }

    /// Its handle.
    pub fn id(&self) -> EnvironmentId {
        self.id
    }

    /// The pixels.
    pub fn pixels(&self) -> &Rgb32FImage {
        &self.pixels
    }

    /// Radiance toward `direction` (nearest texel).
    pub fn radiance(&self, direction: Vec3) -> Vec3 {
        let [u, v] = equirect_uv(direction);
        let (w, h) = self.pixels.dimensions();
        let x = ((u * w as f32) as u32).min(w - 1);
        let y = ((v * h as f32) as u32).min(h - 1);
        Vec3::from_array(self.pixels.get_pixel(x, y).0)
    }
}

/// The unit direction at equirectangular texel coordinates `uv` (module doc).
pub fn equirect_direction([u, v]: [f32; 2]) -> Vec3 {
    let phi = std::f32::consts::TAU * (u - 0.5);
    let theta = std::f32::consts::PI * v;
    Vec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos())
}

/// The equirectangular texel coordinates of `direction` (module doc).
pub fn equirect_uv(direction: Vec3) -> [f32; 2] {
    let d = direction.normalize_or(Vec3::Y);
    let u = d.x.atan2(-d.z) / std::f32::consts::TAU + 0.5;
    let v = d.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
    [u, v]
}

fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_convention_maps_directions_and_texels_both_ways() {
        // The middle looks along -Z, the right quarter along +X, the top up.
        assert!(equirect_direction([0.5, 0.5]).abs_diff_eq(Vec3::NEG_Z, 1e-6));
        assert!(equirect_direction([0.75, 0.5]).abs_diff_eq(Vec3::X, 1e-6));
        assert!(equirect_direction([0.25, 0.5]).abs_diff_eq(Vec3::NEG_X, 1e-6));
        assert!(equirect_direction([0.3, 0.0]).abs_diff_eq(Vec3::Y, 1e-6));
        for uv in [[0.1, 0.2], [0.6, 0.7], [0.9, 0.45]] {
            let back = equirect_uv(equirect_direction(uv));
            assert!((back[0] - uv[0]).abs() < 1e-5 && (back[1] - uv[1]).abs() < 1e-5, "{uv:?} -> {back:?}");
        }
    }

    #[test]
    fn hostile_values_are_made_finite_and_in_range() {
        let pixels = Rgb32FImage::from_raw(2, 1, vec![f32::NAN, -1.0, f32::INFINITY, 1e9, 0.5, 2.0]).unwrap();
        let env = EnvironmentImage::new("hostile", pixels);
        assert_eq!(env.pixels().as_raw(), &[0.0, 0.0, 0.0, MAX_RADIANCE, 0.5, 2.0]);
        assert_ne!(env.id(), EnvironmentImage::uniform(Vec3::ONE).id(), "each image its own id");
    }
}
