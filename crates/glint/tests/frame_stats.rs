//! FrameStats tests: the cost model must show batching, merging and
//! upload-only-what-changed in its numbers.

mod common;

use glam::{Mat4, Quat, Vec3};
use glint::asset::ShapeKind;
use glint::scene::MAX_LIGHTS;
use glint::{
    AlphaMode, Camera, Entity, FrameStats, Gpu, Light, Lighting, Material, OffscreenTarget, RenderError, Renderer,
    Texture,
};

fn camera() -> Camera {
    Camera::perspective(60.0, 0.1, 100.0).looking_at(Vec3::new(0.0, 5.0, 10.0), Vec3::ZERO)
}

fn sun() -> Vec<Light> {
    vec![Light::directional(Vec3::new(-1.0, -1.0, -1.0), Vec3::ONE, 1.0)]
}

fn frame<'l>(renderer: &mut Renderer, gpu: &Gpu, entities: &[&Entity], lights: impl Into<Lighting<'l>>) -> FrameStats {
    frame_of(renderer, gpu, entities, lights, glint::Culling::Cpu)
}

/// [`frame`] culled as `culling` says.
fn frame_of<'l>(
    renderer: &mut Renderer,
    gpu: &Gpu,
    entities: &[&Entity],
    lights: impl Into<Lighting<'l>>,
    culling: glint::Culling,
) -> FrameStats {
    let mut target = OffscreenTarget::new(gpu, 64, 64, 1).expect("target");
    let view = glint::View::new(camera()).with_culling(culling);
    renderer.render(entities.iter().copied(), view, lights, &mut target).expect("frame")
}

/// A renderer holding a cube shape and a default material.
fn renderer_with_cube(gpu: &Gpu) -> (Renderer, glint::ShapeId, glint::MaterialId) {
    let mut r = Renderer::new(gpu);
    let cube = r.add_shape(ShapeKind::Cube.mesh());
    let m = r.add_material(Material::default());
    (r, cube, m)
}

fn grid(n: usize) -> Vec<Mat4> {
    (0..n)
        .map(|i| Mat4::from_translation(Vec3::new((i % 100) as f32 * 0.1 - 5.0, 0.0, (i / 100) as f32 * 0.1 - 5.0)))
        .collect()
}

#[test]
fn ten_thousand_instances_of_one_entity_are_one_draw() {
    let Some(gpu) = common::gpu() else { return };
    let (mut r, cube, m) = renderer_with_cube(gpu);
    let e = Entity::instanced(cube, m, grid(10_000));
    let stats = frame(&mut r, gpu, &[&e], &sun());
    assert_eq!(stats.draw_calls, 1);
    assert_eq!(stats.instances_submitted, 10_000);
    assert!(stats.instances_culled < 100, "the grid is almost all in view: {}", stats.instances_culled);
    assert_eq!(stats.instances_drawn + stats.instances_culled, 10_000);
    assert_eq!(stats.bytes_uploaded.instances, 10_000 * 64, "every instance once, on first sight");
    assert_eq!(stats.bytes_uploaded.draw_indices, 4 * stats.instances_drawn, "one u32 per drawn instance");
    let unculled = frame_of(&mut r, gpu, &[&e], &sun(), glint::Culling::Off);
    assert_eq!((unculled.draw_calls, unculled.instances_drawn, unculled.instances_culled), (1, 10_000, 0));
}

#[test]
fn hundred_entities_sharing_shape_and_material_merge_into_one_draw() {
    let Some(gpu) = common::gpu() else { return };
    let mut r = Renderer::new(gpu);
    let sphere = r.add_shape(ShapeKind::Sphere.mesh());
    let m = r.add_material(Material::color("m", 0.5, 0.5, 0.5));
    let entities: Vec<Entity> = grid(100).into_iter().map(|t| Entity::new(sphere, m, t)).collect();
    let refs: Vec<&Entity> = entities.iter().collect();
    let stats = frame(&mut r, gpu, &refs, &sun());
    assert_eq!(stats.entities_submitted, 100);
    assert_eq!((stats.draw_calls, stats.draws), (1, 1));
    assert_eq!(stats.instances_drawn, 100);
    assert_eq!(stats.pipelines_bound, 1);
}

