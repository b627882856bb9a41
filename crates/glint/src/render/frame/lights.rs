//! The view's lights stage: where its variant clusters
//! ([`FrameVariant::clustered`](crate::render::frame_variant::FrameVariant)),
//! its point and spot lights binned into its cluster grid on the CPU
//! (`render/clusters.rs`), and at the upload the clusters written for
//! `forward.wgsl`'s `CLUSTERED` loops: the cluster words and the lights' records.

use crate::render::clusters::{bin_lights, ClusterGrid};
use crate::render::debug::stats::{ClusterStats, FrameStats, UploadStats};
use crate::render::error::RenderError;
use crate::render::resources::blocks::SceneGpu;
use crate::render::resources::Resources;
use crate::render::view::ViewFrame;
use crate::render::views::ViewGpu;
use crate::scene::{Light, LightKind};

/// Bin `lights`' point and spot lights (in the order the Scene block holds
/// them) into `view`'s clusters, kept in `gpu` until the upload; counted in `stats`.
pub(crate) fn cluster_lights(gpu: &mut ViewGpu, view: &ViewFrame, lights: &[Light], stats: &mut FrameStats) {
    gpu.clusters.binned = None;
    if !view.variant.clustered {
        return;
    }
    let grid = ClusterGrid::new(&view.camera, view.size);
    let positional: Vec<Light> =
        lights.iter().filter(|l| !matches!(l.kind, LightKind::Directional { .. })).copied().collect();
    let clusters = bin_lights(&grid, view.view, &positional);
    let counts = clusters.ranges.iter().map(|r| r[1]);
    stats.light_clusters = Some(ClusterStats {
        grid: [grid.tiles[0], grid.tiles[1], grid.slices],
        tile_pixels: grid.tile_pixels,
        lights_visible: clusters.visible,
        max_per_cluster: counts.clone().max().unwrap_or(0),
        mean_per_cluster: clusters.indices.len() as f64 / grid.clusters() as f64,
        empty: counts.filter(|&c| c == 0).count() as u32,
        overflow: clusters.overflow,
    });
    gpu.clusters.binned = Some(clusters);
}

/// Write the view's binned clusters, if any (only when they changed since
/// the last frame), and return `scene` with their grid. One array of 16-byte
/// texels (`forward.wgsl`'s `cluster_texel`): words, four a texel — word 0 the
/// texel the light records begin at, then per cluster the word its entries
/// begin at and their count, then the entries — and after them the records
/// of `lights`' point and spot lights, in order, each with its first shadow
/// view (`shadowed`, by light), four texels each.
pub(crate) fn upload_clusters(
    res: &Resources,
    gpu: &mut ViewGpu,
    (scene, lights, shadowed): (SceneGpu, &[Light], &[Option<u32>]),
    bytes: &mut UploadStats,
) -> Result<SceneGpu, RenderError> {
    let Some(clusters) = gpu.clusters.binned.take() else { return Ok(scene) };
    let scene = scene.with_clusters(&clusters.grid);
    let head = 1 + 2 * clusters.ranges.len() as u32;
    let mut words: Vec<u32> = std::iter::once(0)
        .chain(clusters.ranges.iter().flat_map(|&[first, count]| [head + first, count]))
        .chain(clusters.indices.iter().copied())
        .collect();
    words.resize(words.len().next_multiple_of(4), 0);
    words[0] = (words.len() / 4) as u32;
    let records = (lights.iter().enumerate())
        .filter(|(_, l)| !matches!(l.kind, LightKind::Directional { .. }))
        .map(|(k, l)| l.to_gpu(shadowed.get(k).copied().flatten()));
    let mut texels: Vec<[u32; 4]> = bytemuck::cast_slice(&words).to_vec();
    for record in records {
        texels.extend_from_slice(bytemuck::cast_slice(&[record]));
    }
    if gpu.clusters.data.reserve(&res.device, 16, texels.len())? {
        gpu.rebind_scene(&res.shared());
        gpu.clusters.written.clear();
    }
    if gpu.clusters.written != texels {
        bytes.lights += gpu.clusters.data.write(&res.queue, 0, &texels);
        gpu.clusters.written = texels;
    }
    Ok(scene)
}
