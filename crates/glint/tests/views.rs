//! Several views in one frame: split screens and pictures in pictures, each view
//! culled, shadowed and drawn on its own, with its own statistics; and the
//! shadow maps a view's shadow pass returns, which only that view's flush takes.

mod common;

use glam::{Mat4, Vec3};
use glint::asset::ShapeKind;
use glint::scene::PostEffect;
use glint::{
    Camera, Entity, FrameInput, Gpu, Light, Material, OffscreenTarget, RenderError, Renderer, Shadows, View, Viewport,
};

/// Draw `views` of `scenes/split.scn` into one `width` × `height` image.
fn split_scene(gpu: &Gpu, views: &[View], (width, height): (u32, u32)) -> (image::RgbaImage, Vec<glint::FrameStats>) {
    let desc = common::load_scene(&common::repo_root().join("scenes/split.scn"));
    let mut renderer = Renderer::new(gpu);
    let entities = renderer.place_scene(&desc).entities;
    let mut target = OffscreenTarget::new(gpu, width, height, 1).expect("target");
    let stats = renderer.render_views(&entities, views, desc.lighting(), &mut target).expect("frame");
    (target.read_rgba8(gpu).expect("readback"), stats)
}

/// The part of `image` at (x, y) of size `width` × `height`.
fn crop(image: &image::RgbaImage, x: u32, y: u32, width: u32, height: u32) -> image::RgbaImage {
    image::imageops::crop_imm(image, x, y, width, height).to_image()
}

#[test]
fn each_half_of_a_split_screen_is_its_camera_drawn_alone_at_that_size() {
    let Some(gpu) = common::gpu() else { return };
    split_screen_halves(gpu);
}

#[test]
fn split_screens_work_on_gl_too() {
    let Some(gpu) = common::gl_gpu() else { return };
    split_screen_halves(gpu);
}

/// `scenes/split.scn` matches its reference, and each half its camera alone.
fn split_screen_halves(gpu: &Gpu) {
    let desc = common::load_scene(&common::repo_root().join("scenes/split.scn"));
    let views = desc.views(&[]);
    assert_eq!(views.len(), 2, "split.scn places two cameras");
    let (split, stats) = split_scene(gpu, &views, (192, 96));
    common::assert_matches_reference("split", &split);
    assert_eq!(stats.len(), 2, "one FrameStats per view");
    for (k, half) in [(0u32, 0u32), (1, 96)] {
        let alone = desc.camera_view(k as usize);
        let (image, single) = split_scene(gpu, &[alone], (96, 96));
        let difference = common::max_difference(&crop(&split, half, 0, 96, 96), &image);
        assert!(difference <= 2, "half {k} differs from its camera alone by {difference}");
        assert_eq!(stats[k as usize].draws, single[0].draws, "half {k}'s draws are its camera's alone");
        assert!(stats[k as usize].shadow_views > 0, "each view draws its own cascades");
    }
}

#[test]
fn a_picture_in_picture_covers_only_its_corner() {
    let Some(gpu) = common::gpu() else { return };
    let desc = common::load_scene(&common::repo_root().join("scenes/split.scn"));
    let (front, above) = (desc.camera_view(0), desc.camera_view(1));
    assert_eq!(above.post, [PostEffect::Edges { color: glam::Vec3::new(0.02, 0.03, 0.12), threshold: 0.3 }]);
    let corner = Viewport { x: 0.5, y: 0.5, width: 0.5, height: 0.5 };
    let (picture, _) = split_scene(gpu, &[front.clone(), above.clone().with_viewport(corner)], (64, 64));
    let (front_alone, _) = split_scene(gpu, std::slice::from_ref(&front), (64, 64));
    let (above_alone, _) = split_scene(gpu, &[above], (32, 32));
    assert!(
        common::max_difference(&crop(&picture, 32, 32, 32, 32), &above_alone) <= 2,
        "the corner is the second camera"
    );
    for (x, y) in [(0, 0), (32, 0), (0, 32)] {
        let quarter = common::max_difference(&crop(&picture, x, y, 32, 32), &crop(&front_alone, x, y, 32, 32));
        assert!(quarter <= 2, "quarter at ({x}, {y}) differs from the first camera by {quarter}");
    }
    // A first view that leaves part of the image uncovered: the rest is black.
    let left = Viewport { width: 0.5, ..Viewport::FULL };
    let (half, _) = split_scene(gpu, &[front.with_viewport(left)], (64, 64));
    assert!(crop(&half, 32, 0, 32, 64).pixels().all(|p| p.0 == [0, 0, 0, 255]), "the right half is cleared");
    assert!(crop(&half, 0, 0, 32, 64).pixels().any(|p| p.0[1] > 60), "the left half is drawn");
}

