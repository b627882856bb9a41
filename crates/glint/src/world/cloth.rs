//! Core layer: a scene's cloth as it runs. The `.scn` block ([`ClothDesc`]) is
//! what the file says, with the mesh at rest; a [`ClothSim`] is the simulation
//! stepping from that rest state, and its meshes at rest and now: on the CPU,
//! its surface shape replaced after each pose; on the GPU (`"solve" "gpu"`
//! where the renderer computes), stepped in the frame's simulate stage and
//! written into its surface shape's vertices there
//! ([`GpuCloth::draw_in_place`]), the CPU's meshes left at rest.

use super::sim_state::{chunks, value_bytes, values, SimKind, SimRecord};
use crate::asset::ClothDesc;
use crate::render::GpuSimulation;
use crate::scene::cloth::{Collider, Solve};
use crate::scene::{Aabb, SimPath};
use crate::sim::cloth::{Cloth, ClothView, GpuCloth, GpuSolve, Integrator};
use crate::{Diagnostic, Entity, Renderer};
use glam::{DVec3, Vec3};
use std::path::Path;

/// A cloth stepped on the GPU, drawn in place.
struct GpuRun {
    cloth: Box<GpuCloth>,
    /// The cloth at rest, which it starts again from.
    start: Box<Cloth>,
    /// Steps recorded (taken or pending).
    steps: u64,
    /// How far its nodes may be from what the CPU knows (its pins, its rest place).
    reach: Reach,
}

/// One cloth's running simulation: the solver and the steps it has taken, and
/// its meshes at rest and as of the last pose; none of them for a setup that
/// cannot be simulated (a description changed after loading:
/// [`SceneDesc::check_pose`](crate::asset::SceneDesc::check_pose) refuses to pose it).
pub(crate) struct ClothSim {
    run: Option<(Box<Cloth>, u64)>,
    /// Where it steps on the GPU instead (`run` is then `None`).
    gpu: Option<GpuRun>,
    rest: Option<ClothView>,
    pub(crate) view: Option<ClothView>,
    /// Resumed from a simulation cache since the last pose, so the next
    /// one shows it even where it takes no step.
    resumed: bool,
}

impl ClothSim {
    /// `desc` started, at rest, on the CPU.
    pub(crate) fn new(desc: &ClothDesc) -> Self {
        let Ok(cloth) = Cloth::start(&desc.setup) else {
            return Self { run: None, gpu: None, rest: None, view: None, resumed: false };
        };
        let rest = ClothView::new(&cloth, desc.debug).ok();
        Self { run: rest.is_some().then(|| (Box::new(cloth), 0)), gpu: None, view: rest.clone(), rest, resumed: false }
    }

    /// Move it onto the GPU, drawn in place, where `desc` asks (`"solve"
    /// "gpu"`) and `renderer` computes: `surface` (the entity drawing its
    /// surface) then gets its vertices from the simulation and is culled by
    /// the box its reach holds ([`Entity::with_gpu_instances`]). It stays on
    /// the CPU, solved to convergence, with a warning, where the renderer has
    /// no compute path (GL, WebGL2), the cloth is static (solved once) or
    /// drawn with its debug view (ribbons and pins made on the CPU), or the
    /// GPU cannot make its buffers.
    pub(crate) fn move_to_gpu(&mut self, desc: &ClothDesc, surface: &mut Entity, renderer: &Renderer) {
        let Some((cloth, 0)) = &self.run else { return };
        if desc.setup.solve != Solve::Gpu {
            return;
        }
        let refused = if !renderer.computes() {
            Some("the renderer has no compute path (GL, WebGL2)")
        } else if desc.integrator == Integrator::Static {
            Some("a static cloth is solved once, on the CPU")
        } else if desc.debug {
            Some("its debug view is made on the CPU")
        } else {
            None
        };
        if let Some(why) = refused {
            return log::warn!("cloth (line {}): solved on the CPU (converged): {why}", desc.line);
        }
        let queue = renderer.device_and_queue();
        let mut gpu = match GpuCloth::on_device(queue, cloth, (desc.dt, desc.integrator), GpuSolve::default()) {
            Ok(gpu) => gpu,
            Err(e) => return log::warn!("cloth (line {}): solved on the CPU (converged): {e}", desc.line),
        };
        gpu.draw_in_place(queue, cloth, surface.shape);
        let reach = Reach::of(cloth);
        surface.set_gpu_instances(Some(reach.held(desc, 0.0)));
        let start = self.run.take().expect("checked above").0;
        self.gpu = Some(GpuRun { cloth: Box::new(gpu), start, steps: 0, reach });
    }

