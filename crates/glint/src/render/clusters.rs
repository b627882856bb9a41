//! Light clusters: a view's frustum cut into screen tiles × depth slices, and
//! the point and spot lights that reach into each (clustered forward
//! shading, Olsson et al. 2012). A fragment then shades with the lights of
//! its cluster only; directional lights stay global.
//!
//! The grid, written down once here:
//! - **Tiles**: squares of a 40th of the view's width ([`TILES_ACROSS`]),
//!   but from [`MIN_TILE_PIXELS`] to [`MAX_TILE_PIXELS`] pixels a side, from
//!   the viewport's top-left corner; the last column and row may be cut
//!   short. So a cluster covers about as much of the picture at any size
//!   (32 pixels at 1280 × 720: 40 × 23 tiles), and a small picture does not
//!   crowd its clusters.
//! - **Slices**: [`DEPTH_SLICES`] slices of view depth d (distance along the
//!   view direction) between the camera's near and far planes, exponential:
//!   slice k holds `near·(far/near)^(k/S) ≤ d < near·(far/near)^((k+1)/S)`,
//!   so a slice's depth is in proportion to its distance, as a tile's width
//!   is in perspective. A fragment's slice is `⌊ln(d/near) / ln(far/near) · S⌋`,
//!   clamped into the grid ([`ClusterGrid::slice_of`]).
//! - **Cluster index** `x + tiles_x · (y + tiles_y · slice)`.
//!
//! A light reaches a cluster when its bounding sphere (a point light's
//! range; a spot light's cone, bounded as tightly as a sphere allows) meets
//! the cluster's view-space bounding box, padded by a hair so that a
//! fragment on a cluster's boundary, placed by single-precision arithmetic
//! on the GPU, still finds every light that reaches it. Lights fade to
//! exactly zero at their range (`light_clusters.wgsl`'s window), so shading with a
//! cluster's lights changes no pixel against the loop over every light.

use crate::render::error::RenderError;
pub use crate::scene::MAX_CLUSTERED_LIGHTS;
use crate::scene::{Camera, Light, LightKind, Projection, MAX_LIGHTS};
use glam::{Mat4, Vec3};
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4};

/// Tiles across a view, where [`MIN_TILE_PIXELS`] and [`MAX_TILE_PIXELS`] allow.
pub const TILES_ACROSS: u32 = 40;
/// The smallest tile side, pixels.
pub const MIN_TILE_PIXELS: u32 = 16;
/// The largest tile side, pixels.
pub const MAX_TILE_PIXELS: u32 = 64;
/// Depth slices between the near and far planes.
pub const DEPTH_SLICES: u32 = 24;
/// Most lights one cluster lists; more are counted in
/// [`LightClusters::overflow`] and left out (the lowest-numbered lights stay).
pub const MAX_CLUSTER_LIGHTS: u32 = 256;
/// The farthest a light is taken to reach, world units: an endless one's
/// bounding sphere (its square, and a box's distance's, within `f32`).
const MAX_LIGHT_REACH: f32 = 1e18;
/// How much a cluster's box is padded, in proportion to its depth.
const PAD: f32 = 1e-4;

/// Point and spot lights a frame needs before [`Clusters::Auto`] clusters them:
/// below, the unrolled loop over every light (constant indices) is cheaper.
pub const AUTO_CLUSTER_LIGHTS: usize = 8;

/// Whether views shade point and spot lights from their clusters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Clusters {
    /// Clustered when a frame has more than [`AUTO_CLUSTER_LIGHTS`] point
    /// and spot lights, or more lights than the Scene block holds
    /// ([`MAX_LIGHTS`]).
    #[default]
    Auto,
    /// Clustered whenever a frame has a point or spot light.
    On,
    /// Every fragment loops over every light (for comparison and teaching).
    Off,
}