#[test]
fn three_materials_by_two_shapes_are_six_draws_in_one_indirect_call() {
    let Some(gpu) = common::gpu() else { return };
    let mut r = Renderer::new(gpu);
    let shapes = [r.add_shape(ShapeKind::Cube.mesh()), r.add_shape(ShapeKind::Torus.mesh())];
    let materials = [0.2, 0.5, 0.8].map(|g| r.add_material(Material::color("m", g, g, g)));
    // 60 entities submitted interleaved: every (material, shape) pair ten times.
    let entities: Vec<Entity> =
        grid(60).into_iter().enumerate().map(|(i, t)| Entity::new(shapes[(i / 3) % 2], materials[i % 3], t)).collect();
    let refs: Vec<&Entity> = entities.iter().collect();
    // With levels of detail the torus's pipeline cross-fades them and the
    // cube's (no levels) keeps its early depth test: two pipelines, two calls.
    let faded = frame(&mut r, gpu, &refs, &sun());
    assert_eq!((faded.draws, faded.pipelines_bound), (6, 2));
    assert_eq!(faded.draw_calls, if gpu.draws_indirect() { 2 } else { 6 });
    r.set_levels_of_detail(false);
    let stats = frame(&mut r, gpu, &refs, &sun());
    assert_eq!(stats.draws, 6);
    // One pipeline, one texture set (none), one mesh-pool page: one multi-draw-indirect call.
    assert_eq!(stats.draw_calls, if gpu.draws_indirect() { 1 } else { 6 });
    assert_eq!(stats.instances_drawn, 60);
    assert_eq!(stats.pipelines_bound, 1, "all opaque, single-sided: one pipeline");
    assert_eq!(stats.bind_groups_set, 3 + 1, "scene, camera, instances once; the untextured set once");
    assert_eq!(stats.bytes_uploaded.indirect, if gpu.draws_indirect() { 6 * 20 } else { 0 });
}

#[test]
fn materials_with_different_maps_split_the_indirect_call() {
    let Some(gpu) = common::gpu() else { return };
    let mut r = Renderer::new(gpu);
    let cube = r.add_shape(ShapeKind::Cube.mesh());
    let pixel = |r: &mut Renderer, v| {
        r.add_texture(Texture::new("t", image::RgbaImage::from_pixel(1, 1, image::Rgba([v, v, v, 255])), true))
    };
    let (t1, t2) = (pixel(&mut r, 100), pixel(&mut r, 200));
    let textured = |map| Material { diffuse_map: Some(map), ..Material::default() };
    let materials = [textured(t1), textured(t2), textured(t1)].map(|m| r.add_material(m));
    let entities: Vec<Entity> = grid(3).into_iter().zip(materials).map(|(t, m)| Entity::new(cube, m, t)).collect();
    let refs: Vec<&Entity> = entities.iter().collect();
    let stats = frame(&mut r, gpu, &refs, &sun());
    assert_eq!(stats.draws, 3);
    assert_eq!(stats.draw_calls, if gpu.draws_indirect() { 2 } else { 3 }, "t1's two materials share a call");
    assert_eq!(stats.bind_groups_set, 3 + 2, "two texture sets");
}

