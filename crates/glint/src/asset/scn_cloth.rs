//! The `.scn` `cloth` class: a Discrete Elastic Plates sheet simulated in world
//! space. This is what the block says, with the sheet at rest; a
//! [`World`](crate::World) runs it to the requested time, deterministically (the
//! same time always gives the same shape).

use super::scn_fields::Fields;
use super::{AssetFolder, Diagnostic};
use crate::scene::cloth::{ClothMesh, ClothParams, ClothSetup, Collider, Integrator, PinMotion, PinSelector, Solve};
use crate::text::quote;
use glam::{DVec3, Vec3};
use std::path::Path;

pub use crate::scene::MAX_POSE_STEPS;

/// Most work posing a scene may take, in node²-steps: steps × nodes² summed
/// over its cloths. A step's Newton solve costs about 2–3·10⁻⁸ s × nodes² on the
/// 2-core reference machine (measured: 0.07 s at 33 × 33, 0.42 s at 65 × 65,
/// 5.1 s at 129 × 129, 119 s at 257 × 257), so this bound keeps the work it
/// allows to about half a minute of free swinging, a minute or two with
/// contact (see `docs/limits.md`). A static cloth's equilibrium counts as
/// [`STATIC_STEPS`] steps.
pub const MAX_POSE_NODE_STEPS: u64 = 1_000_000_000;

/// Most cloth nodes one scene may have, over all its cloth blocks: four
/// 129 × 129 sheets. Each cloth's solver is built when a world places the
/// scene (about 14 KB a node), so this bounds what that allocates.
pub const MAX_SCENE_CLOTH_NODES: u64 = 4 * 129 * 129;

/// Steps a static cloth's equilibrium counts as against [`MAX_POSE_NODE_STEPS`]:
/// its load is applied in increments, each a Newton solve like a step's, and
/// it may take `MAX_STATIC_ITERATIONS` (`sim::cloth`)
/// Newton iterations in all, about four to a step's solve. (Counted as ten
/// steps before, a 65 × 65 static sheet that did not converge ran 25–30 s.)
pub const STATIC_STEPS: u64 = 500;

pub use crate::scene::cloth::MAX_COLLIDERS;

/// Longest `gravity`, m/s² (a thousand g), and fastest `pin_velocity` (m/s) and
/// `pin_spin` (rad/s): beyond them no time step resolves the motion, and
/// Newton's method fails at run time instead of the scene at its line.
pub const MAX_CLOTH_ACCELERATION: f32 = 1e4;

/// Most nodes a `resolution` may give a side of a cloth sheet (one step of a
/// 257 × 257 sheet took two minutes: see [`MAX_POSE_NODE_STEPS`]).
const MAX_SIDE: i64 = 129;

/// A `cloth` block: everything needed to (re)start its simulation, and how it
/// is drawn (a [`World`](crate::World) makes its meshes from the simulation).
#[derive(Clone, Debug)]
pub struct ClothDesc {
    /// The simulation at rest.
    pub setup: ClothSetup,
    /// How it steps.
    pub integrator: Integrator,
    /// Time step, seconds.
    pub dt: f64,
    /// Index into [`SceneDesc::materials`](super::SceneDesc::materials); `None` for the default.
    pub material: Option<usize>,
    /// Shadow flags and draw order.
    pub draw: super::DrawOptions,
    /// Whether to draw seed 003's debug view (edge ribbons, pin markers) too.
    pub debug: bool,
    /// The block's line, for errors while posing.
    pub line: usize,
}

impl ClothDesc {
    /// Steps a pose at `time` takes from rest (1 for a static cloth).
    pub fn steps_to(&self, time: f32) -> u64 {
        match self.integrator {
            Integrator::Static => 1,
            _ => (f64::from(time.max(0.0)) / self.dt + 1e-6).floor() as u64,
        }
    }

    /// Steps posing at `time` takes from its state at `from` (`None`: from
    /// rest; a later `from` counts as rest too, as the cloth starts again).
    pub fn steps_from(&self, from: Option<f32>, time: f32) -> u64 {
        let taken = match from.filter(|&f| f <= time) {
            None => 0,
            Some(f) => self.steps_to(f),
        };
        self.steps_to(time).saturating_sub(taken)
    }

