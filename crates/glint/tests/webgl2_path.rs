//! The WebGL2 path, natively: a GPU context with WebGL2's limits
//! ([`Gpu::with_webgl2_limits`]: instance, draw-index and material data in data
//! textures instead of storage buffers, vertex buffers bound at each mesh
//! instead of a base vertex, one draw call per batch) draws the main path's
//! reference images, on Vulkan and on GL.

mod common;

use glam::{Mat4, Vec3};
use glint::asset::ShapeKind;
use glint::{Camera, Entity, Gpu, Light, Material, OffscreenTarget, Renderer};

/// The reference scenes of `tests/scenes`, with their draws besides whole
/// tiles (culled on the CPU, each tile drawn is a draw of its own: `tiles`
/// draws half of each, so no two are contiguous).
const SCENES: [(&str, u32); 9] = [
    ("shapes", 7),
    ("textures", 2),
    ("alpha", 4),
    ("lights", 2),
    ("instancing", 3),
    ("ortho", 2),
    ("states", 6),
    ("pbr", 25),
    ("tiles", 2),
];

fn reference_scenes(gpu: &Gpu) {
    assert!(!gpu.vertex_storage() && !gpu.base_vertex() && !gpu.draws_indirect());
    for (name, draws) in SCENES {
        let (image, stats) = common::render_scene(gpu, name, 256);
        let draws = draws + stats.tiles_drawn as u32;
        assert_eq!((stats.draws, stats.draw_calls), (draws, draws), "{name}: one call per draw");
        common::assert_matches_reference(name, &image);
    }
}

#[test]
fn the_reference_scenes_match_through_data_textures() {
    let Some(gpu) = common::webgl2_gpu() else { return };
    reference_scenes(gpu);
}

#[test]
fn the_reference_scenes_match_through_data_textures_on_gl() {
    let Some(gpu) = common::gl_webgl2_gpu() else { return };
    reference_scenes(gpu);
}

#[test]
fn ten_thousand_shadowed_cubes_a_split_screen_and_a_monitor_match() {
    // Records over many texture rows, shadow passes, post chains and render targets.
    let Some(gpu) = common::webgl2_gpu() else { return };
    let root = common::repo_root();
    let cubes = common::load_scene(&root.join("scenes/bench/peer_cubes_10k.scn"));
    let (image, stats) = common::render_sized(gpu, &cubes, (640, 360), 1, glint::Culling::Cpu);
    assert_eq!((stats.instances_drawn, stats.draw_calls), (5_130, 1));
    common::assert_matches_reference("peer_cubes_10k", &image);
    // Split: a sun, whose cascades each view draws; monitor: a lamp, whose six
    // cube faces the first view drawn (the security camera's) draws for both.
    for (scene, (width, height), samples, shadow_views) in
        [("split", (192, 96), 1, [4, 4]), ("monitor", (160, 90), 4, [6, 0])]
    {
        let desc = common::load_scene(&root.join(format!("scenes/{scene}.scn")));
        let mut renderer = Renderer::new(gpu);
        let placed = renderer.place_scene(&desc);
        let mut target = OffscreenTarget::new(gpu, width, height, samples).expect("target");
        let views = desc.views(&placed.render_targets);
        let stats = renderer.render_views(&placed.entities, &views, desc.lighting(), &mut target).expect("frame");
        assert_eq!(stats.iter().map(|s| s.shadow_views).collect::<Vec<_>>(), shadow_views, "{scene}");
        common::assert_matches_reference(scene, &target.read_rgba8(gpu).expect("readback"));
    }
}

#[test]
fn an_edit_from_the_middle_of_a_texture_row_is_drawn_as_on_the_main_path() {
    // Records are four texels. A still entity of 600 instances fills texels
    // 0..2,400; a moving one of 1,000 follows at 2,400..6,400, so rewriting it
    // writes the rest of row 1, all of row 2 and the start of row 3.
    let (Some(main), Some(webgl2)) = (common::gpu(), common::webgl2_gpu()) else { return };
    let grid = |count: usize, z0: f32| -> Vec<Mat4> {
        (0..count)
            .map(|i| {
                let at = Vec3::new((i % 50) as f32 - 25.0, 0.0, (i / 50) as f32 + z0);
                Mat4::from_scale_rotation_translation(Vec3::splat(0.4), Default::default(), at)
            })
            .collect()
    };
    let draw = |gpu: &Gpu| {
        let mut renderer = Renderer::new(gpu);
        let cube = renderer.add_shape(ShapeKind::Cube.mesh());
        let red = renderer.add_material(Material::color("red", 0.8, 0.2, 0.1));
        let blue = renderer.add_material(Material::color("blue", 0.1, 0.2, 0.8));
        let still = Entity::instanced(cube, blue, grid(600, -12.0));
        let mut moving = Entity::instanced(cube, red, grid(1000, 0.0));
        let camera = Camera::perspective(50.0, 0.1, 100.0).looking_at(Vec3::new(0.0, 30.0, 25.0), Vec3::ZERO);
        let lights = [Light::directional(Vec3::new(-0.3, -1.0, -0.5), Vec3::ONE, 1.5)];
        let mut target = OffscreenTarget::new(gpu, 128, 128, 1).expect("target");
        renderer.render([&still, &moving], camera, &lights, &mut target).expect("frame");
        let big = Mat4::from_scale_rotation_translation(Vec3::splat(4.0), Default::default(), Vec3::new(0.0, 2.0, 0.0));
        moving.transforms_mut()[500] = big;
        let stats = renderer.render([&still, &moving], camera, &lights, &mut target).expect("frame");
        (target.read_rgba8(gpu).expect("readback"), stats)
    };
    let ((on_main, main_stats), (on_webgl2, webgl2_stats)) = (draw(main), draw(webgl2));
    let written = webgl2_stats.bytes_uploaded.instances;
    assert_eq!(written, main_stats.bytes_uploaded.instances);
    assert!(written > 0 && written <= 1000 * 64, "the moving entity's records only: {written} bytes");
    let difference = common::max_difference(&on_main, &on_webgl2);
    assert!(difference <= 2, "the WebGL2 path differs from the main one by {difference}");
    let red = on_webgl2.pixels().filter(|p| u16::from(p.0[0]) > 2 * u16::from(p.0[2].max(40))).count();
    assert!(red > 1000, "the big red cube is drawn: {red} red pixels");
}