#[test]
fn a_second_identical_frame_uploads_no_uniform_bytes() {
    let Some(gpu) = common::gpu() else { return };
    let (mut r, cube, m) = renderer_with_cube(gpu);
    let e = Entity::instanced(cube, m, grid(10));
    let first = frame(&mut r, gpu, &[&e], &sun());
    assert!(first.bytes_uploaded.uniforms > 0);
    let mesh = r.shape(cube).expect("shape");
    assert_eq!(first.bytes_uploaded.meshes, (mesh.vertices().len() * 48 + mesh.indices().len() * 4) as u64);
    assert_eq!(first.bytes_uploaded.draw_indices, 10 * 4);
    let second = frame(&mut r, gpu, &[&e], &sun());
    assert_eq!(second.bytes_uploaded.uniforms, 0);
    assert_eq!(second.bytes_uploaded.meshes, 0);
    assert_eq!(second.bytes_uploaded.instances, 0, "unchanged instances stay on the GPU");
    assert_eq!(second.bytes_uploaded.total, 0, "the same visible set: not even the draw indices");
    assert_eq!(second.draw_calls, 1);
}

#[test]
fn moving_one_entity_reuploads_only_its_transforms() {
    let Some(gpu) = common::gpu() else { return };
    let (mut r, cube, m) = renderer_with_cube(gpu);
    let still = Entity::instanced(cube, m, grid(100));
    let mut moving = Entity::instanced(cube, m, grid(5));
    assert_eq!(frame(&mut r, gpu, &[&still, &moving], &sun()).bytes_uploaded.instances, 105 * 64);
    moving.set_transform(2, Mat4::from_translation(Vec3::Y));
    let stats = frame(&mut r, gpu, &[&still, &moving], &sun());
    assert_eq!(stats.bytes_uploaded.instances, 5 * 64, "the moved entity's range, nothing else");
    assert_eq!(stats.draws, 1, "still one batch: same shape and material");
    // A new material for the entity rewrites its range (the material index is per instance).
    let other = r.add_material(Material::color("other", 1.0, 0.0, 0.0));
    moving.material = other;
    let stats = frame(&mut r, gpu, &[&still, &moving], &sun());
    assert_eq!(stats.bytes_uploaded.instances, 5 * 64);
    assert_eq!(stats.bytes_uploaded.material, 128, "the new material's table entry");
    assert_eq!(stats.draws, 2);
}

#[test]
fn culled_and_invalid_instances_are_counted_and_not_drawn() {
    let Some(gpu) = common::gpu() else { return };
    let (mut r, cube, m) = renderer_with_cube(gpu);
    // The camera is at (0, 5, 10) looking at the origin: z = 50 is behind it.
    let behind = Entity::instanced(cube, m, vec![Mat4::from_translation(Vec3::Z * 50.0); 7]);
    let mut mixed =
        Entity::instanced(cube, m, vec![Mat4::IDENTITY, Mat4::from_translation(Vec3::Z * 50.0), Mat4::IDENTITY]);
    mixed.set_transform(2, Mat4::from_translation(Vec3::new(f32::NAN, 0.0, 0.0)));
    let stats = frame(&mut r, gpu, &[&behind, &mixed], &sun());
    assert_eq!(stats.instances_submitted, 10);
    assert_eq!(stats.instances_invalid, 1);
    assert_eq!(stats.instances_culled, 8);
    assert_eq!(stats.instances_drawn, 1);
    assert_eq!(stats.draw_calls, 1);
    // An entity wholly in view skips per-instance tests, but never its invalid instances.
    let mut inside = Entity::instanced(cube, m, vec![Mat4::IDENTITY; 4]);
    inside.set_transform(3, Mat4::from_scale(Vec3::splat(f32::INFINITY)));
    let stats = frame(&mut r, gpu, &[&inside], &sun());
    assert_eq!((stats.instances_invalid, stats.instances_drawn, stats.instances_culled), (1, 3, 0));
}

#[test]
fn pipelines_compile_once_and_a_changed_flag_compiles_exactly_one() {
    let Some(gpu) = common::gpu() else { return };
    let (mut r, cube, m) = renderer_with_cube(gpu);
    let e = Entity::new(cube, m, Mat4::IDENTITY);
    assert_eq!(frame(&mut r, gpu, &[&e], &sun()).pipelines_compiled, 1);
    assert_eq!(frame(&mut r, gpu, &[&e], &sun()).pipelines_compiled, 0, "steady state");
    r.material_mut(m).expect("material").double_sided = true;
    assert_eq!(frame(&mut r, gpu, &[&e], &sun()).pipelines_compiled, 1);
    r.material_mut(m).expect("material").double_sided = false;
    assert_eq!(frame(&mut r, gpu, &[&e], &sun()).pipelines_compiled, 0, "back to a cached variant");
}

