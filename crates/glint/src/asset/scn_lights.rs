//! `.scn` light blocks: `light_directional`, `light_point` and `light_spot`,
//! with their shadow keys (see `docs/scn.md`).

use super::scn_fields::{numbers, Fields};
use super::Diagnostic;
use crate::scene::{Light, ShadowSettings};
use glam::Vec3;

/// The light a `light_*` block describes; `class` is its classname, known to be
/// one of the three. Shadow keys on a light without `"shadows" "1"` add a warning.
pub(super) fn light(class: &str, f: &mut Fields, warnings: &mut Vec<Diagnostic>) -> Result<Light, Diagnostic> {
    let light = match class {
        "light_directional" => {
            let direction = direction(f)?;
            let (color, intensity) = color_intensity(f)?;
            Light::directional(direction, color, intensity)
        }
        "light_point" => {
            let origin = Vec3::from(numbers::<3>(f.path, f.require("origin")?, "3 numbers (x y z)")?);
            let (color, intensity) = color_intensity(f)?;
            Light::point(origin, color, intensity, range(f)?)
        }
        _ => {
            let origin = Vec3::from(numbers::<3>(f.path, f.require("origin")?, "3 numbers (x y z)")?);
            let direction = direction(f)?;
            let (color, intensity) = color_intensity(f)?;
            let range = range(f)?;
            let outer = f.number("outer_angle", 0.1..=90.0)?.unwrap_or(30.0);
            let inner = f.number("inner_angle", 0.0..=outer)?.unwrap_or(outer * 0.8);
            Light::spot(origin, direction, color, intensity, range, (inner.to_radians(), outer.to_radians()))
        }
    };
    let on = f.flag("shadows")?.unwrap_or(false);
    let defaults = ShadowSettings::default();
    let settings = ShadowSettings {
        map_size: f.integer("shadow_map_size", 16..=8192)?.map_or(defaults.map_size, |v| v as u32),
        depth_bias: f.number("shadow_bias", 0.0..=100.0)?.unwrap_or(defaults.depth_bias),
        normal_bias: f.number("shadow_normal_bias", 0.0..=100.0)?.unwrap_or(defaults.normal_bias),
        distance: if class == "light_directional" { f.number("shadow_distance", 1e-3..=1e9)? } else { None },
        light_size: match class {
            "light_directional" => f.number("light_size", 0.0..=20.0)?,
            _ => f.number("light_size", 0.0..=1e4)?,
        }
        .unwrap_or(defaults.light_size),
    };
    if class == "light_point" && settings.light_size > 0.0 {
        let why = "\"light_size\" is ignored: a point light's shadows keep the 3x3 filter (soft shadows are for directional and spot lights)";
        let line = f.get("light_size").map_or(f.block.line, |pair| pair.line);
        warnings.push(Diagnostic::at(f.path, line, why));
    }
    if !on && settings != defaults {
        warnings.push(Diagnostic::at(
            f.path,
            f.block.line,
            "shadow keys are ignored: this light has no \"shadows\" \"1\"",
        ));
    }
    Ok(if on { light.with_shadows(settings) } else { light })
}

/// A directional light's `sway` key: "DEGREES PERIOD", its direction
/// swinging that far either way with that period in seconds, like sunlight
/// through waves (Tiny Graphics' underwater scene).
pub(super) fn sway(f: &mut Fields, direction: Vec3, light: usize) -> Result<Option<super::LightSway>, Diagnostic> {
    let Some(pair) = f.get("sway") else { return Ok(None) };
    match numbers::<2>(f.path, pair, "2 numbers (degrees period)")? {
        [degrees, period] if (0.0..=90.0).contains(&degrees) && (0.01..=1e6).contains(&period) => {
            Ok(Some(super::LightSway { light, base: direction, degrees, period }))
        }
        _ => Err(Diagnostic::at(
            f.path,
            pair.line,
            "\"sway\" must be degrees period with 0 <= degrees <= 90, period 0.01 to 1000000 s",
        )),
    }
}

