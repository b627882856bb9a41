//! Particles drawn: the emitter scene's picture at a fixed time on the GPU
//! path (compute in the frame's simulate stage) and on GL (the CPU path),
//! the GPU's slots against the CPU's, and the alive and spawned counts.

mod common;

use glam::Vec3;
use glint::render::{ParticleBlend, ParticleLook};
use glint::sim::particles::{EmitterParams, GpuParticles, ParticleSystem};
use glint::{OffscreenTarget, Renderer, World};

/// `tests/scenes/emitter.scn` drawn at each of `times` in turn, 256 × 256.
fn emitter_at(gpu: &glint::Gpu, times: &[f32]) -> (Vec<image::RgbaImage>, Vec<glint::FrameStats>, World, Renderer) {
    let desc = common::load_scene(&common::repo_root().join("tests/scenes/emitter.scn"));
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    let mut renderer = Renderer::new(gpu);
    let mut world = World::place(desc, &mut renderer).expect("placed");
    let mut target = OffscreenTarget::new(gpu, 256, 256, 4).expect("target");
    let (mut pictures, mut stats) = (Vec::new(), Vec::new());
    for &time in times {
        world.pose(time, &mut renderer).expect("posed");
        let views = world.views(None);
        stats.push(world.draw(&mut renderer, &views, &mut target).expect("frame").remove(0));
        pictures.push(target.read_rgba8(gpu).expect("readback"));
    }
    (pictures, stats, world, renderer)
}

#[test]
fn an_emitter_scene_draws_its_particles_the_same_at_the_same_time() {
    let Some(gpu) = common::gpu() else { return };
    let (pictures, stats, world, renderer) = emitter_at(gpu, &[2.0, 2.0]);
    assert_eq!(world.particles_on_gpu(), gpu.culls_on_gpu());
    assert_eq!(pictures[0], pictures[1], "the same time, the same picture");
    // The floor, and one draw a particle layer.
    assert_eq!(stats[0].draws, 3, "{:?}", stats[0]);
    assert!(stats[0].particles_alive > 800, "{:?}", stats[0].particles_alive);
    if world.particles_on_gpu() {
        assert!(renderer.frame_outline().iter().any(|g| g.ends_with("› simulate")), "{:?}", renderer.frame_outline());
    }
    common::assert_matches_reference("emitter", &pictures[0]);
}

#[test]
fn gl_and_the_webgl2_path_step_the_particles_on_the_cpu_and_draw_them_alike() {
    for gpu in [common::gl_gpu(), common::webgl2_gpu(), common::gl_webgl2_gpu()].into_iter().flatten() {
        let (pictures, _, world, _) = emitter_at(gpu, &[2.0]);
        assert!(!world.particles_on_gpu(), "no compute path here");
        common::assert_matches_reference("emitter", &pictures[0]);
    }
}

#[test]
fn the_frames_count_particles_alive_and_spawned() {
    let Some(gpu) = common::gpu() else { return };
    let times = [0.0, 0.5, 1.0, 1.7, 1.7, 3.0];
    let (_, stats, world, _) = emitter_at(gpu, &times);
    let spawned: u64 = stats.iter().map(|s| s.particles_spawned).sum();
    let desc = world.desc();
    let expected: u64 =
        desc.emitters.iter().map(|e| glint::sim::particles::Schedule::new(&e.params).spawned_at(3.0)).sum();
    assert_eq!(spawned, expected, "every spawn counted once");
    assert_eq!(stats[4].particles_spawned, 0, "no time passed");
    // Sparks: 400 a second for 1.2–2.2 s and a burst of 150; smoke: 60 for 2–3 s.
    let steady = stats[5].particles_alive as f32;
    assert!((650.0..=1050.0).contains(&steady), "{steady} alive at 3 s");
}

