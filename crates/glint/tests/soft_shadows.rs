//! Soft shadows (percentage-closer soft shadows, [`ShadowSettings::light_size`]):
//! a thin slab over a plane at two heights, seen straight down through an
//! orthographic camera centred on one edge of its shadow, lit by a directional
//! light of a given angular diameter or a spot light of a given radius. The
//! penumbra's width across that edge, measured from the picture, widens with
//! the distance from the slab to the plane and is within 15 % of the
//! similar-triangles estimate; the default size keeps the hard filter. On
//! Vulkan, GL and the WebGL2 path.

mod common;

use glam::{Mat4, Vec3};
use glint::asset::ShapeKind;
use glint::scene::ShadowSettings;
use glint::{Camera, Entity, Environment, FrameInput, Gpu, Light, Lighting, Material, OffscreenTarget, Renderer, View};

/// Side of the pictures, in pixels.
const SIZE: u32 = 256;
/// Height of the orthographic view, in world units.
const VIEW: f32 = 1.0;
/// The slab: 2 wide (its shadow's edge at x = 1), 0.02 thick, 1 deep, over
/// z −0.5..0.5, where it hides the ground from the camera.
const SLAB: Vec3 = Vec3::new(2.0, 0.02, 1.0);

/// The GPUs the tests draw on: the default one, GL, and GL within WebGL2's limits.
fn gpus() -> Vec<(&'static str, &'static Gpu)> {
    let all = [("default", common::gpu()), ("GL", common::gl_gpu()), ("GL, WebGL2 limits", common::gl_webgl2_gpu())];
    all.into_iter().filter_map(|(name, gpu)| Some((name, gpu?))).collect()
}

