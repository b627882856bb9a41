//! Culling on the GPU (`Culling::Gpu`) against culling on the CPU: the same
//! instances kept in every view (camera and shadow views, read back), the same
//! counts a frame or two later, no instance data uploaded for a moving camera,
//! and the CPU's path where the device cannot cull on the GPU.

mod common;

use glam::{Mat4, Quat, Vec3};
use glint::asset::ShapeKind;
use glint::{
    AlphaMode, Camera, Culling, Entity, FrameStats, Gpu, Light, Material, OffscreenTarget, Renderer, ShadowSettings,
    View,
};
use rand::{Rng, SeedableRng};

/// A GPU that culls on the GPU, or `None` (with a message) where it cannot.
fn culling_gpu() -> Option<&'static Gpu> {
    let gpu = common::gpu()?;
    if !gpu.culls_on_gpu() {
        eprintln!("skipping: {} cannot cull on the GPU", gpu.info().name);
        return None;
    }
    Some(gpu)
}

/// A random scene around the origin: cubes and spheres, opaque, alpha-tested
/// and blended, in entities of one to 3,000 instances, some of them with NaN
/// transforms, every fourth in tiles of random sizes drawn at a random
/// density; its lights cast shadows (a sun's cascades, a spot light and a
/// point light's six faces).
struct RandomScene {
    entities: Vec<Entity>,
    lights: Vec<Light>,
    renderer: Renderer,
}

fn random_scene(gpu: &Gpu, seed: u64) -> RandomScene {
    scene_of(gpu, seed, true)
}

/// [`random_scene`], its blended entities alpha-tested instead unless `blended`.
fn scene_of(gpu: &Gpu, seed: u64, blended: bool) -> RandomScene {
    let mut rng = rand_pcg::Pcg32::seed_from_u64(seed);
    let mut renderer = Renderer::new(gpu);
    let shapes = [renderer.add_shape(ShapeKind::Cube.mesh()), renderer.add_shape(ShapeKind::Sphere.mesh())];
    let materials = [
        renderer.add_material(Material::default()),
        renderer.add_material(Material { alpha_mode: AlphaMode::Mask { cutoff: 0.5 }, ..Material::default() }),
        renderer.add_material(Material {
            alpha_mode: if blended { AlphaMode::Blend } else { AlphaMode::Mask { cutoff: 0.3 } },
            ..Material::default()
        }),
    ];
    let entities = (0..12)
        .map(|k| {
            let count = [1, 40, 700, 3000][rng.random_range(0..4)];
            let spread = rng.random_range(5.0..40.0);
            let transforms = (0..count)
                .map(|i| {
                    if i % 97 == 13 {
                        return Mat4::from_translation(Vec3::new(f32::NAN, 0.0, 0.0));
                    }
                    let p = Vec3::new(
                        rng.random_range(-spread..spread),
                        rng.random_range(-3.0..6.0),
                        rng.random_range(-spread..spread),
                    );
                    let rotation = Quat::from_euler(glam::EulerRot::XYZ, rng.random(), rng.random(), rng.random());
                    Mat4::from_scale_rotation_translation(Vec3::splat(rng.random_range(0.2..2.5)), rotation, p)
                })
                .collect();
            let entity = Entity::instanced(shapes[k % 2], materials[k % 3], transforms);
            if k % 4 != 3 {
                return entity;
            }
            let mut left = count;
            let sizes = std::iter::from_fn(|| {
                let n = rng.random_range(0..=left.min(300));
                left -= n;
                (left > 0 || n > 0).then_some(n)
            });
            let mut tiled = entity.with_tiles(glint::Tiles::from_sizes(sizes.collect::<Vec<_>>(), 0.5));
            tiled.density = rng.random_range(0.3..1.0);
            tiled
        })
        .collect();
    let shadows = ShadowSettings { map_size: 256, ..ShadowSettings::default() };
    let lights = vec![
        Light::directional(Vec3::new(-1.0, -2.0, -0.5), Vec3::ONE, 1.0).with_shadows(shadows),
        Light::spot(Vec3::new(4.0, 8.0, 4.0), Vec3::new(-0.5, -1.0, -0.5), Vec3::ONE, 30.0, 40.0, (0.4, 0.6))
            .with_shadows(shadows),
        Light::point(Vec3::new(-6.0, 3.0, 2.0), Vec3::ONE, 20.0, 25.0).with_shadows(shadows),
    ];
    RandomScene { entities, lights, renderer }
}

