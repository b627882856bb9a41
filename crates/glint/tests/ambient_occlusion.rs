//! Screen-space ambient occlusion (`tests/scenes/ssao.scn`: a box on a floor
//! lit only by a sky): the crease where the box meets the floor darkens, open
//! floor stays exactly as it was, on Vulkan (compute passes), GL and the WebGL2
//! path (fragment passes), which agree; the passes' draws and GPU time are in
//! the frame's statistics. With occlusion culling the pre-pass draws the view's
//! depth once a phase, and what the late phase reveals is occluded in the
//! frame it appears.

mod common;

use glam::Vec3;
use glint::asset::SceneDesc;
use glint::{Culling, FrameStats, Gpu, OffscreenTarget, Renderer, View};

const SIZE: u32 = 256;

fn scene() -> SceneDesc {
    common::load_scene(&common::repo_root().join("tests/scenes/ssao.scn"))
}

/// One frame of `desc`'s first camera into a target of `samples`, with its
/// ambient occlusion or without.
fn frame(gpu: &Gpu, desc: &SceneDesc, (occluded, samples): (bool, u32)) -> (image::RgbaImage, FrameStats, Renderer) {
    let mut renderer = Renderer::new(gpu);
    let entities = renderer.place_scene(desc).entities;
    let mut target = OffscreenTarget::new(gpu, SIZE, SIZE, samples).expect("target");
    let mut view = desc.camera_view(0);
    if !occluded {
        view = view.with_ambient_occlusion(None);
    }
    let stats = renderer.render(&entities, view, desc.lighting(), &mut target).expect("frame");
    (target.read_rgba8(gpu).expect("readback"), stats, renderer)
}

/// The pixel where world point `p` lands in the camera's picture.
fn pixel(desc: &SceneDesc, p: Vec3) -> (u32, u32) {
    let camera = desc.cameras[0];
    let ndc = (camera.projection(1.0) * camera.view()).project_point3(p);
    let to = |v: f32| ((v * 0.5 + 0.5) * SIZE as f32) as u32;
    (to(ndc.x), to(-ndc.y))
}

/// The green channel of `image` at `(x, y)`, as a fraction of `reference`'s.
fn ratio(image: &image::RgbaImage, reference: &image::RgbaImage, (x, y): (u32, u32)) -> f32 {
    f32::from(image.get_pixel(x, y)[1]) / f32::from(reference.get_pixel(x, y)[1]).max(1.0)
}