/// A point or spot light's `circle` key: "RADIUS PERIOD [PHASE]", the light
/// going round its `origin` in a level circle of that radius, a turn every
/// PERIOD seconds, starting PHASE degrees round (fireflies, lanterns in wind).
pub(super) fn circle(f: &mut Fields, centre: Vec3, light: usize) -> Result<Option<super::LightCircle>, Diagnostic> {
    let Some(pair) = f.get("circle") else { return Ok(None) };
    let what = "2 or 3 numbers (radius period [phase])";
    let [radius, period, phase] = match pair.value.split_whitespace().count() {
        2 => {
            let [r, p] = numbers::<2>(f.path, pair, what)?;
            [r, p, 0.0]
        }
        _ => numbers::<3>(f.path, pair, what)?,
    };
    if !((0.0..=1e4).contains(&radius) && (0.01..=1e6).contains(&period) && (-360.0..=360.0).contains(&phase)) {
        let message = "\"circle\" must be radius period [phase] with radius 0 to 10000, period 0.01 to 1000000 s, phase -360 to 360 degrees";
        return Err(Diagnostic::at(f.path, pair.line, message));
    }
    Ok(Some(super::LightCircle { light, centre, radius, period, phase }))
}

/// The fraction of a turn, in radians, `time` seconds into turns of `period`
/// seconds. Taken modulo one turn in f64 first: 2π·t overflows f32 at
/// t ≈ 5·10³⁷ s, and sin(∞) is NaN.
fn turned(time: f32, period: f32) -> f32 {
    let turns = (f64::from(time) / f64::from(period)).rem_euclid(1.0);
    (turns * std::f64::consts::TAU) as f32
}

impl super::LightCircle {
    /// Where the light is at `time` seconds.
    pub fn position_at(&self, time: f32) -> Vec3 {
        let angle = turned(time, self.period) + self.phase.to_radians();
        self.centre + self.radius * Vec3::new(angle.cos(), 0.0, -angle.sin())
    }
}

fn direction(f: &mut Fields) -> Result<Vec3, Diagnostic> {
    let pair = f.require("direction")?;
    let direction = Vec3::from(numbers::<3>(f.path, pair, "3 numbers (x y z)")?);
    if direction.length_squared() < 1e-12 {
        return Err(Diagnostic::at(f.path, pair.line, "\"direction\" must not be zero"));
    }
    Ok(direction)
}

fn color_intensity(f: &mut Fields) -> Result<(Vec3, f32), Diagnostic> {
    Ok((f.color("color")?.unwrap_or(Vec3::ONE), f.number("intensity", 0.0..=1e9)?.unwrap_or(1.0)))
}

fn range(f: &mut Fields) -> Result<f32, Diagnostic> {
    Ok(f.number("range", 1e-3..=1e9)?.unwrap_or(10.0))
}