/// A renderer with one cube at the origin and a sun that casts shadows.
fn cube_scene(gpu: &Gpu) -> (Renderer, Entity, [Light; 1]) {
    let mut renderer = Renderer::new(gpu);
    let cube = renderer.add_shape(ShapeKind::Cube.mesh());
    let material = renderer.add_material(Material::default());
    let sun =
        Light::directional(Vec3::new(-1.0, -2.0, -1.0), Vec3::ONE, 1.0).with_shadows(glint::ShadowSettings::default());
    (renderer, Entity::new(cube, material, Mat4::IDENTITY), [sun])
}

#[test]
fn each_view_is_culled_on_its_own() {
    let Some(gpu) = common::gpu() else { return };
    let (mut renderer, cube, lights) = cube_scene(gpu);
    let toward = Camera::perspective(60.0, 0.1, 100.0).looking_at(Vec3::new(0.0, 1.0, 4.0), Vec3::ZERO);
    let away = Camera::perspective(60.0, 0.1, 100.0).looking_at(Vec3::new(0.0, 1.0, 4.0), Vec3::new(0.0, 1.0, 8.0));
    let halves = [Viewport { width: 0.5, ..Viewport::FULL }, Viewport { x: 0.5, width: 0.5, ..Viewport::FULL }];
    // Culled on the CPU, so that this frame's counts are known now.
    let views = [View::new(toward).with_viewport(halves[0]), View::new(away).with_viewport(halves[1])]
        .map(|v| v.with_culling(glint::Culling::Cpu));
    let mut target = OffscreenTarget::new(gpu, 64, 32, 1).expect("target");
    let stats = renderer.render_views([&cube], &views, &lights, &mut target).expect("frame");
    assert_eq!((stats[0].instances_drawn, stats[0].instances_culled), (1, 0), "the cube is in front of the first");
    assert_eq!((stats[1].instances_drawn, stats[1].instances_culled), (0, 1), "and behind the second");
    // Its shadow view still sees the cube (it casts into the second view's cascades).
    assert!(stats[1].passes.shadow.draws > 0);
}

#[test]
fn a_flush_takes_only_the_shadow_maps_drawn_for_its_view_this_frame() {
    let Some(gpu) = common::gpu() else { return };
    let (mut renderer, cube, lights) = cube_scene(gpu);
    let camera = Camera::perspective(60.0, 0.1, 100.0).looking_at(Vec3::new(0.0, 1.0, 4.0), Vec3::ZERO);
    let mut target = OffscreenTarget::new(gpu, 32, 32, 1).expect("target");
    renderer.submit(&cube);
    let shadows = renderer.shadow_pass(camera, &lights, &target).expect("shadow pass");
    let stats = renderer.flush(camera, &lights, &shadows, &mut target).expect("frame");
    assert_eq!(stats.shadow_views, 4, "one directional light: four cascades");
    // The next frame, with last frame's maps.
    renderer.submit(&cube);
    let error = renderer.flush(camera, &lights, &shadows, &mut target).expect_err("stale maps");
    assert!(matches!(error, RenderError::StaleShadows), "{error}");
    // Maps drawn for other lights, or for another camera.
    for (other_camera, other_lights) in [(camera, &[][..]), (camera.looking_at(Vec3::ONE, Vec3::ZERO), &lights[..])] {
        renderer.submit(&cube);
        let shadows = renderer.shadow_pass(other_camera, other_lights, &target).expect("shadow pass");
        let error = renderer.flush(camera, &lights, &shadows, &mut target).expect_err("other maps");
        assert!(matches!(error, RenderError::ShadowsForOtherView), "{error}");
    }
    // Without maps: no shadows, and no error.
    renderer.submit(&cube);
    let stats = renderer.flush(camera, &lights, &Shadows::none(), &mut target).expect("frame");
    assert_eq!(stats.shadow_views, 0);
    // A viewport outside the target.
    renderer.submit(&cube);
    let outside = View::new(camera).with_viewport(Viewport { x: 0.75, width: 0.5, ..Viewport::FULL });
    let error = renderer.flush(outside, &lights, &Shadows::none(), &mut target).expect_err("outside");
    assert!(matches!(error, RenderError::BadViewport(_)), "{error}");
}

