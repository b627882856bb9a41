//! Levels of detail (`scene/levels.rs`, `render/lod.rs`): a near instance is
//! drawn at full detail and its picture equals full detail's exactly, a far one
//! at a coarser level; the GPU's cull pass and the CPU pick the same levels;
//! shadows of far casters are drawn coarser; a sphere crossing from one level
//! to the next shows each pixel from one of the two; a skinned model keeps
//! its pose at every level; the reference scenes stay within the reference
//! tolerance.

mod common;

use glam::{Mat4, Vec3};
use glint::asset::{Model, ShapeKind};
use glint::scene::levels::MAX_LEVELS;
use glint::scene::ShadowSettings;
use glint::{Camera, Culling, Entity, FrameStats, Light, Material, OffscreenTarget, Renderer, View};

/// Spheres in a row going away from the camera, from `near` to `far` units.
fn row(renderer: &mut Renderer, (near, far): (f32, f32), count: usize) -> Entity {
    let sphere = renderer.add_shape(ShapeKind::Sphere.mesh());
    let material =
        renderer.add_material(Material { base_color: glam::Vec4::new(0.9, 0.5, 0.2, 1.0), ..Material::default() });
    let step = (far - near) / count.saturating_sub(1).max(1) as f32;
    let transforms = (0..count).map(|k| Mat4::from_translation(Vec3::new(0.0, 0.0, -near - step * k as f32))).collect();
    Entity::instanced(sphere, material, transforms)
}

fn camera() -> Camera {
    Camera::perspective(40.0, 0.1, 500.0).looking_at(Vec3::new(0.0, 0.4, 1.0), Vec3::new(0.0, 0.0, -10.0))
}

/// One frame of `entities`, levels of detail as `levels` says, culled as `culling` says,
/// and its picture; GPU-culled counts waited for.
fn frame(
    gpu: &glint::Gpu,
    entities: &[Entity],
    (levels, culling): (bool, Culling),
    lights: &[Light],
) -> (FrameStats, image::RgbaImage) {
    let mut renderer = Renderer::new(gpu);
    renderer.set_levels_of_detail(levels);
    // The entities' ids are the same in a new renderer made the same way.
    let mut placed = Vec::new();
    for e in entities {
        let shape = renderer.add_shape(ShapeKind::Sphere.mesh());
        let material =
            renderer.add_material(Material { base_color: glam::Vec4::new(0.9, 0.5, 0.2, 1.0), ..Material::default() });
        placed.push(Entity::instanced(shape, material, e.transforms().to_vec()));
    }
    let mut target = OffscreenTarget::new(gpu, 128, 128, 1).expect("target");
    let view = View::new(camera()).with_culling(culling);
    let mut stats = renderer.render(&placed, view, lights, &mut target).expect("frame");
    renderer.wait_for_counts(std::slice::from_mut(&mut stats));
    (stats, target.read_rgba8(gpu).expect("readback"))
}

fn sphere_triangles() -> u64 {
    (ShapeKind::Sphere.mesh().indices().len() / 3) as u64
}

#[test]
fn a_near_instance_is_drawn_at_full_detail_exactly_as_without_levels() {
    let Some(gpu) = common::gpu() else { return };
    let mut r = Renderer::new(gpu);
    let near = row(&mut r, (3.0, 3.0), 1);
    for culling in [Culling::Cpu, Culling::Gpu] {
        let (with, image) = frame(gpu, std::slice::from_ref(&near), (true, culling), &[]);
        let (without, full) = frame(gpu, std::slice::from_ref(&near), (false, culling), &[]);
        assert_eq!(with.instances_per_level, [1, 0, 0, 0, 0], "{culling:?}");
        assert_eq!((with.triangles_drawn, without.triangles_drawn), (sphere_triangles(), sphere_triangles()));
        assert!(image == full, "{culling:?}: a near sphere's picture equals full detail's");
    }
}