impl Clusters {
    /// Whether a frame lit by `lights` may be drawn: with light clusters, at
    /// most [`MAX_CLUSTERED_LIGHTS`] lights of which at most
    /// [`MAX_LIGHTS`] directional; without, at most [`MAX_LIGHTS`].
    pub fn check(self, lights: &[Light]) -> Result<(), RenderError> {
        let directional = lights.iter().filter(|l| matches!(l.kind, LightKind::Directional { .. })).count();
        let (given, what, most) = if directional > MAX_LIGHTS {
            (directional, "directional lights", MAX_LIGHTS)
        } else if !self.applies(lights) && lights.len() > MAX_LIGHTS {
            (lights.len(), "lights with light clusters off", MAX_LIGHTS)
        } else if lights.len() > MAX_CLUSTERED_LIGHTS {
            (lights.len(), "lights", MAX_CLUSTERED_LIGHTS)
        } else {
            return Ok(());
        };
        Err(RenderError::TooManyLights { given, what, most })
    }

    /// Whether a frame lit by `lights` is clustered.
    pub fn applies(self, lights: &[Light]) -> bool {
        let positional = lights.iter().filter(|l| !matches!(l.kind, LightKind::Directional { .. })).count();
        match self {
            Self::Auto => positional > AUTO_CLUSTER_LIGHTS || (positional > 0 && lights.len() > MAX_LIGHTS),
            Self::On => positional > 0,
            Self::Off => false,
        }
    }
}

/// A view's cluster grid: its tiles, slices and the camera's projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClusterGrid {
    /// Tiles across and down the viewport.
    pub tiles: [u32; 2],
    /// A tile's side, pixels.
    pub tile_pixels: u32,
    /// Depth slices ([`DEPTH_SLICES`]).
    pub slices: u32,
    size: [u32; 2],
    /// View-space x and y at depth 1 (perspective) or at any depth
    /// (orthographic) of the viewport's right and top edges.
    half_extent: [f32; 2],
    perspective: bool,
    /// Where the view begins: the near plane's depth (an orthographic
    /// camera's may be 0 or behind the eye).
    front: f32,
    /// Where the slices begin (above 0) and end.
    near: f32,
    far: f32,
}

impl ClusterGrid {
    /// The grid of a view of `size` pixels (at least 1 × 1) through `camera`.
    pub fn new(camera: &Camera, size: [u32; 2]) -> Self {
        let size = [size[0].max(1), size[1].max(1)];
        let aspect = size[0] as f32 / size[1] as f32;
        let (half_extent, perspective, near, far) = match camera.projection {
            Projection::Perspective { fov_y, near, far } => {
                let t = (fov_y * 0.5).tan();
                ([t * aspect, t], true, near, far)
            }
            Projection::Orthographic { height, near, far } => ([height * 0.5 * aspect, height * 0.5], false, near, far),
        };
        // The first slice begins at the near plane, or (an orthographic
        // camera's reaching to or behind the eye) just in front of the eye
        // and reaches back to that plane.
        let front = near;
        let near = near.max(far.abs() * 1e-6).max(1e-6);
        let far = far.max(near * (1.0 + 1e-3));
        let tile = (size[0] / TILES_ACROSS).clamp(MIN_TILE_PIXELS, MAX_TILE_PIXELS);
        Self {
            tiles: [size[0].div_ceil(tile), size[1].div_ceil(tile)],
            tile_pixels: tile,
            slices: DEPTH_SLICES,
            size,
            half_extent,
            perspective,
            front,
            near,
            far,
        }
    }

    /// Clusters in the grid.
    pub fn clusters(&self) -> usize {
        (self.tiles[0] * self.tiles[1] * self.slices) as usize
    }

    /// The cluster at tile (`x`, `y`) and `slice`.
    pub fn index(&self, x: u32, y: u32, slice: u32) -> usize {
        (x + self.tiles[0] * (y + self.tiles[1] * slice)) as usize
    }

    /// The slice of view depth `depth`, clamped into the grid (the shader's rule).
    pub fn slice_of(&self, depth: f32) -> u32 {
        let (scale, bias) = self.slice_rule();
        let k = (depth.ln() * scale + bias).floor();
        if k.is_nan() {
            return 0;
        }
        k.clamp(0.0, (self.slices - 1) as f32) as u32
    }

    /// The shader's slice rule `⌊ln(depth)·scale + bias⌋` (before clamping):
    /// (scale, bias).
    pub fn slice_rule(&self) -> (f32, f32) {
        let scale = self.slices as f32 / (self.far / self.near).ln();
        (scale, -self.near.ln() * scale)
    }