#[test]
fn only_the_changed_block_is_uploaded() {
    let Some(gpu) = common::gpu() else { return };
    let (mut r, cube, m) = renderer_with_cube(gpu);
    let e = Entity::new(cube, m, Mat4::IDENTITY);
    frame(&mut r, gpu, &[&e], &sun());
    // A material edit rewrites that material's 128-byte block, nothing else.
    r.material_mut(m).expect("material").base_color.x = 0.1;
    assert_eq!(frame(&mut r, gpu, &[&e], &sun()).bytes_uploaded.uniforms, 128);
    // A new light rewrites the scene block (128 + 64 × 64 bytes), nothing else.
    let mut lights = sun();
    lights.push(Light::point(Vec3::Y, Vec3::ONE, 1.0, 5.0));
    let stats = frame(&mut r, gpu, &[&e], &lights);
    assert_eq!(stats.bytes_uploaded.scene, 128 + 64 * MAX_LIGHTS as u64);
    assert_eq!(stats.bytes_uploaded.uniforms, stats.bytes_uploaded.scene);
}

#[test]
fn precompile_leaves_the_first_frame_nothing_to_compile() {
    let Some(gpu) = common::gpu() else { return };
    let mut r = Renderer::new(gpu);
    let cube = r.add_shape(ShapeKind::Cube.mesh());
    let plain = r.add_material(Material::default());
    let glass = r.add_material(Material { alpha_mode: AlphaMode::Blend, ..Material::default() });
    let a = Entity::new(cube, plain, Mat4::IDENTITY);
    let b = Entity::new(cube, glass, Mat4::IDENTITY);
    assert_eq!(r.precompile(&[&a, &b], &sun(), 1).expect("precompile"), 2, "two variants");
    assert_eq!(r.precompile(&[&a, &b], &sun(), 1).expect("precompile"), 0, "already built");
    let stats = frame(&mut r, gpu, &[&a, &b], &sun());
    assert_eq!(stats.pipelines_compiled, 0);
    assert_eq!((stats.draws, stats.draw_calls), (2, 2), "two pipelines: two calls");
}

#[test]
fn adding_a_map_compiles_exactly_one_new_variant() {
    let Some(gpu) = common::gpu() else { return };
    let (mut r, cube, m) = renderer_with_cube(gpu);
    let e = Entity::new(cube, m, Mat4::IDENTITY);
    frame(&mut r, gpu, &[&e], &sun());
    let bumps = r.add_texture(Texture::new(
        "flat",
        image::RgbaImage::from_pixel(2, 2, image::Rgba([128, 128, 255, 255])),
        false,
    ));
    r.material_mut(m).expect("material").normal_map = Some(bumps);
    assert_eq!(frame(&mut r, gpu, &[&e], &sun()).pipelines_compiled, 1);
}

#[test]
fn a_sky_with_only_blended_entities_and_the_naive_mode_draw() {
    let Some(gpu) = common::gpu() else { return };
    let mut r = Renderer::new(gpu);
    let sky = glint::Environment {
        background: glint::Background::Gradient { top: Vec3::Z, bottom: Vec3::ONE },
        ..Default::default()
    };
    let lights = sun();
    let sky = Lighting::new(&lights, sky);
    let cube = r.add_shape(ShapeKind::Cube.mesh());
    let glass = r.add_material(Material { alpha_mode: AlphaMode::Blend, ..Material::default() });
    let e = Entity::instanced(cube, glass, grid(3));
    assert_eq!(frame(&mut r, gpu, &[&e], sky).draw_calls, 2, "sky first (no opaque before it), then the glass");
    // Naive: one draw per instance, the sky first, everything bound per draw.
    r.set_mode(glint::FrameMode::Naive);
    let naive = frame(&mut r, gpu, &[&e], sky);
    assert_eq!((naive.draw_calls, naive.draws), (1 + 3, 1 + 3));
    assert_eq!(naive.instances_culled, 0);
    assert_eq!(naive.bytes_uploaded.material, 3 * 128, "the material block before every draw");
    assert_eq!(naive.bytes_uploaded.draw_indices, 3 * 4);
}

