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
    // Culled on the CPU, so that this frame's counts are known now.
    let view = glint::View::new(scene.camera).with_culling(glint::Culling::Cpu);
    let shadows = scene.renderer.shadow_pass(&view, lights, &target).expect("shadow pass");
    let stats = scene.renderer.flush(view, lights, &shadows, &mut target).expect("frame");
    (target.read_rgba8(gpu).expect("readback"), stats)
}

fn luma(p: &image::Rgba<u8>) -> f32 {
    0.299 * f32::from(p[0]) + 0.587 * f32::from(p[1]) + 0.114 * f32::from(p[2])
}

/// Pixels in `xs` × `ys` at least 5% darker in `image` than in `unshadowed`
/// (one of two lights blocked dims a surface by little more).
fn darker(
    image: &image::RgbaImage,
    unshadowed: &image::RgbaImage,
    xs: std::ops::Range<u32>,
    ys: std::ops::Range<u32>,
) -> usize {
    let darker = |x, y| luma(image.get_pixel(x, y)) < 0.95 * luma(unshadowed.get_pixel(x, y));
    ys.flat_map(|y| xs.clone().map(move |x| (x, y))).filter(|&(x, y)| darker(x, y)).count()
}

fn without_shadows(lights: &[Light]) -> Vec<Light> {
    lights.iter().map(|l| Light { shadows: None, ..*l }).collect()
}

#[test]
fn a_directional_light_casts_a_contact_shadow_without_acne_at_a_grazing_angle() {
    let Some(gpu) = common::gpu() else { return };
    let mut scene = cube_on_plane(gpu);
    // A sun 10 degrees above the horizon, from the left and behind: the shadow
    // runs long to the front right, and the lit plane is grazed.
    let sun = Light::directional(Vec3::new(1.0, -0.2, 0.5), Vec3::ONE, 1.0)
        .with_shadows(ShadowSettings { map_size: 512, ..Default::default() });
    let (image, stats) = render(&mut scene, gpu, &[sun], 128);
    let (unshadowed, _) = render(&mut scene, gpu, &without_shadows(&[sun]), 128);
    assert_eq!(stats.shadow_views, 4, "four cascades");
    assert!(stats.passes.shadow.draws >= 4, "the cube and the plane in each cascade: {:?}", stats.passes.shadow);
    assert_eq!(stats.passes.opaque.draws, stats.draws, "every forward draw here is opaque");
    // The shadow runs from the cube's foot to the front right.
    assert!(darker(&image, &unshadowed, 76..128, 60..95) > 600, "a long shadow to the front right");
    assert!(darker(&image, &unshadowed, 70..80, 60..72) > 40, "touching the cube (no peter-panning)");
    // The plane left of the cube is lit: no pixel darker than without shadows (acne).
    for y in 50..110 {
        for x in 0..48 {
            let (a, b) = (luma(image.get_pixel(x, y)), luma(unshadowed.get_pixel(x, y)));
            assert!(a >= b - 3.0, "acne at ({x}, {y}): {a} against {b}");
        }
    }
    common::assert_matches_reference("shadow_directional", &image);
}

#[test]
fn two_point_lights_cast_cube_shadows() {
    let Some(gpu) = common::gpu() else { return };
    let mut scene = cube_on_plane(gpu);
    let settings = ShadowSettings { map_size: 256, ..Default::default() };
    let lights = [
        Light::point(Vec3::new(-2.0, 2.0, 0.5), Vec3::new(1.0, 0.8, 0.6), 2.5, 12.0).with_shadows(settings),
        Light::point(Vec3::new(2.0, 1.5, -1.0), Vec3::new(0.6, 0.8, 1.0), 2.5, 12.0).with_shadows(settings),
    ];
    let (image, stats) = render(&mut scene, gpu, &lights, 128);
    assert_eq!(stats.shadow_views, 12, "six faces per light");
    let (unshadowed, _) = render(&mut scene, gpu, &without_shadows(&lights), 128);
    // Each light alone casting: the left one's shadow falls to the right, the right one's to the front left.
    let (left_only, _) = render(&mut scene, gpu, &[lights[0], without_shadows(&lights)[1]], 128);
    let (right_only, _) = render(&mut scene, gpu, &[without_shadows(&lights)[0], lights[1]], 128);
    assert!(darker(&left_only, &unshadowed, 72..128, 48..74) > 150, "the left light's shadow");
    assert_eq!(darker(&left_only, &unshadowed, 0..50, 50..110), 0, "nothing of it on the left");
    assert!(darker(&right_only, &unshadowed, 0..60, 64..110) > 150, "the right light's shadow");
    assert_eq!(darker(&right_only, &unshadowed, 80..128, 50..110), 0, "nothing of it on the right");
    common::assert_matches_reference("shadow_point_cubes", &image);
}