    /// The work of posing at `time` from its state at `from` (as
    /// [`steps_from`](Self::steps_from)) in node²-steps (see `MAX_POSE_NODE_STEPS`).
    pub fn pose_work(&self, from: Option<f32>, time: f32) -> u64 {
        self.steps_work(self.steps_from(from, time))
    }

    /// The work of `steps` steps in node²-steps (a static solve's, whatever
    /// their number, is [`STATIC_STEPS`]').
    fn steps_work(&self, steps: u64) -> u64 {
        let steps = match (self.integrator, steps) {
            (_, 0) => 0,
            (Integrator::Static, _) => STATIC_STEPS,
            (_, steps) => steps,
        };
        let nodes = self.setup.mesh.nodes.len() as u64;
        steps.saturating_mul(nodes.saturating_mul(nodes))
    }

    /// Check that posing at `time` from its state at `from` (as
    /// [`steps_from`](Self::steps_from)), after `others` node²-steps spent on
    /// the scene's other cloths, stays within [`MAX_POSE_STEPS`] and
    /// `MAX_POSE_NODE_STEPS`, without stepping.
    pub fn check_pose(&self, (from, time): (Option<f32>, f32), others: u64, scene: &Path) -> Result<(), Diagnostic> {
        self.check_steps(self.steps_from(from, time), (from, time), others, scene)
    }

    /// Check that taking `steps` steps to `time` from the state at `from`
    /// (for the message), after `others` node²-steps spent on the scene's
    /// other cloths, stays within the posing limits, without stepping.
    pub(crate) fn check_steps(
        &self,
        steps: u64,
        (from, time): (Option<f32>, f32),
        others: u64,
        scene: &Path,
    ) -> Result<(), Diagnostic> {
        // The message is made only for an error: this runs every pose.
        let when = || super::scene_desc::span(from, time);
        if steps > MAX_POSE_STEPS {
            let message = format!(
                "cloth: {} is {steps} steps of dt {} s, more than the {MAX_POSE_STEPS} one pose may take",
                when(),
                self.dt
            );
            return Err(Diagnostic::at(scene, self.line, message));
        }
        let work = self.steps_work(steps).saturating_add(others);
        if work > MAX_POSE_NODE_STEPS {
            let nodes = self.setup.mesh.nodes.len();
            let what = match self.integrator {
                Integrator::Static => format!("a static solve of {nodes} nodes counts as {STATIC_STEPS} steps"),
                _ => format!("{} is {steps} steps of dt {} s for {nodes} nodes", when(), self.dt),
            };
            let others = if others > 0 { format!(" with the scene's other cloths ({others})") } else { String::new() };
            let message = format!(
                "cloth: {what}: {work} node²-steps{others}, more than the {MAX_POSE_NODE_STEPS} a scene's pose may take \
                 (a coarser resolution, a larger \"dt\" or an earlier time fits)"
            );
            return Err(Diagnostic::at(scene, self.line, message));
        }
        Ok(())
    }
}

