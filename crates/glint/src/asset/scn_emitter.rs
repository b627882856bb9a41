//! The `.scn` `emitter` class: a particle emitter ([`EmitterParams`]) and how
//! its particles look. A [`World`](crate::World) steps it to the scene time:
//! with compute shaders where the device has them, else on the CPU, from
//! the same description and seed.

use super::scn_fields::{numbers, Fields};
use super::scn_syntax::Pair;
use super::{Diagnostic, TextureRef};
use crate::scene::emitter::{Burst, EmitterParams, SpawnShape, MAX_PARTICLES};
use crate::scene::ParticleBlend;
use crate::text::quote;
use glam::{Vec3, Vec4};

/// Most particle-steps one pose may take over a scene's emitters (steps to
/// the time × (slots + [`STEP_OVERHEAD`])): a far `--time` is an error
/// rather than minutes. At the edge, 400 steps of 10⁶ slots took 13 s on
/// lavapipe's compute and 10 s on the CPU (GL) on this project's 2-core machine.
pub const MAX_POSE_PARTICLE_STEPS: u64 = 400_000_000;

/// What one step of an emitter costs beside its slots, in particle-steps:
/// its compute pass and dispatches recorded (or the CPU's loop over the
/// schedule). Measured, a 2-slot emitter's step took about 50 µs, what 1,500
/// slots take; it counts more than twice that, so a tiny emitter stepped a
/// million times counts as the work (and the recorded commands) it is.
pub const STEP_OVERHEAD: u64 = 4_096;

/// Most `emitter` blocks in a scene: each is a particle layer drawn in every
/// view and, on the GPU, a compute pass every frame.
pub const MAX_EMITTERS: usize = 256;

/// Most particle slots over a scene's emitters: what one emitter may hold
/// ([`MAX_PARTICLES`]), about 300 MB of GPU buffers; twenty emitters at
/// their largest ran the machine out of memory.
pub const MAX_SCENE_PARTICLES: u64 = MAX_PARTICLES as u64;

/// Whether a scene with `emitters` has room for one more of `params`: at most
/// [`MAX_EMITTERS`] emitters and [`MAX_SCENE_PARTICLES`] slots in all.
pub(crate) fn check_scene_room(emitters: &[EmitterDesc], params: &EmitterParams) -> Result<(), String> {
    if emitters.len() >= MAX_EMITTERS {
        return Err(format!("a scene may have at most {MAX_EMITTERS} emitters; this is one more"));
    }
    let slots = |p: &EmitterParams| p.slots();
    let total = emitters.iter().map(|e| slots(&e.params)).sum::<u64>() + slots(params);
    if total > MAX_SCENE_PARTICLES {
        return Err(format!(
            "the scene's emitters hold {total} particle slots with this one, more than the \
             {MAX_SCENE_PARTICLES} a scene may have: lower \"rate\", \"lifetime\" or \"burst\""
        ));
    }
    Ok(())
}

/// An `emitter` block.
#[derive(Clone, Debug)]
pub struct EmitterDesc {
    /// The block's line.
    pub line: usize,
    /// The emitter.
    pub params: EmitterParams,
    /// How its particles blend.
    pub blend: ParticleBlend,
    /// World units over which its particles fade in front of geometry (0: none).
    pub soft: f32,
    /// Whether the scene's lights light its particles (`"lit" "1"`; else
    /// their colour is a light of its own).
    pub lit: bool,
    /// The sprite each particle shows (a scene texture), if any.
    pub texture: Option<TextureRef>,
    /// Seconds a step.
    pub dt: f32,
}

impl EmitterDesc {
    /// Steps from time 0 to `time`.
    pub fn steps_to(&self, time: f32) -> u64 {
        (f64::from(time.max(0.0)) / f64::from(self.dt)).round() as u64
    }

    /// Steps posing at `time` takes from its state at `from` (`None`: from
    /// time 0; a later `from` counts as time 0 too, as it starts again).
    pub fn steps_from(&self, from: Option<f32>, time: f32) -> u64 {
        let taken = from.filter(|&f| f <= time).map_or(0, |f| self.steps_to(f));
        self.steps_to(time).saturating_sub(taken)
    }

    /// Particle-steps posing at `time` from `from` takes: every slot, every
    /// step ([`steps_from`](Self::steps_from)), and each step's own [`STEP_OVERHEAD`].
    pub fn pose_work(&self, from: Option<f32>, time: f32) -> u64 {
        let slots = self.params.slots();
        self.steps_from(from, time).saturating_mul(slots.saturating_add(STEP_OVERHEAD))
    }
}