    /// The view depth where `slice` begins (the far plane for `slices`).
    pub fn slice_start(&self, slice: u32) -> f32 {
        self.near * (self.far / self.near).powf(slice as f32 / self.slices as f32)
    }

    /// Normalised device coordinate (−1 left or bottom, 1 right or top) of
    /// pixel edge `pixel` on `axis`.
    fn ndc(&self, axis: usize, pixel: u32) -> f32 {
        let t = pixel.min(self.size[axis]) as f32 / self.size[axis] as f32;
        if axis == 0 {
            2.0 * t - 1.0
        } else {
            1.0 - 2.0 * t
        }
    }

    /// The tables the grid's cluster boxes are built from, on the CPU and the GPU.
    pub fn boxes(&self) -> ClusterBoxes {
        let edges = |axis: usize| -> Vec<f32> {
            (0..=self.tiles[axis]).map(|t| self.ndc(axis, t * self.tile_pixels) * self.half_extent[axis]).collect()
        };
        // Slice 0 begins at the view's front (`front`, never behind the eye in perspective).
        let first = if self.perspective { self.front.max(1e-6).min(self.near) } else { self.front.min(self.near) };
        let depths: Vec<f32> = std::iter::once(first).chain((1..=self.slices).map(|k| self.slice_start(k))).collect();
        let pads = depths[1..].iter().map(|&d1| PAD * d1 + 1e-6).collect();
        ClusterBoxes { xs: edges(0), ys: edges(1), depths, pads, perspective: self.perspective }
    }
}

/// A grid's cluster boxes as tables, read alike by the CPU's binning
/// ([`bin_lights`]) and the GPU's (`bin_lights.wgsl`), so both decide with the
/// same single-precision products. Cluster (i, j, k)'s view-space box, with
/// d0 = `depths[k]`, d1 = `depths[k + 1]` and s = d (perspective) or 1:
/// x from min(`xs[i]`·s0, `xs[i]`·s1) to max(`xs[i+1]`·s0, `xs[i+1]`·s1),
/// y from min(`ys[j+1]`·s0, `ys[j+1]`·s1) to max(`ys[j]`·s0, `ys[j]`·s1),
/// z from −d1 to −d0; each side moved out by `pads[k]`.
#[derive(Clone, Debug, PartialEq)]
pub struct ClusterBoxes {
    /// View-space x of the tile columns' edges, left to right, at depth 1
    /// (perspective) or any depth (orthographic).
    pub xs: Vec<f32>,
    /// View-space y of the tile rows' edges, top to bottom, likewise.
    pub ys: Vec<f32>,
    /// The view depths the slices begin at, and the last one's end.
    pub depths: Vec<f32>,
    /// Each slice's padding.
    pub pads: Vec<f32>,
    /// Whether x and y grow with depth.
    pub perspective: bool,
}

impl ClusterBoxes {
    /// Slice `k`'s factors for x and y at its front and back, and its padding.
    fn scales(&self, k: usize) -> (f32, f32, f32) {
        match self.perspective {
            true => (self.depths[k], self.depths[k + 1], self.pads[k]),
            false => (1.0, 1.0, self.pads[k]),
        }
    }

    /// The padded view-space box of cluster (`i`, `j`, `k`): its x, y and z
    /// ranges, each from one table's entries.
    #[cfg(test)]
    fn cluster_box(&self, i: usize, j: usize, k: usize) -> (Vec3, Vec3) {
        let ([x0, x1], [y0, y1], [z0, z1]) = (self.x_range(i, k), self.y_range(j, k), self.z_range(k));
        (Vec3::new(x0, y0, z0), Vec3::new(x1, y1, z1))
    }

    /// Column `i`'s padded x range in slice `k`.
    fn x_range(&self, i: usize, k: usize) -> [f32; 2] {
        let (s0, s1, pad) = self.scales(k);
        let (a, b) = (self.xs[i], self.xs[i + 1]);
        [(a * s0).min(a * s1) - pad, (b * s0).max(b * s1) + pad]
    }

    /// Row `j`'s padded y range in slice `k` (rows run top to bottom).
    fn y_range(&self, j: usize, k: usize) -> [f32; 2] {
        let (s0, s1, pad) = self.scales(k);
        let (top, bottom) = (self.ys[j], self.ys[j + 1]);
        [(bottom * s0).min(bottom * s1) - pad, (top * s0).max(top * s1) + pad]
    }

