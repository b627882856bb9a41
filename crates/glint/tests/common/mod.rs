//! Shared test helpers: one GPU per test binary (skipped when there is none),
//! rendering a `.scn` file, and reference-image comparison.
#![allow(dead_code)] // each test binary uses its own subset

use glint::compare::{BAD_PIXEL_DELTA, MAX_BAD_PIXELS, MIN_SIMILARITY};
use glint::{FrameStats, Gpu, OffscreenTarget, Renderer};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The repository root (reference images and scenes live there).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The shared GPU, or `None` (after a message) when this machine has no adapter.
/// With `GLINT_REQUIRE_ADAPTER=1` a missing adapter fails the test instead.
pub fn gpu() -> Option<&'static Gpu> {
    static GPU: OnceLock<Result<Gpu, String>> = OnceLock::new();
    shared(&GPU, Gpu::headless)
}

/// A GPU on wgpu's GL backend (Mesa llvmpipe through EGL here), like [`gpu`].
pub fn gl_gpu() -> Option<&'static Gpu> {
    static GPU: OnceLock<Result<Gpu, String>> = OnceLock::new();
    shared(&GPU, || Gpu::headless_on(wgpu::Backends::GL))
}

/// The default GPU drawing as on WebGL2 ([`Gpu::with_webgl2_limits`]), like [`gpu`].
pub fn webgl2_gpu() -> Option<&'static Gpu> {
    static GPU: OnceLock<Result<Gpu, String>> = OnceLock::new();
    shared(&GPU, || Gpu::headless().and_then(Gpu::with_webgl2_limits))
}

/// The GL backend's GPU drawing as on WebGL2, like [`gpu`].
pub fn gl_webgl2_gpu() -> Option<&'static Gpu> {
    static GPU: OnceLock<Result<Gpu, String>> = OnceLock::new();
    shared(&GPU, || Gpu::headless_on(wgpu::Backends::GL).and_then(Gpu::with_webgl2_limits))
}

/// The largest difference of any channel of any pixel.
pub fn max_difference(a: &image::RgbaImage, b: &image::RgbaImage) -> u8 {
    assert_eq!(a.dimensions(), b.dimensions());
    a.pixels().zip(b.pixels()).flat_map(|(p, q)| p.0.iter().zip(q.0).map(|(x, y)| x.abs_diff(y))).max().unwrap_or(0)
}

fn shared(
    cell: &'static OnceLock<Result<Gpu, String>>,
    create: impl FnOnce() -> Result<Gpu, glint::GpuError>,
) -> Option<&'static Gpu> {
    match cell.get_or_init(|| create().map_err(|e| e.to_string())) {
        Ok(gpu) => Some(gpu),
        Err(e) if std::env::var("GLINT_REQUIRE_ADAPTER").as_deref() == Ok("1") => {
            panic!("GLINT_REQUIRE_ADAPTER=1 but there is no adapter: {e}")
        }
        Err(e) => {
            eprintln!("skipping GPU test: {e}");
            None
        }
    }
}

/// Load a scene file with the repository root as an asset root (the tests run
/// in the crate's folder, so the current directory does not widen it).
pub fn load_scene(path: &Path) -> glint::asset::SceneDesc {
    let options = glint::asset::LoadOptions { asset_roots: vec![repo_root()], ..Default::default() };
    glint::asset::load_scene_with(path, options).unwrap_or_else(|e| panic!("{e}"))
}

/// Render one frame of a scene under `tests/scenes/` at `size`×`size` with 4× MSAA.
pub fn render_scene(gpu: &Gpu, name: &str, size: u32) -> (image::RgbaImage, FrameStats) {
    render_file(gpu, &repo_root().join("tests/scenes").join(format!("{name}.scn")), size, glint::Culling::Gpu)
}

/// Render one frame of the scene file at `path`, culled as `culling` says.
pub fn render_file(gpu: &Gpu, path: &Path, size: u32, culling: glint::Culling) -> (image::RgbaImage, FrameStats) {
    let desc = load_scene(path);
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    render_desc(gpu, &desc, size, culling)
}

/// Render one frame of a loaded scene from its first camera, `size`×`size`, 4× MSAA.
pub fn render_desc(
    gpu: &Gpu,
    desc: &glint::asset::SceneDesc,
    size: u32,
    culling: glint::Culling,
) -> (image::RgbaImage, FrameStats) {
    render_sized(gpu, desc, (size, size), 4, culling)
}

