//! Core layer: a view's point and spot lights binned into its light clusters
//! on the GPU (`shader/bin_lights.wgsl`), where the view culls on the GPU:
//! the rule and the result of the CPU's binning (`render/clusters.rs`), read
//! from the same tables.
//!
//! The view's cluster array (layout in `render/frame/lights.rs`) then gives
//! every cluster room for [`MAX_CLUSTER_LIGHTS`] entries, cluster c's from
//! word `1 + 2·clusters + c·MAX_CLUSTER_LIGHTS`, so that no cluster waits on
//! another's count; the CPU writes only the light records after them. The
//! pass's counts (entries, the most in a cluster, empty clusters, overflow,
//! lights visible) come back a frame or two late, as GPU culling's do.

use crate::gpu::{bind_buffers, compute_pipeline};
use crate::render::clusters::{ClusterBoxes, ClusterGrid, LightClusters, MAX_CLUSTER_LIGHTS};
use crate::render::debug::readback::CountReadback;
use crate::render::debug::stats::ClusterStats;
use crate::render::debug::timer::{GpuTimer, Timed};
use crate::render::error::RenderError;
use crate::render::resources::gpu_array::GrowBuffer;
use glam::Vec3;

/// Words before the tables in the pass's input (`bin_lights.wgsl`'s `grid`).
const HEADER_WORDS: usize = 16;
/// Words of the pass's counts before the lights' bits.
const COUNT_WORDS: u32 = 8;
/// Invocations of a workgroup, one a light or a tile.
const WORKGROUP: u32 = 64;
/// The most depth slices the pass holds counts for (`bin_lights.wgsl`'s `MOST_SLICES`).
const MOST_SLICES: u32 = 64;
const _: () = assert!(crate::render::clusters::DEPTH_SLICES <= MOST_SLICES);

/// The binning passes' pipelines, one pair per renderer that culls on the GPU.
pub(crate) struct LightBinning {
    layout: wgpu::BindGroupLayout,
    /// Each light's slices and tiles.
    bound: wgpu::ComputePipeline,
    /// Each tile's clusters' lights.
    bin: wgpu::ComputePipeline,
}

impl LightBinning {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let storage = |binding, read_only| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("light binning"),
            entries: &[storage(0, true), storage(1, false), storage(2, false), storage(3, false)],
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("bin_lights.wgsl"),
            source: wgpu::ShaderSource::Wgsl(crate::shader::BIN_LIGHTS.into()),
        });
        let bound = compute_pipeline(device, &module, "bound", &[Some(&layout)]);
        let bin = compute_pipeline(device, &module, "bin", &[Some(&layout)]);
        Self { layout, bound, bin }
    }
}

/// A view's binning on the GPU: the pass's input and counts, and the counts
/// read back.
pub(crate) struct GpuBins {
    input: GrowBuffer,
    counts: GrowBuffer,
    /// Each light's slices and tiles, from the first pass to the second.
    bounds: GrowBuffer,
    readback: CountReadback,
    /// The input as last written.
    written: Vec<u32>,
    /// The grid of the last binning recorded.
    grid: Option<ClusterGrid>,
}

impl GpuBins {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let storage = wgpu::BufferUsages::STORAGE;
        Self {
            input: GrowBuffer::new(device, "light binning: grid and spheres", storage, 1024),
            counts: GrowBuffer::new(device, "light binning: counts", storage | wgpu::BufferUsages::COPY_SRC, 256),
            bounds: GrowBuffer::new(device, "light binning: each light's tiles", storage, 1024),
            readback: CountReadback::new(device, COUNT_WORDS),
            written: Vec::new(),
            grid: None,
        }
    }

    /// The grid of the last binning recorded.
    pub(crate) fn grid(&self) -> Option<ClusterGrid> {
        self.grid
    }

    /// The counts of the newest binning that came back (waiting for the GPU
    /// when `wait`, until the queue has made `submits` submissions), as stats.
    pub(crate) fn stats(&mut self, device: &wgpu::Device, submits: u64, wait: bool) -> Option<ClusterStats> {
        let grid = self.grid?;
        let counts = match wait {
            true => self.readback.wait_all(device, submits)?,
            false => self.readback.collect(device, submits)?,
        };
        // The counts' own grid (a frame or two old, as they are).
        let &[entries, most, empty, overflow, visible, x, y, z] = counts else { return None };
        Some(ClusterStats {
            grid: [x, y, z],
            lights_visible: visible,
            max_per_cluster: most,
            mean_per_cluster: f64::from(entries) / (f64::from(x) * f64::from(y) * f64::from(z)).max(1.0),
            empty,
            overflow,
            ..ClusterStats::of_grid(&grid, true)
        })
    }
}

/// Words of a view's cluster array where the GPU bins: word 0, the (first,
/// count) pairs and every cluster's room, padded to whole texels.
pub(crate) fn binned_words(grid: &ClusterGrid) -> usize {
    let clusters = grid.clusters();
    (1 + 2 * clusters + clusters * MAX_CLUSTER_LIGHTS as usize).next_multiple_of(4)
}

