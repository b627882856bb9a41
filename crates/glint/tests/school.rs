//! Fish schooling with compute shaders against the CPU's: the same start,
//! the same rules and the same neighbour order, statistics that agree (not
//! bit for bit: rounding differs between the two, and grows over steps), two
//! GPU runs bit for bit alike, and the GPU's counting sort found complete;
//! a scene's school drawn in place from the GPU's buffers.

mod common;

use glam::Vec3;
use glint::scene::{Aabb, PathCounts, SimPath};
use glint::sim::school::{GpuSchool, Hunter, Obstacle, School, SchoolParams};

fn params() -> SchoolParams {
    SchoolParams {
        count: 3000,
        bounds: Aabb { min: Vec3::new(-9.0, -4.0, -9.0), max: Vec3::new(9.0, 5.0, 9.0) },
        obstacles: vec![Obstacle { center: Vec3::new(2.0, -3.0, 1.0), radius: 2.0 }],
        floor: Some(-3.5),
        predator: Some(Hunter { start: Vec3::new(-5.0, 0.0, 0.0), speed: 3.5, accel: 6.0, fear: 4.0 }),
        seed: 21,
        ..SchoolParams::default()
    }
}

#[test]
fn gpu_and_cpu_schooling_agree_statistically() {
    let Some(gpu) = common::gpu() else { return };
    if !gpu.culls_on_gpu() {
        let err = GpuSchool::new(gpu, &School::new(params()).unwrap()).err().expect("refused without compute");
        assert!(err.to_string().contains("CPU"), "{err}");
        return;
    }
    let mut cpu = School::new(params()).unwrap();
    let mut on_gpu = GpuSchool::new(gpu, &cpu).unwrap();
    let start = cpu.stats();
    let dt = 1.0 / 30.0;
    for _ in 0..120 {
        cpu.step(dt);
        on_gpu.step(gpu, dt);
    }
    let mut from_gpu = on_gpu.read(gpu).unwrap();
    let (a, b) = (cpu.stats(), from_gpu.stats());
    println!("start {start:?}\ncpu   {a:?}\ngpu   {b:?}");
    let close = |x: f32, y: f32, tol: f32| (x - y).abs() <= tol * x.abs().max(y.abs()).max(1e-3);
    assert!(close(a.mean_speed, b.mean_speed, 0.05), "mean speed {a:?} vs {b:?}");
    assert!((a.polarisation - b.polarisation).abs() < 0.08, "polarisation {a:?} vs {b:?}");
    assert!(close(a.nearest, b.nearest, 0.05), "nearest neighbour {a:?} vs {b:?}");
    assert!(close(a.predator_distance, b.predator_distance, 0.25), "predator distance {a:?} vs {b:?}");
    // The school changed: the statistics compare something.
    assert!((a.polarisation - start.polarisation).abs() > 0.05 || (a.nearest - start.nearest).abs() > 0.05);
    // Every fish came back, inside the bounds and above the floor.
    let p = params();
    assert_eq!(from_gpu.fish().len(), 3000);
    for f in from_gpu.fish() {
        assert!(f.position.cmpge(p.bounds.min).all() && f.position.cmple(p.bounds.max).all() && f.position.y >= -3.5);
        assert!((0.0..1.0).contains(&f.phase));
    }
}

#[test]
fn two_gpu_runs_from_one_start_give_the_same_bits() {
    // 3,000 fish in a ball of radius 0.3, so cells hold hundreds to
    // thousands and the atomics' order varies from run to run; the stable
    // sort makes it not matter.
    let Some(gpu) = common::gpu() else { return };
    if !gpu.culls_on_gpu() {
        return;
    }
    let crowded = SchoolParams { clusters: Some((1, 0.3)), ..params() };
    let start = School::new(crowded).unwrap();
    let run = || {
        let mut on_gpu = GpuSchool::new(gpu, &start).unwrap();
        for _ in 0..40 {
            on_gpu.step(gpu, 1.0 / 30.0);
        }
        let school = on_gpu.read(gpu).unwrap();
        let mut bits: Vec<u32> = Vec::new();
        for f in school.fish().iter().chain(school.predator()) {
            bits.extend(f.position.to_array().iter().chain(&f.velocity.to_array()).map(|x| x.to_bits()));
            bits.push(f.phase.to_bits());
        }
        bits
    };
    let first = run();
    let moved = first.chunks(7).zip(start.fish()).any(|(f, s)| f32::from_bits(f[0]) != s.position.x);
    assert!(moved, "the school moved");
    for _ in 0..2 {
        assert!(run() == first, "a second run differs");
    }
}

