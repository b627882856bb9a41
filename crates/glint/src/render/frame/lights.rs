//! The view's lights stage: where its variant clusters
//! ([`FrameVariant::clustered`](crate::render::frame_variant::FrameVariant)),
//! its point and spot lights binned into its cluster grid — by a compute
//! pass where the view culls on the GPU (`render/gpu_driven/light_binning.rs`),
//! else on the CPU (`render/clusters.rs`), by the same rule with the same
//! result — and at the upload the clusters written for `forward.wgsl`'s
//! `CLUSTERED` loops: the cluster words and the lights' records.
//!
//! The view's cluster array, 16-byte texels of four words: word 0 the texel
//! the light records begin at; from word 1, per cluster, the word its
//! entries begin at and their count; then the entries (binned on the CPU,
//! each cluster's after the one before; on the GPU, every cluster with room
//! for `MAX_CLUSTER_LIGHTS`); then, from a whole texel, the records of the
//! point and spot lights in order, four texels each.

use crate::render::clusters::{bin_lights, light_bounds, Binned, ClusterGrid, LightClusters};
use crate::render::debug::explain::PassType;
use crate::render::debug::stats::{ClusterStats, FrameStats, UploadStats};
use crate::render::error::RenderError;
use crate::render::frame::state::Frame;
use crate::render::gpu_driven::light_binning::{binned_words, fits, record_binning, GpuBins};
use crate::render::resources::blocks::SceneGpu;
use crate::render::resources::Resources;
use crate::render::view::ViewFrame;
use crate::render::views::ViewGpu;
use crate::scene::{Culling, Light, LightKind};

/// Bin `lights`' point and spot lights (in the order the Scene block holds
/// them) into `view`'s clusters: on the GPU where it culls there (the pass
/// recorded into `frame`'s encoder), else on the CPU, kept in `gpu` until the
/// upload; counted in `stats` (on the GPU, from a frame or two before).
pub(crate) fn cluster_lights(
    res: &mut Resources,
    frame: &mut Frame,
    (gpu, view): (&mut ViewGpu, &ViewFrame),
    lights: &[Light],
    stats: &mut FrameStats,
) -> Result<(), RenderError> {
    gpu.clusters.binned = None;
    if !view.variant.clustered {
        return Ok(());
    }
    let grid = ClusterGrid::new(&view.camera, view.size);
    let positional: Vec<Light> =
        lights.iter().filter(|l| !matches!(l.kind, LightKind::Directional { .. })).copied().collect();
    let on_gpu = view.culling == Culling::Gpu
        && gpu.clusters.data.buffer().is_some()
        && fits(&res.device, &grid, positional.len());
    let Some(binning) = res.light_binning.as_ref().filter(|_| on_gpu) else {
        let clusters = bin_lights(&grid, view.view, &positional);
        stats.light_clusters = Some(ClusterStats::of(&clusters));
        gpu.clusters.binned = Some(Binned::Cpu(clusters));
        return Ok(());
    };
    // Where a light reaches; one that reaches nothing (`light_bounds`) far behind the eye.
    let nowhere = (glam::Vec3::new(0.0, 0.0, 1e30), 0.0);
    let spheres: Vec<_> = (positional.iter())
        .map(|l| light_bounds(l).map_or(nowhere, |(c, r)| (view.view.transform_point3(c), r)))
        .collect();
    let texels = binned_words(&grid) / 4 + 4 * positional.len();
    if gpu.clusters.data.reserve(&res.device, 16, texels)? {
        gpu.rebind_scene(&res.shared());
        gpu.clusters.written.clear();
    }
    let buffer = gpu.clusters.data.buffer().expect("a storage buffer");
    let bins = gpu.clusters.bins.get_or_insert_with(|| GpuBins::new(&res.device));
    frame.outline.enter(&mut frame.encoder, "lights");
    frame.outline.pass("bin lights", PassType::Compute, &[]);
    let submits = res.queue.submits();
    let at = (res.gpu_timer.as_mut(), frame.index, submits);
    let device = (&res.device, &*res.queue, binning);
    let written = record_binning(device, bins, (&grid, &spheres), buffer, &mut frame.encoder, at);
    frame.outline.leave(&mut frame.encoder);
    stats.bytes_uploaded.lights += written?;
    stats.light_clusters = Some(bins.stats(&res.device, submits, false).unwrap_or(ClusterStats::of_grid(&grid, true)));
    gpu.clusters.binned = Some(Binned::Gpu(grid));
    Ok(())
}

/// Write the view's binned clusters, if any, and return `scene` with their
/// grid (and the heat map where [`Renderer::set_cluster_heat_map`](crate::Renderer::set_cluster_heat_map) asked for it): binned on the CPU, every word and record; on the GPU, the records
/// (only when they changed since the last frame).
pub(crate) fn upload_clusters(
    res: &Resources,
    gpu: &mut ViewGpu,
    (scene, lights, shadowed): (SceneGpu, &[Light], &[Option<u32>]),
    bytes: &mut UploadStats,
) -> Result<SceneGpu, RenderError> {
    let Some(binned) = gpu.clusters.binned.take() else { return Ok(scene) };
    let (grid, mut texels) = match binned {
        Binned::Cpu(clusters) => (clusters.grid, cluster_texels(&clusters)),
        // Marked apart from any CPU-binned array, whose word 1 is below `u32::MAX`.
        Binned::Gpu(grid) => (grid, vec![[(binned_words(&grid) / 4) as u32, u32::MAX, 0, 0]]),
    };
    let records_at = texels[0][0] as usize;
    let records = (lights.iter().enumerate())
        .filter(|(_, l)| !matches!(l.kind, LightKind::Directional { .. }))
        .map(|(k, l)| l.to_gpu(shadowed.get(k).copied().flatten()));
    for record in records {
        texels.extend_from_slice(bytemuck::cast_slice(&[record]));
    }
    let gpu_binned = texels[0][1] == u32::MAX;
    let end = if gpu_binned { records_at + texels.len() - 1 } else { texels.len() };
    if gpu.clusters.data.reserve(&res.device, 16, end)? {
        gpu.rebind_scene(&res.shared());
        gpu.clusters.written.clear();
    }
    if gpu.clusters.written != texels {
        bytes.lights += match gpu_binned {
            true => gpu.clusters.data.write(&res.queue, records_at as u64, &texels[1..]),
            false => gpu.clusters.data.write(&res.queue, 0, &texels),
        };
        gpu.clusters.written = texels;
    }
    Ok(scene.with_clusters(&grid, res.cluster_heat_map))
}

/// The words of clusters binned on the CPU, four a texel, padded to whole
/// texels, word 0 the texel after them.
fn cluster_texels(clusters: &LightClusters) -> Vec<[u32; 4]> {
    let head = 1 + 2 * clusters.ranges.len() as u32;
    let mut words: Vec<u32> = std::iter::once(0)
        .chain(clusters.ranges.iter().flat_map(|&[first, count]| [head + first, count]))
        .chain(clusters.indices.iter().copied())
        .collect();
    words.resize(words.len().next_multiple_of(4), 0);
    words[0] = (words.len() / 4) as u32;
    bytemuck::cast_slice(&words).to_vec()
}
