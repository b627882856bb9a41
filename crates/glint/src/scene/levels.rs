//! Levels of detail: a mesh's coarser triangle lists over its own vertices,
//! each with the geometric error it makes, from meshoptimizer's
//! attribute-aware edge-collapse simplifier (its pure-Rust port, so the web
//! page makes the same levels).
//!
//! Levels share the mesh's vertices (only indices are added; given levels,
//! below, bring their own), so a level keeps
//! the skin weights, colours and UVs of the vertices it keeps, and the
//! vertex shader's motions (swim, wind) move it as they move the full mesh.
//! Vertices on a UV or normal seam are kept apart, so seams stay closed. A
//! skinned mesh's joints weigh in as an attribute (each joint a fixed
//! direction, a vertex the weighted sum of its joints'), so vertices that
//! different joints move are not merged: a bent arm stays bent at every level.
//!
//! A level's error is in units of the mesh's bounding-sphere radius: an
//! instance whose world radius is `r` is off by at most about `error × r`.
//! The renderer picks, per instance and view, the coarsest level whose error
//! projects to at most [`View::lod_error`](crate::scene::View::lod_error) pixels.
//!
//! A mesh may instead carry levels its author made ([`with_given_levels`], from
//! glTF's `MSFT_lod`): their vertices are appended to full detail's, and each
//! one's error is measured against full detail's surface by the same crate.

use crate::scene::{Mesh, MeshError};
use meshoptimizer_rs::{
    build_lod_chain, measure_lod_quality, Attributes, LodChainAttributes, LodChainOptions, LodErrors, LodQualityMesh,
    LodQualityOptions, LodTargets, Positions, Workspace,
};

/// Levels a shape draws at most: full detail and four coarser ones.
pub const MAX_LEVELS: usize = 5;

/// Meshes with fewer triangles get no coarser levels: what they would save is
/// less than a draw of their own costs.
pub const MIN_TRIANGLES: usize = 64;

/// Meshes with more triangles get no levels (drawn at full detail): making
/// them takes 1.5–1.9 s a million triangles on one core (`benches/levels.rs`)
/// and memory to match; see `docs/limits.md`.
pub const MAX_TRIANGLES: usize = 4_000_000;

/// Each level aims at this fraction of the triangles of the one before; a
/// mesh over [`LARGE`] triangles takes longer steps, so that its coarsest
/// level is a few thousand triangles, not tens of thousands.
const STEP: f32 = 0.5;
const LARGE_STEP: f32 = 0.25;
const LARGE: usize = 16_384;

/// A level keeps at least this many triangles.
const MIN_LEVEL_TRIANGLES: usize = 8;

/// How much normals, UVs and joints weigh against position in the
/// simplifier's error (positions are relative to the mesh's extent, so these
/// are comparable).
const NORMAL_WEIGHT: f32 = 0.5;
const UV_WEIGHT: f32 = 0.5;
const JOINT_WEIGHT: f32 = 1.0;

/// Attributes per vertex: normal, UV, joints.
const ATTRIBUTES: usize = 8;

/// One coarser level of a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct DetailLevel {
    /// Triangles over the mesh's vertices.
    pub indices: Vec<u32>,
    /// The most any surface point moved, in units of the mesh's bounding-sphere
    /// radius (the sum of the chain's steps: each level is simplified from the
    /// one before). Non-decreasing along the chain.
    pub error: f32,
}

impl DetailLevel {
    /// Its triangles.
    pub fn triangles(&self) -> usize {
        self.indices.len() / 3
    }
}

/// The coarser levels of `mesh`, finest first: those its author gave
/// ([`Mesh::given_levels`]), else the simplifier's: each at most about half the
/// triangles of the one before (a quarter past [`LARGE`] triangles), at most
/// `MAX_LEVELS - 1` of them; none for a mesh under [`MIN_TRIANGLES`] or over
/// [`MAX_TRIANGLES`], or where the simplifier cannot remove a quarter of the
/// triangles (a mesh of separate triangles).
pub fn detail_levels(mesh: &Mesh) -> Vec<DetailLevel> {
    match mesh.given_levels() {
        [] => detail_levels_within(mesh, MAX_TRIANGLES),
        given => given.to_vec(),
    }
}