#[test]
fn a_spot_light_casts_through_its_cone() {
    let Some(gpu) = common::gpu() else { return };
    lone_spot_light(gpu);
}

#[test]
fn a_lone_point_light_casts_a_cube_shadow() {
    let Some(gpu) = common::gpu() else { return };
    lone_point_light(gpu);
}

/// wgpu's GL backend fixes a texture's binding type from its layer count when
/// it is made: one layer reads as a 2D texture, six as one cube. A lone spot or
/// point light is the case where the shadow maps would have those counts.
#[test]
fn on_gl_a_lone_spot_and_a_lone_point_light_cast_the_same_shadows() {
    let Some(gpu) = common::gl_gpu() else { return };
    lone_spot_light(gpu);
    lone_point_light(gpu);
}

/// Point lights' cube faces are layers of one 2D array, so every adapter (GL
/// drivers and WebGL2 without cube-map arrays too) gives each shadow-casting
/// point light its own cube: both lights' shadows, each where only it darkens.
#[test]
fn two_point_lights_cast_two_shadows() {
    let Some(gpu) = common::gpu() else { return };
    two_point_lights(gpu);
}

#[test]
fn on_gl_two_point_lights_cast_two_shadows() {
    let Some(gpu) = common::gl_gpu() else { return };
    two_point_lights(gpu);
}

fn two_point_lights(gpu: &glint::Gpu) {
    let mut scene = cube_on_plane(gpu);
    let settings = ShadowSettings { map_size: 256, ..Default::default() };
    let lights = [
        Light::point(Vec3::new(-2.0, 2.0, 0.5), Vec3::new(1.0, 0.8, 0.6), 2.5, 12.0).with_shadows(settings),
        Light::point(Vec3::new(2.0, 1.5, -1.0), Vec3::new(0.6, 0.8, 1.0), 2.5, 12.0).with_shadows(settings),
    ];
    let unlit = without_shadows(&lights);
    let (image, stats) = render(&mut scene, gpu, &lights, 128);
    assert_eq!(stats.shadow_views, 12, "two cubes");
    let (first_only, _) = render(&mut scene, gpu, &[lights[0], unlit[1]], 128);
    let (second_only, _) = render(&mut scene, gpu, &[unlit[0], lights[1]], 128);
    let all = || 0..128;
    assert!(darker(&image, &second_only, all(), all()) > 150, "the first light's shadow");
    assert!(darker(&image, &first_only, all(), all()) > 150, "the second light's shadow");
    assert!(darker(&first_only, &image, all(), all()) == 0, "the second shadow only darkens");
}

/// A spot light, the only shadow caster of a fresh renderer: one 2D shadow map.
fn lone_spot_light(gpu: &glint::Gpu) {
    let mut scene = cube_on_plane(gpu);
    let spot = Light::spot(Vec3::new(-1.5, 3.0, -1.5), Vec3::new(1.0, -2.0, 1.0), Vec3::ONE, 12.0, 10.0, (0.5, 0.7))
        .with_shadows(ShadowSettings { map_size: 256, ..Default::default() });
    let (image, stats) = render(&mut scene, gpu, &[spot], 128);
    let (unshadowed, _) = render(&mut scene, gpu, &without_shadows(&[spot]), 128);
    assert_eq!(stats.shadow_views, 1);
    assert!(darker(&image, &unshadowed, 64..100, 64..90) > 300, "the cube's shadow in the cone");
    common::assert_matches_reference("shadow_spot", &image);
}

/// A point light, the only shadow caster of a fresh renderer: one cube of six faces.
fn lone_point_light(gpu: &glint::Gpu) {
    let mut scene = cube_on_plane(gpu);
    let settings = ShadowSettings { map_size: 256, ..Default::default() };
    let light = Light::point(Vec3::new(-2.0, 2.0, 0.5), Vec3::new(1.0, 0.8, 0.6), 2.5, 12.0).with_shadows(settings);
    let (image, stats) = render(&mut scene, gpu, &[light], 128);
    let (unshadowed, _) = render(&mut scene, gpu, &without_shadows(&[light]), 128);
    assert_eq!(stats.shadow_views, 6);
    assert!(darker(&image, &unshadowed, 72..128, 48..74) > 150, "the shadow to the right of the cube");
    assert_eq!(darker(&image, &unshadowed, 0..50, 50..110), 0, "nothing of it on the left");
    common::assert_matches_reference("shadow_point_lone", &image);
}