/// The crease in front of the box is darker with ambient occlusion; floor
/// further than the radius from the box is the same bytes (into a target of
/// `samples`). Returns the picture.
fn assert_crease_darkens(gpu: &Gpu, samples: u32) -> image::RgbaImage {
    let desc = scene();
    let radius = desc.camera_views[0].ambient_occlusion.expect("the camera's ssao").radius;
    let (occluded, stats, _) = frame(gpu, &desc, (true, samples));
    let (open, plain, _) = frame(gpu, &desc, (false, samples));
    // The floor just in front of each visible face of the box (a unit cube at 0 0.5 0).
    for crease in [Vec3::new(0.0, 0.0, 0.55), Vec3::new(0.55, 0.0, 0.0)] {
        let at = pixel(&desc, crease);
        let r = ratio(&occluded, &open, at);
        assert!(r < 0.9, "the crease at {crease} ({at:?}) darkens by at least 10 %: ratio {r}");
    }
    // The bottom of the box's front face darkens too, its top does not.
    let low = ratio(&occluded, &open, pixel(&desc, Vec3::new(0.0, 0.05, 0.5)));
    let high = ratio(&occluded, &open, pixel(&desc, Vec3::new(0.0, 0.95, 0.5)));
    assert!(low < 0.95 && high > 0.99, "the box's face: {low} near the floor, {high} at its top");
    // Every pixel of floor further than the radius (and a pixel) from the box is unchanged.
    let camera = desc.cameras[0];
    let inverse = (camera.projection(1.0) * camera.view()).inverse();
    let mut checked = 0;
    for (x, y, p) in occluded.enumerate_pixels() {
        let ndc = |v: u32| (v as f32 + 0.5) / SIZE as f32 * 2.0 - 1.0;
        let (near, far) = (
            inverse.project_point3(Vec3::new(ndc(x), -ndc(y), 0.0)),
            inverse.project_point3(Vec3::new(ndc(x), -ndc(y), 1.0)),
        );
        if far.y >= near.y {
            continue; // the sky
        }
        let floor = near + (far - near) * (near.y / (near.y - far.y));
        let outside = (floor.abs() - Vec3::new(0.5, 0.0, 0.5)).max(Vec3::ZERO).length();
        if floor.x.abs().max(floor.z.abs()) < 3.5 && outside > radius + 0.1 && pixel_is_floor(&desc, floor) {
            assert_eq!(p, open.get_pixel(x, y), "open floor at {floor} ({x}, {y}) is unchanged");
            checked += 1;
        }
    }
    assert!(checked > 10_000, "{checked} open floor pixels checked");
    assert_eq!(plain.passes.ambient_occlusion, Default::default(), "no passes without it");
    let ao = stats.passes.ambient_occlusion;
    // Compute passes where views cull on the GPU, else two fragment passes.
    let fragment = if gpu.culls_on_gpu() { 0 } else { 2 };
    assert_eq!((ao.draws, ao.instances), (2 + fragment, 2), "the pre-pass's floor and box: {ao:?}");
    assert_eq!(stats.draws, plain.draws, "the forward pass draws the same");
    occluded
}

/// Whether floor point `p` is not hidden by the box from the camera.
fn pixel_is_floor(desc: &SceneDesc, p: Vec3) -> bool {
    let eye = desc.cameras[0].eye;
    // The segment from the eye to p misses the box (slab test).
    let (lo, hi) = (Vec3::new(-0.5, 0.0, -0.5), Vec3::new(0.5, 1.0, 0.5));
    let d = p - eye;
    let (mut enter, mut exit) = (0.0f32, 1.0f32);
    for k in 0..3 {
        if d[k].abs() < 1e-9 {
            if eye[k] < lo[k] || eye[k] > hi[k] {
                return true;
            }
            continue;
        }
        let (a, b) = ((lo[k] - eye[k]) / d[k], (hi[k] - eye[k]) / d[k]);
        enter = enter.max(a.min(b));
        exit = exit.min(a.max(b));
    }
    enter > exit
}

#[test]
fn ambient_occlusion_darkens_the_crease_and_leaves_open_floor() {
    let Some(gpu) = common::gpu() else { return };
    // Multisampled, the pre-pass draws the target's depth with its samples.
    assert_crease_darkens(gpu, 4);
    assert_crease_darkens(gpu, 1);
}

#[test]
fn compute_and_fragment_passes_agree() {
    let (Some(compute), Some(fragment)) = (common::gpu(), common::webgl2_gpu()) else { return };
    assert!(compute.culls_on_gpu() && !fragment.culls_on_gpu(), "one path each");
    // Into one sample both read the same pre-pass, the target's depth.
    let (a, b) = (assert_crease_darkens(compute, 1), assert_crease_darkens(fragment, 1));
    assert!(common::max_difference(&a, &b) <= 2, "differ by {}", common::max_difference(&a, &b));
    // Multisampled, fragment passes cannot read the target's samples: their
    // pre-pass has one sample and a depth of its own, and still darkens the crease.
    assert_crease_darkens(fragment, 4);
}

#[test]
fn ambient_occlusion_on_gl() {
    let Some(gpu) = common::gl_gpu() else { return };
    assert_crease_darkens(gpu, 4);
}

#[test]
fn ambient_occlusion_on_the_webgl2_path() {
    let Some(gpu) = common::gl_webgl2_gpu() else { return };
    assert_crease_darkens(gpu, 4);
}