    /// Slice `k`'s padded z range.
    fn z_range(&self, k: usize) -> [f32; 2] {
        [-self.depths[k + 1] - self.pads[k], -self.depths[k] + self.pads[k]]
    }

    /// Whether the view-space sphere (`centre`, `radius`) meets cluster (`i`,
    /// `j`, `k`): the rule both binnings follow, term by term as `bin_lights.wgsl` has it.
    #[cfg(test)]
    fn meets(&self, (i, j, k): (usize, usize, usize), centre: Vec3, radius: f32) -> bool {
        let (lo, hi) = self.cluster_box(i, j, k);
        let d = centre.max(lo).min(hi) - centre;
        d.x * d.x + d.y * d.y + d.z * d.z <= radius * radius
    }
}

/// The square of the distance from `v` to the range [`lo`, `hi`] (0 inside):
/// one term of [`ClusterBoxes::meets`].
fn gap_squared(v: f32, [lo, hi]: [f32; 2]) -> f32 {
    let d = v.max(lo).min(hi) - v;
    d * d
}

/// A view's clusters, binned this frame and not yet uploaded
/// (`render/frame/lights.rs`).
pub(crate) enum Binned {
    /// On the CPU: the lists, written at the upload.
    Cpu(LightClusters),
    /// On the GPU, by a pass recorded already: only the records are written at the upload.
    Gpu(ClusterGrid),
}

/// Which point and spot lights reach each cluster of a view.
#[derive(Clone, Debug, PartialEq)]
pub struct LightClusters {
    /// The grid.
    pub grid: ClusterGrid,
    /// Per cluster ([`ClusterGrid::index`]): its first entry in `indices` and
    /// how many it has.
    pub ranges: Vec<[u32; 2]>,
    /// Lights (their indices in the binned slice), each cluster's in
    /// ascending order.
    pub indices: Vec<u32>,
    /// Cluster entries left out because a cluster already listed
    /// [`MAX_CLUSTER_LIGHTS`] lights.
    pub overflow: u32,
    /// Point and spot lights that reach at least one cluster.
    pub visible: u32,
}

impl LightClusters {
    /// The lights listed for cluster `index`.
    pub fn lights(&self, index: usize) -> &[u32] {
        let [first, count] = self.ranges[index];
        &self.indices[first as usize..(first + count) as usize]
    }
}

/// A sphere holding everything `light` reaches, in world space; `None` for
/// directional lights (they reach everything) and lights that reach nothing.
pub fn light_bounds(light: &Light) -> Option<(Vec3, f32)> {
    let (position, range, cone) = match light.kind {
        LightKind::Directional { .. } => return None,
        LightKind::Point { position, range } => (position, range, None),
        LightKind::Spot { position, direction, range, outer_angle, .. } => {
            // A cone of no angle (NaN) is bounded as the widest.
            let angle = if outer_angle.is_nan() { FRAC_PI_2 } else { outer_angle.clamp(1e-3, FRAC_PI_2) };
            (position, range, Some((direction.normalize_or(Vec3::NEG_Y), angle)))
        }
    };
    // As the light's record has it (`LightGpu`): at least a millimetre (a NaN
    // range is one); an endless one reaches everything, as far as a sphere
    // can say whose radius squared stays finite (the GPU may assume no infinities).
    let range = if range.is_nan() { 1e-3 } else { range.clamp(1e-3, MAX_LIGHT_REACH) };
    if !position.is_finite() {
        return None;
    }
    Some(match cone {
        // A cone of half-angle θ ≤ 45° fits in the sphere through its apex
        // and rim; a wider one in the sphere round its rim's disc (which
        // holds the apex too, and the cap, for θ up to 90°).
        Some((axis, angle)) if angle <= FRAC_PI_4 => {
            let radius = range / (2.0 * angle.cos());
            (position + axis * radius, radius)
        }
        Some((axis, angle)) => (position + axis * (range * angle.cos()), range * angle.sin()),
        None => (position, range),
    })
}

