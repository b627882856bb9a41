//! Binning point and spot lights into a view's clusters on the CPU
//! (`render/clusters.rs`), as the GL and WebGL2 paths do every frame: the
//! 1,264 lights of `scenes/lights.scn` (at its paused time, from its camera)
//! and the first 64 and 1,024 of them, and 4,096 small lights on a square
//! grid, at 1280 × 720; and lights.scn at the browser test's 256 × 160.
//! Median, min and max of 200 runs. Run: `cargo bench -p
//! glint --bench clusters`.

use glam::Vec3;
use glint::render::clusters::{bin_lights, ClusterGrid};
use glint::scene::LightKind;
use glint::Light;
use std::path::Path;
use std::time::Instant;

const RUNS: usize = 200;
const SIZE: [u32; 2] = [1280, 720];
/// The web page's picture in its browser test.
const PAGE: [u32; 2] = [256, 160];

fn measure(name: &str, camera: &glint::Camera, lights: &[Light]) {
    measure_at(name, camera, lights, SIZE);
}

fn measure_at(name: &str, camera: &glint::Camera, lights: &[Light], size: [u32; 2]) {
    let grid = ClusterGrid::new(camera, size);
    let view = camera.view();
    let mut ms = Vec::with_capacity(RUNS);
    let mut binned = bin_lights(&grid, view, lights);
    for _ in 0..RUNS {
        let start = Instant::now();
        binned = bin_lights(&grid, view, lights);
        ms.push(start.elapsed().as_secs_f64() * 1e3);
    }
    ms.sort_by(f64::total_cmp);
    println!(
        "{name}: {} lights ({} visible) into {} clusters in {:.3} ms median (min {:.3}, max {:.3}, {RUNS} runs); {} entries, {} at most",
        lights.len(),
        binned.visible,
        grid.clusters(),
        ms[RUNS / 2],
        ms[0],
        ms[RUNS - 1],
        binned.indices.len(),
        binned.ranges.iter().map(|r| r[1]).max().unwrap_or(0)
    );
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let desc = glint::asset::load_scene(&root.join("scenes/lights.scn")).expect("scenes/lights.scn");
    let camera = desc.cameras[0];
    let positional: Vec<Light> =
        desc.lights.iter().filter(|l| !matches!(l.kind, LightKind::Directional { .. })).copied().collect();
    measure("lights.scn, first 64", &camera, &positional[..64]);
    measure("lights.scn, first 1,024", &camera, &positional[..1024]);
    measure("lights.scn", &camera, &positional);
    measure_at("lights.scn at the page's 256 x 160", &camera, &positional, PAGE);
    // 64 × 64 lights 0.5 m apart on the ground, seen from above and aside.
    let grid: Vec<Light> = (0..4096)
        .map(|i| {
            Light::point(
                Vec3::new((i % 64) as f32 * 0.5 - 16.0, 0.3, (i / 64) as f32 * 0.5 - 16.0),
                Vec3::ONE,
                1.0,
                0.8,
            )
        })
        .collect();
    let camera = glint::Camera::perspective(60.0, 0.1, 100.0).looking_at(Vec3::new(0.0, 12.0, 24.0), Vec3::ZERO);
    measure("4,096 on a grid", &camera, &grid);
}