    /// On the GPU, record the steps up to `time` seconds (starting again from
    /// rest for an earlier time, or after a failed frame) for the next
    /// frame's simulate stage ([`simulation`](Self::simulation)), and move
    /// `surface`'s held box along; returns false, doing nothing, when the CPU
    /// steps it ([`pose`](Self::pose)). The posing budget was checked before
    /// ([`SceneDesc::check_pose_from`](crate::asset::SceneDesc::check_pose_from)).
    pub(crate) fn pose_on_gpu(
        &mut self,
        desc: &ClothDesc,
        time: f32,
        queue: &wgpu::Queue,
        surface: &mut Entity,
    ) -> bool {
        let Some(run) = &mut self.gpu else { return false };
        let target = desc.steps_to(time);
        if run.steps > target {
            run.cloth.restart(queue, &run.start);
            run.steps = 0;
        }
        // `check_pose_from` bounds the steps by MAX_POSE_STEPS.
        let more = target - run.steps;
        run.cloth.advance(u32::try_from(more).unwrap_or(u32::MAX));
        run.steps += more;
        let held = run.reach.held(desc, time);
        if surface.gpu_instances() != Some(held) {
            surface.set_gpu_instances(Some(held));
        }
        true
    }

    /// On the CPU, advance (or restart and advance) to `time` seconds and
    /// update the view; returns whether the view changed. A static cloth takes
    /// its one equilibrium step whatever the time. Refuses work past the
    /// posing budget from the steps it has taken, before stepping
    /// ([`SceneDesc::check_pose_from`](crate::asset::SceneDesc::check_pose_from)
    /// checks the whole scene); a step that fails is [`Error::Posing`](crate::Error::Posing), naming `scene`, the
    /// block's line and the time it stepped from.
    pub(crate) fn pose(&mut self, desc: &ClothDesc, time: f32, scene: &Path) -> Result<bool, crate::Error> {
        let target = desc.steps_to(time);
        // Checked again here, from the steps it has taken, for a caller that did not.
        let taken = match &self.run {
            Some((_, taken)) if *taken <= target => *taken,
            _ => 0,
        };
        desc.check_steps(target - taken, (None, time), 0, scene)?;
        let Some(rest) = &self.rest else { return Ok(false) };
        let (mut run, restarted) = match self.run.take() {
            Some(run) if run.1 <= target => (run, false),
            earlier => {
                if target == 0 && desc.integrator != Integrator::Static {
                    // The rest state: no solver is needed to show it.
                    self.view = Some(rest.clone());
                    return Ok(earlier.is_some());
                }
                let cloth =
                    Cloth::start(&desc.setup).map_err(|e| Diagnostic::at(scene, desc.line, format!("cloth: {e}")))?;
                ((Box::new(cloth), 0), true)
            }
        };
        let moved = restarted || run.1 < target || std::mem::take(&mut self.resumed);
        while run.1 < target {
            let from = run.0.time;
            let failed = |source| {
                let place = Diagnostic::at(scene, desc.line, format!("cloth, stepping from {from} s"));
                crate::Error::Posing { place, source }
            };
            run.0.step(desc.dt, desc.integrator).map_err(failed)?;
            run.1 += 1;
        }
        if let Some(view) = self.view.as_mut().filter(|_| moved) {
            view.update(&run.0);
        }
        self.run = Some(run);
        Ok(moved)
    }

    /// Its state for a simulation cache ([`World::sim_state`](super::World::sim_state)),
    /// `None` when it cannot run or has GPU steps pending.
    pub(crate) fn save(&self, gpu: (&wgpu::Device, &wgpu::Queue)) -> Result<Option<SimRecord>, crate::GpuError> {
        let record = |path, steps, chunks| SimRecord { kind: SimKind::Cloth, path, steps, chunks };
        if let Some(run) = &self.gpu {
            return Ok(run.cloth.save(gpu)?.map(|chunks| record(SimPath::Gpu, run.steps, chunks)));
        }
        let Some((cloth, steps)) = &self.run else { return Ok(None) };
        let xyz = |v: &[DVec3]| value_bytes(v.iter().map(|p| p.to_array()));
        let (p, v, a) = (xyz(&cloth.positions), xyz(&cloth.velocities), xyz(cloth.accelerations()));
        Ok(Some(record(SimPath::Cpu, *steps, vec![p, v, a, value_bytes([cloth.time])])))
    }