/// Read a `cloth` block (all but `material` and the draw options, which the
/// loader reads as for entities); `dir` anchors a relative `mesh` path.
/// `nodes_before` is how many cloth nodes the scene's earlier blocks have: the
/// total is checked against [`MAX_SCENE_CLOTH_NODES`] before the solver is built.
pub(crate) fn parse(f: &mut Fields, assets: &AssetFolder, nodes_before: u64) -> Result<ClothDesc, Diagnostic> {
    let at = |line: usize, m: String| Diagnostic::at(f.path, line, m);
    let local = local_mesh(f, assets)?;
    let nodes = nodes_before.saturating_add(local.nodes.len() as u64);
    if nodes > MAX_SCENE_CLOTH_NODES {
        let message = format!(
            "cloth: the scene's cloths would have {nodes} nodes, more than the {MAX_SCENE_CLOTH_NODES} glint \
             simulates in one scene (four 129 × 129 sheets)"
        );
        return Err(at(f.block.line, message));
    }
    let origin = f.vec3("origin")?.unwrap_or(Vec3::ZERO);
    let rotation = super::scn::rotation(f.vec3("angles")?.unwrap_or(Vec3::ZERO));
    let pins_pair = f.get("pins");
    let selector = match pins_pair {
        Some(p) => PinSelector::parse(&p.value).map_err(|m| at(p.line, format!("\"pins\": {m}")))?,
        None => PinSelector::None,
    };
    let pinned = selector
        .select(&local.nodes)
        .map_err(|m| at(pins_pair.map_or(f.block.line, |p| p.line), format!("\"pins\": {m}")))?;
    let (rotation, origin) = (rotation.as_dquat(), exact3(origin));
    let place = |p: DVec3| rotation * p + origin;
    let mesh = ClothMesh::new(local.nodes.iter().map(|&p| place(p)).collect(), local.triangles.clone())
        .map_err(|e| at(f.block.line, format!("cloth mesh: {e}")))?;
    let thickness = exact(f.number("thickness", 1e-6..=1.0)?.unwrap_or(1e-3));
    let params = ClothParams {
        thickness,
        young: exact(f.number("young", 1.0..=1e13)?.unwrap_or(1e7)),
        poisson: exact(f.number("poisson", 0.0..=0.5)?.unwrap_or(0.3)),
        density: exact(f.number("density", 1e-3..=1e5)?.unwrap_or(200.0)),
        gravity: exact3(f.bounded_vec3("gravity", MAX_CLOTH_ACCELERATION)?.unwrap_or(Vec3::new(0.0, -9.81, 0.0))),
    };
    let pin_motion = PinMotion {
        velocity: exact3(f.bounded_vec3("pin_velocity", MAX_CLOTH_ACCELERATION)?.unwrap_or(Vec3::ZERO)),
        angular_velocity: exact3(f.bounded_vec3("pin_spin", MAX_CLOTH_ACCELERATION)?.unwrap_or(Vec3::ZERO)),
        centre: origin,
    };
    let colliders = match f.get("colliders") {
        None => Vec::new(),
        Some(p) => {
            let texts: Vec<&str> = p.value.split(';').map(str::trim).filter(|c| !c.is_empty()).collect();
            if texts.len() > MAX_COLLIDERS {
                let message = format!("\"colliders\": {} colliders, at most {MAX_COLLIDERS}", texts.len());
                return Err(at(p.line, message));
            }
            (texts.into_iter())
                .map(|c| Collider::parse(c).map_err(|m| at(p.line, format!("\"colliders\": {m}"))))
                .collect::<Result<_, _>>()?
        }
    };
    let contact_distance = f.number("contact_distance", 1e-6..=1.0)?.map_or(thickness.max(1e-3), exact);
    let integrator = match f.choice("integrator", &["implicit_euler", "newmark", "static"])? {
        None | Some((0, _)) => Integrator::ImplicitEuler,
        Some((1, _)) => Integrator::Newmark,
        Some(_) => Integrator::Static,
    };
    let dt = exact(f.number("dt", 1e-5..=1.0)?.unwrap_or(0.01));
    let damping = exact(f.number("damping", 0.0..=1e6)?.unwrap_or(0.0));
    let solve = match f.choice("solve", &["converged", "realtime", "gpu"])? {
        None | Some((0, _)) => Solve::Converged,
        Some((1, _)) => Solve::Realtime,
        Some(_) => Solve::Gpu,
    };
    let debug = f.flag("debug")?.unwrap_or(false);
    let setup = ClothSetup { mesh, params, pinned, pin_motion, colliders, contact_distance, damping, solve };
    setup.check().map_err(|e| at(f.block.line, format!("cloth: {e}")))?;
    Ok(ClothDesc {
        setup,
        integrator,
        dt,
        material: None,
        draw: super::DrawOptions::default(),
        debug,
        line: f.block.line,
    })
}