#[test]
fn gpu_timing_reads_the_last_frames_pass_time() {
    let Some(gpu) = common::gpu() else { return };
    let (mut r, cube, m) = renderer_with_cube(gpu);
    if !r.enable_gpu_timing() {
        eprintln!("skipping: {} has no timestamp queries", gpu.info().name);
        return;
    }
    assert_eq!(r.read_gpu_times(), None, "no frame yet");
    let e = Entity::instanced(cube, m, grid(1000));
    frame(&mut r, gpu, &[&e], &sun());
    let times = r.read_gpu_times().expect("timed frame");
    assert!(times.forward_ms > 0.0 && times.forward_ms < 60_000.0, "{times:?}");
    assert_eq!(times.shadow_ms, None, "no shadow pass ran");
    assert_eq!(r.read_gpu_times(), None, "each frame is read once");
    let shadowed = [sun()[0].with_shadows(glint::ShadowSettings { map_size: 256, ..Default::default() })];
    frame(&mut r, gpu, &[&e], &shadowed);
    let times = r.read_gpu_times().expect("timed frame");
    let shadow_ms = times.shadow_ms.expect("the shadow pass is timed");
    assert!(shadow_ms > 0.0 && shadow_ms < 60_000.0, "{times:?}");

    // Each frame's statistics carry the newest finished frame's times, read
    // without waiting: here the frame before, which `read_gpu_times` waited for.
    let mut target = OffscreenTarget::new(gpu, 64, 64, 1).expect("target");
    let post = vec![glint::scene::PostEffect::Vignette { strength: 0.5 }, glint::scene::PostEffect::Fxaa];
    let view = glint::View::new(camera()).with_post(post);
    let first = r.render([&e], view.clone(), &sun(), &mut target).expect("frame");
    assert!(first.gpu.as_ref().is_none_or(|g| g.frame < first.frame), "never this frame's own: {first:?}");
    let finished = r.read_gpu_times().expect("timed frame");
    let next = r.render([&e], view, &sun(), &mut target).expect("frame");
    assert_eq!(next.frame, first.frame + 1);
    let carried = next.gpu.expect("the finished frame's times");
    assert_eq!((carried.frame, &carried), (first.frame, &finished));
    assert!(carried.forward_ms > 0.0 && carried.shadow_ms.is_none(), "{carried:?}");
    assert_eq!(carried.post_ms.len(), 2, "one time per post effect: {carried:?}");
    assert!(carried.post_ms.iter().all(|&ms| ms > 0.0 && ms < 60_000.0), "{carried:?}");
}

#[test]
fn textures_upload_once_on_first_use() {
    let Some(gpu) = common::gpu() else { return };
    let mut r = Renderer::new(gpu);
    let plane = r.add_shape(ShapeKind::Plane.mesh());
    let texture = r.add_texture(Texture::new(
        "checker",
        image::RgbaImage::from_fn(8, 4, |x, y| image::Rgba([(x * 30) as u8, (y * 60) as u8, 0, 255])),
        true,
    ));
    let m = r.add_material(Material { diffuse_map: Some(texture), ..Material::default() });
    let e = Entity::new(plane, m, Mat4::IDENTITY);
    assert_eq!(frame(&mut r, gpu, &[&e], &sun()).bytes_uploaded.textures, 8 * 4 * 4);
    assert_eq!(frame(&mut r, gpu, &[&e], &sun()).bytes_uploaded.textures, 0);
}