/// `school` stepped once (1/30 s) on the GPU, through a frame's simulate
/// stage before an empty view, and read back.
fn gpu_step(gpu: &glint::Gpu, school: &School) -> School {
    let mut on_gpu = GpuSchool::new(gpu, school).unwrap();
    let mut renderer = glint::Renderer::new(gpu);
    on_gpu.advance(&gpu.queue, 1, 1.0 / 30.0);
    let mut target = glint::OffscreenTarget::new(gpu, 32, 32, 1).unwrap();
    let view = glint::View::new(glint::Camera::perspective(60.0, 0.1, 10.0));
    let lighting = glint::Lighting::new(&[], Default::default());
    let input = glint::FrameInput::new(&[], lighting).view(glint::ViewKey(0), &view).simulate(&mut on_gpu);
    renderer.render_frame(input, &mut target).unwrap();
    assert!(renderer.frame_outline().iter().any(|g| g.ends_with("› simulate")), "{:?}", renderer.frame_outline());
    on_gpu.read(gpu).unwrap()
}

#[test]
fn one_gpu_step_matches_the_cpu_step_closely() {
    // One step from the same state, in a frame's simulate stage: the GPU's
    // grid must find the same neighbours, or some fish would steer
    // differently by far more than rounding.
    let Some(gpu) = common::gpu() else { return };
    if !gpu.culls_on_gpu() {
        return;
    }
    let mut cpu = School::new(params()).unwrap();
    for _ in 0..30 {
        cpu.step(1.0 / 30.0);
    }
    let stepped = gpu_step(gpu, &cpu);
    cpu.step(1.0 / 30.0);
    let worst =
        cpu.fish().iter().zip(stepped.fish()).map(|(a, b)| (a.velocity - b.velocity).length()).fold(0.0, f32::max);
    assert!(worst < 1e-3, "largest velocity difference {worst}");
    let (a, b) = (cpu.predator().unwrap(), stepped.predator().unwrap());
    assert!((a.position - b.position).length() < 1e-4, "the predator hunts the same fish: {a:?} vs {b:?}");
}

#[test]
fn in_a_crowd_the_gpu_samples_neighbours_as_the_cpu_does() {
    // 3,000 fish in a ball of radius 0.3: each has far more than
    // MAX_NEIGHBOUR_TESTS others in its 27 cells and tests an even sample of
    // them, on the GPU as on the CPU. The GPU orders a cell's fish by number
    // as the CPU does, so the samples are the same and one step turns the
    // fish alike but for rounding.
    let Some(gpu) = common::gpu() else { return };
    if !gpu.culls_on_gpu() {
        return;
    }
    let params = SchoolParams {
        count: 3000,
        bounds: Aabb { min: Vec3::splat(-20.0), max: Vec3::splat(20.0) },
        clusters: Some((1, 0.3)),
        seed: 3,
        ..SchoolParams::default()
    };
    let mut cpu = School::new(params).unwrap();
    let before: Vec<Vec3> = cpu.fish().iter().map(|f| f.velocity).collect();
    let stepped = gpu_step(gpu, &cpu);
    cpu.step(1.0 / 30.0);
    let (mut apart, mut turned) = (0.0, 0.0);
    for ((v0, a), b) in before.iter().zip(cpu.fish()).zip(stepped.fish()) {
        assert!(b.velocity.is_finite() && b.position.is_finite());
        apart += (a.velocity - b.velocity).length();
        turned += (a.velocity - *v0).length();
    }
    assert!(turned > 100.0, "the crowd pushes the fish apart: {turned}");
    assert!(apart < 1e-5 * turned, "CPU and GPU turn the fish alike: {apart} against {turned}");
}

