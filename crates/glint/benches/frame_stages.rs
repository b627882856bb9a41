//! Criterion micro-benchmarks of the CPU frame stages that scale with instances:
//! culling 100,000 boxes, sorting 100,000 draw items, merging them into batches.
//! Run: `cargo bench -p glint --bench frame_stages`.

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::{Vec3, Vec3A};
use glint::render::batch::merge;
use glint::render::cull::{cull_boxes, Boxes, Frustum};
use glint::render::queue::{sort, sort_key, DrawItem, Queue};
use glint::{MaterialId, ShapeId};
use rand::{Rng, SeedableRng};

const N: usize = 100_000;

fn frustum() -> Frustum {
    let view = glam::camera::rh::view::look_at_mat4(Vec3::new(0.0, 25.0, -40.0), Vec3::new(0.0, 0.0, 60.0), Vec3::Y);
    let proj = glam::camera::rh::proj::directx::perspective(60f32.to_radians(), 16.0 / 9.0, 0.1, 400.0);
    Frustum::from_view_proj(proj * view)
}

fn random_boxes(n: usize) -> Boxes {
    let mut rng = rand_pcg::Pcg32::seed_from_u64(7);
    let mut boxes = Boxes::default();
    boxes.resize(n);
    for i in 0..n {
        let c = Vec3A::new(rng.random_range(-100.0..100.0), 0.5, rng.random_range(-100.0..100.0));
        boxes.set(i, c, Vec3A::splat(0.5));
    }
    boxes
}

fn random_items(n: usize) -> Vec<DrawItem> {
    let mut rng = rand_pcg::Pcg32::seed_from_u64(8);
    (0..n as u32)
        .map(|i| {
            let (m, s) = (MaterialId(rng.random_range(0..10)), ShapeId(rng.random_range(0..10)));
            DrawItem {
                level: 0,
                copies: false,
                key: sort_key(Queue::Opaque.stage(), false, 0, 0, m, s, rng.random()),
                pipeline: 0,
                material: m,
                shape: s,
                first: i,
                count: 1,
                entry: 0,
            }
        })
        .collect()
}

fn cull(c: &mut Criterion) {
    let (frustum, boxes) = (frustum(), random_boxes(N));
    let mut group = c.benchmark_group("cull");
    group.throughput(Throughput::Elements(N as u64));
    for chunk in [2_000, N] {
        group.bench_with_input(BenchmarkId::new("boxes_in_ranges_of", chunk), &chunk, |b, &chunk| {
            let mut out = Vec::with_capacity(N);
            b.iter(|| {
                out.clear();
                for start in (0..N).step_by(chunk) {
                    cull_boxes(&frustum, &boxes, start..(start + chunk).min(N), &mut out);
                }
                black_box(out.len())
            })
        });
    }
    group.finish();
}

fn sort_and_batch(c: &mut Criterion) {
    let items = random_items(N);
    let visible: Vec<u32> = (0..N as u32).collect();
    let mut group = c.benchmark_group("queue");
    group.throughput(Throughput::Elements(N as u64));
    group.bench_function("radix_sort_100k_items", |b| {
        b.iter_batched_ref(|| items.clone(), |items| sort(items), criterion::BatchSize::LargeInput)
    });
    let mut sorted = items.clone();
    sort(&mut sorted);
    group.bench_function("merge_100k_sorted_items", |b| {
        let (mut indices, mut batches) = (Vec::with_capacity(N), Vec::new());
        b.iter(|| {
            merge(&sorted, &visible, &mut indices, &mut batches);
            black_box(batches.len())
        })
    });
    group.finish();
}

criterion_group!(benches, cull, sort_and_batch);
criterion_main!(benches);
