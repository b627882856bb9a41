//! Vertex animation with the scene time (`tests/scenes/motion.scn`): grass in
//! the wind, butterflies flapping and ants on their circles, shadows included.
//! The same time draws the same picture; another time moves them; the culler's
//! boxes hold the motion (GPU and CPU culling keep the same instances).

mod common;

use glint::{Culling, OffscreenTarget, Renderer, World};

/// The scene posed at `time`, 256 × 256 with 4× MSAA, culled as `culling` says.
fn at(gpu: &glint::Gpu, time: f32, culling: Culling) -> (image::RgbaImage, glint::FrameStats) {
    let desc = common::load_scene(&common::repo_root().join("tests/scenes/motion.scn"));
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    let mut renderer = Renderer::new(gpu);
    let mut world = World::place(desc, &mut renderer).expect("placed");
    world.pose(time, &mut renderer).expect("posed");
    let views: Vec<_> = world.views(None).into_iter().map(|v| v.with_culling(culling)).collect();
    let mut target = OffscreenTarget::new(gpu, 256, 256, 4).expect("target");
    let mut stats = world.draw(&mut renderer, &views, &mut target).expect("frame");
    renderer.wait_for_counts(&mut stats);
    (target.read_rgba8(gpu).expect("readback"), stats.remove(0))
}

#[test]
fn the_same_time_draws_the_same_picture_and_another_time_moves_everything() {
    let Some(gpu) = common::gpu() else { return };
    let (early, stats) = at(gpu, 0.3, Culling::Gpu);
    assert!(stats.shadow_views > 0, "the sun casts shadows");
    assert_eq!(at(gpu, 0.3, Culling::Gpu).0, early, "the same time, the same picture");
    let (late, _) = at(gpu, 1.1, Culling::Gpu);
    let differs = |(a, b): &(&image::Rgba<u8>, &image::Rgba<u8>)| a.0.iter().zip(b.0).any(|(x, y)| x.abs_diff(y) > 24);
    let moved = early.pixels().zip(late.pixels()).filter(differs).count();
    assert!(moved > 1_000, "grass, wings, ants and their shadows moved: {moved} pixels");
    common::assert_matches_reference("motion_early", &early);
    common::assert_matches_reference("motion_late", &late);
}

#[test]
fn culling_keeps_every_moving_instance_on_both_paths() {
    let Some(gpu) = common::gpu() else { return };
    for time in [0.3, 1.1, 7.9] {
        let (off, all) = at(gpu, time, Culling::Off);
        let (cpu, on_cpu) = at(gpu, time, Culling::Cpu);
        let (gpu_culled, on_gpu) = at(gpu, time, Culling::Gpu);
        assert_eq!(on_cpu.instances_drawn, on_gpu.instances_drawn, "time {time}");
        assert!(on_cpu.instances_drawn <= all.instances_drawn);
        // Culling never cuts a moving instance off: the pictures agree.
        for (name, picture) in [("cpu", &cpu), ("gpu", &gpu_culled)] {
            assert!(common::max_difference(&off, picture) <= 2, "time {time}, culled on the {name}");
        }
    }
}

#[test]
fn gl_and_the_webgl2_path_move_them_alike() {
    for gpu in [common::gl_gpu(), common::webgl2_gpu(), common::gl_webgl2_gpu()].into_iter().flatten() {
        let (late, _) = at(gpu, 1.1, Culling::Gpu);
        common::assert_matches_reference("motion_late", &late);
    }
}

#[test]
fn a_model_whose_material_moves_is_drawn_at_the_scene_time_mid_flap() {
    // The wing material moves through an `mtl.` override of the model's own.
    let Some(gpu) = common::gpu() else { return };
    let desc = common::load_scene(&common::repo_root().join("tests/scenes/butterflies.scn"));
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    let mut renderer = Renderer::new(gpu);
    let mut world = World::place(desc, &mut renderer).expect("placed");
    let mut pictures = Vec::new();
    // A quarter beat (wings up) and three quarters (down), at one beat a second.
    for time in [0.25, 0.75] {
        world.pose(time, &mut renderer).expect("posed");
        assert_eq!(world.lighting().environment.time, time);
        let mut target = OffscreenTarget::new(gpu, 128, 128, 4).expect("target");
        world.draw(&mut renderer, &world.views(None), &mut target).expect("frame");
        pictures.push(target.read_rgba8(gpu).expect("readback"));
    }
    assert!(common::max_difference(&pictures[0], &pictures[1]) > 64, "the wings moved");
    common::assert_matches_reference("butterflies_mid_flap", &pictures[0]);
}
