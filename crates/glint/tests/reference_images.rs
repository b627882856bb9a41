//! Reference-image tests: each scene under `tests/scenes/` rendered at 256×256
//! (4× MSAA) must match `tests/reference/NAME.png` within the tolerance in
//! `common`. Regenerate on purpose with `GLINT_BLESS=1 cargo test -p glint --test reference_images`.

mod common;

fn check(name: &str, expected_draws: u32) {
    let Some(gpu) = common::gpu() else { return };
    let (image, stats) = common::render_scene(gpu, name, 256);
    assert_eq!(stats.draws, expected_draws, "{name}: draws");
    common::assert_matches_reference(name, &image);
}

#[test]
fn every_shape() {
    // Plane, two cube entities (one draw: same shape and material), sphere,
    // cylinder, cone, torus, sky.
    check("shapes", 7);
}

#[test]
fn textures_srgb_colour_and_normal_maps() {
    check("textures", 2);
}

#[test]
fn alpha_mask_and_blend() {
    // Bar (opaque), leaf (alpha-test), two glass spheres (transparent).
    check("alpha", 4);
}

#[test]
fn several_point_lights() {
    check("lights", 2);
}

#[test]
fn instancing_700_instances_in_two_draws() {
    // Two instanced draws plus the sky.
    check("instancing", 3);
}

#[test]
fn tiles_culled_whole_and_half_of_each_drawn() {
    let Some(gpu) = common::gpu() else { return };
    let (image, stats) = common::render_scene(gpu, "tiles", 256);
    // Ground, cones (one batch, whatever the tiles), sky.
    assert_eq!(stats.draws, 3);
    assert!(stats.tiles_drawn > 8 && stats.tiles_drawn < stats.tiles_tested, "{stats:?}");
    assert_eq!(stats.tiles_tested, 64);
    common::assert_matches_reference("tiles", &image);
}

#[test]
fn orthographic_camera() {
    check("ortho", 2);
}

#[test]
fn render_states_fog_and_unlit_variants() {
    // Floor, pillars, marker, inside-out sphere, sky colour only (no gradient),
    // glow, tint: six draws.
    check("states", 6);
}

#[test]
fn soft_shadows_from_a_sun_and_a_spot_light_with_a_size() {
    // Ground, cube, slab: three draws.
    check("soft_shadows", 3);
}

#[test]
fn smaa_after_tonemapping() {
    // Ground, rails (one draw), post, ball (a plain background, no sky).
    check("smaa", 4);
}

#[test]
fn crossing_glass_drawn_exactly_from_per_pixel_lists() {
    // Ground, post, three panes and a sphere; the panes and the sphere in
    // the transparency pass, then its composite.
    check("transparency", 7);
}

/// The scenes whose references the CPU's culling (and GL's) must match too.
const CULLED_ON_THE_CPU: [&str; 11] = [
    "shapes",
    "textures",
    "alpha",
    "lights",
    "instancing",
    "ortho",
    "states",
    "tiles",
    "soft_shadows",
    "smaa",
    "transparency",
];

#[test]
fn every_scene_matches_its_reference_culled_on_the_cpu_too() {
    // The tests above cull on the GPU where the adapter can (the default).
    let Some(gpu) = common::gpu() else { return };
    for name in CULLED_ON_THE_CPU {
        let path = common::repo_root().join("tests/scenes").join(format!("{name}.scn"));
        let (image, stats) = common::render_file(gpu, &path, 256, glint::Culling::Cpu);
        assert_eq!(stats.culling, glint::Culling::Cpu);
        common::assert_matches_reference(name, &image);
    }
}

#[test]
fn every_scene_matches_its_reference_on_gl_which_culls_on_the_cpu() {
    let Some(gl) = common::gl_gpu() else { return };
    for name in CULLED_ON_THE_CPU {
        let path = common::repo_root().join("tests/scenes").join(format!("{name}.scn"));
        let (image, stats) = common::render_file(gl, &path, 256, glint::Culling::Gpu);
        assert_eq!((stats.culling, stats.occlusion), (glint::Culling::Cpu, false), "{name}");
        common::assert_matches_reference(name, &image);
    }
}