#[test]
fn far_instances_draw_coarser_levels_and_the_gpu_picks_what_the_cpu_picks() {
    let Some(gpu) = common::gpu() else { return };
    let mut r = Renderer::new(gpu);
    let spheres = row(&mut r, (2.0, 300.0), 40);
    let (cpu, cpu_image) = frame(gpu, std::slice::from_ref(&spheres), (true, Culling::Cpu), &[]);
    let (on_gpu, gpu_image) = frame(gpu, std::slice::from_ref(&spheres), (true, Culling::Gpu), &[]);
    let (full, full_image) = frame(gpu, std::slice::from_ref(&spheres), (false, Culling::Cpu), &[]);
    assert_eq!(on_gpu.culling, Culling::Gpu, "this adapter culls on the GPU");
    assert_eq!(cpu.instances_drawn, 40);
    // Near ones at full detail, the farthest at the coarsest level.
    assert!(cpu.instances_per_level[0] >= 1 && cpu.instances_per_level[MAX_LEVELS - 1] >= 1, "{cpu:?}");
    assert_eq!(cpu.instances_per_level.iter().sum::<u64>(), 40);
    assert_eq!(full.instances_per_level, [40, 0, 0, 0, 0]);
    assert!(cpu.triangles_drawn * 3 < full.triangles_drawn, "{} of {}", cpu.triangles_drawn, full.triangles_drawn);
    // The same rule on the GPU, term for term: the same levels, triangles and picture.
    assert_eq!(on_gpu.instances_per_level, cpu.instances_per_level);
    assert_eq!(on_gpu.triangles_drawn, cpu.triangles_drawn);
    assert!(gpu_image == cpu_image, "culled on the GPU, the picture with levels is the CPU's");
    let (mean, _) = glint::compare::mean_difference(&cpu_image, &full_image, 4).expect("same size");
    assert!(mean < 1.0, "levels change the picture little: {mean}/255");
}

#[test]
fn a_coarser_error_draws_fewer_triangles_and_zero_draws_full_detail() {
    let Some(gpu) = common::gpu() else { return };
    let triangles = |error: f32| {
        let mut renderer = Renderer::new(gpu);
        let e = row(&mut renderer, (2.0, 300.0), 40);
        let mut target = OffscreenTarget::new(gpu, 128, 128, 1).expect("target");
        let view = View::new(camera()).with_culling(Culling::Cpu).with_lod_error(error);
        renderer.render([&e], view, &[] as &[Light], &mut target).expect("frame").triangles_drawn
    };
    let (none, half, four) = (triangles(0.0), triangles(0.5), triangles(4.0));
    assert_eq!(none, 40 * sphere_triangles());
    assert!(four < half && half < none, "{four} < {half} < {none}");
}