/// The names of the last explained frame's passes, in encoding order.
fn pass_names(renderer: &Renderer) -> Vec<String> {
    renderer.explained().expect("explained").passes.iter().map(|p| p.name.clone()).collect()
}

#[test]
fn with_occlusion_culling_depth_is_drawn_once_a_phase_and_what_the_late_phase_reveals_is_occluded() {
    let Some(gpu) = common::gpu() else { return };
    if !gpu.occlusion_culls() {
        eprintln!("skipping: {} cannot occlusion-cull", gpu.info().name);
        return;
    }
    let desc = scene();
    let view = desc.camera_view(0).with_culling(Culling::Gpu);
    let camera = desc.cameras[0];
    // Looking away from the box (behind the camera), then at it: the box was
    // not seen last frame, so the late phase draws it.
    let away = View { camera: camera.looking_at(camera.eye, camera.eye * 2.0), ..view.clone() };
    let mut renderer = Renderer::new(gpu);
    let entities = renderer.place_scene(&desc).entities;
    let mut target = OffscreenTarget::new(gpu, SIZE, SIZE, 4).expect("target");
    renderer.set_explaining(true);
    let mut draw = |renderer: &mut Renderer, view: &View| {
        let stats = renderer.render(&entities, view.clone(), desc.lighting(), &mut target).expect("frame");
        (target.read_rgba8(gpu).expect("readback"), stats)
    };
    draw(&mut renderer, &away);
    let (revealed, stats) = draw(&mut renderer, &view);
    assert!(stats.occlusion, "occlusion-culled: {stats:?}");
    let expected = [
        "cull instances",
        "depth pre-pass: early",
        "depth pyramid",
        "cull instances: late",
        "depth pre-pass: late",
        "ambient occlusion",
        "ambient occlusion: blur",
        "forward pass",
    ];
    assert_eq!(pass_names(&renderer), expected, "one depth pre-pass a phase, one forward pass testing it");
    // Seen again, the box is drawn early: the picture is the one it had when revealed.
    let (seen, _) = draw(&mut renderer, &view);
    assert_eq!(pass_names(&renderer), expected);
    assert!(common::max_difference(&revealed, &seen) <= 2, "differ by {}", common::max_difference(&revealed, &seen));
    // And the crease of the revealed box is darkened.
    let (open, _, _) = frame(gpu, &desc, (false, 4));
    let at = pixel(&desc, Vec3::new(0.0, 0.0, 0.55));
    let r = ratio(&revealed, &open, at);
    assert!(r < 0.9, "the revealed box's crease ({at:?}) darkens in its first frame: ratio {r}");
}

#[test]
fn ambient_occlusion_has_its_gpu_time() {
    let Some(gpu) = common::gpu() else { return };
    let desc = scene();
    let mut renderer = Renderer::new(gpu);
    if !renderer.enable_gpu_timing() {
        eprintln!("skipping: {} has no timestamp queries", gpu.info().name);
        return;
    }
    let entities = renderer.place_scene(&desc).entities;
    let mut target = OffscreenTarget::new(gpu, 64, 64, 1).expect("target");
    let mut draw = |view: View| {
        renderer.render(&entities, view, desc.lighting(), &mut target).expect("frame");
        renderer.read_gpu_times().expect("timed frame")
    };
    let times = draw(desc.camera_view(0));
    let ms = times.ambient_occlusion_ms.expect("the occlusion passes are timed");
    assert!(ms > 0.0 && ms < 60_000.0, "{times:?}");
    let depth = times.depth_prepass_ms.expect("the depth pre-pass the forward pass shares is timed");
    assert!(depth > 0.0 && depth < 60_000.0, "{times:?}");
    let without = draw(desc.camera_view(0).with_ambient_occlusion(None));
    assert_eq!((without.ambient_occlusion_ms, without.depth_prepass_ms), (None, None), "{without:?}");
}