#[test]
fn a_caster_outside_the_camera_view_still_shadows_what_is_in_view() {
    let Some(gpu) = common::gpu() else { return };
    let mut scene = cube_on_plane(gpu);
    // Look straight down at a small patch of the plane beside the cube; a slab
    // hangs high above and to the side, outside the view, in the sun's way.
    scene.camera = Camera::perspective(30.0, 0.1, 50.0).looking_at(Vec3::new(1.5, 3.0, 0.01), Vec3::new(1.5, 0.0, 0.0));
    let slab = Entity::new(
        scene.entities[1].shape,
        scene.entities[1].material,
        Mat4::from_scale_rotation_translation(
            Vec3::new(1.0, 0.2, 1.0),
            glam::Quat::IDENTITY,
            Vec3::new(-1.5, 6.0, 0.0),
        ),
    );
    scene.entities.push(slab);
    let sun = Light::directional(Vec3::new(0.5, -1.0, 0.0), Vec3::ONE, 1.0).with_shadows(ShadowSettings::default());
    let (image, stats) = render(&mut scene, gpu, &[sun], 64);
    assert_eq!(stats.instances_drawn, 1, "only the plane is in view");
    scene.entities[2].cast_shadows = false;
    let (clear, _) = render(&mut scene, gpu, &[sun], 64);
    let (a, b) = (luma(image.get_pixel(32, 32)), luma(clear.get_pixel(32, 32)));
    assert!(a < 0.7 * b, "the slab's shadow reaches the view: {a} against {b}");
}

/// World point → pixel of a `size`×`size` image seen by `camera`.
fn pixel(camera: &Camera, size: u32, p: Vec3) -> (u32, u32) {
    let clip = camera.projection(1.0) * camera.view() * p.extend(1.0);
    let ndc = clip.truncate() / clip.w;
    let s = size as f32;
    (((ndc.x * 0.5 + 0.5) * s) as u32, ((0.5 - ndc.y * 0.5) * s) as u32)
}

#[test]
fn cascades_shadow_every_pillar_down_a_three_hundred_metre_field() {
    let Some(gpu) = common::gpu() else { return };
    let mut renderer = Renderer::new(gpu);
    let plane = renderer.add_shape(ShapeKind::Plane.mesh());
    let cube = renderer.add_shape(ShapeKind::Cube.mesh());
    let grey = renderer.add_material(Material::color("grey", 0.8, 0.8, 0.8));
    let red = renderer.add_material(Material::color("red", 0.8, 0.2, 0.2));
    // Sixteen 2×4×5 pillars every 14 m down a 500 m field, seen from so high at one
    // end that no pillar hides the ground either side of another.
    let pillars: Vec<Vec3> = (1..=16).map(|k| Vec3::new(0.0, 2.0, -14.0 * k as f32)).collect();
    let entities = [
        Entity::new(plane, grey, Mat4::from_scale(Vec3::splat(500.0))),
        Entity::instanced(
            cube,
            red,
            pillars
                .iter()
                .map(|&p| Mat4::from_scale_rotation_translation(Vec3::new(2.0, 4.0, 5.0), glam::Quat::IDENTITY, p))
                .collect(),
        ),
    ];
    let camera =
        Camera::perspective(40.0, 0.5, 400.0).looking_at(Vec3::new(-10.0, 60.0, 60.0), Vec3::new(0.0, 0.0, -80.0));
    // The sun shines along +X and down at 45°: each pillar's shadow lies 1..5 m to its right.
    let sun = Light::directional(Vec3::new(1.0, -1.0, 0.0), Vec3::ONE, 1.0)
        .with_shadows(ShadowSettings { map_size: 1024, ..Default::default() });
    let size = 192;
    let mut frame = |lights: &[Light]| {
        let mut target = OffscreenTarget::new(gpu, size, size, 4).expect("target");
        let stats = renderer.render(&entities, camera, lights, &mut target).expect("frame");
        (target.read_rgba8(gpu).expect("readback"), stats)
    };
    let (image, stats) = frame(&[sun]);
    let (unshadowed, _) = frame(&without_shadows(&[sun]));
    assert_eq!(stats.shadow_views, 4);
    // Luma ratio, shadowed over unshadowed, of the 3×3 pixels around a ground point.
    let ratios = |x: f32, z: f32| {
        let (px, py) = pixel(&camera, size, Vec3::new(x, 0.0, z));
        let around = (py - 1..=py + 1).flat_map(|y| (px - 1..=px + 1).map(move |x| (x, y)));
        around.map(|(x, y)| luma(image.get_pixel(x, y)) / luma(unshadowed.get_pixel(x, y))).collect::<Vec<f32>>()
    };
    for (k, p) in pillars.iter().enumerate() {
        let distance = (*p - camera.eye).length();
        let shadow = ratios(3.0, p.z).into_iter().fold(f32::MAX, f32::min);
        assert!(shadow < 0.6, "pillar {k} at {distance:.0} m: its shadow is only {shadow} as bright");
        let sunny = ratios(-4.0, p.z).into_iter().fold(f32::MAX, f32::min);
        assert!(sunny > 0.98, "pillar {k} at {distance:.0} m: its sunny side is {sunny} as bright (acne)");
    }
    common::assert_matches_reference("shadow_cascades", &image);
}