#[test]
fn a_material_shows_a_render_target_drawn_earlier_in_the_same_frame() {
    let Some(gpu) = common::gpu() else { return };
    let mut renderer = Renderer::new(gpu);
    let (monitor, screen) = renderer.add_render_target(16, 16, false).expect("render target");
    let cube = renderer.add_shape(ShapeKind::Cube.mesh());
    let unlit = |r: &mut Renderer, material: Material| {
        r.add_material(Material { shading: glint::scene::ShadingModel::Unlit, ..material })
    };
    let red = unlit(&mut renderer, Material::color("red", 1.0, 0.0, 0.0));
    let shown = unlit(&mut renderer, Material { diffuse_map: Some(screen), ..Material::default() });
    // A red cube far to the left, seen by the security camera; a screen at the origin.
    let thing = Entity::new(cube, red, Mat4::from_translation(Vec3::new(-20.0, 0.0, 0.0)));
    let panel = Entity::new(cube, shown, Mat4::from_scale(Vec3::new(2.0, 2.0, 0.1)));
    let security =
        Camera::perspective(40.0, 0.1, 100.0).looking_at(Vec3::new(-20.0, 0.0, 3.0), Vec3::new(-20.0, 0.0, 0.0));
    let main = Camera::perspective(60.0, 0.1, 100.0).looking_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO);
    let mut target = OffscreenTarget::new(gpu, 32, 32, 1).expect("target");
    // Given main first: the security view is still drawn before it.
    let views = [View::new(main), View::new(security).with_output(monitor)];
    let stats = renderer.render_views([&thing, &panel], &views, &[], &mut target).expect("frame");
    assert_eq!(stats.len(), 2);
    assert_eq!(stats[1].instances_submitted, 1, "the screen is not drawn into its own target");
    let image = target.read_rgba8(gpu).expect("readback");
    let centre = image.get_pixel(16, 16).0;
    assert!(centre[0] > 200 && centre[1] < 40 && centre[2] < 40, "the screen shows the red cube: {centre:?}");
    // Two views each showing the other's target: a cycle.
    let (other, other_screen) = renderer.add_render_target(8, 8, true).expect("render target");
    let shows_other = unlit(&mut renderer, Material { diffuse_map: Some(other_screen), ..Material::default() });
    let second_panel = Entity::new(cube, shows_other, Mat4::IDENTITY);
    let views = [View::new(main).with_output(monitor), View::new(security).with_output(other)];
    let error = renderer.render_views([&panel, &second_panel], &views, &[], &mut target).expect_err("cycle");
    assert!(matches!(error, RenderError::RenderTargetCycle), "{error}");
    let unknown = [View::new(main).with_output(glint::RenderTargetId(9))];
    let error = renderer.render_views([&panel], &unknown, &[], &mut target).expect_err("unknown");
    assert!(matches!(error, RenderError::UnknownRenderTarget(_)), "{error}");
}

#[test]
fn the_monitor_shows_the_security_cameras_picture() {
    let Some(gpu) = common::gpu() else { return };
    let desc = common::load_scene(&common::repo_root().join("scenes/monitor.scn"));
    // Draws the views after the first `skip` of the scene's.
    let draw = |skip: usize| {
        let mut renderer = Renderer::new(gpu);
        let placed = renderer.place_scene(&desc);
        let views = desc.views(&placed.render_targets);
        assert_eq!(views.len(), 2, "the security camera into its target, the room into the image");
        assert_eq!(views[0].output, Some(placed.render_targets[0]));
        let mut target = OffscreenTarget::new(gpu, 160, 90, 4).expect("target");
        renderer.render_views(&placed.entities, &views[skip..], desc.lighting(), &mut target).expect("frame");
        target.read_rgba8(gpu).expect("readback")
    };
    let image = draw(0);
    common::assert_matches_reference("monitor", &image);
    // The screen's middle (x 71..96, y 33..48 of 160 × 90) shows
    // the room; without the security camera it shows a black, never-drawn target.
    let screen = |image: &image::RgbaImage| crop(image, 76, 36, 14, 10);
    let lit = |image: &image::RgbaImage| screen(image).pixels().filter(|p| p.0[..3].iter().any(|&c| c > 60)).count();
    let unfed = draw(1);
    assert!(lit(&image) > 60, "the feed is on the screen: {} bright pixels", lit(&image));
    assert_eq!(lit(&unfed), 0, "no security camera, no picture");
}