/// `tests/scenes/school.scn` posed at `time` on `gpu`, its school stepped
/// on `sim`, 256 × 256 with 4× MSAA: the picture, the world and the frame's statistics.
fn school_at(gpu: &glint::Gpu, time: f32, sim: SimPath) -> (image::RgbaImage, glint::World, glint::FrameStats) {
    let mut desc = common::load_scene(&common::repo_root().join("tests/scenes/school.scn"));
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    desc.schools[0].sim = sim;
    let mut renderer = glint::Renderer::new(gpu);
    let mut world = glint::World::place(desc, &mut renderer).expect("placed");
    world.pose(time, &mut renderer).expect("posed");
    let mut target = glint::OffscreenTarget::new(gpu, 256, 256, 4).expect("target");
    let stats = world.draw(&mut renderer, &world.views(None), &mut target).expect("frame").remove(0);
    (target.read_rgba8(gpu).expect("readback"), world, stats)
}

fn sun(world: &glint::World) -> Vec3 {
    match world.lighting().lights[0].kind {
        glint::scene::LightKind::Directional { direction } => direction,
        _ => unreachable!("the scene's first light is the sun"),
    }
}

#[test]
fn a_school_scene_draws_the_same_picture_at_the_same_time_and_its_sun_sways() {
    // The CPU school, the reference.
    let Some(gpu) = common::gpu() else { return };
    let (picture, world, stats) = school_at(gpu, 3.0, SimPath::Cpu);
    assert_eq!(stats.simulations.schools, PathCounts { cpu: 1, gpu: 0 });
    let (again, ..) = school_at(gpu, 3.0, SimPath::Cpu);
    assert_eq!(picture, again, "the same time, the same picture");
    let (later, later_world, _) = school_at(gpu, 3.5, SimPath::Cpu);
    assert!(common::max_difference(&picture, &later) > 64, "the fish swam on");
    let (a, b) = (sun(&world), sun(&later_world));
    let turned = a.angle_between(b).to_degrees();
    assert!(turned > 0.5 && turned < 2.0 * 8.0 * 1.5, "the sun swayed {turned}° (sway 8° either way)");
    common::assert_matches_reference("school", &picture);
}

#[test]
fn the_gpu_school_is_drawn_in_place_the_same_at_the_same_time() {
    let Some(gpu) = common::gpu() else { return };
    let (picture, world, stats) = school_at(gpu, 3.0, SimPath::Gpu);
    if !gpu.culls_on_gpu() {
        assert_eq!(world.school_paths(), [Some(SimPath::Cpu)], "no compute path: the CPU steps it");
        return;
    }
    assert_eq!(world.school_paths(), [Some(SimPath::Gpu)]);
    assert_eq!(stats.simulations.schools, PathCounts { cpu: 0, gpu: 1 });
    let (again, ..) = school_at(gpu, 3.0, SimPath::Gpu);
    assert!(picture == again, "two GPU runs to the same time draw the same bytes");
    let (later, ..) = school_at(gpu, 3.5, SimPath::Gpu);
    assert!(common::max_difference(&picture, &later) > 64, "the fish swam on");
    // The same rules from the same start: three seconds on, the GPU's
    // school still looks like the CPU's (each fish placed, turned, scaled
    // and beating its tail as the CPU places it).
    common::assert_matches_reference("school", &picture);
}

#[test]
fn the_gpu_school_uploads_no_instances_once_running_and_the_cpu_school_does() {
    let Some(gpu) = common::gpu() else { return };
    if !gpu.culls_on_gpu() {
        return;
    }
    let uploads = |sim: SimPath| {
        let mut desc = common::load_scene(&common::repo_root().join("tests/scenes/school.scn"));
        desc.schools[0].sim = sim;
        let mut renderer = glint::Renderer::new(gpu);
        let mut world = glint::World::place(desc, &mut renderer).expect("placed");
        let mut target = glint::OffscreenTarget::new(gpu, 64, 64, 1).expect("target");
        let views = world.views(None);
        (0..4)
            .map(|frame| {
                world.pose(1.0 + frame as f32 / 30.0, &mut renderer).expect("posed");
                let mut stats = world.draw(&mut renderer, &views, &mut target).expect("frame");
                renderer.wait_for_counts(&mut stats);
                let stats = &stats[0];
                assert!(stats.instances_drawn > 300, "the fish are drawn: {}", stats.instances_drawn);
                stats.bytes_uploaded.instances
            })
            .collect::<Vec<u64>>()
    };
    let (on_gpu, on_cpu) = (uploads(SimPath::Gpu), uploads(SimPath::Cpu));
    assert!(on_gpu[0] > 0, "the first frame writes every record once: {on_gpu:?}");
    assert_eq!(on_gpu[1..], [0, 0, 0], "then the simulation writes them on the GPU");
    // 400 fish and the shark, 64 bytes each, every frame they move.
    assert!(on_cpu[1..].iter().all(|&b| b >= 401 * 64), "{on_cpu:?}");
}

