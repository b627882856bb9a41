//! Making levels of detail (`scene/levels.rs`) for a mesh of about a million
//! triangles, on the CPU: the time (median, min and max of a few runs; the
//! simplifier runs on one core) and what the levels add: their triangles and
//! the bytes of their indices (they share the mesh's vertices); then the time
//! to read them back from the level cache (`scene/level_cache.rs`: hashing the
//! mesh, reading and checking the file), the other side of "cached where that
//! pays". Run: `cargo bench -p glint --bench levels`.

use glint::scene::level_cache::{LevelCache, LevelSource};
use glint::scene::levels::detail_levels;
use glint::scene::{procedural, Mesh};
use std::time::Instant;

const RUNS: usize = 3;

fn measure(name: &str, mesh: &Mesh) {
    let triangles = mesh.indices().len() / 3;
    let mut ms = Vec::new();
    let mut levels = Vec::new();
    for _ in 0..RUNS {
        let start = Instant::now();
        levels = detail_levels(mesh);
        ms.push(start.elapsed().as_secs_f64() * 1e3);
    }
    ms.sort_by(f64::total_cmp);
    let added: usize = levels.iter().map(|l| l.indices.len() * 4).sum();
    let mesh_bytes = std::mem::size_of_val(mesh.vertices()) + std::mem::size_of_val(mesh.indices());
    println!(
        "{name}: {triangles} triangles, levels made in {:.0} ms median (min {:.0}, max {:.0}, {RUNS} runs)",
        ms[RUNS / 2],
        ms[0],
        ms[RUNS - 1]
    );
    println!(
        "  levels: {:?} triangles, errors {:?} (bounding radii); {added} bytes added ({:.1}% of the mesh's {mesh_bytes})",
        levels.iter().map(|l| l.triangles()).collect::<Vec<_>>(),
        levels.iter().map(|l| (l.error * 1e4).round() / 1e4).collect::<Vec<_>>(),
        100.0 * added as f64 / mesh_bytes as f64
    );
    let cache = LevelCache::new(std::env::temp_dir().join(format!("glint-levels-bench-{}", std::process::id())));
    assert_eq!(cache.levels(mesh).1, LevelSource::Made);
    let mut read_ms = Vec::new();
    for _ in 0..RUNS {
        let start = Instant::now();
        let (read, source) = cache.levels(mesh);
        read_ms.push(start.elapsed().as_secs_f64() * 1e3);
        assert_eq!((source, &read), (LevelSource::Read, &levels));
    }
    read_ms.sort_by(f64::total_cmp);
    println!(
        "  read back from the level cache in {:.1} ms median (min {:.1}, max {:.1})",
        read_ms[RUNS / 2],
        read_ms[0],
        read_ms[RUNS - 1]
    );
    let _ = std::fs::remove_dir_all(cache.dir());
}

fn main() {
    // 1000 × 500 quads: 1,000,000 triangles.
    measure("sphere", &procedural::sphere(1000, 500));
    // 708² quads: 1,002,528 triangles.
    measure("blob", &procedural::blob(708, 3));
}
