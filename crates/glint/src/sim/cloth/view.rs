//! What a [`Cloth`] looks like to the renderer: its surface as a [`Mesh`] whose
//! positions and normals follow the simulation, and seed 003's debug view (every
//! edge as a thin ribbon, every pinned node as a marker).
//!
//! The renderer draws triangles only, so an edge "line" is a ribbon a fixed
//! fraction of the mean edge length wide, lying in the cloth's surface and
//! lifted off it along the normal on both sides so it shows from either side
//! without fighting the surface for depth.

use super::Cloth;
use crate::scene::{Mesh, MeshError, Vertex};
use glam::{Vec2, Vec3};

/// Ribbon width as a fraction of the mean rest edge length.
const RIBBON_WIDTH: f32 = 0.1;
/// How far each ribbon sits off the surface, as a fraction of the mean rest edge length.
const RIBBON_LIFT: f32 = 0.03;
/// Pin marker diameter as a fraction of the mean rest edge length.
const PIN_SIZE: f32 = 0.5;

/// Render meshes of one cloth, rebuilt from its positions every frame.
#[derive(Clone, Debug)]
pub struct ClothView {
    /// The cloth's surface: one vertex per node, smooth normals, UVs spread over
    /// the rest mesh's two longest extents.
    pub surface: Mesh,
    /// The debug ribbons (one quad above and one below the surface per edge), if asked for.
    pub edges: Option<Mesh>,
    /// Where the pinned nodes are now (debug markers go here).
    pub pins: Vec<Vec3>,
    /// Pin marker diameter, metres.
    pub pin_size: f32,
    /// Mean rest edge length, metres: the scale of the debug geometry.
    pub edge_length: f32,
}

impl ClothView {
    /// The view of `cloth` as it is now, with debug ribbons when `debug`. Fails
    /// when a position does not fit in single precision.
    pub fn new(cloth: &Cloth, debug: bool) -> Result<Self, MeshError> {
        let positions = positions(cloth);
        let normals = node_normals(&positions, &cloth.mesh().triangles);
        let uvs = rest_uvs(&cloth.mesh().nodes);
        let indices = cloth.mesh().triangles.iter().flatten().copied().collect();
        let surface = Mesh::from_attributes(&positions, &normals, &uvs, indices)?;
        let edges = &cloth.topology().edges;
        let rest = &cloth.mesh().nodes;
        let total: f64 = edges.iter().map(|[a, b]| rest[*a as usize].distance(rest[*b as usize])).sum();
        let edge_length = (total / edges.len().max(1) as f64) as f32;
        let pins = pinned_positions(cloth, &positions);
        let mut view = Self { surface, edges: None, pins, pin_size: PIN_SIZE * edge_length, edge_length };
        if debug {
            let ribbons = view.ribbon_vertices(cloth, &positions, &normals);
            let indices = (0..edges.len() as u32 * 2).flat_map(|q| [0, 1, 2, 0, 2, 3].map(|k| 4 * q + k)).collect();
            view.edges = Some(Mesh::from_vertices(ribbons, indices)?);
        }
        Ok(view)
    }

    /// Move every mesh to `cloth`'s current positions. Returns false (and leaves
    /// the meshes as they were) if a position is not finite.
    pub fn update(&mut self, cloth: &Cloth) -> bool {
        let positions = positions(cloth);
        let normals = node_normals(&positions, &cloth.mesh().triangles);
        if !self.surface.set_positions_normals(&positions, &normals) {
            return false;
        }
        if self.edges.is_some() {
            let ribbons = self.ribbon_vertices(cloth, &positions, &normals);
            let (p, n): (Vec<Vec3>, Vec<Vec3>) =
                ribbons.iter().map(|v| (Vec3::from(v.position), Vec3::from(v.normal))).unzip();
            if let Some(edges) = &mut self.edges {
                edges.set_positions_normals(&p, &n);
            }
        }
        self.pins = pinned_positions(cloth, &positions);
        true
    }

    /// Four vertices above and four below the surface per edge.
    fn ribbon_vertices(&self, cloth: &Cloth, positions: &[Vec3], normals: &[Vec3]) -> Vec<Vertex> {
        let (half, lift) = (0.5 * RIBBON_WIDTH * self.edge_length, RIBBON_LIFT * self.edge_length);
        let mut out = Vec::with_capacity(cloth.topology().edges.len() * 8);
        for &[a, b] in &cloth.topology().edges {
            let (pa, pb) = (positions[a as usize], positions[b as usize]);
            let n = (normals[a as usize] + normals[b as usize]).normalize_or(Vec3::Y);
            let side = (pb - pa).cross(n).normalize_or(Vec3::X) * half;
            for up in [n, -n] {
                let o = up * lift;
                for p in [pa - side + o, pb - side + o, pb + side + o, pa + side + o] {
                    out.push(Vertex {
                        position: p.to_array(),
                        normal: up.to_array(),
                        uv: [0.0, 0.0],
                        tangent: [1.0, 0.0, 0.0, 1.0],
                    });
                }
            }
        }
        out
    }
}

