//! The `.scn` `school` class: a school of fish (instances of one mesh) and
//! optionally a predator hunting it, simulated by `sim::school::School`.
//! This is what the block says; a [`World`](crate::World) steps the school to
//! the requested time from its seeded start, deterministically.

use super::scn::{Loader, Placement};
use super::scn_fields::{numbers, Fields};
use super::Diagnostic;
use crate::scene::school::{Hunter, Obstacle, SchoolParams, Weights, MAX_FISH};
use crate::scene::Aabb;
use glam::{Mat4, Quat, Vec3};

/// Most work one pose may take over a scene's schools, in neighbour tests
/// (steps to the time × [`SchoolParams::step_cost`]: each fish's tests at
/// its starting density, its own rules, and the grid's cells), so a far
/// `--time` is an error rather than minutes: at about 3 ns a test, 21–23 s of
/// stepping on this project's 2-core machine (`docs/limits.md`).
pub const MAX_POSE_SCHOOL_TESTS: u64 = 7_000_000_000;

/// Most obstacles one school may have (the GPU school's block holds as many).
pub use crate::scene::school::MAX_OBSTACLES;

/// A `school` block: the simulation's parameters and how its fish are drawn.
#[derive(Clone, Debug)]
pub struct SchoolDesc {
    /// The block's line, for errors while posing.
    pub line: usize,
    /// The simulation.
    pub params: SchoolParams,
    /// Seconds a step.
    pub dt: f32,
    /// Each fish's scale (varied ±15 % per fish).
    pub size: f32,
    /// The predator's scale.
    pub predator_size: f32,
    /// The scene entity drawing the fish (an index into
    /// [`SceneDesc::entities`](super::SceneDesc::entities)).
    pub fish_entity: usize,
    /// The scene entity drawing the predator, with one.
    pub predator_entity: Option<usize>,
    /// Where it steps (`"sim" "cpu"` or `"gpu"`, the default): on the GPU it
    /// is drawn in place from the simulation's buffers, where the renderer
    /// computes; on the CPU (GL, WebGL2) otherwise.
    pub sim: crate::scene::SimPath,
}

impl SchoolDesc {
    /// Steps from the start to `time` seconds (0 for a negative time).
    pub fn steps_to(&self, time: f32) -> u64 {
        (f64::from(time.max(0.0)) / f64::from(self.dt)).round() as u64
    }

    /// Steps posing at `time` takes from its state at `from` (`None`: from
    /// its start; a later `from` counts as the start too, as it starts again).
    pub fn steps_from(&self, from: Option<f32>, time: f32) -> u64 {
        let taken = from.filter(|&f| f <= time).map_or(0, |f| self.steps_to(f));
        self.steps_to(time).saturating_sub(taken)
    }

    /// Neighbour tests posing at `time` from `from` counts as
    /// ([`SchoolParams::step_cost`] a step, [`steps_from`](Self::steps_from) steps).
    pub fn pose_work(&self, from: Option<f32>, time: f32) -> u64 {
        self.steps_from(from, time).saturating_mul(self.params.step_cost())
    }

    /// The largest scale [`fish_scale`](Self::fish_scale) gives a fish.
    pub fn largest_fish_scale(&self) -> f32 {
        self.size * 1.15
    }

    /// Each fish's scale: `size` varied ±15 % by its number.
    pub fn fish_scale(&self, i: usize) -> f32 {
        let h = (i as u32).wrapping_mul(0x9e37_79b9) ^ 0x85eb_ca6b;
        let unit = (h.wrapping_mul(0xc2b2_ae35) >> 8) as f32 / (1u32 << 24) as f32;
        self.size * (0.85 + 0.3 * unit)
    }
}