/// Bin `lights` (directional ones are skipped) into `grid`'s clusters for a
/// camera whose world-to-view matrix is `view`.
pub fn bin_lights(grid: &ClusterGrid, view: Mat4, lights: &[Light]) -> LightClusters {
    // (cluster, light) pairs in light order, then a stable counting sort.
    let mut pairs: Vec<(u32, u32)> = Vec::new();
    let mut visible = 0;
    let boxes = grid.boxes();
    let mut gaps = (Vec::new(), Vec::new()); // touch_clusters' rows and columns, made once
    for (index, light) in lights.iter().enumerate() {
        let Some((centre, radius)) = light_bounds(light) else { continue };
        let c = view.transform_point3(centre);
        let before = pairs.len();
        let touch = |cluster: usize| pairs.push((cluster as u32, index as u32));
        touch_clusters((&boxes, grid), (c, radius), &mut gaps, touch);
        visible += u32::from(pairs.len() > before);
    }
    let mut counts = vec![0u32; grid.clusters()];
    for &(cluster, _) in &pairs {
        counts[cluster as usize] += 1;
    }
    let mut ranges = Vec::with_capacity(counts.len());
    let mut overflow = 0;
    let mut first = 0;
    for &count in &counts {
        let kept = count.min(MAX_CLUSTER_LIGHTS);
        overflow += count - kept;
        ranges.push([first, 0]);
        first += kept;
    }
    let mut indices = vec![0; first as usize];
    for &(cluster, light) in &pairs {
        let [start, count] = &mut ranges[cluster as usize];
        if *count < MAX_CLUSTER_LIGHTS {
            indices[(*start + *count) as usize] = light;
            *count += 1;
        }
    }
    LightClusters { grid: *grid, ranges, indices, overflow, visible }
}

/// Call `touch` with every cluster the view-space sphere (`centre`,
/// `radius`) meets ([`ClusterBoxes::meets`]), in index order within each
/// slice. Only the slices, rows and columns whose boxes' sides the sphere
/// reaches (found by bisection, with a little to spare) are tested; `gaps`
/// holds the sphere's distances from them.
fn touch_clusters(
    (b, grid): (&ClusterBoxes, &ClusterGrid),
    (centre, radius): (Vec3, f32),
    (across, down): &mut (Vec<f32>, Vec<f32>),
    mut touch: impl FnMut(usize),
) {
    let r = radius * (1.0 + 1e-4) + 1e-6;
    let (columns, rows) = (grid.tiles[0] as usize, grid.tiles[1] as usize);
    let k0 = first_false(b.pads.len(), |k| b.z_range(k)[0] > centre.z + r);
    let k1 = first_false(b.pads.len(), |k| b.z_range(k)[1] >= centre.z - r);
    for k in k0..k1 {
        let i0 = first_false(columns, |i| b.x_range(i, k)[1] < centre.x - r);
        let i1 = first_false(columns, |i| b.x_range(i, k)[0] <= centre.x + r);
        let j0 = first_false(rows, |j| b.y_range(j, k)[0] > centre.y + r);
        let j1 = first_false(rows, |j| b.y_range(j, k)[1] >= centre.y - r);
        // The sphere's distance from each column, row and the slice, squared
        // (a box's x range depends on its column and slice only, and so on):
        // the terms of `ClusterBoxes::meets`, each worked out once.
        across.clear();
        across.extend((i0..i1).map(|i| gap_squared(centre.x, b.x_range(i, k))));
        down.clear();
        down.extend((j0..j1).map(|j| gap_squared(centre.y, b.y_range(j, k))));
        let dz = gap_squared(centre.z, b.z_range(k));
        for (j, dy) in (j0..j1).zip(down.iter()) {
            for (i, dx) in (i0..i1).zip(across.iter()) {
                if dx + dy + dz <= radius * radius {
                    touch(grid.index(i as u32, j as u32, k as u32));
                }
            }
        }
    }
}

/// The first of `0..n` where `holds` is false, for a `holds` true up to some
/// point and false from there on.
fn first_false(n: usize, holds: impl Fn(usize) -> bool) -> usize {
    let (mut lo, mut hi) = (0, n);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if holds(mid) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo
}

#[cfg(test)]
#[path = "clusters_tests.rs"]
mod tests;