#[test]
fn queues_draw_opaque_then_blended_with_their_own_pipelines() {
    let Some(gpu) = common::gpu() else { return };
    let mut r = Renderer::new(gpu);
    let cube = r.add_shape(ShapeKind::Cube.mesh());
    let solid = r.add_material(Material::default());
    let glass = r.add_material(Material { alpha_mode: AlphaMode::Blend, ..Material::default() });
    let a = Entity::new(cube, glass, Mat4::IDENTITY);
    let b = Entity::new(cube, solid, Mat4::from_translation(Vec3::X * 2.0));
    let empty = Entity::instanced(cube, solid, Vec::new());
    let stats = frame(&mut r, gpu, &[&a, &b, &empty], &sun());
    assert_eq!((stats.draws, stats.draw_calls), (2, 2), "an entity with no instances draws nothing");
    assert_eq!(stats.pipelines_bound, 2);
}

#[test]
fn too_many_lights_and_foreign_ids_are_errors_not_panics() {
    let Some(gpu) = common::gpu() else { return };
    let (mut r, cube, m) = renderer_with_cube(gpu);
    let e = Entity::new(cube, m, Mat4::IDENTITY);
    let mut target = OffscreenTarget::new(gpu, 32, 32, 1).expect("target");
    let lights = vec![sun()[0]; MAX_LIGHTS + 1];
    r.submit(&e);
    assert!(matches!(
        r.flush(camera(), &lights, &glint::Shadows::none(), &mut target),
        Err(RenderError::TooManyLights { given: 65, what: "directional lights", most: 64 })
    ));
    r.submit(&e);
    assert!(
        r.flush(camera(), &lights[..MAX_LIGHTS], &glint::Shadows::none(), &mut target).is_ok(),
        "exactly the limit is fine"
    );

    let mut other = Renderer::new(gpu);
    other.submit(&e); // ids from `r`: `other` has no shapes
    assert!(matches!(
        other.flush(camera(), &sun(), &glint::Shadows::none(), &mut target),
        Err(RenderError::UnknownShape(_))
    ));
    // The failed frame's entities are dropped: the next frame is empty.
    let stats = other.flush(camera(), &sun(), &glint::Shadows::none(), &mut target).expect("empty frame");
    assert_eq!((stats.draws, stats.draw_calls), (0, 0));
}

#[test]
fn targets_reject_bad_sizes_and_sample_counts() {
    let Some(gpu) = common::gpu() else { return };
    assert!(matches!(OffscreenTarget::new(gpu, 0, 10, 1), Err(glint::GpuError::TargetSize { .. })));
    assert!(matches!(OffscreenTarget::new(gpu, 10, 10, 3), Err(glint::GpuError::SampleCount(3))));
}

#[test]
fn shadow_lookups_are_compiled_in_only_for_frames_that_draw_shadow_maps() {
    // The SHADOWS variant: a frame without shadow maps shades without the lookups
    // (untaken, they cost llvmpipe four times the rest of a simple frame).
    let Some(gpu) = common::gpu() else { return };
    let (mut r, cube, m) = renderer_with_cube(gpu);
    let e = Entity::new(cube, m, Mat4::IDENTITY);
    let shadowed: Vec<Light> = sun().into_iter().map(|l| l.with_shadows(glint::ShadowSettings::default())).collect();
    assert!(frame(&mut r, gpu, &[&e], &sun()).pipelines_compiled >= 1);
    assert_eq!(frame(&mut r, gpu, &[&e], &sun()).pipelines_compiled, 0);
    let first_shadowed = frame(&mut r, gpu, &[&e], &shadowed);
    assert_eq!(first_shadowed.shadow_views, 4);
    assert_eq!(first_shadowed.pipelines_compiled, 2, "the SHADOWS forward variant and the depth pipeline");
    assert_eq!(frame(&mut r, gpu, &[&e], &shadowed).pipelines_compiled, 0);
    assert_eq!(frame(&mut r, gpu, &[&e], &sun()).pipelines_compiled, 0, "both variants stay cached");
}