/// A school block's simulation keys (the meshes and materials are the
/// loader's): `count` fish in `bounds`, and the rules' settings.
pub(crate) fn parse(f: &mut Fields, line: usize) -> Result<(SchoolParams, f32, f32, f32), Diagnostic> {
    let at = |pair_line: usize, m: String| Diagnostic::at(f.path, pair_line, m);
    let count = f.integer("count", 1..=MAX_FISH as i64)?.unwrap_or(1000) as usize;
    let bounds_pair = f.require("bounds")?;
    let b = numbers::<6>(f.path, bounds_pair, "6 numbers (min x y z, max x y z)")?;
    let bounds = Aabb { min: Vec3::new(b[0], b[1], b[2]), max: Vec3::new(b[3], b[4], b[5]) };
    if bounds.min.cmpge(bounds.max).any() || bounds.min.abs().max(bounds.max.abs()).max_element() > 1e5 {
        return Err(at(bounds_pair.line, "\"bounds\" must have min below max on every axis, within ±100000".into()));
    }
    let radius = f.number("radius", 1e-3..=1e4)?.unwrap_or(1.5);
    let view_angle = f.number("view_angle", 1.0..=360.0)?.unwrap_or(270.0);
    let [min_speed, max_speed] = f.numbers::<2>("speed", "2 numbers (min max)")?.unwrap_or([1.0, 3.0]);
    if !(0.0..=1e4).contains(&min_speed) || !(min_speed..=1e4).contains(&max_speed) || max_speed <= 0.0 {
        return Err(at(line, "\"speed\" must be min max with 0 <= min <= max <= 10000, max above 0".into()));
    }
    let max_accel = f.number("accel", 1e-3..=1e5)?.unwrap_or(12.0);
    let d = Weights::default();
    let w = f.numbers::<6>("weights", "6 numbers (separation alignment cohesion bounds avoid flee)")?.unwrap_or([
        d.separation,
        d.alignment,
        d.cohesion,
        d.bounds,
        d.avoid,
        d.flee,
    ]);
    if w.iter().any(|w| !(0.0..=1e4).contains(w)) {
        return Err(at(line, "\"weights\" must each be 0 to 10000".into()));
    }
    let weights = Weights { separation: w[0], alignment: w[1], cohesion: w[2], bounds: w[3], avoid: w[4], flee: w[5] };
    let obstacles = match f.get("obstacles") {
        None => Vec::new(),
        Some(pair) => {
            let list: Vec<&str> = pair.value.split(';').map(str::trim).filter(|s| !s.is_empty()).collect();
            if list.len() > MAX_OBSTACLES {
                let m = format!("\"obstacles\" lists {} spheres, more than {MAX_OBSTACLES}", list.len());
                return Err(at(pair.line, m));
            }
            list.iter()
                .map(|s| {
                    let one = super::scn_syntax::Pair { key: pair.key.clone(), value: s.to_string(), line: pair.line };
                    let [x, y, z, r] = numbers::<4>(f.path, &one, "spheres \"x y z radius\" separated by ;")?;
                    if !(r > 0.0 && r <= 1e5) {
                        return Err(at(
                            pair.line,
                            format!("\"obstacles\": radius {r} must be above 0 and at most 100000"),
                        ));
                    }
                    Ok(Obstacle { center: Vec3::new(x, y, z), radius: r })
                })
                .collect::<Result<_, _>>()?
        }
    };
    let floor = f.number("floor", -1e5..=1e5)?;
    let beat_rate = f.number("beat_rate", 0.0..=100.0)?.unwrap_or(3.0);
    let seed = f.integer("seed", 0..=i64::MAX)?.unwrap_or(1) as u64;
    let clusters = match f.numbers::<2>("clusters", "2 numbers (count radius)")? {
        None => None,
        Some([n, r]) if (1.0..=1e4).contains(&n) && n.fract() == 0.0 && (1e-3..=1e5).contains(&r) => {
            Some((n as u32, r))
        }
        Some(_) => {
            return Err(at(
                line,
                "\"clusters\" must be count radius, a whole count 1..10000 and a radius 0.001..100000".into(),
            ))
        }
    };
    let dt = f.number("dt", 1e-4..=1.0)?.unwrap_or(1.0 / 60.0);
    let size = f.number("size", 1e-4..=1e4)?.unwrap_or(1.0);
    let predator_size = f.number("predator_size", 1e-4..=1e4)?.unwrap_or(1.0);
    let predator = match f.get("predator_mesh") {
        None => None,
        Some(_) => Some(Hunter {
            start: f.bounded_vec3("predator_start", 1e5)?.unwrap_or((bounds.min + bounds.max) * 0.5),
            speed: f.number("predator_speed", 1e-3..=1e4)?.unwrap_or(max_speed * 1.2),
            accel: f.number("predator_turn", 1e-3..=1e5)?.unwrap_or(6.0),
            fear: f.number("predator_fear", 1e-3..=1e4)?.unwrap_or(radius * 3.0),
        }),
    };
    let params = SchoolParams {
        count,
        bounds,
        radius,
        view_angle,
        weights,
        min_speed,
        max_speed,
        max_accel,
        obstacles,
        floor,
        predator,
        beat_rate,
        clusters,
        seed,
    };
    params.check().map_err(|m| at(line, format!("school: {m}")))?;
    Ok((params, dt, size, predator_size))
}

