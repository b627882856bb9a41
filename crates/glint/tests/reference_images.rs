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
fn culling_never_changes_the_picture() {
    let Some(gpu) = common::gpu() else { return };
    let showcase = common::repo_root().join("scenes/showcase.scn");
    let (culled, stats) = common::render_file(gpu, &showcase, 192, true);
    let (unculled, all) = common::render_file(gpu, &showcase, 192, false);
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
    let desc = glint::asset::load_scene(&path).expect("scene");
    let mut renderer = glint::Renderer::new(gpu);
    let entities = desc.instantiate(&mut renderer);
    let mut target = glint::OffscreenTarget::new(gpu, 256, 256, 4).expect("target");
    for e in &entities {
        renderer.submit(e);
    }
    let without_red: Vec<_> = desc.lights.iter().copied().filter(|l| l.color.x < 0.99 || l.color.y > 0.5).collect();
    assert_eq!(without_red.len(), desc.lights.len() - 1);
    renderer.flush(&desc.cameras[0], &without_red, &mut target).expect("frame");
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