/// Render one frame of a loaded scene from its first camera at `width`×`height`
/// with `samples` MSAA samples, every mesh at full detail (the references'
/// pictures and counts; `render_with_levels` draws levels of detail).
pub fn render_sized(
    gpu: &Gpu,
    desc: &glint::asset::SceneDesc,
    (width, height): (u32, u32),
    samples: u32,
    culling: glint::Culling,
) -> (image::RgbaImage, FrameStats) {
    render_levels(gpu, desc, ((width, height), samples), (culling, false))
}

/// Render one frame of a scene under `tests/scenes/` at `size`×`size` with
/// 4× MSAA, culled on the GPU where the adapter can, with levels of detail.
pub fn render_with_levels(gpu: &Gpu, name: &str, size: u32) -> (image::RgbaImage, FrameStats) {
    let desc = load_scene(&repo_root().join("tests/scenes").join(format!("{name}.scn")));
    render_levels(gpu, &desc, ((size, size), 4), (glint::Culling::Gpu, true))
}

/// One frame of `desc` from its first camera, levels of detail on where `levels`.
fn render_levels(
    gpu: &Gpu,
    desc: &glint::asset::SceneDesc,
    ((width, height), samples): ((u32, u32), u32),
    (culling, levels): (glint::Culling, bool),
) -> (image::RgbaImage, FrameStats) {
    let mut renderer = Renderer::new(gpu);
    renderer.set_levels_of_detail(levels);
    let entities = renderer.place_scene(desc).entities;
    let mut target = OffscreenTarget::new(gpu, width, height, samples).expect("target");
    let view = glint::View::new(desc.cameras[0]).with_culling(culling).with_transparency(desc.transparency);
    let stats = renderer.render(&entities, view, desc.lighting(), &mut target).expect("frame");
    (target.read_rgba8(gpu).expect("readback"), stats)
}

/// Compare `actual` with `tests/reference/NAME.png`.
///
/// `GLINT_BLESS=1` writes `actual` as the new reference instead. On mismatch the
/// actual image and a diff map go to `tests/output/` and the test fails naming them.
pub fn assert_matches_reference(name: &str, actual: &image::RgbaImage) {
    let root = repo_root();
    let reference_path = root.join("tests/reference").join(format!("{name}.png"));
    if std::env::var("GLINT_BLESS").as_deref() == Ok("1") {
        actual.save(&reference_path).expect("write reference");
        eprintln!("blessed {}", reference_path.display());
        return;
    }
    let expected = image::open(&reference_path)
        .unwrap_or_else(|e| panic!("{}: {e} (run with GLINT_BLESS=1 to create it)", reference_path.display()))
        .into_rgb8();
    let actual_rgb = image::DynamicImage::ImageRgba8(actual.clone()).into_rgb8();
    assert_eq!(expected.dimensions(), actual_rgb.dimensions(), "{name}: size differs from the reference");
    let comparison = glint::compare::compare(&expected, &actual_rgb).expect("same size");
    if !comparison.matches() {
        let out = root.join("tests/output");
        std::fs::create_dir_all(&out).expect("create tests/output");
        let actual_path = out.join(format!("{name}.actual.png"));
        let diff_path = out.join(format!("{name}.diff.png"));
        actual.save(&actual_path).expect("write actual");
        comparison.diff.save(&diff_path).expect("write diff");
        panic!(
            "{name}: differs from {} (similarity {:.4} < {MIN_SIMILARITY} or {:.3}% pixels off by >{BAD_PIXEL_DELTA} > {:.3}%)\n  actual: {}\n  diff:   {}",
            reference_path.display(),
            comparison.similarity,
            comparison.bad_pixels * 100.0,
            MAX_BAD_PIXELS * 100.0,
            actual_path.display(),
            diff_path.display()
        );
    }
}

/// The 0.1 m shell cantilever of `cloth_published.rs` on a regular
/// equilateral sheet (the published mesh's lattice), E = 2·10⁸, clamped where
/// x ≤ 0.01 m, with `damping`, solved to convergence.
pub fn cantilever(damping: f64) -> glint::sim::cloth::Cloth {
    use glint::sim::cloth::{Cloth, ClothMesh, ClothParams};
    let gravity = glam::DVec3::new(0.0, 0.0, -9.81);
    let params = ClothParams { thickness: 1e-3, young: 2e8, poisson: 0.5, density: 1200.0, gravity };
    let mesh = ClothMesh::sheet(0.1, 0.02, 41, 9);
    let pinned: Vec<bool> = mesh.nodes.iter().map(|p| p.x <= 0.01 + 1e-9).collect();
    let mut cloth = Cloth::new(mesh, params, &pinned).expect("cloth");
    cloth.set_damping(damping);
    cloth
}

/// The lowest node's height (z).
pub fn tip(cloth: &glint::sim::cloth::Cloth) -> f64 {
    cloth.positions.iter().map(|p| p.z).fold(f64::INFINITY, f64::min)
}