#[test]
fn each_view_keeps_its_gpu_state_so_an_unchanged_split_screen_uploads_nothing() {
    // Two cameras that see different things: with one shared set of camera
    // records and draw lists, each view rewrote the other's every frame.
    let Some(gpu) = common::gpu() else { return };
    let (mut renderer, cube, lights) = cube_scene(gpu);
    let toward = Camera::perspective(60.0, 0.1, 100.0).looking_at(Vec3::new(0.0, 1.0, 4.0), Vec3::ZERO);
    let away = Camera::perspective(60.0, 0.1, 100.0).looking_at(Vec3::new(0.0, 1.0, 4.0), Vec3::new(0.0, 1.0, 8.0));
    let halves = [Viewport { width: 0.5, ..Viewport::FULL }, Viewport { x: 0.5, width: 0.5, ..Viewport::FULL }];
    let views = [View::new(toward).with_viewport(halves[0]), View::new(away).with_viewport(halves[1])];
    let mut target = OffscreenTarget::new(gpu, 64, 32, 1).expect("target");
    let far = Entity::new(cube.shape, cube.material, Mat4::from_translation(Vec3::new(0.0, 0.0, 8.0)));
    let first = renderer.render_views([&cube, &far], &views, &lights, &mut target).expect("frame");
    let image = target.read_rgba8(gpu).expect("readback");
    assert!(first.iter().all(|s| s.bytes_uploaded.camera > 0), "each view writes its camera once");
    let second = renderer.render_views([&cube, &far], &views, &lights, &mut target).expect("frame");
    for (k, s) in second.iter().enumerate() {
        assert_eq!(s.bytes_uploaded.total, 0, "view {k} uploads nothing the second time: {:?}", s.bytes_uploaded);
        assert_eq!(s.draws, first[k].draws, "view {k} draws the same");
    }
    assert_eq!(target.read_rgba8(gpu).expect("readback"), image, "the same picture");
    // A view's state follows the caller's key, not its place in the list:
    // the same views under new keys write their records once, and listed the
    // other way round under the same keys, nothing.
    let entities = [Entity::new(cube.shape, cube.material, Mat4::IDENTITY), far];
    let (left, right) = (glint::ViewKey(7), glint::ViewKey(3));
    let mut keyed = |order: [(glint::ViewKey, &View); 2]| {
        let mut input = FrameInput::new(&entities, &lights);
        for (key, view) in order {
            input = input.view(key, view);
        }
        renderer.render_frame(input, &mut target).expect("frame")
    };
    let new_keys = keyed([(left, &views[0]), (right, &views[1])]);
    assert!(new_keys.views.iter().all(|s| s.bytes_uploaded.camera > 0), "new keys, new records");
    let swapped = keyed([(right, &views[1]), (left, &views[0])]);
    for (k, s) in swapped.views.iter().enumerate() {
        assert_eq!(s.bytes_uploaded.total, 0, "view {k} under its key uploads nothing: {:?}", s.bytes_uploaded);
    }
    assert_eq!(target.read_rgba8(gpu).expect("readback"), image, "the same picture");
}

/// Two halves of a 64 × 32 target looking at a cube from either side, lit by
/// a point light that casts shadows onto a floor.
fn point_lit_split(gpu: &Gpu) -> (Renderer, [Entity; 2], [Light; 1], [View; 2]) {
    let mut renderer = Renderer::new(gpu);
    let cube = renderer.add_shape(ShapeKind::Cube.mesh());
    let material = renderer.add_material(Material::default());
    let floor = Mat4::from_translation(Vec3::Y * -1.0) * Mat4::from_scale(Vec3::new(8.0, 0.1, 8.0));
    let entities = [Entity::new(cube, material, Mat4::IDENTITY), Entity::new(cube, material, floor)];
    let lamp =
        Light::point(Vec3::new(0.5, 2.5, 0.5), Vec3::ONE, 8.0, 12.0).with_shadows(glint::ShadowSettings::default());
    let camera = |eye: Vec3| Camera::perspective(60.0, 0.1, 100.0).looking_at(eye, Vec3::ZERO);
    let halves = [Viewport { width: 0.5, ..Viewport::FULL }, Viewport { x: 0.5, width: 0.5, ..Viewport::FULL }];
    let views = [
        View::new(camera(Vec3::new(3.0, 2.0, 3.0))).with_viewport(halves[0]),
        View::new(camera(Vec3::new(-3.0, 2.0, -3.0))).with_viewport(halves[1]),
    ];
    (renderer, entities, [lamp], views)
}