    /// Go on from `record` ([`save`](Self::save)d from the same cloth on the
    /// same path): the next pose steps on from it.
    pub(crate) fn load(&mut self, desc: &ClothDesc, record: &SimRecord, queue: &wgpu::Queue) -> Result<(), String> {
        if let Some(run) = &mut self.gpu {
            run.cloth.load(queue, (&run.start, record.steps), chunks::<4>(record)?)?;
            run.steps = record.steps;
            return Ok(());
        }
        let [p, v, a, time] = chunks::<4>(record)?;
        let xyz = |bytes| -> Result<Vec<DVec3>, String> {
            Ok(values::<[f64; 3]>(bytes)?.into_iter().map(DVec3::from_array).collect())
        };
        let time = match values::<f64>(time)?.as_slice() {
            [t] => *t,
            other => return Err(format!("{} values for the time, expected 1", other.len())),
        };
        let state = [xyz(p)?, xyz(v)?, xyz(a)?];
        let (mut cloth, steps) = match self.run.take() {
            Some(run) => run,
            None => (Box::new(Cloth::start(&desc.setup).map_err(|e| format!("cloth: {e}"))?), 0),
        };
        // Nothing changes where the record does not fit.
        let resumed = cloth.resume(state, time);
        self.run = Some((cloth, if resumed.is_ok() { record.steps } else { steps }));
        resumed?;
        if let (Some(view), Some((cloth, _))) = (self.view.as_mut(), &self.run) {
            view.update(cloth);
        }
        self.resumed = true;
        Ok(())
    }

    /// A frame that recorded its GPU steps failed and dropped them: start
    /// again from rest at the next pose.
    pub(crate) fn frame_failed(&mut self) {
        if let Some(run) = &mut self.gpu {
            run.steps = u64::MAX;
        }
    }

    /// Where it steps; `None` when it cannot run.
    pub(crate) fn path(&self) -> Option<SimPath> {
        match (&self.gpu, &self.view) {
            (Some(_), _) => Some(SimPath::Gpu),
            (None, Some(_)) => Some(SimPath::Cpu),
            (None, None) => None,
        }
    }

    /// Its meshes as of the last pose, when the CPU steps it.
    pub(crate) fn cpu_view(&self) -> Option<&ClothView> {
        self.view.as_ref().filter(|_| self.gpu.is_none())
    }

    /// Its steps and surface for the frame's simulate stage, on the GPU.
    pub(crate) fn simulation(&mut self) -> Option<&mut dyn GpuSimulation> {
        self.gpu.as_mut().map(|run| -> &mut dyn GpuSimulation { run.cloth.as_mut() })
    }
}

/// What bounds a GPU cloth's nodes without reading them back. Cloth barely
/// stretches (its membrane is stiff against its weight), so where every node
/// has a path to a pin no node is farther from a pin than twice that path
/// along the rest mesh. Otherwise the cloth falls: it is held within twice
/// the rest mesh's diagonal of its rest place swept along gravity for the
/// time it has fallen, and sideways by half that (as far as sliding down any
/// fixed slope carries it), with its pins where they are; and on the free side
/// of each plane collider facing along an axis that it starts on (a floor).
struct Reach {
    /// Longest rest path from any node to its nearest pin, metres; `None`
    /// when some node has no path to a pin.
    to_pin: Option<f32>,
    /// The rest mesh's box, and its diagonal.
    rest: Aabb,
    diagonal: f32,
}

impl Reach {
    fn of(cloth: &Cloth) -> Self {
        let nodes = &cloth.mesh().nodes;
        let pins: Vec<usize> = (0..nodes.len()).filter(|&i| cloth.is_pinned(i)).collect();
        let paths = rest_paths(nodes, &cloth.topology().edges, &pins);
        let to_pin = paths.iter().copied().reduce(f64::max).filter(|d| d.is_finite() && !pins.is_empty());
        let rest =
            Aabb::from_points(nodes.iter().map(|p| p.as_vec3())).unwrap_or(Aabb { min: Vec3::ZERO, max: Vec3::ZERO });
        Self { to_pin: to_pin.map(|d| d as f32), rest, diagonal: (rest.max - rest.min).length() }
    }