#[test]
fn culling_never_changes_the_picture() {
    let Some(gpu) = common::gpu() else { return };
    let showcase = common::repo_root().join("scenes/showcase.scn");
    let (culled, stats) = common::render_file(gpu, &showcase, 192, glint::Culling::Cpu);
    let (unculled, all) = common::render_file(gpu, &showcase, 192, glint::Culling::Off);
    let (on_gpu, _) = common::render_file(gpu, &showcase, 192, glint::Culling::Gpu);
    assert!(culled == on_gpu, "culled on the CPU and on the GPU, the renders must be identical");
    assert!(stats.instances_culled > 1000, "the showcase has plenty out of view: {}", stats.instances_culled);
    assert_eq!(all.instances_culled, 0);
    assert_eq!(stats.instances_drawn + stats.instances_culled, all.instances_drawn);
    assert!(culled == unculled, "culled and unculled renders must be identical");
}

#[test]
fn a_reference_test_fails_on_a_visibly_different_image() {
    // The comparison itself must be able to fail: a frame missing one light
    // (lights.scn without its red lamp) is rejected against the reference.
    let Some(gpu) = common::gpu() else { return };
    if std::env::var("GLINT_BLESS").as_deref() == Ok("1") {
        return;
    }
    let path = common::repo_root().join("tests/scenes/lights.scn");
    let desc = common::load_scene(&path);
    let mut renderer = glint::Renderer::new(gpu);
    let entities = renderer.place_scene(&desc).entities;
    let mut target = glint::OffscreenTarget::new(gpu, 256, 256, 4).expect("target");
    for e in &entities {
        renderer.submit(e);
    }
    let without_red: Vec<_> = desc.lights.iter().copied().filter(|l| l.color.x < 0.99 || l.color.y > 0.5).collect();
    assert_eq!(without_red.len(), desc.lights.len() - 1);
    let lighting = glint::Lighting::new(&without_red, desc.environment);
    renderer.flush(desc.cameras[0], lighting, &glint::Shadows::none(), &mut target).expect("frame");
    let image = target.read_rgba8(gpu).expect("readback");
    let result = std::panic::catch_unwind(|| common::assert_matches_reference("lights", &image));
    assert!(result.is_err(), "a frame without the red light must not match the reference");
    let _ = std::fs::remove_file(common::repo_root().join("tests/output/lights.actual.png"));
    let _ = std::fs::remove_file(common::repo_root().join("tests/output/lights.diff.png"));
}

#[test]
fn metallic_roughness_grid() {
    // 25 spheres, each its own material: 25 draws, one indirect call.
    check("pbr", 25);
}