impl super::SceneDesc {
    /// Move the sun (the first directional light; one is added when there is
    /// none), the sky gradient and the ambient light to `hours` of the day
    /// ([`Daylight::at`](crate::scene::Daylight::at)): the world's
    /// `time_of_day`. The glare follows the sun, whose direction and colour it takes.
    ///
    /// A scene with no directional light and already
    /// [`MAX_CLUSTERED_LIGHTS`](crate::scene::MAX_CLUSTERED_LIGHTS) lights has no room for a sun: its sky and ambient light still move, its
    /// lights stay as they are, and the error says so.
    pub fn set_time_of_day(&mut self, hours: f32) -> Result<(), Diagnostic> {
        let day = crate::scene::Daylight::at(hours);
        self.time_of_day = Some(hours);
        let directional = |l: &Light| matches!(l.kind, crate::scene::LightKind::Directional { .. });
        match self.lights.iter().position(directional) {
            Some(k) => {
                let sun = &mut self.lights[k];
                sun.kind = crate::scene::LightKind::Directional { direction: day.sun_direction };
                (sun.color, sun.intensity) = (day.sun_color, day.sun_intensity);
            }
            None if self.lights.len() < crate::scene::MAX_CLUSTERED_LIGHTS => {
                self.lights.insert(0, Light::directional(day.sun_direction, day.sun_color, day.sun_intensity));
                // The lights that move are one further on.
                self.light_circles.iter_mut().for_each(|c| c.light += 1);
            }
            None => {}
        }
        let env = &mut self.environment;
        env.background = crate::scene::Background::Gradient { top: day.sky_top, bottom: day.sky_bottom };
        env.ambient = day.ambient;
        match self.lights.iter().any(directional) {
            true => Ok(()),
            false => Err(Diagnostic::file(
                &self.path,
                format!(
                    "time_of_day needs a sun: the scene has {} lights, none directional, and a frame \
                     can use at most {}; make one of them light_directional or leave out a light",
                    self.lights.len(),
                    crate::scene::MAX_CLUSTERED_LIGHTS
                ),
            )),
        }
    }
}

impl super::LightSway {
    /// Its light's direction at `time` seconds: the base direction turned
    /// about two axes across it, by `degrees` · sin(2πt / period) and half as
    /// far at a period 0.7 times as long, so the shadows wander rather than
    /// swing on one line.
    pub fn direction_at(&self, time: f32) -> Vec3 {
        let base = self.base.normalize_or(Vec3::NEG_Y);
        let across = base.cross(Vec3::Y).try_normalize().unwrap_or(Vec3::X);
        let other = base.cross(across);
        let a = self.degrees.to_radians() * turned(time, self.period).sin();
        let b = 0.5 * self.degrees.to_radians() * (turned(time, 0.7 * self.period) + 1.0).sin();
        glam::Quat::from_axis_angle(other, b) * (glam::Quat::from_axis_angle(across, a) * base)
    }
}

#[cfg(test)]
mod tests {
    use crate::asset::{parse_scene, SceneDesc};
    use crate::scene::{LightKind, ShadowSettings};
    use std::path::Path;

    fn parse(text: &str) -> Result<SceneDesc, String> {
        parse_scene(Path::new("t.scn"), text).map_err(|e| e.to_string())
    }

    #[test]
    fn a_circling_light_goes_round_its_origin_and_bad_circles_are_errors() {
        let light = |class: &str, circle: &str| {
            parse(&format!(
                "{{\n\"classname\" \"{class}\"\n\"origin\" \"1 2 3\"\n\"direction\" \"0 -1 0\"\n\"circle\" \"{circle}\"\n}}\n"
            ))
        };
        let scene = light("light_point", "0.5 4").unwrap();
        let circle = &scene.light_circles[0];
        assert_eq!((circle.light, circle.radius, circle.period, circle.phase), (0, 0.5, 4.0, 0.0));
        let centre = glam::Vec3::new(1.0, 2.0, 3.0);
        assert!(circle.position_at(0.0).distance(centre + glam::Vec3::new(0.5, 0.0, 0.0)) < 1e-6);
        // A quarter turn later it is a quarter round (towards −z), at the same height.
        assert!(circle.position_at(1.0).distance(centre + glam::Vec3::new(0.0, 0.0, -0.5)) < 1e-6);
        for t in [0.3, 7.7, 1e9 + 0.25, f32::MAX] {
            let p = circle.position_at(t);
            assert!(p.is_finite() && (p.distance(centre) - 0.5).abs() < 1e-5 && p.y == 2.0, "{t}: {p}");
        }
        let spot = light("light_spot", "2 1 90").unwrap();
        assert!(spot.light_circles[0].position_at(0.0).distance(centre + glam::Vec3::new(0.0, 0.0, -2.0)) < 1e-5);
        for bad in ["1", "-1 2", "1 0", "1 2 400", "1 2 3 4", "a b"] {
            let e = light("light_point", bad).unwrap_err();
            assert!(e.contains("t.scn:5") && e.contains("circle"), "{bad}: {e}");
        }
        // A directional light does not circle: the key is unknown there.
        let sun = light("light_directional", "1 2").unwrap();
        assert!(sun.light_circles.is_empty() && !sun.warnings.is_empty());
    }