#[test]
fn a_large_meshs_levels_are_cached_on_disk_and_drawn_the_same_from_there() {
    use glint::scene::level_cache::{LevelCache, CACHE_FROM};
    let Some(gpu) = common::gpu() else { return };
    let dir = std::env::temp_dir().join(format!("glint-level-cache-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mesh = glint::scene::procedural::sphere(320, 160);
    assert!(mesh.indices().len() / 3 >= CACHE_FROM);
    let triangles = || {
        let mut renderer = Renderer::new(gpu);
        renderer.set_level_cache(Some(LevelCache::new(&dir)));
        let shape = renderer.add_shape(mesh.clone());
        let material = renderer.add_material(Material::default());
        let far = Entity::new(shape, material, Mat4::from_translation(Vec3::new(0.0, 0.0, -60.0)));
        let mut target = OffscreenTarget::new(gpu, 64, 64, 1).expect("target");
        let view = View::new(camera()).with_culling(Culling::Cpu);
        renderer.render([&far], view, &[] as &[Light], &mut target).expect("frame").triangles_drawn
    };
    let made = triangles();
    let files: Vec<_> = std::fs::read_dir(&dir).expect("the cache folder is made").collect();
    assert_eq!(files.len(), 1, "one file for the one large mesh");
    assert!(made < (mesh.indices().len() / 3) as u64 / 4, "a far sphere draws a coarse level: {made}");
    assert_eq!(triangles(), made, "the levels read back draw as those made");
    std::fs::remove_dir_all(&dir).expect("removed");
}

#[test]
fn a_fading_sphere_shows_each_pixel_from_one_of_its_two_levels_never_both() {
    let Some(gpu) = common::gpu() else { return };
    let mut renderer = Renderer::new(gpu);
    let mut sphere = row(&mut renderer, (2.0, 2.0), 1);
    let mut target = OffscreenTarget::new(gpu, 128, 128, 1).expect("target");
    let mut at = |z: f32, error: f32, culling: Culling| {
        sphere.set_transform(0, Mat4::from_translation(Vec3::new(0.0, 0.0, -z)));
        let view = View::new(camera()).with_culling(culling).with_lod_error(error);
        let mut stats = renderer.render([&sphere], view, &[] as &[Light], &mut target).expect("frame");
        renderer.wait_for_counts(std::slice::from_mut(&mut stats));
        (stats, target.read_rgba8(gpu).expect("readback"))
    };
    // The triangles of one level: a sphere drawing any other count draws two.
    let levels = glint::scene::levels::detail_levels(&ShapeKind::Sphere.mesh());
    let single: Vec<u64> =
        std::iter::once(sphere_triangles()).chain(levels.iter().map(|l| l.triangles() as u64)).collect();
    // Levels 8 pixels off: far enough apart to tell in a picture.
    const ERROR: f32 = 8.0;
    let fading: Vec<f32> = (1..240)
        .map(|k| k as f32 * 0.25)
        .filter(|&z| !single.contains(&at(z, ERROR, Culling::Cpu).0.triangles_drawn))
        .collect();
    assert!(fading.len() > 3, "some distances fade: {fading:?}");
    // The middle of the first fade.
    let end = fading.windows(2).position(|w| w[1] - w[0] > 0.3).unwrap_or(fading.len() - 1);
    let z = fading[end / 2];
    let (faded, image) = at(z, ERROR, Culling::Cpu);
    assert_eq!(faded.instances_drawn, 1, "one instance, drawn at two levels");
    // A little less error allowed draws the finer level alone; a little more, the coarser.
    let ((fine, fine_image), (coarse, coarse_image)) =
        (at(z, ERROR * 0.78, Culling::Cpu), at(z, ERROR * 1.3, Culling::Cpu));
    assert!(single.contains(&fine.triangles_drawn) && single.contains(&coarse.triangles_drawn), "{fine:?} {coarse:?}");
    assert_eq!(faded.triangles_drawn, fine.triangles_drawn + coarse.triangles_drawn);
    let pixels = image.pixels().zip(fine_image.pixels()).zip(coarse_image.pixels());
    let (mut from_fine, mut from_coarse) = (0, 0);
    for ((p, f), c) in pixels {
        assert!(p == f || p == c, "each pixel shows one level: {p:?} against {f:?} and {c:?}");
        from_fine += u32::from(p == f && p != c);
        from_coarse += u32::from(p == c && p != f);
    }
    assert!(from_fine > 0 && from_coarse > 0, "both levels show: {from_fine} and {from_coarse} pixels");
    // The GPU's cull pass fades it alike.
    let (on_gpu, gpu_image) = at(z, ERROR, Culling::Gpu);
    assert_eq!(
        (on_gpu.culling, on_gpu.triangles_drawn, on_gpu.instances_drawn),
        (Culling::Gpu, faded.triangles_drawn, 1)
    );
    assert!(gpu_image == image, "the GPU's fade is the CPU's");
}

#[test]
fn shadows_of_far_casters_are_drawn_coarser_and_look_the_same() {
    let Some(gpu) = common::gpu() else { return };
    let mut r = Renderer::new(gpu);
    let mut spheres = row(&mut r, (2.0, 120.0), 30);
    // A ground under them, far below the camera's view, left to the shadows:
    // the casters only.
    *spheres.transforms_mut() = spheres.transforms().iter().map(|t| *t * Mat4::from_scale(Vec3::splat(2.0))).collect();
    let shadows = ShadowSettings { map_size: 512, ..ShadowSettings::default() };
    let sun = [Light::directional(Vec3::new(-0.3, -1.0, -0.2), Vec3::ONE, 1.0).with_shadows(shadows)];
    let (with, image) = frame(gpu, std::slice::from_ref(&spheres), (true, Culling::Cpu), &sun);
    let (without, full) = frame(gpu, std::slice::from_ref(&spheres), (false, Culling::Cpu), &sun);
    assert!(with.shadow_views > 0);
    let (coarse, whole) = (with.passes.shadow.triangles, without.passes.shadow.triangles);
    assert!(coarse > 0 && coarse * 2 < whole, "shadow triangles {coarse} with levels, {whole} without");
    let to_rgb = |i: &image::RgbaImage| image::DynamicImage::ImageRgba8(i.clone()).into_rgb8();
    let comparison = glint::compare::compare(&to_rgb(&full), &to_rgb(&image)).expect("same size");
    assert!(comparison.matches(), "similarity {}, bad pixels {}", comparison.similarity, comparison.bad_pixels);
}

/// The centre of the lit pixels of `image` (the model on black).
fn centroid(image: &image::RgbaImage) -> glam::Vec2 {
    let lit: Vec<glam::Vec2> = (image.enumerate_pixels())
        .filter(|(_, _, p)| p.0[..3].iter().map(|&c| u32::from(c)).sum::<u32>() > 60)
        .map(|(x, y, _)| glam::Vec2::new(x as f32, y as f32))
        .collect();
    assert!(!lit.is_empty(), "the model is in view");
    lit.iter().sum::<glam::Vec2>() / lit.len() as f32
}

#[test]
fn a_skinned_model_keeps_its_pose_at_every_level() {
    let Some(gpu) = common::gpu() else { return };
    let path = common::repo_root().join("tests/models/skinned.gltf");
    let model = Model::load(&path).expect("loads");
    let levels = glint::scene::levels::detail_levels(&model.parts[0].mesh);
    assert!(levels.len() >= 2, "the skinned cylinder has coarser levels");
    let mut desc = model.into_scene();
    desc.environment.background = glint::Background::Color(Vec3::ZERO);
    let eye = (Vec3::new(0.0, 1.2, 5.0), Vec3::new(-0.3, 1.0, 0.0));
    desc.cameras[0] = Camera::perspective(45.0, 0.1, 50.0).looking_at(eye.0, eye.1);
    let mut renderer = Renderer::new(gpu);
    let mut world = glint::World::place(desc, &mut renderer).expect("placed");
    let mut target = OffscreenTarget::new(gpu, 96, 96, 4).expect("target");
    let mut draw = |time: f32, error: f32| {
        world.pose(time, &mut renderer).expect("posed");
        let view = View::new(world.desc().cameras[0]).with_culling(Culling::Cpu).with_lod_error(error);
        let stats = renderer.render(world.entities(), view, world.lighting(), &mut target).expect("frame");
        (stats, centroid(&target.read_rgba8(gpu).expect("readback")))
    };
    let (rest, bent) = (draw(0.0, 0.0).1, draw(1.0, 0.0).1);
    assert!(rest.distance(bent) > 5.0, "the pose moves the model: {rest} to {bent}");
    // Ever larger errors allowed, down to the coarsest level: each level drawn
    // is bent as full detail is.
    let mut seen = Vec::new();
    for error in [2.0, 8.0, 30.0, 1e4] {
        let (stats, at) = draw(1.0, error);
        let level = stats.instances_per_level.iter().position(|&n| n == 1).expect("one instance");
        seen.push(level);
        // The coarsest level of so small a model is a crude shape: nearer the
        // bent pose than the rest pose, by less.
        let near = if level == levels.len() { 0.5 } else { 0.25 };
        assert!(at.distance(bent) < near * at.distance(rest), "level {level}: at {at}, bent {bent}, rest {rest}");
    }
    assert_eq!(seen.last(), Some(&levels.len()), "the coarsest level at last: {seen:?}");
    assert!(seen.windows(2).all(|w| w[0] <= w[1]) && seen[0] < levels.len(), "{seen:?}");
}

#[test]
fn the_reference_scenes_stay_within_tolerance_with_levels_of_detail() {
    let Some(gpu) = common::gpu() else { return };
    for name in ["shapes", "textures", "alpha", "lights", "instancing", "ortho", "states", "tiles", "pbr"] {
        let (image, stats) = common::render_with_levels(gpu, name, 256);
        assert!(stats.triangles_drawn > 0 || stats.culling == Culling::Gpu, "{name}");
        common::assert_matches_reference(name, &image);
    }
}