#[test]
fn cloth_swings_with_its_debug_view_one_vertex_write_per_frame() {
    // tests/scenes/cloth_debug.scn: a 9 × 9 sheet pinned at two corners, with
    // seed 003's debug view (edge ribbons, pin markers). Posing moves it by
    // rewriting the vertex buffers of the surface and the ribbons, nothing else.
    let Some(gpu) = common::gpu() else { return };
    let path = common::repo_root().join("tests/scenes/cloth_debug.scn");
    let mut renderer = glint::Renderer::new(gpu);
    // The draws counted below are at full detail (the cloth's are anyway: it deforms).
    renderer.set_levels_of_detail(false);
    let mut world = glint::World::place(common::load_scene(&path), &mut renderer).expect("placed");
    assert!(world.desc().warnings.is_empty(), "{:?}", world.desc().warnings);
    let entities = world.entities();
    assert_eq!(entities.len(), 4, "floor, cloth, ribbons, pins");
    assert_eq!(entities[3].transforms().len(), 2, "two pinned corners");
    let mut target = glint::OffscreenTarget::new(gpu, 256, 256, 4).expect("target");
    let mut frame = |world: &mut glint::World, time: f32| {
        world.pose(time, &mut renderer).expect("the cloth steps");
        let camera = world.desc().cameras[0];
        let stats = renderer.render(world.entities(), camera, world.lighting(), &mut target).expect("frame");
        (stats, target.read_rgba8(gpu).expect("readback"))
    };
    let cloth = |world: &glint::World| world.cloth_view(0).expect("a cloth").clone();
    let (first, _) = frame(&mut world, 0.0);
    assert_eq!(first.draws, 4, "floor, cloth, ribbons, one instanced draw of both pins");
    let edges = cloth(&world).edges.as_ref().expect("debug view").vertices().len();
    let rest_bottom = cloth(&world).surface.aabb().min.y;
    let (swung, image) = frame(&mut world, 0.6);
    let vertex_bytes = (81 + edges) as u64 * std::mem::size_of::<glint::scene::Vertex>() as u64;
    assert_eq!(swung.bytes_uploaded.meshes, vertex_bytes, "one write of the surface's and the ribbons' vertices");
    // The surface's and the ribbons' bounds moved, so their one instance record
    // each (64 bytes: transform and material) is rewritten for culling; the
    // pins did not move and are not.
    assert_eq!(swung.bytes_uploaded.instances, 2 * 64, "two instance records, not the pins'");
    let bottom = cloth(&world).surface.aabb().min.y;
    assert!(bottom < rest_bottom - 0.3, "the free edge swung down: lowest point {bottom} (was {rest_bottom})");
    common::assert_matches_reference("cloth_debug", &image);

    // Deterministic: going back to 0 restarts from rest, and 0.6 s again is the same shape.
    let before: Vec<_> = cloth(&world).surface.vertices().to_vec();
    frame(&mut world, 0.0);
    assert_eq!(cloth(&world).surface.aabb().min.y, rest_bottom, "back at rest");
    frame(&mut world, 0.6);
    assert!(cloth(&world).surface.vertices() == before.as_slice(), "the same time gives the same shape");
    let (still, _) = frame(&mut world, 0.6);
    assert_eq!(still.bytes_uploaded.meshes, 0, "posing at the same time uploads nothing");
}

#[test]
fn compact_instances_draw_the_full_ones_picture_in_a_quarter_of_the_bytes() {
    // tiles.scn's cones stored in 16 bytes each: the same reference image, on
    // Vulkan (culled on the GPU and on the CPU), GL and the WebGL2 path.
    let gpus = [common::gpu(), common::gl_gpu(), common::webgl2_gpu()];
    for (k, gpu) in gpus.into_iter().enumerate() {
        let Some(gpu) = gpu else { continue };
        let mut desc = common::load_scene(&common::repo_root().join("tests/scenes/tiles.scn"));
        // Culled on the CPU, its counts are there at once.
        let full = common::render_desc(gpu, &desc, 256, glint::Culling::Cpu).1;
        desc.entities.iter_mut().filter(|e| e.tiles.is_some()).for_each(|e| e.compact = true);
        for culling in [glint::Culling::Gpu, glint::Culling::Cpu] {
            let (image, stats) = common::render_desc(gpu, &desc, 256, culling);
            // The ground is one full instance; 6,000 cones take 1,500 records, not 6,000.
            assert_eq!((full.instance_bytes, stats.instance_bytes), (64 * 6_001, 64 * 1_501), "gpu {k}");
            assert_eq!((stats.tiles_tested, stats.tiles_drawn), (full.tiles_tested, full.tiles_drawn));
            if stats.culling == glint::Culling::Cpu {
                // (Culled on the GPU, the ground's count comes back a frame late.)
                assert_eq!(stats.instances_drawn, full.instances_drawn, "gpu {k}");
            }
            common::assert_matches_reference("tiles", &image);
        }
    }
}