    #[test]
    fn a_swaying_sun_turns_within_its_swing_and_bad_sways_are_errors() {
        let light = |sway: &str| {
            parse(&format!(
                "{{\n\"classname\" \"light_directional\"\n\"direction\" \"0 -1 0.2\"\n\"sway\" \"{sway}\"\n}}\n"
            ))
        };
        let scene = light("10 4").unwrap();
        let sway = &scene.light_sways[0];
        assert_eq!((sway.light, sway.degrees, sway.period), (0, 10.0, 4.0));
        // Far in the future the phase is still a phase: no NaN direction.
        for t in [6e37, f32::MAX, 1e9 + 0.25] {
            let d = sway.direction_at(t);
            assert!(d.is_finite() && (d.length() - 1.0).abs() < 1e-4, "{t}: {d}");
        }
        let base = sway.base.normalize();
        let mut most: f32 = 0.0;
        for k in 0..200 {
            let d = sway.direction_at(k as f32 * 0.05);
            assert!((d.length() - 1.0).abs() < 1e-4);
            most = most.max(d.angle_between(base).to_degrees());
        }
        // 10° about one axis and 5° about the other at most.
        assert!(most > 8.0 && most < 11.5, "{most}");
        assert_ne!(sway.direction_at(0.0), sway.direction_at(1.0));
        for bad in ["91 4", "10 0", "10", "x 4"] {
            let err = light(bad).unwrap_err();
            assert!(err.starts_with("t.scn:4: \"sway\""), "{bad}: {err}");
        }
    }

    #[test]
    fn shadow_keys_on_lights() {
        let scene = parse(
            "{ \"classname\" \"light_directional\"\n\"direction\" \"0 -1 0\"\n\"shadows\" \"1\"\n\"shadow_map_size\" \"2048\"\n\"shadow_bias\" \"2\"\n\"shadow_normal_bias\" \"0.5\"\n\"shadow_distance\" \"40\" }\n\
             { \"classname\" \"light_point\"\n\"origin\" \"0 2 0\"\n\"shadows\" \"1\" }\n\
             { \"classname\" \"light_spot\"\n\"origin\" \"0 2 0\"\n\"direction\" \"0 -1 0\"\n\"shadows\" \"0\" }\n",
        )
        .unwrap();
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
        let sun =
            ShadowSettings { map_size: 2048, depth_bias: 2.0, normal_bias: 0.5, distance: Some(40.0), light_size: 0.0 };
        assert_eq!(scene.lights[0].shadows, Some(sun));
        assert_eq!(scene.lights[1].shadows, Some(ShadowSettings::default()));
        assert!(matches!(scene.lights[2].kind, LightKind::Spot { .. }));
        assert_eq!(scene.lights[2].shadows, None);
    }