fn camera(seed: u64) -> Camera {
    let mut rng = rand_pcg::Pcg32::seed_from_u64(seed + 1000);
    let eye = Vec3::new(rng.random_range(-20.0..20.0), rng.random_range(2.0..10.0), rng.random_range(-20.0..20.0));
    Camera::perspective(55.0, 0.5, 60.0).looking_at(eye, Vec3::new(rng.random_range(-5.0..5.0), 0.0, 0.0))
}

fn frame(scene: &mut RandomScene, gpu: &Gpu, view: View) -> FrameStats {
    let mut target = OffscreenTarget::new(gpu, 64, 64, 1).expect("target");
    let RandomScene { entities, lights, renderer } = scene;
    renderer.render(entities.iter(), view, lights.as_slice(), &mut target).expect("frame")
}

#[test]
fn gpu_and_cpu_frustum_culling_keep_exactly_the_same_instances_in_camera_and_shadow_views() {
    let Some(gpu) = culling_gpu() else { return };
    for seed in 0..3 {
        let view = View::new(camera(seed));
        let mut on_cpu = random_scene(gpu, seed);
        let mut on_gpu = random_scene(gpu, seed);
        // Frustum culling alone on both sides (occlusion culling drops more, later).
        on_gpu.renderer.set_occlusion_culling(false);
        let cpu_stats = frame(&mut on_cpu, gpu, view.clone().with_culling(Culling::Cpu));
        let gpu_stats = frame(&mut on_gpu, gpu, view.clone().with_culling(Culling::Gpu));
        assert_eq!((cpu_stats.culling, gpu_stats.culling), (Culling::Cpu, Culling::Gpu));
        let cpu = on_cpu.renderer.drawn_instances().expect("read back");
        let gpu_kept = on_gpu.renderer.drawn_instances().expect("read back");
        // The camera, four cascades, the spot light, six cube faces.
        assert_eq!(cpu.len(), 1 + cpu_stats.shadow_views as usize);
        assert_eq!(cpu_stats.shadow_views, 11, "seed {seed}");
        let submitted = cpu_stats.instances_submitted as usize;
        for (k, (c, g)) in cpu.iter().zip(&gpu_kept).enumerate() {
            assert!(!c.is_empty() && c.len() < submitted, "seed {seed} view {k}: a partial view ({})", c.len());
            let only =
                |a: &[u32], b: &[u32]| a.iter().filter(|i| b.binary_search(i).is_err()).copied().collect::<Vec<_>>();
            let (cpu_only, gpu_only) = (only(c, g), only(g, c));
            assert!(
                cpu_only.is_empty() && gpu_only.is_empty(),
                "seed {seed} view {k}: {} kept on the CPU, {} on the GPU; only on the CPU {:?}, only on the GPU {:?}",
                c.len(),
                g.len(),
                &cpu_only[..cpu_only.len().min(20)],
                &gpu_only[..gpu_only.len().min(20)]
            );
        }
        assert_eq!(cpu.len(), gpu_kept.len());
    }
}