#[test]
fn a_textured_and_a_plain_material_share_their_shadow_pipelines_unless_alpha_tested() {
    // A shadow map needs positions only, and an alpha test's inputs where there
    // is one: every program fewer is one fewer to compile before a WebGL2 page's first frame.
    let Some(gpu) = common::gpu() else { return };
    let (mut r, cube, plain) = renderer_with_cube(gpu);
    let map =
        r.add_texture(Texture::new("t", image::RgbaImage::from_pixel(2, 2, image::Rgba([200, 90, 40, 255])), true));
    let textured = r.add_material(Material { diffuse_map: Some(map), ..Material::default() });
    let cut = r.add_material(Material {
        diffuse_map: Some(map),
        alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
        ..Material::default()
    });
    let shadowed: Vec<Light> = sun().into_iter().map(|l| l.with_shadows(glint::ShadowSettings::default())).collect();
    let at = |x: f32| Mat4::from_translation(Vec3::new(x, 0.0, 0.0));
    let (a, b, c) =
        (Entity::new(cube, plain, at(-1.5)), Entity::new(cube, textured, at(0.0)), Entity::new(cube, cut, at(1.5)));
    let first = frame(&mut r, gpu, &[&a, &b], &shadowed);
    assert_eq!(first.pipelines_compiled, 3, "two forward variants and one depth pipeline for both");
    let masked = frame(&mut r, gpu, &[&a, &b, &c], &shadowed);
    assert_eq!(masked.pipelines_compiled, 2, "the alpha-tested material's forward and depth pipelines");
}

#[test]
fn a_frame_with_shadows_and_a_post_chain_is_one_submission_its_debug_groups_nested_like_its_outline() {
    let Some(gpu) = common::gpu() else { return };
    one_submission_nested_like_the_outline(gpu);
    // GL's llvmpipe takes the debug groups (lavapipe 22 cannot): an unbalanced
    // group would fail the frame there.
    let Some(gl) = common::gl_gpu() else { return };
    assert!(gl.debug_groups(), "{:?}", gl.info());
    one_submission_nested_like_the_outline(gl);
}

fn one_submission_nested_like_the_outline(gpu: &glint::Gpu) {
    let (mut renderer, cube, material) = renderer_with_cube(gpu);
    let textured =
        renderer.add_texture(Texture::new("checker", image::RgbaImage::from_pixel(4, 4, image::Rgba([200; 4])), true));
    let painted = renderer.add_material(Material { diffuse_map: Some(textured), ..Material::default() });
    let plain = Entity::new(cube, material, Mat4::IDENTITY);
    let boxed = Entity::new(cube, painted, Mat4::from_translation(Vec3::X * 2.0));
    let lights = [Light::directional(Vec3::new(-1.0, -2.0, -1.0), Vec3::ONE, 1.0).with_shadows(Default::default())];
    let view =
        glint::View::new(camera()).with_post(vec![glint::scene::PostEffect::BLOOM, glint::scene::PostEffect::TONEMAP]);
    let mut target = OffscreenTarget::new(gpu, 64, 48, 1).expect("target");
    let mut draw = |r: &mut Renderer| r.render([&plain, &boxed], view.clone(), &lights, &mut target).expect("frame");
    let first = draw(&mut renderer);
    assert!(first.shadow_views > 0 && first.passes.post.draws > 0, "shadows and post ran: {first:?}");
    assert_eq!(first.submits, 1, "the texture's mip levels go in the frame's submission too");
    let steady = draw(&mut renderer);
    assert_eq!(steady.submits, 1, "shadow maps, forward pass and post chain in one submission");
    let groups = |frame: u32, k: usize, forward: &str| {
        let view = format!("frame {frame} › view {k}");
        [view.clone(), format!("{view} › shadows"), format!("{view} › {forward}"), format!("{view} › post")]
    };
    // A frame of one view has no view group.
    let one_view = |frame: u32, forward: &str| {
        let parts = ["shadows".to_owned(), forward.to_owned(), "post".to_owned()];
        std::iter::once(format!("frame {frame}")).chain(parts.map(|part| format!("frame {frame} › {part}")))
    };
    assert_eq!(renderer.frame_outline(), one_view(1, "forward").collect::<Vec<_>>());
    // A split screen over part of the target: its clear and both views go in one submission.
    let halves = [
        glint::Viewport { width: 0.5, ..glint::Viewport::FULL },
        glint::Viewport { x: 0.5, width: 0.4, ..glint::Viewport::FULL },
    ];
    let views: Vec<glint::View> = halves.iter().map(|&v| view.clone().with_viewport(v)).collect();
    let stats = renderer.render_views([&plain, &boxed], &views, &lights, &mut target).expect("frame");
    let submits: Vec<u32> = stats.iter().map(|s| s.submits).collect();
    assert_eq!(submits, [1, 0], "both views in one submission, counted in the first");
    // The second view draws only its own cascades: the directional light's.
    let outline: Vec<String> =
        std::iter::once("frame 2".to_owned()).chain(groups(2, 0, "forward")).chain(groups(2, 1, "forward")).collect();
    assert_eq!(renderer.frame_outline(), outline);
    renderer.set_mode(glint::FrameMode::Naive);
    renderer.render([&plain, &boxed], view, &lights, &mut target).expect("naive frame");
    assert_eq!(renderer.frame_outline(), one_view(3, "forward (naive)").collect::<Vec<_>>(), "frames are counted");
}