    #[test]
    fn light_sizes_soften_directional_and_spot_shadows_only() {
        let scene = parse(
            "{ \"classname\" \"light_directional\"\n\"direction\" \"0 -1 0\"\n\"shadows\" \"1\"\n\"light_size\" \"0.53\" }\n\
             { \"classname\" \"light_spot\"\n\"origin\" \"0 2 0\"\n\"direction\" \"0 -1 0\"\n\"shadows\" \"1\"\n\"light_size\" \"0.2\" }\n\
             { \"classname\" \"light_point\"\n\"origin\" \"0 2 0\"\n\"shadows\" \"1\"\n\"light_size\" \"0.2\" }\n",
        )
        .unwrap();
        let sizes: Vec<f32> = scene.lights.iter().map(|l| l.shadows.expect("shadows").light_size).collect();
        assert_eq!(sizes, [0.53, 0.2, 0.2]);
        let soft: Vec<bool> = scene.lights.iter().map(|l| l.shadows.expect("shadows").soft(&l.kind)).collect();
        assert_eq!(soft, [true, true, false], "a point light keeps the 3x3 filter");
        assert_eq!(scene.warnings.len(), 1, "{:?}", scene.warnings);
        assert!(
            scene.warnings[0].to_string().contains("t.scn:13: \"light_size\" is ignored: a point light"),
            "{:?}",
            scene.warnings
        );
        let sun = |size: &str| {
            format!("{{ \"classname\" \"light_directional\"\n\"direction\" \"0 -1 0\"\n\"light_size\" \"{size}\" }}\n")
        };
        assert_eq!(parse(&sun("25")).unwrap_err(), "t.scn:3: \"light_size\" is 25, expected a value in 0..=20");
        assert_eq!(parse(&sun("-1")).unwrap_err(), "t.scn:3: \"light_size\" is -1, expected a value in 0..=20");
        assert!(parse(&sun("1")).unwrap().warnings.iter().any(|w| w.to_string().contains("shadow keys are ignored")));
    }

    #[test]
    fn shadow_keys_without_shadows_warn_and_bad_values_fail() {
        let scene =
            parse("{ \"classname\" \"light_point\"\n\"origin\" \"0 2 0\"\n\"shadow_map_size\" \"512\" }\n").unwrap();
        assert_eq!(scene.lights[0].shadows, None);
        assert_eq!(scene.warnings.len(), 1);
        assert!(scene.warnings[0].to_string().contains("t.scn:1: shadow keys are ignored"), "{:?}", scene.warnings);
        // shadow_distance is a directional light's key only.
        let scene = parse(
            "{ \"classname\" \"light_point\"\n\"origin\" \"0 2 0\"\n\"shadows\" \"1\"\n\"shadow_distance\" \"9\" }\n",
        )
        .unwrap();
        assert!(scene.warnings[0].to_string().contains("t.scn:4: unknown key 'shadow_distance'"));
        for (text, expected) in [
            ("\"shadows\" \"yes\"", "t.scn:3: \"shadows\" is 'yes', expected 0 or 1"),
            ("\"shadow_map_size\" \"8\"", "t.scn:3: \"shadow_map_size\" is '8', expected a whole number in 16..=8192"),
            ("\"shadow_bias\" \"-1\"", "t.scn:3: \"shadow_bias\" is -1, expected a value in 0..=100"),
        ] {
            let block = format!("{{ \"classname\" \"light_point\"\n\"origin\" \"0 2 0\"\n{text} }}\n");
            assert_eq!(parse(&block).unwrap_err(), expected);
        }
    }

    #[test]
    fn cast_and_receive_shadows_on_entities_and_instances() {
        let scene = parse(
            "{ \"classname\" \"entity\"\n\"mesh\" \"cube\"\n\"cast_shadows\" \"0\" }\n\
             { \"classname\" \"entity\"\n\"mesh\" \"cube\" }\n\
             { \"classname\" \"instances\"\n\"mesh\" \"cube\"\n\"count\" \"4\"\n\"receive_shadows\" \"0\" }\n",
        )
        .unwrap();
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
        // Different shadow flags keep the same mesh and material in separate tasks.
        let flags: Vec<_> =
            scene.entities.iter().map(|e| (e.draw.cast_shadows, e.draw.receive_shadows, e.transforms.len())).collect();
        assert_eq!(flags, [(false, true, 1), (true, true, 1), (true, false, 4)]);
        let err = parse("{ \"classname\" \"entity\"\n\"mesh\" \"cube\"\n\"receive_shadows\" \"2\" }\n").unwrap_err();
        assert_eq!(err, "t.scn:3: \"receive_shadows\" is '2', expected 0 or 1");
    }
}