/// A number as written: the shortest decimal that reads back as this `f32`
/// (what the file said, to 7 digits), in double precision, so `0.05` is 0.05
/// and not 0.0500000007.
fn exact(v: f32) -> f64 {
    v.to_string().parse().unwrap_or(f64::from(v))
}

fn exact3(v: Vec3) -> DVec3 {
    DVec3::new(exact(v.x), exact(v.y), exact(v.z))
}

/// The cloth's mesh in its own coordinates: a `mesh` file, or a `size` × `resolution`
/// sheet in the XZ plane centred on the origin, facing +Y (x across its width,
/// z across its depth; pin predicates read these coordinates).
fn local_mesh(f: &mut Fields, assets: &AssetFolder) -> Result<ClothMesh, Diagnostic> {
    if let Some(pair) = f.get("mesh") {
        let at = |e: Diagnostic| Diagnostic::at(f.path, pair.line, format!("\"mesh\": {}", e.message));
        let file = assets.resolve(pair.value.trim(), f.path).map_err(at)?;
        return super::read_cloth_mesh(&file, &assets.files)
            .map_err(|e| Diagnostic::at(f.path, pair.line, format!("\"mesh\": {e}")));
    }
    let [w, d] = f.numbers::<2>("size", "2 numbers (width depth)")?.unwrap_or([1.0, 1.0]);
    if w <= 0.0 || d <= 0.0 {
        return Err(Diagnostic::at(f.path, f.block.line, "\"size\" must be two sizes above 0"));
    }
    let [n, m] = match f.get("resolution") {
        None => [17, 17],
        Some(p) => {
            let words: Vec<Option<i64>> = p.value.split_whitespace().map(|w| w.parse().ok()).collect();
            match words[..] {
                [Some(n), Some(m)] if (2..=MAX_SIDE).contains(&n) && (2..=MAX_SIDE).contains(&m) => [n, m],
                _ => {
                    let message =
                        format!("\"resolution\" is {}, expected 2 whole numbers in 2..={MAX_SIDE}", quote(&p.value));
                    return Err(Diagnostic::at(f.path, p.line, message));
                }
            }
        }
    };
    let (w, d) = (exact(w), exact(d));
    let sheet = ClothMesh::sheet(w, d, n as u32, m as u32);
    let (hw, hd) = (w / 2.0, d / 2.0);
    // The XY sheet turned to lie in XZ facing +Y: (x, y) → (x − w/2, 0, d/2 − y).
    let nodes = sheet.nodes.iter().map(|p| DVec3::new(p.x - hw, 0.0, hd - p.y)).collect();
    Ok(ClothMesh { nodes, triangles: sheet.triangles })
}

#[cfg(test)]
mod tests {
    use super::super::{parse_scene, SceneDesc};
    use super::*;

    fn parse(body: &str) -> Result<SceneDesc, Diagnostic> {
        parse_scene(Path::new("dir/t.scn"), &format!("{{\n\"classname\" \"cloth\"\n{body}}}\n"))
    }