#[test]
fn gpu_particles_match_the_cpu_slot_for_slot() {
    let Some(gpu) = common::gpu() else { return };
    let mut renderer = Renderer::new(gpu);
    if !renderer.computes() {
        return;
    }
    let params = EmitterParams {
        rate: 300.0,
        lifetime: (0.8, 1.6),
        burst: glint::sim::particles::Burst { count: 64, every: 0.5 },
        shape: glint::sim::particles::SpawnShape::Sphere(0.3),
        speed: (1.0, 2.0),
        spread: 40.0,
        gravity: Vec3::new(0.0, -3.0, 0.0),
        drag: 0.5,
        noise: 1.0,
        ground: Some((-0.5, 0.5)),
        ..EmitterParams::default()
    };
    let dt = 1.0 / 60.0;
    let mut cpu = ParticleSystem::new(params.clone(), dt).unwrap();
    let slots = cpu.schedule().slots() as u32;
    let look = ParticleLook { blend: ParticleBlend::Additive, texture: None, soft: 0.0, lit: false };
    let layer = renderer.add_particles(slots, look).unwrap();
    let (buffer, capacity) = renderer.particle_buffer(layer).map(|(b, c)| (b.clone(), c)).unwrap();
    let kernels = std::sync::Arc::new(glint::sim::particles::ParticleKernels::new(renderer.device_and_queue().0));
    let blend = ParticleBlend::Additive;
    let mut on_gpu =
        GpuParticles::new(renderer.device_and_queue(), &kernels, params, dt, (&buffer, capacity), blend).unwrap();
    for _ in 0..100 {
        cpu.step();
    }
    on_gpu.advance_to(&gpu.queue, cpu.time(), Some(Vec3::ZERO));
    let mut target = OffscreenTarget::new(gpu, 64, 64, 1).unwrap();
    let view = glint::View::new(glint::Camera::perspective(60.0, 0.1, 10.0));
    let lighting = glint::Lighting::new(&[], Default::default());
    let input = glint::FrameInput::new(&[], lighting).view(glint::ViewKey(0), &view).simulate(&mut on_gpu);
    renderer.render_frame(input, &mut target).unwrap();
    let from_gpu = on_gpu.read_slots(gpu).unwrap();
    let mut alive = 0;
    for (k, (a, b)) in cpu.slots().iter().zip(&from_gpu).enumerate() {
        assert_eq!(a.id, b.id, "slot {k} holds the same particle");
        let apart = Vec3::from(a.position).distance(Vec3::from(b.position));
        assert!(apart < 2e-3, "slot {k}: {a:?} vs {b:?}");
        alive += usize::from(a.id > 0 && a.age < cpu.params().life(a.id - 1));
    }
    assert!(alive > 300, "{alive} alive compared");
}

/// `tests/scenes/soft.scn` at 3 s on `gpu`, with its emitter's soft distance
/// set to `soft`.
fn soft_at(gpu: &glint::Gpu, soft: f32) -> image::RgbaImage {
    let mut desc = common::load_scene(&common::repo_root().join("tests/scenes/soft.scn"));
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    desc.emitters[0].soft = soft;
    let mut renderer = Renderer::new(gpu);
    let mut world = World::place(desc, &mut renderer).expect("placed");
    world.pose(3.0, &mut renderer).expect("posed");
    let mut target = OffscreenTarget::new(gpu, 256, 256, 4).expect("target");
    let views = world.views(None);
    world.draw(&mut renderer, &views, &mut target).expect("frame");
    target.read_rgba8(gpu).expect("readback")
}

#[test]
fn soft_particles_fade_where_they_meet_the_floor() {
    let Some(gpu) = common::gpu() else { return };
    let (soft, hard) = (soft_at(gpu, 0.6), soft_at(gpu, 0.0));
    let differs = |(a, b): (&image::Rgba<u8>, &image::Rgba<u8>)| a.0.iter().zip(b.0).any(|(x, y)| x.abs_diff(y) > 6);
    let changed = soft.pixels().zip(hard.pixels()).filter(|&p| differs(p)).count();
    if !gpu.occlusion_culls() {
        // No readable depth here: soft layers meet geometry hard.
        assert_eq!(changed, 0);
        return;
    }
    assert!(changed > 2000, "the puffs thin out over the floor: {changed} pixels");
    // Above the floor line (the top rows) nothing is near geometry: the same.
    let top = (0..256 * 40)
        .filter(|&i| differs((soft.get_pixel(i % 256, i / 256), hard.get_pixel(i % 256, i / 256))))
        .count();
    assert_eq!(top, 0, "only where particles meet geometry");
    common::assert_matches_reference("soft", &soft);
}

#[test]
fn soft_layers_meet_geometry_hard_on_gl() {
    let Some(gl) = common::gl_gpu() else { return };
    assert!(common::max_difference(&soft_at(gl, 0.6), &soft_at(gl, 0.0)) <= 1);
}
