//! Image-based lighting: the white furnace (a white sphere of any roughness,
//! dielectric or metal, under a uniform environment returns its radiance), a
//! mirror sphere reflecting the environment the right way round on every
//! path, the environment prefiltered only when it changes, and scenes without
//! one drawing as before.

mod common;

use glam::{Mat4, Vec3, Vec4};
use glint::asset::{EnvironmentImage, ShapeKind};
use glint::scene::{EnvironmentLight, EnvironmentSource, ShadingModel};
use glint::{Camera, Entity, Environment, Gpu, Lighting, Material, OffscreenTarget, Renderer};

/// Linear value of an sRGB byte.
fn linear(byte: u8) -> f32 {
    let c = f32::from(byte) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// White metallic-roughness spheres (metallic, roughness) in a row along x,
/// one unit apart, seen by `camera` under `environment` (lit by `image`
/// where it is the environment's), no lights, into a `width` × `height` image.
fn spheres(
    gpu: &Gpu,
    image: Option<&EnvironmentImage>,
    environment: Environment,
    looks: &[(f32, f32)],
    camera: Camera,
    (width, height): (u32, u32),
) -> (image::RgbaImage, glint::FrameStats) {
    let mut renderer = Renderer::new(gpu);
    if let Some(image) = image {
        renderer.add_environment(image);
    }
    let sphere = renderer.add_shape(ShapeKind::Sphere.mesh());
    let first = -(looks.len() as f32 - 1.0) / 2.0;
    let entities: Vec<Entity> = (looks.iter().enumerate())
        .map(|(k, &(metallic, roughness))| {
            let material = renderer.add_material(Material {
                shading: ShadingModel::MetallicRoughness,
                base_color: Vec4::ONE,
                metallic,
                roughness,
                ..Material::default()
            });
            Entity::new(sphere, material, Mat4::from_translation(Vec3::new(first + k as f32, 0.0, 0.0)))
        })
        .collect();
    let mut target = OffscreenTarget::new(gpu, width, height, 1).expect("target");
    let stats = renderer.render(&entities, camera, Lighting::new(&[], environment), &mut target).expect("frame");
    let mut stats = [stats];
    renderer.wait_for_counts(&mut stats);
    let [stats] = stats;
    (target.read_rgba8(gpu).expect("readback"), stats)
}

fn lit_by(image: &EnvironmentImage, rotation_degrees: f32) -> Environment {
    let light = EnvironmentLight {
        rotation: rotation_degrees.to_radians(),
        ..EnvironmentLight::new(EnvironmentSource::Image(image.id()))
    };
    Environment { light: Some(light), ..Environment::default() }
}

#[test]
fn the_white_furnace_returns_the_environment_for_every_roughness() {
    let Some(gpu) = common::gpu() else { return };
    let radiance = 0.5;
    let furnace = EnvironmentImage::uniform(Vec3::splat(radiance));
    let looks = [(0.0, 0.0), (0.0, 0.5), (0.0, 1.0), (1.0, 0.0), (1.0, 0.5), (1.0, 1.0)];
    let camera = Camera::orthographic(1.2, 0.1, 20.0).looking_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
    let size = (240, 48);
    let (image, stats) = spheres(gpu, Some(&furnace), lit_by(&furnace, 0.0), &looks, camera, size);
    assert_eq!((stats.instances_drawn, stats.passes.sky.draws), (6, 1), "six spheres and the sky");
    assert!(stats.environment_prefiltered);
    // Every pixel, spheres and sky, within 3 % of the radiance.
    for (x, y, p) in image.enumerate_pixels() {
        for c in &p.0[..3] {
            let error = (linear(*c) - radiance).abs() / radiance;
            assert!(error <= 0.03, "pixel ({x}, {y}) {p:?}: {:.1} % off", error * 100.0);
        }
    }
    // The spheres are there: under the flat ambient light instead, their
    // middles are darker than the furnace's.
    let (flat, _) = spheres(gpu, None, Environment::default(), &looks, camera, size);
    for k in 0..6 {
        let middle = flat.get_pixel(20 + 40 * k, 24).0[0];
        assert!(linear(middle) < 0.4 * radiance, "sphere {k} under ambient light: {middle}");
    }
}

/// Red toward +X, blue toward −X, grey between.
fn red_and_blue() -> EnvironmentImage {
    EnvironmentImage::from_fn("red and blue", 64, 32, |d| match d.x {
        x if x > 0.2 => Vec3::new(0.9, 0.05, 0.05),
        x if x < -0.2 => Vec3::new(0.05, 0.05, 0.9),
        _ => Vec3::splat(0.3),
    })
}

/// A mirror sphere (and the sky behind it) shows red on its right and blue on
/// its left, and the other way round with the environment turned half a turn.
fn mirror_the_right_way_round(gpu: &Gpu) {
    let env = red_and_blue();
    let camera = Camera::perspective(90.0, 0.1, 20.0).looking_at(Vec3::new(0.0, 0.0, 1.5), Vec3::ZERO);
    for (turn, right_red) in [(0.0, true), (180.0, false)] {
        let (image, _) = spheres(gpu, Some(&env), lit_by(&env, turn), &[(1.0, 0.0)], camera, (96, 96));
        let red = |x: u32, y: u32| {
            let p = image.get_pixel(x, y).0;
            assert!(p[0].abs_diff(p[2]) > 100, "({x}, {y}) {p:?} is neither red nor blue (turn {turn})");
            p[0] > p[2]
        };
        // The sphere's right and left edges reflect what is to the right and
        // left; the sky's corners show the same sides.
        assert_eq!(red(62, 48), right_red, "the sphere's right side, turn {turn}");
        assert_eq!(red(34, 48), !right_red, "the sphere's left side, turn {turn}");
        assert_eq!(red(93, 48), right_red, "the sky on the right, turn {turn}");
        assert_eq!(red(2, 48), !right_red, "the sky on the left, turn {turn}");
    }
}

#[test]
fn a_mirror_reflects_the_environment_the_right_way_round_on_vulkan() {
    let Some(gpu) = common::gpu() else { return };
    mirror_the_right_way_round(gpu);
}

#[test]
fn a_mirror_reflects_the_environment_the_right_way_round_on_gl() {
    let Some(gpu) = common::gl_gpu() else { return };
    mirror_the_right_way_round(gpu);
}

#[test]
fn a_mirror_reflects_the_environment_the_right_way_round_on_the_webgl2_path() {
    let Some(gpu) = common::gl_webgl2_gpu() else { return };
    mirror_the_right_way_round(gpu);
}

#[test]
fn the_environment_is_prefiltered_only_when_it_changes() {
    let Some(gpu) = common::gpu() else { return };
    let mut desc = common::load_scene(&common::repo_root().join("tests/scenes/environment_sky.scn"));
    let mut renderer = Renderer::new(gpu);
    let entities = renderer.place_scene(&desc).entities;
    let mut target = OffscreenTarget::new(gpu, 32, 32, 1).expect("target");
    let mut frame = |renderer: &mut Renderer, desc: &glint::asset::SceneDesc| {
        let view = glint::View::new(desc.cameras[0]);
        renderer.render(&entities, view, desc.lighting(), &mut target).expect("frame").environment_prefiltered
    };
    assert!(frame(&mut renderer, &desc), "the first frame prefilters");
    assert!(!frame(&mut renderer, &desc), "the same sky: nothing to do");
    desc.set_time_of_day(17.0).unwrap();
    assert!(frame(&mut renderer, &desc), "another time of day bakes and prefilters the sky again");
    assert!(!frame(&mut renderer, &desc));
}

#[test]
fn a_gltf_model_shown_alone_gets_a_studio_environment_and_an_obj_does_not() {
    let models = common::repo_root().join("tests/models");
    let gltf = glint::asset::Model::load(&models.join("animated.gltf")).expect("loads").into_shown_scene();
    let light = gltf.environment.light.expect("a studio environment");
    let image = gltf.environment_image.as_ref().expect("its image");
    assert_eq!(light.source, EnvironmentSource::Image(image.id()));
    let obj = glint::asset::Model::load(&models.join("smoothing.obj")).expect("loads").into_shown_scene();
    assert!(obj.environment.light.is_none() && obj.environment_image.is_none());
    // Drawn, the studio lights it: its sky is the studio's blurred dome, not the gradient.
    let Some(gpu) = common::gpu() else { return };
    let (lit, stats) = common::render_desc(gpu, &gltf, 64, glint::Culling::Cpu);
    assert!(stats.environment_prefiltered && stats.passes.sky.draws == 1);
    let plain = glint::asset::Model::load(&models.join("animated.gltf")).expect("loads").into_scene();
    let (unlit, _) = common::render_desc(gpu, &plain, 64, glint::Culling::Cpu);
    let corner = |image: &image::RgbaImage| image.get_pixel(1, 1).0;
    assert_ne!(corner(&lit), corner(&unlit), "the sky comes from the studio");
}