/// The cloth's node positions in single precision.
fn positions(cloth: &Cloth) -> Vec<Vec3> {
    cloth.positions.iter().map(|p| p.as_vec3()).collect()
}

fn pinned_positions(cloth: &Cloth, positions: &[Vec3]) -> Vec<Vec3> {
    positions.iter().enumerate().filter(|(i, _)| cloth.is_pinned(*i)).map(|(_, p)| *p).collect()
}

/// Area-weighted vertex normals (each triangle adds its unnormalised face
/// normal); a node no triangle with area touches gets +Y.
pub fn node_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut sums = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a);
        for &i in t {
            sums[i as usize] += n;
        }
    }
    sums.into_iter().map(|n| n.normalize_or(Vec3::Y)).collect()
}

/// Texture coordinates from the rest positions: the two axes along which the
/// rest mesh is longest, each mapped to 0..1 (v down the second one).
fn rest_uvs(rest: &[glam::DVec3]) -> Vec<Vec2> {
    let lo = rest.iter().fold(glam::DVec3::INFINITY, |m, p| m.min(*p));
    let hi = rest.iter().fold(glam::DVec3::NEG_INFINITY, |m, p| m.max(*p));
    let size = (hi - lo).max(glam::DVec3::splat(1e-12));
    let mut axes = [0, 1, 2];
    axes.sort_by(|&i, &j| size[j].total_cmp(&size[i]));
    let (u, v) = (axes[0].min(axes[1]), axes[0].max(axes[1]));
    rest.iter().map(|p| Vec2::new(((p[u] - lo[u]) / size[u]) as f32, ((hi[v] - p[v]) / size[v]) as f32)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::cloth::{ClothMesh, ClothParams};
    use glam::DVec3;

    fn cloth(pinned_corner: bool) -> Cloth {
        let mesh = ClothMesh::sheet(1.0, 0.5, 5, 3);
        let mut pinned = vec![false; mesh.nodes.len()];
        pinned[0] = pinned_corner;
        let params =
            ClothParams { thickness: 1e-3, young: 1e6, poisson: 0.3, density: 200.0, gravity: DVec3::NEG_Z * 9.81 };
        Cloth::new(mesh, params, &pinned).unwrap()
    }

    #[test]
    fn surface_has_a_vertex_per_node_facing_the_sheet_normal() {
        let c = cloth(false);
        let view = ClothView::new(&c, false).unwrap();
        assert_eq!(view.surface.vertices().len(), 15);
        assert_eq!(view.surface.indices().len(), 3 * c.mesh().triangles.len());
        assert!(view.surface.vertices().iter().all(|v| Vec3::from(v.normal).distance(Vec3::Z) < 1e-6));
        // uv spans 0..1 over the 1 m × 0.5 m sheet: the far corner of the first row is u = 1, v = 1.
        assert_eq!(view.surface.vertices()[4].uv, [1.0, 1.0]);
        assert_eq!(view.surface.vertices()[14].uv, [1.0, 0.0]);
        assert!(view.edges.is_none());
        assert!(view.pins.is_empty());
        assert!((view.edge_length - (0.25 + 0.25 + 0.25f32.hypot(0.25)) / 3.0).abs() < 0.05);
    }

    #[test]
    fn update_follows_the_positions_and_ribbons_straddle_the_surface() {
        let mut c = cloth(true);
        let mut view = ClothView::new(&c, true).unwrap();
        let edges = c.topology().edges.len();
        assert_eq!(view.edges.as_ref().unwrap().vertices().len(), 8 * edges);
        // Lift the sheet 2 m and fold nothing: every vertex moves by exactly that.
        for p in &mut c.positions {
            *p += DVec3::new(0.0, 0.0, 2.0);
        }
        assert!(view.update(&c));
        for (v, p) in view.surface.vertices().iter().zip(&c.positions) {
            assert_eq!(Vec3::from(v.position), p.as_vec3());
        }
        let ribbon = view.edges.as_ref().unwrap().vertices();
        let lift = RIBBON_LIFT * view.edge_length;
        assert!((ribbon[0].position[2] - (2.0 + lift)).abs() < 1e-5, "top quad above: {:?}", ribbon[0].position);
        assert!((ribbon[4].position[2] - (2.0 - lift)).abs() < 1e-5, "bottom quad below: {:?}", ribbon[4].position);
        assert_eq!(view.pins, vec![Vec3::new(0.0, 0.0, 2.0)]);
        // A NaN is refused, not drawn.
        c.positions[3].x = f64::NAN;
        assert!(!view.update(&c));
        assert_eq!(view.surface.vertices()[3].position[2], 2.0);
    }
}