/// One number, or two (min max); the one number is both.
fn range(f: &mut Fields, key: &str, default: (f32, f32), most: f32) -> Result<(f32, f32), Diagnostic> {
    let Some(pair) = f.get(key) else { return Ok(default) };
    let values: Vec<f32> = pair.value.split_whitespace().map(|w| w.parse().unwrap_or(f32::NAN)).collect();
    let (lo, hi) = match values[..] {
        [v] => (v, v),
        [lo, hi] => (lo, hi),
        _ => (f32::NAN, f32::NAN),
    };
    if !(0.0..=most).contains(&lo) || !(lo..=most).contains(&hi) {
        let message =
            format!("\"{key}\" is {}, expected one number or min max, 0 <= min <= max <= {most}", quote(&pair.value));
        return Err(Diagnostic::at(f.path, pair.line, message));
    }
    Ok((lo, hi))
}

/// A colour: r g b, or r g b a.
fn rgba(f: &mut Fields, key: &str, default: Vec4) -> Result<Vec4, Diagnostic> {
    let Some(pair) = f.get(key) else { return Ok(default) };
    let values: Vec<f32> = pair.value.split_whitespace().map(|w| w.parse().unwrap_or(f32::NAN)).collect();
    match values[..] {
        [r, g, b] if [r, g, b].iter().all(|c| (0.0..=1e4).contains(c)) => Ok(Vec4::new(r, g, b, 1.0)),
        [r, g, b, a] if [r, g, b].iter().all(|c| (0.0..=1e4).contains(c)) && (0.0..=1.0).contains(&a) => {
            Ok(Vec4::new(r, g, b, a))
        }
        _ => Err(Diagnostic::at(
            f.path,
            pair.line,
            format!("\"{key}\" is {}, expected r g b or r g b a (a in 0..1)", quote(&pair.value)),
        )),
    }
}

/// The `shape` key: `point`, `sphere R`, `box X Y Z` (half extents) or `cone R`.
fn shape(f: &mut Fields) -> Result<SpawnShape, Diagnostic> {
    let Some(pair) = f.get("shape") else { return Ok(SpawnShape::Point) };
    let mut words = pair.value.split_whitespace();
    let kind = words.next().unwrap_or("");
    let rest = Pair { key: pair.key.clone(), value: words.collect::<Vec<_>>().join(" "), line: pair.line };
    let bad = |m: &str| Diagnostic::at(f.path, pair.line, format!("\"shape\": {m}"));
    let size = |v: f32| if (0.0..=1e5).contains(&v) { Ok(v) } else { Err(bad("sizes must be 0 to 100000")) };
    match kind {
        "point" if rest.value.is_empty() => Ok(SpawnShape::Point),
        "sphere" => Ok(SpawnShape::Sphere(size(numbers::<1>(f.path, &rest, "sphere RADIUS")?[0])?)),
        "cone" => Ok(SpawnShape::Cone(size(numbers::<1>(f.path, &rest, "cone RADIUS")?[0])?)),
        "box" => {
            let [x, y, z] = numbers::<3>(f.path, &rest, "box X Y Z (half extents)")?;
            Ok(SpawnShape::Box(Vec3::new(size(x)?, size(y)?, size(z)?)))
        }
        _ => Err(bad(&format!("{} is not point, sphere R, box X Y Z or cone R", quote(&pair.value)))),
    }
}

/// How an emitter block's particles look, but their texture (the loader's).
pub(crate) struct Looks {
    pub blend: ParticleBlend,
    pub soft: f32,
    pub lit: bool,
}