/// Whether `grid`'s clusters, each with room for [`MAX_CLUSTER_LIGHTS`], fit
/// one storage binding of `device` beside `lights` light records.
pub(crate) fn fits(device: &wgpu::Device, grid: &ClusterGrid, lights: usize) -> bool {
    let bytes = 4 * binned_words(grid) as u64 + 64 * lights as u64;
    bytes <= device.limits().max_storage_buffer_binding_size
}

/// Record the passes binning `spheres` (view-space centre and radius, by light)
/// into `grid`'s clusters in `clusters` (a buffer of [`binned_words`] words
/// and the records after them), in `encoder`; the input written through
/// `queue` when it changed. Returns the bytes written.
pub(crate) fn record_binning(
    (device, queue, binning): (&wgpu::Device, &wgpu::Queue, &LightBinning),
    bins: &mut GpuBins,
    (grid, spheres): (&ClusterGrid, &[(Vec3, f32)]),
    clusters: &wgpu::Buffer,
    encoder: &mut wgpu::CommandEncoder,
    (timer, frame, submits): (Option<&mut GpuTimer>, u64, u64),
) -> Result<u64, RenderError> {
    let input = input_words(grid, spheres);
    let mut bytes = 0;
    if bins.input.reserve(device, 4 * input.len() as u64)? || bins.written != input {
        bytes += bins.input.write(queue, 0, &input);
        bins.written = input;
    }
    let count_words = u64::from(COUNT_WORDS) + spheres.len().div_ceil(32) as u64;
    bins.counts.reserve(device, 4 * count_words)?;
    bins.bounds.reserve(device, 16 * spheres.len() as u64)?;
    encoder.clear_buffer(&bins.counts.buffer, 0, Some(4 * count_words));
    let group = bind_buffers(
        device,
        "light binning",
        &binning.layout,
        [&bins.input.buffer, clusters, &bins.counts.buffer, &bins.bounds.buffer].map(|b| b.as_entire_binding()),
    );
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("bin lights"),
            timestamp_writes: timer.as_ref().and_then(|t| t.compute_pass_writes(Timed::Lights, true, true)),
        });
        pass.set_bind_group(0, &group, &[]);
        pass.set_pipeline(&binning.bound);
        pass.dispatch_workgroups((spheres.len() as u32).div_ceil(WORKGROUP), 1, 1);
        pass.set_pipeline(&binning.bin);
        pass.dispatch_workgroups((grid.tiles[0] * grid.tiles[1]).div_ceil(WORKGROUP), 1, 1);
    }
    if let Some(timer) = timer {
        timer.resolve(encoder, Timed::Lights, frame);
    }
    bins.readback.copy(encoder, &bins.counts.buffer, 0, COUNT_WORDS, submits);
    bins.grid = Some(*grid);
    Ok(bytes)
}

/// The pass's input (`bin_lights.wgsl`'s `grid`): the header, `grid`'s box
/// tables, then `spheres`.
fn input_words(grid: &ClusterGrid, spheres: &[(Vec3, f32)]) -> Vec<u32> {
    let ClusterBoxes { xs, ys, depths, pads, perspective } = grid.boxes();
    let tables: Vec<u32> = [xs, ys, depths, pads].iter().flatten().map(|v| v.to_bits()).collect();
    let spheres_at = (HEADER_WORDS + tables.len()).next_multiple_of(4);
    let head = 1 + 2 * grid.clusters();
    let mut words = vec![0u32; HEADER_WORDS];
    words[..9].copy_from_slice(&[
        grid.tiles[0],
        grid.tiles[1],
        grid.slices,
        u32::from(perspective),
        spheres.len() as u32,
        spheres_at as u32,
        head as u32,
        (binned_words(grid) / 4) as u32,
        MAX_CLUSTER_LIGHTS,
    ]);
    words.extend(tables);
    words.resize(spheres_at, 0);
    words.extend(spheres.iter().flat_map(|(c, r)| [c.x, c.y, c.z, *r].map(f32::to_bits)));
    words
}

/// The clusters the GPU binned, from the view's cluster array read back
/// (`words`, at least [`binned_words`] of `grid`): to compare with the CPU's.
/// Their counts (`overflow`, `visible`) are the pass's, not read here: 0.
pub(crate) fn read_clusters(grid: &ClusterGrid, words: &[u32]) -> LightClusters {
    let mut ranges = Vec::with_capacity(grid.clusters());
    let mut indices = Vec::new();
    for c in 0..grid.clusters() {
        let (first, count) = (words[1 + 2 * c], words[2 + 2 * c]);
        ranges.push([indices.len() as u32, count]);
        let from = first as usize;
        indices.extend_from_slice(&words[from..from + count as usize]);
    }
    LightClusters { grid: *grid, ranges, indices, overflow: 0, visible: 0 }
}