#[test]
fn gl_and_the_webgl2_path_draw_the_school_alike_and_refuse_the_gpu_school() {
    // The school steps on the CPU on these paths, whatever the scene asks,
    // so their pictures are Vulkan's CPU school's.
    for gpu in [common::gl_gpu(), common::webgl2_gpu()].into_iter().flatten() {
        let (picture, world, stats) = school_at(gpu, 3.0, SimPath::Gpu);
        assert_eq!(world.school_paths(), [Some(SimPath::Cpu)]);
        assert_eq!(stats.simulations.schools, PathCounts { cpu: 1, gpu: 0 });
        common::assert_matches_reference("school", &picture);
        let err = GpuSchool::new(gpu, &School::new(params()).unwrap()).err().expect("no compute path here");
        assert!(err.to_string().contains("step the school on the CPU"), "{err}");
    }
}

#[test]
fn a_school_or_emitter_broken_after_loading_is_an_error_when_posed_not_a_panic() {
    let Some(gpu) = common::gpu() else { return };
    let mut desc = common::load_scene(&common::repo_root().join("tests/scenes/school.scn"));
    desc.schools[0].params.count = 0;
    let mut renderer = glint::Renderer::new(gpu);
    let mut world = glint::World::place(desc, &mut renderer).expect("placed");
    let err = world.pose(1.0, &mut renderer).unwrap_err();
    assert_eq!(err.exit_code(), 1);
    assert!(err.to_string().contains("school.scn:38: school: count must be 1"), "{err}");
    let mut desc = common::load_scene(&common::repo_root().join("tests/scenes/emitter.scn"));
    desc.emitters[1].params.lifetime = (2.0, 1.0);
    let mut world = glint::World::place(desc, &mut renderer).expect("placed");
    let err = world.pose(1.0, &mut renderer).unwrap_err().to_string();
    assert!(err.contains("emitter.scn:35: emitter: lifetime must be min max"), "{err}");
}

#[test]
fn after_a_failed_frame_the_gpu_simulations_restart_and_draw_what_an_unbroken_run_draws() {
    // A frame that fails may have dropped GPU steps it recorded; the school
    // and the emitters then start again from their seeds at the next pose,
    // so the next picture is the one a run that never failed draws.
    let Some(gpu) = common::gpu() else { return };
    for scene in ["tests/scenes/school.scn", "tests/scenes/emitter.scn"] {
        let run = |fail: bool| {
            let desc = common::load_scene(&common::repo_root().join(scene));
            let mut renderer = glint::Renderer::new(gpu);
            let mut world = glint::World::place(desc, &mut renderer).expect("placed");
            let mut target = glint::OffscreenTarget::new(gpu, 64, 64, 1).expect("target");
            let views = world.views(None);
            world.pose(0.5, &mut renderer).expect("posed");
            if fail {
                let mut bad = views.clone();
                bad[0].viewport.width = -1.0;
                assert!(world.draw(&mut renderer, &bad, &mut target).is_err(), "{scene}: a bad viewport fails");
            } else {
                world.draw(&mut renderer, &views, &mut target).expect("frame");
            }
            world.pose(1.0, &mut renderer).expect("posed");
            world.draw(&mut renderer, &views, &mut target).expect("frame");
            target.read_rgba8(gpu).expect("readback")
        };
        assert!(run(true) == run(false), "{scene}: the same picture after a failed frame");
    }
}