    #[test]
    fn a_sheet_is_placed_in_the_world_with_pins_read_in_its_own_coordinates() {
        let scene = parse("\"size\" \"2 1\"\n\"resolution\" \"3 2\"\n\"origin\" \"0 1 0\"\n\"angles\" \"0 90 0\"\n\"pins\" \"x<=-1\"\n\"integrator\" \"newmark\"\n\"colliders\" \"plane 0 0 0 0 1 0; sphere 0 0.5 0 0.25\"\n").unwrap();
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
        let cloth = &scene.cloths[0];
        assert_eq!(cloth.setup.mesh.nodes.len(), 6);
        // Local (-1, 0, 0.5) is the first node; yaw 90° turns +X to -Z, and origin lifts it 1 m.
        let first = cloth.setup.mesh.nodes[0];
        assert!(first.distance(DVec3::new(0.5, 1.0, 1.0)) < 1e-6, "{first}");
        assert_eq!(cloth.setup.pinned, [true, false, false, true, false, false], "the x = -1 edge, before placement");
        assert_eq!(cloth.integrator, Integrator::Newmark);
        assert_eq!(cloth.setup.solve, Solve::Converged, "the default");
        let realtime = parse("\"size\" \"2 1\"\n\"resolution\" \"3 2\"\n\"solve\" \"realtime\"\n").unwrap();
        assert_eq!(realtime.cloths[0].setup.solve, Solve::Realtime);
        let gpu = parse("\"size\" \"2 1\"\n\"resolution\" \"3 2\"\n\"solve\" \"gpu\"\n").unwrap();
        assert_eq!(gpu.cloths[0].setup.solve, Solve::Gpu);
        let wrong = parse("\"size\" \"2 1\"\n\"resolution\" \"3 2\"\n\"solve\" \"fast\"\n").unwrap_err().to_string();
        assert!(wrong.contains("t.scn:5") && wrong.contains("converged") && wrong.contains("gpu"), "{wrong}");
        // `--solve` on `render` and `view`: every cloth, whatever its block says.
        let text = "{\n\"classname\" \"cloth\"\n\"size\" \"2 1\"\n\"resolution\" \"3 2\"\n\"solve\" \"realtime\"\n}\n";
        let options = crate::asset::LoadOptions { cloth_solve: Some(Solve::Converged), ..Default::default() };
        let overridden = super::super::parse_scene_with(Path::new("dir/t.scn"), text, options).unwrap();
        assert_eq!(overridden.cloths[0].setup.solve, Solve::Converged);
        assert_eq!(cloth.setup.colliders.len(), 2);
        assert_eq!(cloth.setup.contact_distance, 1e-3);
        assert_eq!(cloth.setup.params.gravity, DVec3::new(0.0, -9.81, 0.0));
        assert!(!cloth.debug, "no debug view unless asked for");
    }

    #[test]
    fn posing_work_is_capped_over_every_cloth_before_any_step() {
        let block = "{\n\"classname\" \"cloth\"\n\"resolution\" \"65 65\"\n\"pins\" \"z<=-0.5\"\n\"dt\" \"0.01\"\n}\n";
        let one = parse_scene(Path::new("dir/t.scn"), block).unwrap();
        let nodes = 65 * 65;
        let fits = MAX_POSE_NODE_STEPS / (nodes * nodes);
        // Half a step past a whole number of steps, so rounding cannot tip it.
        let at = |steps: u64| (steps as f32 + 0.5) * 0.01;
        assert_eq!(one.cloths[0].steps_to(at(fits)), fits);
        assert!(one.check_pose(at(fits)).is_ok());
        let err = one.check_pose(at(fits + 1)).unwrap_err();
        assert_eq!(err.line, Some(1), "{err}");
        assert!(err.message.contains(&format!("{} node²-steps", (fits + 1) * nodes * nodes)), "{err}");
        assert!(err.message.contains(&format!("more than the {MAX_POSE_NODE_STEPS}")), "{err}");
        // Two cloths share the budget: the second is named.
        let two = parse_scene(Path::new("dir/t.scn"), &block.repeat(2)).unwrap();
        assert!(two.check_pose(at(fits / 2)).is_ok());
        let err = two.check_pose(at(fits)).unwrap_err();
        assert_eq!(err.line, Some(7), "{err}");
        assert!(err.message.contains("other cloths"), "{err}");
        // A sequence posed frame by frame is checked a frame at a time: from a
        // state at one time, only the steps since count (an earlier time
        // starts again, and counts every step).
        let (from, to) = (at(fits + 10), at(2 * fits + 10));
        assert_eq!(one.cloths[0].steps_from(Some(from), to), fits);
        assert!(one.check_pose_from(Some(from), to).is_ok());
        assert!(one.check_pose_from(Some(from), at(2 * fits + 11)).unwrap_err().message.contains(" s to "));
        assert!(one.check_pose_from(Some(to), from).is_err(), "an earlier time steps from rest");
        assert!(one.check_pose_from(None, to).is_err());
    }

