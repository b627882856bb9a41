//! Shadows: a directional light's cascades, point lights' cubes and a spot
//! light's map, drawn by `Renderer::shadow_pass` and read by the forward pass.

mod common;

use glam::{Mat4, Vec3};
use glint::asset::ShapeKind;
use glint::scene::ShadowSettings;
use glint::{Camera, Entity, Light, Material, OffscreenTarget, Renderer};

/// A 6×6 plane with a unit cube standing on it, seen from the front and above.
struct CubeOnPlane {
    renderer: Renderer,
    entities: Vec<Entity>,
    camera: Camera,
}

fn cube_on_plane(gpu: &glint::Gpu) -> CubeOnPlane {
    let mut renderer = Renderer::new(gpu);
    let plane = renderer.add_shape(ShapeKind::Plane.mesh());
    let cube = renderer.add_shape(ShapeKind::Cube.mesh());
    let grey = renderer.add_material(Material::color("grey", 0.8, 0.8, 0.8));
    let red = renderer.add_material(Material::color("red", 0.8, 0.2, 0.2));
    let entities = vec![
        Entity::new(plane, grey, Mat4::from_scale(Vec3::splat(6.0))),
        Entity::new(cube, red, Mat4::from_translation(Vec3::new(0.0, 0.5, 0.0))),
    ];
    let camera = Camera::perspective(50.0, 0.1, 50.0).looking_at(Vec3::new(0.0, 4.0, 6.0), Vec3::ZERO);
    CubeOnPlane { renderer, entities, camera }
}

fn render(
    scene: &mut CubeOnPlane,
    gpu: &glint::Gpu,
    lights: &[Light],
    size: u32,
) -> (image::RgbaImage, glint::FrameStats) {
    let mut target = OffscreenTarget::new(gpu, size, size, 4).expect("target");
    for e in &scene.entities {
        scene.renderer.submit(e);
    }
    scene.renderer.shadow_pass(&scene.camera, lights, &target).expect("shadow pass");
    let stats = scene.renderer.flush(&scene.camera, lights, &mut target).expect("frame");
    (target.read_rgba8(gpu).expect("readback"), stats)
}

#[test]
fn a_directional_light_casts_a_contact_shadow_without_acne() {
    let Some(gpu) = common::gpu() else { return };
    let mut scene = cube_on_plane(gpu);
    // A low sun from the left and behind: the shadow falls to the front right.
    let sun = Light::directional(Vec3::new(1.0, -0.35, 0.6), Vec3::ONE, 1.0)
        .with_shadows(ShadowSettings { map_size: 512, ..Default::default() });
    let (image, stats) = render(&mut scene, gpu, &[sun], 128);
    image.save("/tmp/shadow_dir.png").ok();
    assert_eq!(stats.shadow_views, 4, "four cascades");
    let (unlit, _) = render(&mut scene, gpu, &[Light { shadows: None, ..sun }], 128);
    unlit.save("/tmp/shadow_dir_unlit.png").ok();
}