#[test]
fn a_split_screen_draws_a_point_lights_six_faces_once_in_one_frame_that_prepares_once() {
    let Some(gpu) = common::gpu() else { return };
    let (mut renderer, entities, lights, views) = point_lit_split(gpu);
    let mut target = OffscreenTarget::new(gpu, 64, 32, 1).expect("target");
    let input = FrameInput::new(&entities, &lights).views(&views);
    let frame = renderer.render_frame(input, &mut target).expect("frame");
    let faces: Vec<u32> = frame.views.iter().map(|s| s.shadow_views).collect();
    assert_eq!(faces, [6, 0], "the first view draws the six cube faces, the second samples them");
    assert_eq!(frame.views.iter().map(|s| s.frame).collect::<Vec<_>>(), [frame.frame; 2], "one frame number");
    assert_eq!((frame.prepares, frame.submits), (1, 1), "both views draw with one prepared table, one submission");
    let instances: Vec<u64> = frame.views.iter().map(|s| s.bytes_uploaded.instances).collect();
    assert!(instances[0] > 0 && instances[1] == 0, "the instances go up once: {instances:?}");
    let split = target.read_rgba8(gpu).expect("readback");
    // Each half is its camera drawn alone (whose frame draws the faces itself).
    for (k, view) in views.iter().enumerate() {
        let (mut alone, _, _, _) = point_lit_split(gpu);
        let whole = view.clone().with_viewport(Viewport::FULL);
        let mut half = OffscreenTarget::new(gpu, 32, 32, 1).expect("target");
        let stats = alone.render(&entities, whole, &lights, &mut half).expect("frame");
        assert_eq!(stats.shadow_views, 6);
        let image = half.read_rgba8(gpu).expect("readback");
        let difference = common::max_difference(&crop(&split, 32 * k as u32, 0, 32, 32), &image);
        assert!(difference <= 2, "half {k} differs from its camera alone by {difference}");
    }
    // The next frame is the next number, for both views.
    let next = renderer.render_frame(FrameInput::new(&entities, &lights).views(&views), &mut target).expect("frame");
    assert_eq!(next.frame, frame.frame + 1);
    assert!(next.views.iter().all(|s| s.frame == next.frame));
}

/// The median of `ms`.
fn median(mut ms: Vec<f64>) -> f64 {
    ms.sort_by(f64::total_cmp);
    ms[ms.len() / 2]
}

#[test]
fn a_frames_gpu_times_are_its_views_summed() {
    let Some(gpu) = common::gpu() else { return };
    let desc = common::load_scene(&common::repo_root().join("tests/scenes/ssao.scn"));
    let mut renderer = Renderer::new(gpu);
    if !renderer.enable_gpu_timing() {
        eprintln!("skipping: {} has no timestamp queries", gpu.info().name);
        return;
    }
    let entities = renderer.place_scene(&desc).entities;
    let mut target = OffscreenTarget::new(gpu, 256, 256, 1).expect("target");
    // The whole picture, and one pixel in its corner drawn after it.
    let whole = View::new(desc.cameras[0]);
    let corner = whole.clone().with_viewport(Viewport { width: 1.0 / 256.0, height: 1.0 / 256.0, ..Viewport::FULL });
    let mut forward_ms = |views: &[View]| {
        let input = FrameInput::new(&entities, desc.lighting()).views(views);
        renderer.render_frame(input, &mut target).expect("frame");
        renderer.read_gpu_times().expect("timed frame").forward_ms
    };
    // The three frames of a round run back to back, so a neighbour test
    // loading the CPU (lavapipe's GPU) slows all three alike; each round
    // gives ratios and the test takes their medians.
    let rounds: Vec<[f64; 3]> = (0..7)
        .map(|_| {
            let alone_ms = forward_ms(std::slice::from_ref(&whole));
            let corner_ms = forward_ms(std::slice::from_ref(&corner));
            let both_ms = forward_ms(&[whole.clone(), corner.clone()]);
            [alone_ms, corner_ms, both_ms]
        })
        .collect();
    let corner_share = median(rounds.iter().map(|[alone, corner, _]| corner / alone).collect());
    let both_share = median(rounds.iter().map(|[alone, _, both]| both / alone).collect());
    // The corner's pass alone is the smaller by far: were only the last view's
    // pass reported, the frame would show about the corner's time.
    assert!(corner_share < 0.25, "the corner takes {corner_share} of the whole picture's time ({rounds:?})");
    assert!(both_share > 0.5, "both views take {both_share} of the whole picture's time alone ({rounds:?})");
}
