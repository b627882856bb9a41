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
//! exactly zero at their range (`forward.wgsl`'s window), so shading with a
//! cluster's lights changes no pixel against the loop over every light.

use crate::render::error::RenderError;
pub use crate::scene::MAX_CLUSTERED_LIGHTS;
use crate::scene::{Camera, Light, LightKind, Projection, MAX_LIGHTS};
use glam::{Mat4, Vec3, Vec4Swizzles};
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

    /// The tile column (`axis` 0) or row (1) of a pixel coordinate, clamped.
    fn tile_of(&self, axis: usize, pixel: f32) -> u32 {
        (pixel / self.tile_pixels as f32).floor().clamp(0.0, (self.tiles[axis] - 1) as f32) as u32
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

    /// View-space x (`axis` 0) or y (1) of normalised device coordinate `ndc` at `depth`.
    fn view_coordinate(&self, axis: usize, ndc: f32, depth: f32) -> f32 {
        let scale = if self.perspective { depth } else { 1.0 };
        ndc * self.half_extent[axis] * scale
    }

    /// The view-space box of cluster (`x`, `y`, `slice`), padded.
    fn cluster_box(&self, x: u32, y: u32, slice: u32) -> (Vec3, Vec3) {
        let first = if slice == 0 { self.front.min(self.near) } else { self.slice_start(slice) };
        let (d0, d1) = (first, self.slice_start(slice + 1));
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for depth in [d0, d1] {
            for px in [x, x + 1] {
                for py in [y, y + 1] {
                    let xv = self.view_coordinate(0, self.ndc(0, px * self.tile_pixels), depth);
                    let yv = self.view_coordinate(1, self.ndc(1, py * self.tile_pixels), depth);
                    let p = Vec3::new(xv, yv, -depth);
                    (lo, hi) = (lo.min(p), hi.max(p));
                }
            }
        }
        let pad = PAD * d1 + 1e-6;
        (lo - Vec3::splat(pad), hi + Vec3::splat(pad))
    }

    /// The tiles on `axis` a view-space box [`lo`, `hi`] (in front of the
    /// near plane) covers, or `None` where it is off the viewport.
    fn tile_span(&self, axis: usize, (lo, hi): (f32, f32), (d0, d1): (f32, f32)) -> Option<(u32, u32)> {
        let to_ndc = |v: f32, d: f32| v / (self.half_extent[axis] * if self.perspective { d } else { 1.0 });
        let ndcs = [to_ndc(lo, d0), to_ndc(lo, d1), to_ndc(hi, d0), to_ndc(hi, d1)];
        let (min, max) = ndcs.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &n| (a.min(n), b.max(n)));
        if max < -1.0 || min > 1.0 {
            return None;
        }
        // Pixel coordinates grow right and down.
        let pixel = |n: f32| {
            let t = if axis == 0 { (n + 1.0) * 0.5 } else { (1.0 - n) * 0.5 };
            t * self.size[axis] as f32
        };
        let (a, b) = (pixel(min), pixel(max));
        Some((self.tile_of(axis, a.min(b) - 0.5), self.tile_of(axis, a.max(b) + 0.5)))
    }
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
            (position, range, Some((direction.normalize_or(Vec3::NEG_Y), outer_angle.clamp(1e-3, FRAC_PI_2))))
        }
    };
    // As the light's record has it (`LightGpu`): at least a millimetre (a NaN
    // range is one); an endless one reaches everything, as far as a sphere can say.
    let range = if range.is_nan() { 1e-3 } else { range.clamp(1e-3, f32::MAX) };
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
    for (index, light) in lights.iter().enumerate() {
        let Some((centre, radius)) = light_bounds(light) else { continue };
        let c = (view * centre.extend(1.0)).xyz();
        let before = pairs.len();
        touch_clusters(grid, c, radius, |cluster| pairs.push((cluster as u32, index as u32)));
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

/// Call `touch` with every cluster the view-space sphere (`centre`, `radius`) meets.
fn touch_clusters(grid: &ClusterGrid, centre: Vec3, radius: f32, mut touch: impl FnMut(usize)) {
    let depth = -centre.z;
    let (d0, d1) = (depth - radius, depth + radius);
    if d1 < grid.front || d0 > grid.far {
        return;
    }
    let (s0, s1) = (grid.slice_of(d0.max(grid.near)), grid.slice_of(d1.min(grid.far)));
    // Where the sphere reaches in front of the eye, the tiles its box covers;
    // one reaching behind (or through) the eye in perspective may cover any.
    let all = |axis: usize| Some((0, grid.tiles[axis] - 1));
    let near_box = d0.max(grid.near * 0.5);
    let span = |axis: usize| {
        if grid.perspective && d0 <= grid.near * 0.5 {
            all(axis)
        } else {
            grid.tile_span(axis, (centre[axis] - radius, centre[axis] + radius), (near_box, d1))
        }
    };
    let (Some((x0, x1)), Some((y0, y1))) = (span(0), span(1)) else { return };
    for slice in s0..=s1 {
        for y in y0..=y1 {
            for x in x0..=x1 {
                let (lo, hi) = grid.cluster_box(x, y, slice);
                if centre.clamp(lo, hi).distance_squared(centre) <= radius * radius {
                    touch(grid.index(x, y, slice));
                }
            }
        }
    }
}

#[cfg(test)]
#[path = "clusters_tests.rs"]
mod tests;
