//! Scene cloth solved on the GPU and drawn in place (`"solve" "gpu"`): the
//! surface's vertices written by a compute pass into the mesh pool, never
//! read back, against the CPU's converged solve of the same scene, the
//! reference; and the CPU fallback where the renderer has no compute path.
//! `tests/scenes/cloth_gpu.scn` has a pinned sheet swinging down and a free
//! one dropped onto the floor, so both ways of holding a GPU cloth's box
//! (near its pins; its rest place swept down to a floor) are drawn.

mod common;

use glint::scene::cloth::Solve;
use glint::scene::{PathCounts, SimPath};

const TIME: f32 = 0.5;

/// `tests/scenes/cloth_gpu.scn`, every cloth solved as `solve`, placed on `gpu`.
fn world(gpu: &glint::Gpu, solve: Solve) -> (glint::World, glint::Renderer) {
    let mut desc = common::load_scene(&common::repo_root().join("tests/scenes/cloth_gpu.scn"));
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    desc.cloths.iter_mut().for_each(|c| c.setup.solve = solve);
    let mut renderer = glint::Renderer::new(gpu);
    let world = glint::World::place(desc, &mut renderer).expect("placed");
    (world, renderer)
}

/// The scene at `time`, solved as `solve`, 256 × 256 with 4× MSAA: the
/// picture, the world and the frame's statistics.
fn cloth_at(gpu: &glint::Gpu, time: f32, solve: Solve) -> (image::RgbaImage, glint::World, glint::FrameStats) {
    let (mut world, mut renderer) = world(gpu, solve);
    world.pose(time, &mut renderer).expect("posed");
    let mut target = glint::OffscreenTarget::new(gpu, 256, 256, 4).expect("target");
    let stats = world.draw(&mut renderer, &world.views(None), &mut target).expect("frame").remove(0);
    (target.read_rgba8(gpu).expect("readback"), world, stats)
}

#[test]
fn the_gpu_cloth_is_drawn_in_place_as_the_converged_solve_draws_it() {
    let Some(gpu) = common::gpu() else { return };
    let (reference, cpu_world, stats) = cloth_at(gpu, TIME, Solve::Converged);
    assert_eq!(cpu_world.cloth_paths(), [Some(SimPath::Cpu); 2]);
    assert_eq!(stats.simulations.cloths, PathCounts { cpu: 2, gpu: 0 });
    common::assert_matches_reference("cloth_gpu", &reference);
    let (picture, world, stats) = cloth_at(gpu, TIME, Solve::Gpu);
    if !gpu.culls_on_gpu() {
        assert_eq!(world.cloth_paths(), [Some(SimPath::Cpu); 2], "no compute path: the CPU solves them");
        return;
    }
    assert_eq!(world.cloth_paths(), [Some(SimPath::Gpu); 2]);
    assert_eq!(stats.simulations.cloths, PathCounts { cpu: 0, gpu: 2 });
    assert!(world.cloth_view(0).is_none(), "nothing is read back to make a CPU mesh");
    // The sheets swung and fell: the picture is not the one at rest.
    let (rest, ..) = cloth_at(gpu, 0.0, Solve::Gpu);
    assert!(common::max_difference(&picture, &rest) > 64, "the GPU cloths moved");
    // Vertex Block Descent's drape is the converged one's within the
    // reference tolerance (tests/cloth_gpu.rs measures it in centimetres).
    let rgb = |image: &image::RgbaImage| image::DynamicImage::ImageRgba8(image.clone()).into_rgb8();
    let alike = glint::compare::compare(&rgb(&reference), &rgb(&picture)).expect("same size");
    assert!(alike.matches(), "GPU against CPU: similarity {}, {} bad", alike.similarity, alike.bad_pixels);
    let (again, ..) = cloth_at(gpu, TIME, Solve::Gpu);
    assert!(picture == again, "two GPU runs to the same time draw the same bytes");
}

#[test]
fn the_gpu_cloth_uploads_no_vertices_once_running_and_the_cpu_cloth_does() {
    let Some(gpu) = common::gpu() else { return };
    if !gpu.culls_on_gpu() {
        return;
    }
    let uploads = |solve: Solve| {
        let (mut world, mut renderer) = world(gpu, solve);
        let mut target = glint::OffscreenTarget::new(gpu, 64, 64, 1).expect("target");
        let views = world.views(None);
        (1..=3)
            .map(|frame| {
                world.pose(frame as f32 * 0.05, &mut renderer).expect("posed");
                world.draw(&mut renderer, &views, &mut target).expect("frame")[0].bytes_uploaded.meshes
            })
            .collect::<Vec<u64>>()
    };
    let (on_gpu, on_cpu) = (uploads(Solve::Gpu), uploads(Solve::Converged));
    // The first frame copies every mesh into the pool once, the surfaces among them.
    assert!(on_gpu[0] >= 2 * 81 * 48, "{on_gpu:?}");
    assert_eq!(on_gpu[1..], [0, 0], "then the simulation writes the surfaces on the GPU");
    // Two 81-node surfaces, 48 bytes a vertex, every frame they move.
    assert!(on_cpu[1..].iter().all(|&b| b >= 2 * 81 * 48), "{on_cpu:?}");
}

#[test]
fn after_a_refused_frame_the_gpu_cloth_draws_what_an_unbroken_run_draws() {
    // A frame refused (a bad viewport) starts the GPU cloths again at the
    // next pose; the picture is the one a run that never failed draws. (A
    // frame that fails after its simulate stage, its steps dropped, is
    // `world/cloth.rs`'s unit test.)
    let Some(gpu) = common::gpu() else { return };
    let run = |fail: bool| {
        let (mut world, mut renderer) = world(gpu, Solve::Gpu);
        let mut target = glint::OffscreenTarget::new(gpu, 64, 64, 1).expect("target");
        let views = world.views(None);
        world.pose(0.1, &mut renderer).expect("posed");
        if fail {
            let mut bad = views.clone();
            bad[0].viewport.width = -1.0;
            assert!(world.draw(&mut renderer, &bad, &mut target).is_err(), "a bad viewport fails");
        } else {
            world.draw(&mut renderer, &views, &mut target).expect("frame");
        }
        world.pose(0.2, &mut renderer).expect("posed");
        world.draw(&mut renderer, &views, &mut target).expect("frame");
        target.read_rgba8(gpu).expect("readback")
    };
    assert!(run(true) == run(false), "the same picture after a failed frame");
}

#[test]
fn gl_and_the_webgl2_path_solve_the_gpu_cloth_on_the_cpu_and_draw_the_reference() {
    for gpu in [common::gl_gpu(), common::webgl2_gpu()].into_iter().flatten() {
        let (picture, world, stats) = cloth_at(gpu, TIME, Solve::Gpu);
        assert_eq!(world.cloth_paths(), [Some(SimPath::Cpu); 2]);
        assert_eq!(stats.simulations.cloths, PathCounts { cpu: 2, gpu: 0 });
        assert!(world.cloth_view(0).is_some());
        common::assert_matches_reference("cloth_gpu", &picture);
    }
}