    #[test]
    fn a_static_solve_counts_as_ten_steps_whatever_the_time() {
        let scene = parse("\"resolution\" \"9 9\"\n\"pins\" \"z<=-0.5\"\n\"integrator\" \"static\"\n").unwrap();
        let cloth = &scene.cloths[0];
        assert_eq!((cloth.steps_to(1e6), cloth.pose_work(None, 1e6)), (1, STATIC_STEPS * 81 * 81));
        assert!(scene.check_pose(1e6).is_ok());
        // Solved once: posing it again takes no work.
        assert_eq!(cloth.pose_work(Some(1.0), 1e6), 0);
    }

    #[test]
    fn a_cloth_mesh_with_too_many_nodes_is_refused_at_its_block() {
        // A 320 × 320 grid of nodes from a mesh file: more nodes than a scene
        // may simulate, refused before its solver is built.
        let dir = tempfile_dir();
        let n = 320u32;
        let mut obj = String::new();
        for j in 0..n {
            for i in 0..n {
                obj.push_str(&format!("v {} {} 0\n", i as f64 / 100.0, j as f64 / 100.0));
            }
        }
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = j * n + i + 1;
                obj.push_str(&format!("f {a} {} {}\nf {a} {} {}\n", a + 1, a + n + 1, a + n + 1, a + n));
            }
        }
        std::fs::write(dir.join("big.obj"), obj).unwrap();
        let scene = dir.join("t.scn");
        std::fs::write(&scene, "// big\n{\n\"classname\" \"cloth\"\n\"mesh\" \"big.obj\"\n}\n").unwrap();
        let err = super::super::load_scene(&scene).unwrap_err();
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(err.line, Some(2), "{err}");
        assert!(err.message.contains(&format!("would have {} nodes, more than the", n * n)), "{err}");
    }

    /// A fresh folder under the system's temporary folder.
    fn tempfile_dir() -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!(
            "glint-scn-cloth-{}-{:?}",
            std::process::id(),
            std::thread::current().id()
        ));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn bad_cloth_blocks_say_where_and_what() {
        for (body, line, message) in [
            ("\"resolution\" \"1 5\"\n", 3, "expected 2 whole numbers in 2..=129"),
            ("\"resolution\" \"5\"\n", 3, "expected 2 whole numbers"),
            ("\"size\" \"0 1\"\n", 1, "\"size\" must be two sizes above 0"),
            ("\"pins\" \"w<3\"\n", 3, "\"pins\""),
            ("\"pins\" \"nodes 1 9999\"\n", 3, "\"pins\""),
            ("\"colliders\" \"plane 0 0 0\"\n", 3, "\"colliders\": 'plane 0 0 0' is not a collider"),
            ("\"integrator\" \"rk4\"\n", 3, "expected one of: implicit_euler, newmark, static"),
            ("\"dt\" \"0\"\n", 3, "\"dt\" is 0"),
            ("\"young\" \"-5\"\n", 3, "\"young\" is -5"),
            ("\"mesh\" \"missing.obj\"\n", 3, "\"mesh\": "),
            ("\"material\" \"silk\"\n", 3, "unknown material 'silk'"),
            ("\"debug\" \"yes\"\n", 3, "expected 0 or 1"),
            ("\"size\" \"1e38 1e38\"\n\"origin\" \"3.4e38 0 0\"\n", 1, "cloth: "),
        ] {
            let err = parse(body).unwrap_err();
            assert_eq!(err.line, Some(line), "{body}: {err}");
            assert!(err.message.contains(message), "{body}: {err}");
        }
        let warned = parse("\"sise\" \"1 1\"\n").unwrap();
        assert!(warned.warnings[0].message.contains("unknown key 'sise' in cloth block"));
    }

    #[test]
    fn the_tablecloth_scene_loads_without_warnings() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/tablecloth.scn");
        let scene = super::super::load_scene(&path).unwrap();
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
        assert_eq!(scene.cloths.len(), 1);
        assert_eq!(scene.cloths[0].setup.mesh.nodes.len(), 33 * 33);
        assert_eq!(scene.cloths[0].setup.colliders.len(), 2);
    }
}