impl Loader<'_> {
    /// A `school` block: the simulation ([`parse`]), and two
    /// placements of their own, the fish (`mesh`, `material`; in the middle
    /// of their bounds until a world places them at their seeded start) and
    /// the predator (`predator_mesh`, `predator_material`) at its start.
    pub(super) fn school(&mut self, f: &mut Fields) -> Result<(), Diagnostic> {
        let line = f.block.line;
        let mesh = self.mesh(f, "mesh")?;
        let material = Self::material_ref(f);
        let predator_mesh = match f.get("predator_mesh") {
            Some(_) => Some(self.mesh(f, "predator_mesh")?),
            None => None,
        };
        let predator_material = f.get("predator_material").map(|p| (p.value.trim().to_string(), p.line));
        let (params, dt, size, predator_size) = parse(f, line)?;
        self.count_instances(params.count as u64, &mesh, line)?;
        if let Some(predator) = &predator_mesh {
            self.count_instances(1, predator, line)?;
        }
        let draw = Self::draw_options(f)?;
        let sim = match f.choice("sim", &["cpu", "gpu"])? {
            Some((0, _)) => crate::scene::SimPath::Cpu,
            _ => crate::scene::SimPath::Gpu,
        };
        let sim = self.options.sim.unwrap_or(sim);
        let mut school = SchoolDesc {
            line,
            params,
            dt,
            size,
            predator_size,
            fish_entity: self.placements.len(),
            predator_entity: None,
            sim,
        };
        school.params.check().map_err(|m| Diagnostic::at(self.path, line, m))?;
        // The fish in the middle of their bounds until a world places them at
        // their seeded start ([`World::place`](crate::World::place)).
        let middle = (school.params.bounds.min + school.params.bounds.max) * 0.5;
        let at =
            |scale: f32, position| Mat4::from_scale_rotation_translation(Vec3::splat(scale), Quat::IDENTITY, position);
        let transforms = (0..school.params.count).map(|i| at(school.fish_scale(i), middle)).collect();
        self.placements.push(Placement { mesh, material, draw, transforms, tiles: None, alone: true });
        if let (Some(mesh), Some(hunter)) = (predator_mesh, school.params.predator) {
            school.predator_entity = Some(self.placements.len());
            // Its start, facing +Z as it starts.
            let transforms = vec![at(predator_size, hunter.start)];
            self.placements.push(Placement {
                mesh,
                material: predator_material,
                draw,
                transforms,
                tiles: None,
                alone: true,
            });
        }
        self.schools.push(school);
        Ok(())
    }
}

/// What posing every school at `time` from `from` takes, for [`SceneDesc::check_pose_from`](super::SceneDesc::check_pose_from):
/// each block's line, steps, neighbour tests, and what they are.
pub(crate) fn pose_work(
    schools: &[SchoolDesc],
    (from, time): (Option<f32>, f32),
) -> impl Iterator<Item = (usize, u64, u64, String)> + '_ {
    schools.iter().map(move |s| {
        let steps = s.steps_from(from, time);
        let what = format!(
            "school: {} is {steps} steps of {} fish, counted as {} neighbour tests a step",
            super::scene_desc::span(from, time),
            s.params.count,
            s.params.step_cost()
        );
        (s.line, steps, s.pose_work(from, time), what)
    })
}

#[cfg(test)]
mod tests {
    use crate::asset::{parse_scene, Diagnostic, MeshRef, SceneDesc};
    use std::path::Path;