/// The picture of the slab at `height` (its centre) under `light`, the
/// camera looking straight down at `(1, 0, z)`, in linear light (grey only).
fn picture(gpu: &Gpu, light: Light, height: f32, z: f32) -> Vec<f32> {
    let mut renderer = Renderer::new(gpu);
    let plane = renderer.add_shape(ShapeKind::Plane.mesh());
    let cube = renderer.add_shape(ShapeKind::Cube.mesh());
    let grey = renderer.add_material(Material::color("grey", 0.8, 0.8, 0.8));
    let entities = vec![
        Entity::new(plane, grey, Mat4::from_scale(Vec3::splat(12.0))),
        Entity::new(cube, grey, Mat4::from_scale_rotation_translation(SLAB, glam::Quat::IDENTITY, Vec3::Y * height)),
    ];
    let target_point = Vec3::new(1.0, 0.0, z);
    let camera = Camera::orthographic(VIEW, 0.1, 20.0).looking_at(target_point + Vec3::Y * 6.0, target_point);
    // −z up the picture, so +x runs to the right.
    let camera = Camera { up: Vec3::NEG_Z, ..camera };
    let views = [View::new(camera)];
    let environment = Environment { ambient: Vec3::splat(0.1), ..Default::default() };
    let lights = [light];
    let mut target = OffscreenTarget::new(gpu, SIZE, SIZE, 1).expect("target");
    let input = FrameInput::new(&entities, Lighting::new(&lights, environment)).views(&views);
    renderer.render_frame(input, &mut target).expect("frame");
    let decode = |c: u8| {
        let c = f32::from(c) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    target.read_rgba8(gpu).expect("readback").pixels().map(|p| decode(p.0[1])).collect()
}

/// The penumbra's width in world units across the shadow's edge (shadow to
/// the left, light to the right), from the rows `rows` of `image`: on each
/// row, where the light rises from 5 % to 95 % of the way from shadow to light,
/// over 0.9 (a box filter's ramp is linear), averaged over the rows.
fn penumbra(image: &[f32], rows: std::ops::Range<u32>) -> f32 {
    let mut widths = Vec::new();
    for y in rows {
        let row = &image[(y * SIZE) as usize..((y + 1) * SIZE) as usize];
        let (shadow, light) = (row[..16].iter().sum::<f32>() / 16.0, row[row.len() - 16..].iter().sum::<f32>() / 16.0);
        assert!(light > shadow * 2.0, "row {y}: {shadow} in the shadow, {light} in the light");
        let level = |k: usize| (row[k] - shadow) / (light - shadow);
        let crossing = |t: f32| {
            let k = (1..row.len()).find(|&k| level(k) >= t).expect("the row reaches the light");
            (k - 1) as f32 + (t - level(k - 1)) / (level(k) - level(k - 1)).max(1e-6)
        };
        widths.push((crossing(0.95) - crossing(0.05)) / 0.9 * VIEW / SIZE as f32);
    }
    widths.iter().sum::<f32>() / widths.len() as f32
}

/// The rows of the picture centred on `z` that show ground from `from` to `to`
/// (world z; the image's top is −z).
fn rows(centre: f32, from: f32, to: f32) -> std::ops::Range<u32> {
    let row = |z: f32| ((z - centre) / VIEW + 0.5) * SIZE as f32;
    row(from).ceil() as u32..row(to).floor() as u32
}

#[test]
fn a_directional_lights_penumbra_widens_as_similar_triangles_say() {
    // The light travels 45° down towards +z: the shadow of the slab at height h
    // lies h further along z, and the distance along the ray from the slab's
    // top to the ground is √2 (h + 0.01).
    let degrees = 3.0;
    let settings = ShadowSettings { map_size: 1024, light_size: degrees, ..Default::default() };
    let sun = Light::directional(Vec3::new(0.0, -1.0, 1.0), Vec3::ONE, 1.0).with_shadows(settings);
    for (name, gpu) in gpus() {
        let mut measured = Vec::new();
        for height in [0.6, 1.2] {
            let expected =
                std::f32::consts::SQRT_2 * (height + 0.5 * SLAB.y) * 2.0 * (0.5 * degrees).to_radians().tan();
            // The shadow lies over z h − 0.5..h + 0.5, the slab hides z < 0.5.
            let (from, to) = ((height - 0.4).max(0.6), height + 0.4);
            let image = picture(gpu, sun, height, 0.5 * (from + to));
            let width = penumbra(&image, rows(0.5 * (from + to), from, to));
            eprintln!("{name}: slab at {height}: penumbra {width:.4}, similar triangles {expected:.4}");
            assert!((width / expected - 1.0).abs() < 0.15, "{name}, height {height}: {width} against {expected}");
            measured.push(width);
        }
        assert!(measured[1] > measured[0] * 1.6, "{name}: the penumbra widens with the distance: {measured:?}");
        // Without a size: the hard filter's few texels, whatever the height.
        let hard = sun.with_shadows(ShadowSettings { light_size: 0.0, ..settings });
        let width = penumbra(&picture(gpu, hard, 1.2, 1.2), rows(1.2, 0.9, 1.5));
        eprintln!("{name}: without a size: penumbra {width:.4}");
        assert!(width < measured[0] * 0.6, "{name}: hard {width}, soft {measured:?}");
    }
}

#[test]
fn a_spot_lights_penumbra_widens_as_similar_triangles_say() {
    // A spot light of radius 0.1 at (1, 4, -2), above the edge's line x = 1,
    // shining down towards +z. A slab whose top is h up casts, by similar
    // triangles, a penumbra 2 · 0.1 · h / (4 − h) wide across x on the ground,
    // its shadow from z = -2 + 1.5 · 4 / (4 − h) to -2 + 2.5 · 4 / (4 − h).
    let radius = 0.1;
    let settings = ShadowSettings { map_size: 1024, light_size: radius, ..Default::default() };
    let spot = Light::spot(Vec3::new(1.0, 4.0, -2.0), Vec3::new(0.0, -4.0, 2.7), Vec3::ONE, 10.0, 12.0, (0.6, 0.7))
        .with_shadows(settings);
    for (name, gpu) in gpus() {
        let mut measured = Vec::new();
        for height in [1.0, 1.5] {
            let top = height + 0.5 * SLAB.y;
            let expected = 2.0 * radius * top / (4.0 - top);
            let (near, far) = (-2.0 + 1.5 * 4.0 / (4.0 - top), -2.0 + 2.5 * 4.0 / (4.0 - top));
            // The slab hides z < 0.5.
            let (from, to) = (near.max(0.5) + 0.1, (far - 0.1).min(near.max(0.5) + 0.8));
            let centre = 0.5 * (from + to);
            let image = picture(gpu, spot, height, centre);
            let width = penumbra(&image, rows(centre, from, to));
            eprintln!("{name}: slab at {height}: penumbra {width:.4}, similar triangles {expected:.4}");
            assert!((width / expected - 1.0).abs() < 0.15, "{name}, height {height}: {width} against {expected}");
            measured.push(width);
        }
        assert!(measured[1] > measured[0] * 1.4, "{name}: the penumbra widens with the distance: {measured:?}");
    }
}

#[test]
fn the_sun_size_control_reaches_every_shadowed_sun_also_while_shadows_are_off() {
    let Some(gpu) = common::gpu() else { return };
    let text = "{ \"classname\" \"light_directional\"\n\"direction\" \"0 -1 0\"\n\"shadows\" \"1\" }\n\
                { \"classname\" \"light_directional\"\n\"direction\" \"1 -1 0\" }\n\
                { \"classname\" \"light_spot\"\n\"origin\" \"0 2 0\"\n\"direction\" \"0 -1 0\"\n\"shadows\" \"1\"\n\"light_size\" \"0.1\" }\n\
                { \"classname\" \"entity\"\n\"mesh\" \"cube\" }\n";
    let desc = glint::asset::parse_scene("t.scn".as_ref(), text).expect("scene");
    let mut renderer = Renderer::new(gpu);
    let mut world = glint::World::place(desc, &mut renderer).expect("placed");
    let sizes = |world: &glint::World| -> Vec<Option<f32>> {
        world.desc().lights.iter().map(|l| l.shadows.map(|s| s.light_size)).collect()
    };
    assert_eq!(world.sun_size(), Some(0.0));
    world.set_sun_size(0.5);
    assert_eq!(sizes(&world), [Some(0.5), None, Some(0.1)], "the shadowed sun only; the spot keeps its radius");
    world.set_shadows(false);
    world.set_sun_size(2.0);
    assert_eq!(world.sun_size(), Some(2.0), "the size it will have");
    world.set_shadows(true);
    assert_eq!(sizes(&world), [Some(2.0), None, Some(0.1)], "kept while shadows were off");
}