/// Surface samples (besides every triangle's corners) that measure a given
/// level's error: spread over full detail's area.
const ERROR_SAMPLES: f64 = 4096.0;

/// `mesh` with `coarser` as its levels of detail, finest first: each level's
/// vertices are appended to the mesh's (they must have its vertex streams) and
/// its error is the largest distance between its surface and full detail's,
/// sampled both ways, in units of the bounding-sphere radius (made
/// non-decreasing along the chain). Levels are kept while each has fewer
/// triangles than the one before and its error can be measured, at most
/// `MAX_LEVELS - 1` of them; the rest are dropped, vertices and all (compare
/// the count of [`Mesh::given_levels`] with `coarser`).
pub fn with_given_levels(mesh: Mesh, coarser: &[Mesh]) -> Result<Mesh, MeshError> {
    let mut kept: Vec<&Mesh> = Vec::new();
    let mut before = mesh.indices().len();
    for level in coarser.iter().take(MAX_LEVELS - 1) {
        if level.indices().len() >= before {
            break;
        }
        before = level.indices().len();
        kept.push(level);
    }
    loop {
        let mut merged = mesh.clone();
        let mut levels = Vec::with_capacity(kept.len());
        for level in &kept {
            let base = merged.append_vertices(level)?;
            levels.push(DetailLevel { indices: level.indices().iter().map(|&i| i + base).collect(), error: 0.0 });
        }
        let measured = measure_errors(&merged, levels);
        // A level that cannot be measured ends the chain: its vertices go too.
        if measured.len() == kept.len() {
            merged.set_given_levels(measured);
            return Ok(merged);
        }
        kept.truncate(measured.len());
        if kept.is_empty() {
            return Ok(mesh);
        }
    }
}

/// `levels` of `mesh` with their errors, measured against full detail's
/// surface (sampled at about [`ERROR_SAMPLES`] points over the larger of the
/// two), while they can be measured.
fn measure_errors(mesh: &Mesh, levels: Vec<DetailLevel>) -> Vec<DetailLevel> {
    let radius = f64::from(mesh.bounding_sphere().radius);
    let (Ok(positions), true) = (positions_of(mesh), radius > 0.0) else {
        return Vec::new();
    };
    let area = |indices: &[u32]| -> f64 {
        (indices.chunks_exact(3))
            .map(|t| {
                let p = |i: u32| glam::Vec3::from(mesh.vertices()[i as usize].position);
                f64::from((p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length() / 2.0)
            })
            .sum()
    };
    let full_area = area(mesh.indices());
    let full = LodQualityMesh::new(mesh.indices(), positions);
    let mut workspace = Workspace::default();
    let (mut error, mut measured) = (0.0f32, Vec::with_capacity(levels.len()));
    for mut level in levels {
        let mut options = LodQualityOptions::default();
        let most = full_area.max(area(&level.indices));
        options.samples_per_unit_area = if most > 0.0 { ERROR_SAMPLES / most } else { 0.0 };
        let surface = LodQualityMesh::new(&level.indices, positions);
        let Ok(quality) = measure_lod_quality(full, surface, &options, &mut workspace) else { break };
        error = error.max((quality.symmetric.max / radius) as f32);
        level.error = error;
        measured.push(level);
    }
    measured
}

/// The positions of `mesh`'s interleaved vertices, as the simplifier reads them.
fn positions_of(mesh: &Mesh) -> Result<Positions<'_>, meshoptimizer_rs::Error> {
    let floats: &[f32] = bytemuck::cast_slice(mesh.vertices());
    let stride = std::mem::size_of::<crate::scene::Vertex>() / 4;
    Positions::from_interleaved(floats, mesh.vertices().len(), stride, 0)
}