    fn school(body: &str) -> Result<SceneDesc, Diagnostic> {
        let text =
            format!("{{\n\"classname\" \"school\"\n\"mesh\" \"cone\"\n\"bounds\" \"-5 -5 -5 5 5 5\"\n{body}}}\n");
        parse_scene(Path::new("s.scn"), &text)
    }

    fn error(body: &str) -> String {
        school(body).unwrap_err().to_string()
    }

    #[test]
    fn a_school_block_places_its_fish_and_predator_as_entities_of_their_own() {
        let scene = school(
            "\"count\" \"50\"\n\"size\" \"0.5\"\n\"predator_mesh\" \"sphere\"\n\"predator_speed\" \"4\"\n\"obstacles\" \"1 0 0 1; -2 0 0 0.5\"\n\"floor\" \"-4\"\n\"seed\" \"9\"\n",
        )
        .unwrap();
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
        let s = &scene.schools[0];
        assert_eq!(s.params.count, 50);
        assert_eq!(s.params.obstacles.len(), 2);
        assert_eq!((s.params.floor, s.params.seed, s.size), (Some(-4.0), 9, 0.5));
        assert_eq!(s.params.predator.unwrap().speed, 4.0);
        assert_eq!(scene.entities[s.fish_entity].transforms.len(), 50);
        let predator = s.predator_entity.expect("a predator");
        assert_eq!(scene.entities[predator].transforms.len(), 1);
        assert!(matches!(scene.entities[predator].mesh, MeshRef::Shape(_)));
        // Another block of the same mesh is not merged into the school's entity.
        let two = parse_scene(
            Path::new("s.scn"),
            "{\n\"classname\" \"entity\"\n\"mesh\" \"cone\"\n}\n{\n\"classname\" \"school\"\n\"mesh\" \"cone\"\n\"bounds\" \"0 0 0 1 1 1\"\n\"count\" \"3\"\n}\n",
        )
        .unwrap();
        assert_eq!(two.entities.len(), 2);
        assert_eq!(two.entities[two.schools[0].fish_entity].transforms.len(), 3);
    }

    #[test]
    fn bad_school_keys_are_errors_at_their_line() {
        let missing =
            parse_scene(Path::new("s.scn"), "{\n\"classname\" \"school\"\n\"mesh\" \"cone\"\n}\n").unwrap_err();
        assert!(missing.to_string().contains("\"bounds\""), "{missing}");
        assert!(error("\"bounds\" \"1 1 1 0 0 0\"\n").contains("min below max"));
        assert!(error("\"speed\" \"3 1\"\n").starts_with("s.scn:1: \"speed\" must be min max"));
        assert!(error("\"count\" \"0\"\n").starts_with("s.scn:5: \"count\""));
        assert!(error("\"weights\" \"1 2 3\"\n").contains("6 numbers"));
        assert!(error("\"obstacles\" \"0 0 0 -1\"\n").contains("radius -1"));
        let many = vec!["0 0 0 1"; super::MAX_OBSTACLES + 1].join("; ");
        assert!(error(&format!("\"obstacles\" \"{many}\"\n")).contains("more than 64"));
        assert!(error("\"view_angle\" \"0\"\n").contains("view_angle"));
        assert!(error("\"predator_mesh\" \"teapot\"\n").contains("unknown mesh"));
        let unknown = school("\"schol\" \"1\"\n").unwrap();
        assert!(unknown.warnings.iter().any(|w| w.to_string().contains("schol")), "{:?}", unknown.warnings);
    }

    #[test]
    fn posing_a_school_past_its_budget_is_refused_before_stepping() {
        let scene = school("\"count\" \"100000\"\n").unwrap();
        let ok = 1.0;
        assert!(scene.check_pose(ok).is_ok());
        let err = scene.check_pose(1e6).unwrap_err().to_string();
        assert!(
            err.starts_with("s.scn:1: school: time 1000000 s is ") && err.contains("steps of 100000 fish"),
            "{err}"
        );
        // One fish is little work, but not a million steps.
        let one = school("\"count\" \"1\"\n").unwrap();
        let err = one.check_pose(1e4).unwrap_err().to_string();
        assert!(err.ends_with("more than the 100000 steps one pose may take"), "{err}");
    }
}