/// An emitter block's keys but `texture` (the loader's): the emitter, its
/// looks and step.
pub(crate) fn parse(f: &mut Fields, line: usize) -> Result<(EmitterParams, Looks, f32), Diagnostic> {
    let d = EmitterParams::default();
    let rate = f.number("rate", 0.0..=1e8)?.unwrap_or(d.rate);
    let burst = match f.get("burst") {
        None => d.burst,
        Some(pair) => {
            let values: Vec<f32> = pair.value.split_whitespace().map(|w| w.parse().unwrap_or(f32::NAN)).collect();
            match values[..] {
                [n] if (0.0..=MAX_PARTICLES as f32).contains(&n) && n.fract() == 0.0 => {
                    Burst { count: n as u32, every: 0.0 }
                }
                [n, every]
                    if (0.0..=MAX_PARTICLES as f32).contains(&n)
                        && n.fract() == 0.0
                        && (0.01..=1e6).contains(&every) =>
                {
                    Burst { count: n as u32, every }
                }
                _ => {
                    let m = format!(
                        "\"burst\" is {}, expected COUNT or COUNT EVERY (a whole count, every 0.01..1000000 s)",
                        quote(&pair.value)
                    );
                    return Err(Diagnostic::at(f.path, pair.line, m));
                }
            }
        }
    };
    let lifetime = range(f, "lifetime", d.lifetime, 1e4)?;
    let speed = range(f, "speed", d.speed, 1e5)?;
    let noise = match f.numbers::<2>("noise", "2 numbers (strength scale)")? {
        Some([strength, scale]) if (0.0..=1e4).contains(&strength) && (1e-3..=1e5).contains(&scale) => {
            (strength, scale)
        }
        Some(_) => {
            return Err(Diagnostic::at(f.path, line, "\"noise\" must be strength scale, 0..10000 and 0.001..100000"))
        }
        None => (d.noise, d.noise_scale),
    };
    let ground = match f.get("ground") {
        None => None,
        Some(pair) => {
            let values: Vec<f32> = pair.value.split_whitespace().map(|w| w.parse().unwrap_or(f32::NAN)).collect();
            match values[..] {
                [y] if y.abs() <= 1e5 => Some((y, 0.3)),
                [y, bounce] if y.abs() <= 1e5 && (0.0..=1.0).contains(&bounce) => Some((y, bounce)),
                _ => {
                    return Err(Diagnostic::at(
                        f.path,
                        pair.line,
                        "\"ground\" must be Y or Y BOUNCE (|Y| <= 100000, bounce 0..1)",
                    ))
                }
            }
        }
    };
    let blend = match f.choice("blend", &["additive", "alpha"])? {
        Some((1, _)) => ParticleBlend::Alpha,
        _ => ParticleBlend::Additive,
    };
    let size = f.number("size", 0.0..=1e4)?.unwrap_or(d.size);
    let params = EmitterParams {
        origin: f.bounded_vec3("origin", 1e5)?.unwrap_or(d.origin),
        direction: f.bounded_vec3("direction", 1e5)?.unwrap_or(d.direction),
        rate,
        burst,
        lifetime,
        shape: shape(f)?,
        speed,
        spread: f.number("spread", 0.0..=180.0)?.unwrap_or(d.spread),
        gravity: f.bounded_vec3("gravity", 1e5)?.unwrap_or(d.gravity),
        drag: f.number("drag", 0.0..=1e4)?.unwrap_or(d.drag),
        noise: noise.0,
        noise_scale: noise.1,
        color: rgba(f, "color", d.color)?,
        color_end: rgba(f, "color_end", d.color_end)?,
        size,
        size_end: f.number("size_end", 0.0..=1e4)?.unwrap_or(size),
        ground,
        seed: f.integer("seed", 0..=i64::from(u32::MAX))?.unwrap_or(1) as u32,
    };
    if params.direction.length_squared() < 1e-12 {
        return Err(Diagnostic::at(f.path, line, "\"direction\" must not be zero"));
    }
    let dt = f.number("dt", 1e-4..=1.0)?.unwrap_or(1.0 / 60.0);
    params.check().map_err(|m| Diagnostic::at(f.path, line, format!("emitter: {m}")))?;
    let soft = f.number("soft", 0.0..=1e4)?.unwrap_or(0.0);
    let lit = f.flag("lit")?.unwrap_or(false);
    Ok((params, Looks { blend, soft, lit }, dt))
}

/// What posing every emitter at `time` from `from` takes, for [`SceneDesc::check_pose_from`](super::SceneDesc::check_pose_from):
/// each block's line, steps, particle-steps, and what they are.
pub(crate) fn pose_work(
    emitters: &[EmitterDesc],
    (from, time): (Option<f32>, f32),
) -> impl Iterator<Item = (usize, u64, u64, String)> + '_ {
    emitters.iter().map(move |e| {
        let (slots, steps) = (e.params.slots(), e.steps_from(from, time));
        let what = format!(
            "emitter: {} is {steps} steps of {slots} particle slots (each step counting {STEP_OVERHEAD} more for itself)",
            super::scene_desc::span(from, time),
        );
        (e.line, steps, e.pose_work(from, time), what)
    })
}

#[cfg(test)]
mod tests {
    use crate::asset::{parse_scene, Diagnostic, SceneDesc};
    use crate::scene::emitter::SpawnShape;
    use crate::scene::ParticleBlend;
    use glam::Vec3;
    use std::path::Path;