    /// The box holding the cloth `desc` at `time` seconds.
    fn held(&self, desc: &ClothDesc, time: f32) -> Aabb {
        let setup = &desc.setup;
        let t = time.max(0.0);
        let pinned = setup.mesh.nodes.iter().zip(&setup.pinned).filter(|(_, &p)| p);
        let pins = Aabb::from_points(pinned.map(|(p, _)| setup.pin_motion.at(*p, f64::from(t)).as_vec3()));
        let (lo, hi) = match (self.to_pin, pins) {
            (Some(path), Some(pins)) => (pins.min - Vec3::splat(2.0 * path), pins.max + Vec3::splat(2.0 * path)),
            _ => {
                let g = setup.params.gravity.as_vec3();
                let fall = 0.5 * g * t * t;
                let sideways = Vec3::splat(0.25 * g.length() * t * t) - 0.5 * fall.abs();
                let Aabb { min: rest_lo, max: rest_hi } = self.rest;
                let reach = Vec3::splat(2.0 * self.diagonal) + sideways.max(Vec3::ZERO);
                let mut lo = rest_lo.min(rest_lo + fall) - reach;
                let mut hi = rest_hi.max(rest_hi + fall) + reach;
                if let Some(pins) = pins {
                    (lo, hi) = (lo.min(pins.min), hi.max(pins.max));
                }
                // Past a floor it starts on only by the contact's give.
                let give = setup.contact_distance as f32 + 0.05 * self.diagonal;
                for collider in &setup.colliders {
                    let Collider::Plane { point, normal } = *collider else { continue };
                    let (point, normal) = (point.as_vec3(), normal.as_vec3());
                    for axis in 0..3 {
                        if normal[axis] > 1.0 - 1e-6 && rest_lo[axis] >= point[axis] - give {
                            lo[axis] = lo[axis].max(point[axis] - give);
                        } else if normal[axis] < -1.0 + 1e-6 && rest_hi[axis] <= point[axis] + give {
                            hi[axis] = hi[axis].min(point[axis] + give);
                        }
                    }
                }
                (lo, hi)
            }
        };
        let grow = Vec3::splat(setup.contact_distance as f32);
        Aabb { min: lo - grow, max: hi + grow }
    }
}