/// [`detail_levels`] for meshes of at most `most` triangles.
fn detail_levels_within(mesh: &Mesh, most: usize) -> Vec<DetailLevel> {
    let triangles = mesh.indices().len() / 3;
    let radius = mesh.bounding_sphere().radius;
    if !(MIN_TRIANGLES..=most).contains(&triangles) || radius.is_nan() || radius <= 0.0 {
        return Vec::new();
    }
    let count = mesh.vertices().len();
    let packed = attributes_of(mesh);
    let (Ok(positions), Ok(attributes)) =
        (positions_of(mesh), Attributes::from_interleaved(&packed, count, ATTRIBUTES, ATTRIBUTES, 0))
    else {
        return Vec::new();
    };
    let weights =
        [NORMAL_WEIGHT, NORMAL_WEIGHT, NORMAL_WEIGHT, UV_WEIGHT, UV_WEIGHT, JOINT_WEIGHT, JOINT_WEIGHT, JOINT_WEIGHT];
    let step = if triangles > LARGE { LARGE_STEP } else { STEP };
    let ratios: Vec<f32> = (1..MAX_LEVELS as i32).map(|k| step.powi(k)).collect();
    let options = LodChainOptions::new(LodTargets::Ratios(&ratios), LodErrors::Uniform(1.0))
        .with_attributes(LodChainAttributes::new(attributes, &weights));
    let Ok(chain) = build_lod_chain(mesh.indices(), positions, &options, &mut Workspace::default()) else {
        return Vec::new();
    };
    let mut levels: Vec<DetailLevel> = Vec::new();
    let (mut error, mut before) = (0.0f32, triangles);
    for level in chain.levels {
        // The simplifier's error is relative to the extent of its input.
        error += level.error * level.scale / radius;
        let kept = level.triangle_count;
        if kept < MIN_LEVEL_TRIANGLES || kept * 4 > before * 3 || !error.is_finite() {
            break;
        }
        levels.push(DetailLevel { indices: level.indices, error });
        before = kept;
    }
    levels
}

/// Each vertex's normal, UV and joints (0 without a skin): the weighted sum of
/// its joints' directions, each joint a fixed direction of its own.
fn attributes_of(mesh: &Mesh) -> Vec<f32> {
    let joint = |j: u16| {
        let j = f32::from(j);
        glam::Vec3::new((1.7 * j + 0.3).sin(), (2.9 * j + 1.1).sin(), (4.3 * j + 2.3).sin())
    };
    let skin = mesh.skin();
    let mut packed = Vec::with_capacity(mesh.vertices().len() * ATTRIBUTES);
    for (k, v) in mesh.vertices().iter().enumerate() {
        let joints = skin.map_or(glam::Vec3::ZERO, |skin| {
            (skin[k].joints.iter().zip(skin[k].weights)).map(|(&j, w)| joint(j) * w).sum()
        });
        packed.extend_from_slice(&[v.normal[0], v.normal[1], v.normal[2], v.uv[0], v.uv[1]]);
        packed.extend_from_slice(&joints.to_array());
    }
    packed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::procedural;

    #[test]
    fn a_spheres_levels_halve_their_triangles_and_grow_their_error() {
        let sphere = procedural::sphere(48, 32);
        let levels = detail_levels(&sphere);
        assert_eq!(levels.len(), MAX_LEVELS - 1, "{:?}", levels.iter().map(DetailLevel::triangles).collect::<Vec<_>>());
        let mut before = (sphere.indices().len() / 3, 0.0);
        for level in &levels {
            assert!(level.triangles() * 4 <= before.0 * 3, "{} after {}", level.triangles(), before.0);
            assert!(level.error >= before.1 && level.error > 0.0 && level.error < 1.0, "{}", level.error);
            assert!(level.indices.iter().all(|&i| (i as usize) < sphere.vertices().len()));
            before = (level.triangles(), level.error);
        }
    }

    #[test]
    fn small_and_too_large_meshes_have_no_levels_and_a_flat_grid_loses_nothing() {
        assert!(detail_levels(&procedural::cube()).is_empty());
        let sphere = procedural::sphere(48, 32);
        let n = sphere.indices().len() / 3;
        assert!(detail_levels_within(&sphere, n - 1).is_empty() && !detail_levels_within(&sphere, n).is_empty());
        let grid = detail_levels(&procedural::plane(16));
        assert!(
            !grid.is_empty() && grid.iter().all(|l| l.error < 1e-3),
            "{:?}",
            grid.iter().map(|l| l.error).collect::<Vec<_>>()
        );
    }
}