    fn emitter(body: &str) -> Result<SceneDesc, Diagnostic> {
        parse_scene(Path::new("e.scn"), &format!("{{\n\"classname\" \"emitter\"\n{body}}}\n"))
    }

    fn error(body: &str) -> String {
        emitter(body).unwrap_err().to_string()
    }

    #[test]
    fn every_emitter_key_is_read() {
        let scene = emitter(
            "\"origin\" \"1 2 3\"\n\"direction\" \"0 0 1\"\n\"rate\" \"50\"\n\"burst\" \"20 0.5\"\n\"lifetime\" \"1 2\"\n\
             \"shape\" \"box 0.1 0.2 0.3\"\n\"speed\" \"2 3\"\n\"spread\" \"30\"\n\"gravity\" \"0 -9.8 0\"\n\"drag\" \"0.2\"\n\
             \"noise\" \"0.5 2\"\n\"color\" \"1 0.5 0\"\n\"color_end\" \"0 0 1 0.5\"\n\"size\" \"0.2\"\n\"size_end\" \"0.4\"\n\
             \"ground\" \"-1 0.6\"\n\"blend\" \"alpha\"\n\"seed\" \"9\"\n\"dt\" \"0.02\"\n",
        )
        .unwrap();
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
        let e = &scene.emitters[0];
        let p = &e.params;
        assert_eq!((p.origin, p.direction, p.rate), (Vec3::new(1.0, 2.0, 3.0), Vec3::Z, 50.0));
        assert_eq!((p.burst.count, p.burst.every, p.lifetime, p.speed), (20, 0.5, (1.0, 2.0), (2.0, 3.0)));
        assert_eq!(p.shape, SpawnShape::Box(Vec3::new(0.1, 0.2, 0.3)));
        assert_eq!((p.spread, p.drag, p.noise, p.noise_scale, p.seed), (30.0, 0.2, 0.5, 2.0, 9));
        assert_eq!((p.color.w, p.color_end.w, p.size, p.size_end, p.ground), (1.0, 0.5, 0.2, 0.4, Some((-1.0, 0.6))));
        assert_eq!((e.blend, e.dt, e.texture, e.soft), (ParticleBlend::Alpha, 0.02, None, 0.0));
        assert_eq!(emitter("\"soft\" \"0.5\"\n").unwrap().emitters[0].soft, 0.5);
        assert!(error("\"soft\" \"-1\"\n").starts_with("e.scn:3: \"soft\""));
        assert!(!emitter("").unwrap().emitters[0].lit, "unlit unless asked");
        assert!(emitter("\"lit\" \"1\"\n").unwrap().emitters[0].lit);
        assert!(error("\"lit\" \"yes\"\n").starts_with("e.scn:3: \"lit\""), "{}", error("\"lit\" \"yes\"\n"));
        assert_eq!(emitter("").unwrap().emitters[0].params.shape, SpawnShape::Point);
    }

    #[test]
    fn bad_emitter_keys_are_errors_at_their_line() {
        assert!(error("\"lifetime\" \"2 1\"\n").starts_with("e.scn:3: \"lifetime\""));
        assert!(error("\"shape\" \"torus 1\"\n").contains("not point, sphere R, box X Y Z or cone R"));
        assert!(error("\"shape\" \"box 1 2\"\n").starts_with("e.scn:3:"));
        assert!(error("\"burst\" \"2.5\"\n").contains("COUNT or COUNT EVERY"));
        assert!(error("\"rate\" \"0\"\n").contains("needs a rate or a burst"));
        assert!(error("\"rate\" \"1e8\"\n\"lifetime\" \"100\"\n").contains("alive at once"));
        assert!(error("\"color\" \"1 1 1 2\"\n").contains("r g b or r g b a"));
        assert!(error("\"direction\" \"0 0 0\"\n").contains("must not be zero"));
        assert!(error("\"blend\" \"multiply\"\n").contains("blend"));
        assert!(error("\"ground\" \"0 2\"\n").contains("BOUNCE"));
        assert!(error("\"texture\" \"missing.png\"\n").starts_with("e.scn:3: \"texture\""));
        let many = emitter("\"rate\" \"1000000\"\n\"lifetime\" \"4\"\n").unwrap();
        assert!(many.check_pose(100.0).unwrap_err().to_string().contains("particle-steps"));
        assert!(many.check_pose(1.0).is_ok());
        let one = emitter("\"rate\" \"0\"\n\"burst\" \"1\"\n").unwrap();
        assert!(one.check_pose(1e4).unwrap_err().to_string().ends_with("more than the 100000 steps one pose may take"));
    }
}