/// Each node's shortest path along the rest mesh's `edges` to one of `pins`
/// (Dijkstra's algorithm; infinite where none reaches).
fn rest_paths(nodes: &[DVec3], edges: &[[u32; 2]], pins: &[usize]) -> Vec<f64> {
    let mut neighbours = vec![Vec::new(); nodes.len()];
    for &[a, b] in edges {
        let length = nodes[a as usize].distance(nodes[b as usize]);
        neighbours[a as usize].push((b as usize, length));
        neighbours[b as usize].push((a as usize, length));
    }
    let mut best = vec![f64::INFINITY; nodes.len()];
    // Non-negative lengths order as their bits do.
    let mut queue = std::collections::BinaryHeap::new();
    for &p in pins {
        best[p] = 0.0;
        queue.push(std::cmp::Reverse((0u64, p)));
    }
    while let Some(std::cmp::Reverse((bits, i))) = queue.pop() {
        let d = f64::from_bits(bits);
        if d > best[i] {
            continue;
        }
        for &(j, length) in &neighbours[i] {
            if d + length < best[j] {
                best[j] = d + length;
                queue.push(std::cmp::Reverse(((d + length).to_bits(), j)));
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::asset::{parse_scene, SceneDesc};

    fn parse(body: &str) -> SceneDesc {
        parse_scene(Path::new("dir/t.scn"), &format!("{{\n\"classname\" \"cloth\"\n{body}}}\n")).unwrap()
    }

    /// The bounds of `cloth`'s surface as last posed.
    fn surface(cloth: &ClothSim) -> crate::scene::Aabb {
        cloth.view.as_ref().expect("a cloth that can be simulated").surface.aabb()
    }

    #[test]
    fn posing_steps_to_the_time_and_restarts_when_it_goes_back() {
        let scene = parse("\"size\" \"1 1\"\n\"resolution\" \"4 4\"\n\"pins\" \"z<=-0.5\"\n\"dt\" \"0.05\"\n");
        let desc = &scene.cloths[0];
        let mut cloth = ClothSim::new(desc);
        let at = |cloth: &mut ClothSim, time: f32| cloth.pose(desc, time, Path::new("t.scn"));
        let rest = surface(&cloth);
        assert!(!at(&mut cloth, 0.0).unwrap(), "time 0 is the rest state it already has");
        assert!(at(&mut cloth, 0.5).unwrap());
        let swung = surface(&cloth);
        assert!(swung.min.y < rest.min.y - 0.2, "the free edge fell: {swung:?}");
        assert!(!at(&mut cloth, 0.52).unwrap(), "less than a step later: no new step");
        assert!(at(&mut cloth, 0.1).unwrap(), "earlier: restarted from rest");
        assert!(surface(&cloth).min.y > swung.min.y);
        assert!(at(&mut cloth, 0.0).unwrap(), "back to rest");
        assert_eq!(surface(&cloth), rest);
        let err = at(&mut cloth, 1e6).unwrap_err().to_string();
        assert!(err.starts_with("t.scn:1: cloth: time 1000000 s is 20000000 steps"), "{err}");
    }

    #[test]
    fn a_started_cloth_solves_as_its_block_says() {
        let scene = parse("\"size\" \"2 1\"\n\"resolution\" \"3 2\"\n\"solve\" \"realtime\"\n");
        let cloth = Cloth::start(&scene.cloths[0].setup).unwrap();
        assert_eq!(cloth.solve(), crate::sim::cloth::Solve::Realtime);
    }

    #[test]
    fn a_static_cloth_takes_its_equilibrium_step_at_any_time() {
        // A 0.1 m cantilever clamped by its back two rows of nodes (one row
        // alone would be a hinge, free to swing).
        let body = "\"size\" \"0.1 0.1\"\n\"resolution\" \"5 5\"\n\"pins\" \"z<=-0.02\"\n\"young\" \"1e9\"\n";
        let scene = parse(&format!("{body}\"integrator\" \"static\"\n"));
        let desc = &scene.cloths[0];
        let mut cloth = ClothSim::new(desc);
        assert!(cloth.pose(desc, 0.0, Path::new("t.scn")).unwrap());
        let hanging = surface(&cloth);
        assert!(hanging.min.y < -1e-4, "it sags at equilibrium: {hanging:?}");
        assert!(!cloth.pose(desc, 5.0, Path::new("t.scn")).unwrap(), "the same equilibrium later");
    }

    #[test]
    fn a_cloth_that_cannot_be_solved_names_its_scene_block_and_time() {
        // No pins and no floor: a static sheet under gravity has no equilibrium.
        let scene = parse("\"resolution\" \"3 3\"\n\"integrator\" \"static\"\n");
        let err = ClothSim::new(&scene.cloths[0]).pose(&scene.cloths[0], 0.0, Path::new("dir/t.scn")).unwrap_err();
        assert_eq!(err.exit_code(), 3);
        let text = err.to_string();
        assert!(text.starts_with("dir/t.scn:1: cloth, stepping from 0 s: "), "{text}");
    }

    /// `tests/scenes/cloth_gpu.scn` placed in a renderer on `gpu`.
    fn gpu_world(gpu: &crate::Gpu) -> (crate::World, Renderer) {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().expect("the repo");
        let options = crate::asset::LoadOptions { asset_roots: vec![root.clone()], ..Default::default() };
        let desc = crate::asset::load_scene_with(&root.join("tests/scenes/cloth_gpu.scn"), options).expect("scene");
        let mut renderer = Renderer::new(gpu);
        let world = crate::World::place(desc, &mut renderer).expect("placed");
        (world, renderer)
    }

    /// Each GPU cloth's state read back: positions, in file order.
    fn gpu_positions(gpu: &crate::Gpu, world: &crate::World) -> Vec<Vec<DVec3>> {
        let read = |(sim, desc): (&ClothSim, &ClothDesc)| {
            let mut cloth = Cloth::start(&desc.setup).expect("the cloth");
            sim.gpu.as_ref().expect("on the GPU").cloth.read_into(gpu, &mut cloth).expect("read back");
            cloth.positions
        };
        world.cloths.iter().zip(&world.desc.cloths).map(read).collect()
    }

    #[test]
    fn the_place_pass_writes_each_node_and_its_normal_into_the_surface_vertices() {
        let Some(gpu) = crate::gpu::test_gpu() else { return };
        if !gpu.culls_on_gpu() {
            return;
        }
        let (mut world, mut renderer) = gpu_world(&gpu);
        world.pose(0.3, &mut renderer).expect("posed");
        let mut target = crate::OffscreenTarget::new(&gpu, 16, 16, 1).expect("target");
        world.draw(&mut renderer, &world.views(None), &mut target).expect("frame");
        let positions = gpu_positions(&gpu, &world);
        // The cloths' surfaces are the entities after the floor's.
        for (k, nodes) in positions.iter().enumerate() {
            let shape = world.entities()[1 + k].shape;
            let at = renderer.res.registry.vertex_target(shape).expect("in the pool");
            assert_eq!(at.count as usize, nodes.len());
            let bytes = gpu.read_buffer(at.buffer).expect("vertices");
            let all: &[crate::scene::Vertex] = bytemuck::cast_slice(&bytes[..bytes.len() / 48 * 48]);
            let vertices = &all[at.first as usize..][..nodes.len()];
            let nodes: Vec<glam::Vec3> = nodes.iter().map(|p| p.as_vec3()).collect();
            let triangles = &world.desc.cloths[k].setup.mesh.triangles;
            let normals = crate::sim::cloth::view::node_normals(&nodes, triangles);
            assert!(nodes.iter().any(|p| p.y < 0.9), "cloth {k} moved: {nodes:?}");
            for ((v, p), n) in vertices.iter().zip(&nodes).zip(&normals) {
                assert_eq!(glam::Vec3::from(v.position), *p, "cloth {k}: the node itself");
                assert!(glam::Vec3::from(v.normal).distance(*n) < 1e-4, "cloth {k}: {:?} against {n}", v.normal);
            }
        }
    }

    #[test]
    fn a_gpu_cloth_starts_again_after_a_frame_that_dropped_its_steps() {
        // A frame that fails after its simulate stage drops the steps it
        // recorded; the next pose starts the cloths again from rest, so they
        // end where a run that never failed ends.
        let Some(gpu) = crate::gpu::test_gpu() else { return };
        if !gpu.culls_on_gpu() {
            return;
        }
        let run = |fail: bool| {
            let (mut world, mut renderer) = gpu_world(&gpu);
            let mut target = crate::OffscreenTarget::new(&gpu, 16, 16, 1).expect("target");
            let views = world.views(None);
            world.pose(0.1, &mut renderer).expect("posed");
            if fail {
                let (device, queue) = renderer.device_and_queue();
                let mut dropped = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
                for cloth in &mut world.cloths {
                    cloth.simulation().expect("on the GPU").encode(device, queue, &mut dropped);
                    cloth.frame_failed();
                }
            } else {
                world.draw(&mut renderer, &views, &mut target).expect("frame");
            }
            // (What a dropped frame leaves on the GPU is not read: it is not
            // the steps recorded.)
            let early = (!fail).then(|| gpu_positions(&gpu, &world));
            world.pose(0.2, &mut renderer).expect("posed");
            world.draw(&mut renderer, &views, &mut target).expect("frame");
            (early, gpu_positions(&gpu, &world))
        };
        let ((_, broken), (early, whole)) = (run(true), run(false));
        assert!(early.expect("read")[0] != whole[0], "the cloth moved between 0.1 and 0.2 s");
        assert!(broken == whole, "the same state after a failed frame");
    }

    #[test]
    fn the_held_box_holds_every_node_of_the_cpu_run() {
        // A sheet swinging from one edge, a free one falling onto a floor,
        // and one sliding down a 30° slope: at every step the box the CPU
        // holds a GPU cloth in (without reading it back) holds every node of
        // the converged solve.
        let sheet = "\"size\" \"1 1\"\n\"resolution\" \"5 5\"\n\"dt\" \"0.02\"\n\"origin\" \"0 1 0\"\n";
        let slope = format!("\"colliders\" \"plane 0 0 0 0.5 {} 0\"\n", 0.75f64.sqrt());
        let cases = [
            format!("{sheet}\"pins\" \"z<=-0.5\"\n"),
            format!("{sheet}\"colliders\" \"plane 0 0.2 0 0 1 0\"\n"),
            format!("{sheet}{slope}"),
        ];
        for case in &cases {
            let scene = parse(case);
            let desc = &scene.cloths[0];
            let mut cloth = Cloth::start(&desc.setup).expect("cloth");
            let reach = Reach::of(&cloth);
            for step in 1..=50 {
                cloth.step(desc.dt, desc.integrator).expect("a step");
                let held = reach.held(desc, cloth.time as f32);
                for p in &cloth.positions {
                    let p = p.as_vec3();
                    assert!(
                        p.cmpge(held.min).all() && p.cmple(held.max).all(),
                        "{case}step {step}: {p} outside {held:?}"
                    );
                }
            }
        }
    }
}