#[test]
fn whole_tiles_culled_on_the_cpu_write_no_draw_index_per_instance() {
    // 20,000 cubes in 8 × 8 tiles of a 40 × 40 field around the origin.
    let Some(gpu) = common::gpu() else { return };
    let (mut renderer, cube, material) = renderer_with_cube(gpu);
    let (side, cells) = (141usize, 8usize);
    let mut tiles: Vec<Vec<Mat4>> = vec![Vec::new(); cells * cells];
    for k in 0..side * side {
        let (x, z) = ((k % side) as f32 / side as f32 * 40.0 - 20.0, (k / side) as f32 / side as f32 * 40.0 - 20.0);
        let cell = |v: f32| (((v + 20.0) / 40.0 * cells as f32) as usize).min(cells - 1);
        tiles[cell(x) + cells * cell(z)].push(Mat4::from_scale_rotation_translation(
            Vec3::splat(0.1),
            Quat::IDENTITY,
            Vec3::new(x, 0.0, z),
        ));
    }
    let sizes = glint::Tiles::from_sizes(tiles.iter().map(|t| t.len() as u32), 0.0);
    let field = Entity::instanced(cube, material, tiles.concat()).with_tiles(sizes);
    let mut target = OffscreenTarget::new(gpu, 64, 64, 1).expect("target");
    let mut draw = |r: &mut Renderer, eye: Vec3| {
        let view = glint::View::new(Camera::perspective(50.0, 0.1, 100.0).looking_at(eye, Vec3::ZERO));
        r.render([&field], view.with_culling(glint::Culling::Cpu), &sun(), &mut target).expect("frame")
    };
    let first = draw(&mut renderer, Vec3::new(0.0, 8.0, 30.0));
    assert!(first.tiles_drawn > 0 && first.tiles_drawn < 64, "{first:?}");
    assert_eq!(first.bytes_uploaded.draw_indices, 4 * 32_768, "the ramp, once: {:?}", first.bytes_uploaded);
    let moved = draw(&mut renderer, Vec3::new(12.0, 8.0, 28.0));
    assert_ne!(moved.instances_drawn, first.instances_drawn, "the camera moved");
    assert_eq!(moved.bytes_uploaded.draw_indices, 0, "whole tiles need no index each: {:?}", moved.bytes_uploaded);
    // Each visible run of contiguous tiles is one batch: fewer batches than tiles.
    assert!(moved.draws <= 1 + moved.tiles_drawn as u32, "{moved:?}");
}
