//! The GPU side of hostile input: what the documented maxima let through must run or
//! fail with an error naming the limit, never a panic inside wgpu; and a scene
//! check refuses what the renderer would refuse.

mod common;

use glam::{Mat4, Vec3};
use glint::asset::{parse_scene, ShapeKind, MAX_INSTANCES};
use glint::render::MAX_SHADOW_MAP_BYTES;
use glint::scene::ShadowSettings;
use glint::{Camera, Entity, Light, Material, OffscreenTarget, RenderError, Renderer};
use std::path::Path;

fn camera() -> Camera {
    Camera::perspective(60.0, 0.1, 100.0).looking_at(Vec3::new(0.0, 5.0, 10.0), Vec3::ZERO)
}

fn suns(n: usize, map_size: u32) -> Vec<Light> {
    let settings = ShadowSettings { map_size, ..ShadowSettings::default() };
    (0..n).map(|i| Light::directional(Vec3::new(-1.0, -1.0, i as f32), Vec3::ONE, 1.0).with_shadows(settings)).collect()
}

#[test]
fn shadow_maps_past_the_memory_limit_are_an_error_not_a_panic() {
    // Three suns at 8192²: 12 cascades of 256 MiB. wgpu panicked with out of memory.
    let Some(gpu) = common::gpu() else { return };
    let mut renderer = Renderer::new(gpu);
    let cube = renderer.add_shape(ShapeKind::Cube.mesh());
    let material = renderer.add_material(Material::default());
    let entity = Entity::new(cube, material, Mat4::IDENTITY);
    let mut target = OffscreenTarget::new(gpu, 32, 32, 1).expect("target");
    let error = renderer.render([&entity], camera(), &suns(3, 8192), &mut target).expect_err("3 GiB of shadow maps");
    match &error {
        RenderError::TooLarge { what, bytes, limit, .. } => {
            assert_eq!(*what, "the shadow maps");
            assert_eq!(*bytes, 12 * 8192 * 8192 * 4);
            assert_eq!(*limit, MAX_SHADOW_MAP_BYTES);
        }
        other => panic!("expected TooLarge, got {other}"),
    }
    // The renderer is still usable: the same lights at a size that fits cast shadows.
    let stats = renderer.render([&entity], camera(), &suns(3, 1024), &mut target).expect("12 cascades of 4 MiB fit");
    assert_eq!(stats.shadow_views, 12);
}

#[test]
fn instances_past_the_storage_binding_are_an_error_not_a_panic() {
    // More 64-byte records than the 128 MiB storage binding of wgpu's baseline
    // limits holds: creating the bind group panicked inside wgpu.
    let Some(gpu) = common::gpu() else { return };
    let binding = gpu.device.limits().max_storage_buffer_binding_size;
    let count = (binding / 64 + 1) as usize;
    let mut renderer = Renderer::new(gpu);
    let cube = renderer.add_shape(ShapeKind::Cube.mesh());
    let material = renderer.add_material(Material::default());
    let transforms = vec![Mat4::from_translation(Vec3::new(0.0, 0.0, -200.0)); count];
    let entity = Entity::instanced(cube, material, transforms);
    let mut target = OffscreenTarget::new(gpu, 32, 32, 1).expect("target");
    renderer.submit(&entity);
    let error = renderer
        .flush(camera(), &[], &glint::Shadows::none(), &mut target)
        .expect_err("too many instances for one binding");
    match &error {
        RenderError::TooLarge { what, bytes, limit, limit_name } => {
            assert_eq!(*what, "renderer block: instances");
            assert_eq!(*bytes, count as u64 * 64);
            assert_eq!(*limit, binding);
            assert!(limit_name.contains("max_storage_buffer_binding_size"), "{limit_name}");
        }
        other => panic!("expected TooLarge, got {other}"),
    }
    // A scene at the documented maximum fits the baseline binding.
    assert!(MAX_INSTANCES * 64 <= wgpu::Limits::downlevel_defaults().max_storage_buffer_binding_size);
}

#[test]
fn a_scene_check_refuses_shadow_maps_the_renderer_would_refuse() {
    let light = |line_size: u32| {
        format!("{{\n\"classname\" \"light_directional\"\n\"direction\" \"0 -1 0\"\n\"shadows\" \"1\"\n\"shadow_map_size\" \"{line_size}\"\n}}\n")
    };
    // One sun at 8192² is exactly the limit (four 256 MiB cascades).
    parse_scene(Path::new("s.scn"), &light(8192)).expect("one sun at 8192 fits");
    let two = format!("{}{}", light(8192), light(16));
    let error = parse_scene(Path::new("s.scn"), &two).expect_err("two suns share the 8192 size");
    assert!(error.to_string().starts_with("s.scn:7: with this light the shadow maps need 2048 MiB"), "{error}");
    let small = format!("{}{}{}", light(2048), light(2048), light(2048));
    parse_scene(Path::new("s.scn"), &small).expect("three suns at 2048 fit");
}

#[test]
fn a_texture_wider_than_the_adapter_allows_is_an_error_not_a_panic() {
    let Some(gpu) = common::gpu() else { return };
    let side = gpu.device.limits().max_texture_dimension_2d;
    let mut renderer = Renderer::new(gpu);
    let cube = renderer.add_shape(ShapeKind::Cube.mesh());
    let wide = renderer.add_texture(glint::Texture::new("wide", image::RgbaImage::new(side + 1, 1), true));
    let material = renderer.add_material(Material { diffuse_map: Some(wide), ..Material::default() });
    let entity = Entity::new(cube, material, Mat4::IDENTITY);
    let mut target = OffscreenTarget::new(gpu, 32, 32, 1).expect("target");
    renderer.submit(&entity);
    let error =
        renderer.flush(camera(), &[], &glint::Shadows::none(), &mut target).expect_err("wider than the adapter allows");
    assert!(
        matches!(&error, RenderError::TextureTooLarge { name, width, .. } if name == "wide" && *width == side + 1),
        "{error}"
    );
}

#[test]
fn a_png_that_cannot_be_written_is_an_error() {
    // image's own save dropped a failed final write of its buffer: /dev/full "succeeded".
    let Some(gpu) = common::gpu() else { return };
    if !Path::new("/dev/full").exists() {
        return;
    }
    let target = OffscreenTarget::new(gpu, 8, 8, 1).expect("target");
    let error = target.save_png(gpu, "/dev/full").expect_err("no space left on the device");
    assert!(error.to_string().starts_with("/dev/full: cannot write PNG"), "{error}");
}
