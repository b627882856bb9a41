//! Core layer: the sun and sky at an hour of the day, as the vegetation
//! demo's time-of-day control moves them together: the sun rises in the east
//! (+x) at 6, stands 65° high in the south (+z) at noon and sets in the west
//! at 18; its light reddens near the horizon and fades out below it; the sky
//! goes from night through dusk to day; the glare follows the sun (it is drawn
//! in the first directional light's direction and colour).

use glam::Vec3;

/// The sun and sky at one hour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Daylight {
    /// The direction the sunlight travels (from the sun to the ground), unit.
    pub sun_direction: Vec3,
    /// The sun's linear colour.
    pub sun_color: Vec3,
    /// The sun's intensity: 0 below the horizon.
    pub sun_intensity: f32,
    /// The sky straight up and at the horizon.
    pub sky_top: Vec3,
    /// See `sky_top`.
    pub sky_bottom: Vec3,
    /// Ambient light.
    pub ambient: Vec3,
}

/// The sun's height at noon, in degrees.
const NOON_ELEVATION: f32 = 65.0;

impl Daylight {
    /// The sun and sky at `hours` (taken modulo 24; NaN counts as noon).
    pub fn at(hours: f32) -> Self {
        let hours = if hours.is_finite() { hours.rem_euclid(24.0) } else { 12.0 };
        // 0 at sunrise, π at sunset; the sun is below the horizon the other half of the day.
        let angle = std::f32::consts::PI * (hours - 6.0) / 12.0;
        let tilt = NOON_ELEVATION.to_radians();
        let to_sun = Vec3::new(angle.cos(), angle.sin() * tilt.sin(), angle.sin() * tilt.cos()).normalize();
        let height = to_sun.y;
        let smooth = |lo: f32, hi: f32, x: f32| {
            let t = ((x - lo) / (hi - lo)).clamp(0.0, 1.0);
            t * t * (3.0 - 2.0 * t)
        };
        let (day, lit) = (smooth(0.05, 0.45, height), smooth(-0.15, 0.05, height));
        let warm = Vec3::new(1.0, 0.5, 0.25);
        let white = Vec3::new(1.0, 0.96, 0.9);
        let sky = |night: Vec3, dusk: Vec3, noon: Vec3| night.lerp(dusk, lit).lerp(noon, day);
        Self {
            sun_direction: -to_sun,
            sun_color: warm.lerp(white, smooth(0.0, 0.5, height)),
            sun_intensity: 1.3 * smooth(-0.02, 0.12, height),
            sky_top: sky(Vec3::new(0.01, 0.015, 0.04), Vec3::new(0.2, 0.25, 0.5), Vec3::new(0.22, 0.45, 0.85)),
            sky_bottom: sky(Vec3::new(0.03, 0.03, 0.07), Vec3::new(0.95, 0.5, 0.3), Vec3::new(0.72, 0.83, 0.95)),
            ambient: Vec3::splat(0.04).lerp(Vec3::splat(0.28), lit),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sun_rises_in_the_east_stands_south_at_noon_and_is_gone_at_night() {
        let (dawn, noon, dusk, night) = (Daylight::at(6.5), Daylight::at(12.0), Daylight::at(17.5), Daylight::at(0.0));
        assert!(dawn.sun_direction.x < -0.9, "light travels west from an eastern sun: {:?}", dawn.sun_direction);
        assert!(dusk.sun_direction.x > 0.9);
        let elevation = (-noon.sun_direction.y).asin().to_degrees();
        assert!((elevation - NOON_ELEVATION).abs() < 1e-3, "{elevation}");
        assert!(noon.sun_direction.z < 0.0, "a southern (+z) noon sun shines toward -z");
        assert_eq!(night.sun_intensity, 0.0);
        assert!(noon.sun_intensity > 1.2 && dawn.sun_intensity > 0.0);
        assert!(dawn.sun_color.z < 0.7 * noon.sun_color.z, "red near the horizon");
        assert!(night.sky_top.length() < 0.1 && noon.sky_top.z > 0.8);
        assert!(dusk.sky_bottom.x > dusk.sky_bottom.z, "a warm horizon at dusk");
        assert_eq!(Daylight::at(36.0), Daylight::at(12.0), "hours wrap");
        // Continuous: no jump between minutes anywhere in the day.
        for m in 0..24 * 60 {
            let (a, b) = (Daylight::at(m as f32 / 60.0), Daylight::at((m + 1) as f32 / 60.0));
            assert!((a.sun_direction - b.sun_direction).length() < 0.01);
            assert!((a.sky_bottom - b.sky_bottom).length() < 0.05, "{m}");
        }
    }
}