#[test]
fn gpu_culled_counts_come_back_a_frame_or_two_late_and_equal_the_cpu_counts() {
    let Some(gpu) = culling_gpu() else { return };
    let view = View::new(camera(7));
    let mut on_cpu = random_scene(gpu, 7);
    let expected = frame(&mut on_cpu, gpu, view.clone().with_culling(Culling::Cpu));
    let mut on_gpu = random_scene(gpu, 7);
    on_gpu.renderer.set_occlusion_culling(false);
    let mut first = frame(&mut on_gpu, gpu, view.clone());
    assert_eq!(first.instances_drawn, 0, "nothing has come back from the first frame yet");
    // Waiting for the GPU, a frame on its own has its counts at once.
    on_gpu.renderer.wait_for_counts(std::slice::from_mut(&mut first));
    assert_eq!((first.instances_drawn, first.instances_culled), (expected.instances_drawn, expected.instances_culled));
    let counted = (0..6)
        .map(|_| frame(&mut on_gpu, gpu, view.clone()))
        .find(|s| s.instances_drawn > 0 && s.passes.shadow.instances > 0)
        .expect("a count comes back within six frames");
    assert_eq!(counted.culling, Culling::Gpu);
    assert_eq!(counted.instances_drawn, expected.instances_drawn);
    assert_eq!(counted.instances_culled, expected.instances_culled);
    assert_eq!(counted.instances_invalid, expected.instances_invalid);
    assert_eq!(counted.passes.shadow.instances, expected.passes.shadow.instances);
    assert!(expected.instances_culled > 0 && expected.instances_invalid > 0);
    assert_eq!((counted.tiles_tested, counted.tiles_drawn), (expected.tiles_tested, expected.tiles_drawn));
    assert!(expected.tiles_drawn > 0 && expected.tiles_drawn < expected.tiles_tested, "{expected:?}");
}

#[test]
fn a_moving_camera_uploads_no_instance_data_or_draw_indices_on_the_gpu_path() {
    let Some(gpu) = culling_gpu() else { return };
    let mut bytes = Vec::new();
    for culling in [Culling::Gpu, Culling::Cpu] {
        // Blended instances are sorted far to near on the CPU, so culled there: none here.
        let mut scene = scene_of(gpu, 3, false);
        frame(&mut scene, gpu, View::new(camera(3)).with_culling(culling));
        let moved = frame(&mut scene, gpu, View::new(camera(4)).with_culling(culling));
        bytes.push(moved.bytes_uploaded);
    }
    let (on_gpu, on_cpu) = (bytes[0], bytes[1]);
    assert_eq!((on_gpu.instances, on_gpu.bounds, on_gpu.draw_indices), (0, 0, 0), "{on_gpu:?}");
    assert!(on_cpu.draw_indices > 0, "the CPU's path rewrites its visible lists: {on_cpu:?}");
    assert!(on_gpu.camera > 0, "the camera moved");
}

#[test]
fn gpu_culling_draws_the_cpu_culled_picture() {
    let Some(gpu) = culling_gpu() else { return };
    let mut pictures = Vec::new();
    for culling in [Culling::Cpu, Culling::Gpu] {
        let mut scene = random_scene(gpu, 11);
        let mut target = OffscreenTarget::new(gpu, 96, 96, 4).expect("target");
        let view = View::new(camera(11)).with_culling(culling);
        let RandomScene { entities, lights, renderer } = &mut scene;
        renderer.render(entities.iter(), view, lights.as_slice(), &mut target).expect("frame");
        pictures.push(target.read_rgba8(gpu).expect("readback"));
    }
    // Only the order of one batch's instances may differ, which shows only where
    // two of them meet at exactly the same depth: the pictures are the same.
    let differing = pictures[0].pixels().zip(pictures[1].pixels()).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "pixels that differ");
}

#[test]
fn gl_takes_the_cpu_path_and_says_so() {
    let Some(gl) = common::gl_gpu() else { return };
    assert!(!gl.culls_on_gpu());
    let mut scene = random_scene(gl, 5);
    let stats = frame(&mut scene, gl, View::new(camera(5)));
    assert_eq!(stats.culling, Culling::Cpu, "asked for the GPU, culled on the CPU");
    assert!(stats.instances_drawn > 0 && stats.instances_culled > 0);
}
