//! Beginner layer: procedural shapes ([`ShapeKind`]), built as plain [`Mesh`]es. Every shape fits the unit box [−0.5, 0.5]³
//! (scale it with the entity's transform), has unit normals, UVs in 0..1,
//! MikkTSpace tangents and counter-clockwise front faces seen from outside.

use crate::scene::Mesh;
use glam::{Vec2, Vec3};
use std::f32::consts::TAU;

/// The built-in shape kinds, as named in `.scn` files.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ShapeKind {
    /// Unit cube, 24 vertices (hard edges).
    Cube,
    /// UV sphere of radius 0.5.
    Sphere,
    /// 1×1 plane in XZ facing +Y.
    Plane,
    /// Capped cylinder, radius 0.5, height 1.
    Cylinder,
    /// Capped cone, base radius 0.5 at y = −0.5, apex at y = 0.5.
    Cone,
    /// Torus around Y, ring radius 0.35, tube radius 0.15.
    Torus,
    /// A lumpy sphere: `detail` rings × `detail` segments (2·detail² − 2·detail
    /// triangles), displaced by smooth noise chosen by `seed`, so every seed is a
    /// different mesh. For benchmarks and organic props.
    Blob {
        /// Rings and segments, 3..=1024.
        detail: u32,
        /// Picks the lumps.
        seed: u32,
    },
}

impl ShapeKind {
    /// Every fixed kind, in a stable order (blobs are parameterised; see [`ShapeKind::Blob`]).
    pub const ALL: [ShapeKind; 6] =
        [ShapeKind::Cube, ShapeKind::Sphere, ShapeKind::Plane, ShapeKind::Cylinder, ShapeKind::Cone, ShapeKind::Torus];

    /// The `.scn` name of this kind.
    pub fn name(self) -> &'static str {
        match self {
            ShapeKind::Cube => "cube",
            ShapeKind::Sphere => "sphere",
            ShapeKind::Plane => "plane",
            ShapeKind::Cylinder => "cylinder",
            ShapeKind::Cone => "cone",
            ShapeKind::Torus => "torus",
            ShapeKind::Blob { .. } => "blob",
        }
    }

    /// The fixed kind named `name` in a `.scn` file (`blob` needs its parameters:
    /// see [`ShapeKind::Blob`]).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// Build the mesh of this kind at default tessellation.
    pub fn mesh(self) -> Mesh {
        match self {
            ShapeKind::Cube => cube(),
            ShapeKind::Sphere => sphere(40, 20),
            ShapeKind::Plane => plane(1),
            ShapeKind::Cylinder => cylinder(32),
            ShapeKind::Cone => cone(32),
            ShapeKind::Torus => torus(32, 16),
            ShapeKind::Blob { detail, seed } => blob(detail, seed),
        }
    }
}

/// Collects parametric patches into one mesh.
#[derive(Default)]
struct Builder {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    indices: Vec<u32>,
}

impl Builder {
    /// Add an (nu+1)×(nv+1) vertex grid over (u, v) ∈ [0,1]²; `f` gives position,
    /// normal and uv. Each triangle is wound so its face normal agrees with its vertex
    /// normals (counter-clockwise from the side the normals face); triangles that
    /// collapse to a point or line (poles, apexes, cap centres) are left out.
    fn grid(&mut self, nu: u32, nv: u32, f: impl Fn(f32, f32) -> (Vec3, Vec3, Vec2)) {
        let base = self.positions.len() as u32;
        for j in 0..=nv {
            for i in 0..=nu {
                let (p, n, uv) = f(i as f32 / nu as f32, j as f32 / nv as f32);
                self.positions.push(p);
                self.normals.push(n.normalize());
                self.uvs.push(uv);
            }
        }
        let at = |i: u32, j: u32| base + j * (nu + 1) + i;
        for j in 0..nv {
            for i in 0..nu {
                let quad = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
                self.triangle(quad[0], quad[1], quad[2]);
                self.triangle(quad[0], quad[2], quad[3]);
            }
        }
    }

    fn triangle(&mut self, a: u32, b: u32, c: u32) {
        let p = |i: u32| self.positions[i as usize];
        let face = (p(b) - p(a)).cross(p(c) - p(a));
        if face.length_squared() < 1e-14 {
            return;
        }
        let n = self.normals[a as usize] + self.normals[b as usize] + self.normals[c as usize];
        if face.dot(n) >= 0.0 {
            self.indices.extend([a, b, c]);
        } else {
            self.indices.extend([a, c, b]);
        }
    }

    fn finish(self) -> Mesh {
        Mesh::from_attributes(&self.positions, &self.normals, &self.uvs, self.indices)
            .expect("procedural shapes are valid by construction")
    }
}

/// Unit cube with one flat patch per face; each face's image reads upright from outside.
pub fn cube() -> Mesh {
    let mut b = Builder::default();
    for n in [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z] {
        // Image "up" on the face: +Y on the sides, −Z on top, +Z underneath.
        let up = if n.y > 0.5 {
            Vec3::NEG_Z
        } else if n.y < -0.5 {
            Vec3::Z
        } else {
            Vec3::Y
        };
        let (s, t) = (up.cross(n), -up); // s: image right, t: image down
        b.grid(1, 1, |u, v| (n * 0.5 + s * (u - 0.5) + t * (v - 0.5), n, Vec2::new(u, v)));
    }
    b.finish()
}

/// 1×1 plane in XZ facing +Y, `divisions` quads per side.
pub fn plane(divisions: u32) -> Mesh {
    let mut b = Builder::default();
    b.grid(divisions, divisions, |u, v| (Vec3::new(u - 0.5, 0.0, v - 0.5), Vec3::Y, Vec2::new(u, v)));
    b.finish()
}

/// Direction around Y at angle `phi` (0 → +Z, growing towards +X).
fn around_y(phi: f32) -> Vec3 {
    Vec3::new(phi.sin(), 0.0, phi.cos())
}

/// UV sphere of radius 0.5 with `segments` around and `rings` from pole to pole.
pub fn sphere(segments: u32, rings: u32) -> Mesh {
    let mut b = Builder::default();
    b.grid(segments, rings, |u, v| {
        let theta = v * std::f32::consts::PI;
        // sin(π) is −8.7e-8 in f32, not 0: snap the poles so each is one exact point.
        let (ring, height) = if v == 0.0 || v == 1.0 { (0.0, theta.cos().round()) } else { (theta.sin(), theta.cos()) };
        let d = around_y(u * TAU) * ring + Vec3::Y * height;
        (d * 0.5, d, Vec2::new(u, v))
    });
    b.finish()
}

/// A disc cap of radius 0.5 at height `y`, facing +Y or −Y, mapped like the cube's faces.
fn cap(b: &mut Builder, segments: u32, y: f32, up: bool) {
    let n = if up { Vec3::Y } else { Vec3::NEG_Y };
    b.grid(segments, 1, |u, v| {
        let p = around_y(u * TAU) * (0.5 * v) + Vec3::Y * y;
        let uv_v = if up { 0.5 + p.z } else { 0.5 - p.z };
        (p, n, Vec2::new(0.5 + p.x, uv_v))
    });
}

/// Capped cylinder, radius 0.5, height 1, `segments` around.
pub fn cylinder(segments: u32) -> Mesh {
    let mut b = Builder::default();
    b.grid(segments, 1, |u, v| {
        let d = around_y(u * TAU);
        (d * 0.5 + Vec3::Y * (0.5 - v), d, Vec2::new(u, v))
    });
    cap(&mut b, segments, 0.5, true);
    cap(&mut b, segments, -0.5, false);
    b.finish()
}

/// Capped cone, base radius 0.5 at y = −0.5, apex at y = 0.5, `segments` around.
pub fn cone(segments: u32) -> Mesh {
    let mut b = Builder::default();
    b.grid(segments, 8, |u, v| {
        let d = around_y(u * TAU);
        // Slant normal of a cone with radius 0.5 over height 1: (d·1, 0.5).
        let n = d + Vec3::Y * 0.5;
        (d * (0.5 * v) + Vec3::Y * (0.5 - v), n, Vec2::new(u, v))
    });
    cap(&mut b, segments, -0.5, false);
    b.finish()
}

/// Torus around Y: ring radius 0.35, tube radius 0.15.
pub fn torus(segments: u32, sides: u32) -> Mesh {
    const RING: f32 = 0.35;
    const TUBE: f32 = 0.15;
    let mut b = Builder::default();
    b.grid(segments, sides, |u, v| {
        let out = around_y(u * TAU);
        let theta = -v * TAU;
        let d = out * theta.cos() + Vec3::Y * theta.sin();
        (out * RING + d * TUBE, d, Vec2::new(u, v))
    });
    b.finish()
}

/// Most vertices the distinct `blob` meshes of one scene may have together
/// (blobs of the same detail and seed share one mesh): about four blobs at
/// detail 1024 (4.2 M vertices, 8.4 M triangles, built with normals and
/// tangents when the scene is instantiated); see `docs/limits.md`.
pub const MAX_SCENE_BLOB_VERTICES: u64 = 4 * 1025 * 1025;

/// Vertices of a blob of `detail` rings and segments: a (detail + 1)² grid.
pub fn blob_vertex_count(detail: u32) -> u64 {
    let side = u64::from(detail.clamp(3, 1024)) + 1;
    side * side
}

/// A sphere of radius ≤ 0.5 whose radius varies smoothly with direction: four
/// random plane waves picked by `seed` (PCG32), `detail` rings and segments.
pub fn blob(detail: u32, seed: u32) -> Mesh {
    use rand::{Rng, SeedableRng};
    const AMPLITUDE: f32 = 0.18;
    let detail = detail.clamp(3, 1024);
    let mut rng = rand_pcg::Pcg32::seed_from_u64(u64::from(seed));
    let waves: Vec<(Vec3, f32, f32)> = (0..4)
        .map(|i| {
            let dir = Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            (dir.normalize_or(Vec3::Y) * (2.0 + i as f32 * 1.5), rng.random_range(0.0..TAU), 0.5 / (1.0 + i as f32))
        })
        .collect();
    let total: f32 = waves.iter().map(|w| w.2).sum();
    let surface = |u: f32, v: f32| {
        let theta = v.clamp(0.0, 1.0) * std::f32::consts::PI;
        let d = around_y(u * TAU) * theta.sin() + Vec3::Y * theta.cos();
        let lumps: f32 = waves.iter().map(|(k, phase, amp)| amp * (k.dot(d) + phase).sin()).sum::<f32>() / total;
        d * (0.5 * (1.0 + AMPLITUDE * lumps) / (1.0 + AMPLITUDE))
    };
    let mut b = Builder::default();
    let e = 0.25 / detail as f32;
    b.grid(detail, detail, |u, v| {
        let p = surface(u, v);
        // Normal from central differences; radial at the poles, where dP/du vanishes.
        let n = (surface(u + e, v) - surface(u - e, v)).cross(surface(u, v + e) - surface(u, v - e));
        let radial = p.normalize_or(Vec3::Y);
        let n = if n.length_squared() > 1e-12 { n.normalize() } else { radial };
        (p, if n.dot(radial) < 0.0 { -n } else { n }, Vec2::new(u, v))
    });
    b.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(mesh: &Mesh, t: usize) -> [crate::scene::Vertex; 3] {
        let i = &mesh.indices()[t * 3..t * 3 + 3];
        [0, 1, 2].map(|k| mesh.vertices()[i[k] as usize])
    }

    #[test]
    fn every_shape_fits_the_unit_box_with_unit_normals_and_uvs_in_range() {
        for kind in ShapeKind::ALL {
            let mesh = kind.mesh();
            let aabb = mesh.aabb();
            assert!(aabb.min.cmpge(Vec3::splat(-0.5 - 1e-5)).all(), "{kind:?} {aabb:?}");
            assert!(aabb.max.cmple(Vec3::splat(0.5 + 1e-5)).all(), "{kind:?} {aabb:?}");
            assert!(mesh.bounding_sphere().radius <= 0.8661, "{kind:?}");
            for v in mesh.vertices() {
                assert!((Vec3::from(v.normal).length() - 1.0).abs() < 1e-4, "{kind:?}");
                assert!(v.uv.iter().all(|c| (-1e-5..=1.0 + 1e-5).contains(c)), "{kind:?} {:?}", v.uv);
            }
        }
    }

    #[test]
    fn triangles_are_counter_clockwise_seen_from_outside() {
        for kind in ShapeKind::ALL {
            let mesh = kind.mesh();
            for t in 0..mesh.indices().len() / 3 {
                let [a, b, c] = tri(&mesh, t).map(|v| Vec3::from(v.position));
                let face = (b - a).cross(c - a);
                let n: Vec3 = tri(&mesh, t).iter().map(|v| Vec3::from(v.normal)).sum();
                assert!(face.dot(n) > 0.0, "{kind:?} triangle {t} winds against its normals");
                // Closed convex shapes: the face also points away from the centre.
                if matches!(kind, ShapeKind::Cube | ShapeKind::Sphere | ShapeKind::Cylinder | ShapeKind::Cone) {
                    assert!(face.dot((a + b + c) / 3.0) > 0.0, "{kind:?} triangle {t} faces inwards");
                }
            }
        }
    }

    #[test]
    fn normals_match_the_surface() {
        // Sphere: normal is the direction from the centre.
        for v in sphere(16, 8).vertices() {
            let p = Vec3::from(v.position);
            assert!(p.normalize().dot(Vec3::from(v.normal)) > 0.999);
        }
        // Torus: normal points from the ring circle to the surface point.
        for v in torus(16, 8).vertices() {
            let p = Vec3::from(v.position);
            let ring = Vec3::new(p.x, 0.0, p.z).normalize() * 0.35;
            assert!((p - ring).normalize().dot(Vec3::from(v.normal)) > 0.999);
        }
        // Cube: each vertex normal is the axis of its face.
        for v in cube().vertices() {
            let n = Vec3::from(v.normal);
            assert!((Vec3::from(v.position).dot(n) - 0.5).abs() < 1e-6);
        }
    }

    #[test]
    fn tangents_are_unit_perpendicular_and_follow_u() {
        for kind in ShapeKind::ALL {
            let mesh = kind.mesh();
            for v in mesh.vertices() {
                let t = Vec3::new(v.tangent[0], v.tangent[1], v.tangent[2]);
                assert!((t.length() - 1.0).abs() < 1e-3, "{kind:?} tangent {t}");
                assert!(t.dot(Vec3::from(v.normal)).abs() < 1e-3, "{kind:?}");
                assert!(v.tangent[3].abs() == 1.0, "{kind:?}");
            }
            // dP/du of each non-degenerate triangle points along its vertices' tangents.
            for t in 0..mesh.indices().len() / 3 {
                let vs = tri(&mesh, t);
                let (p, uv) = (vs.map(|v| Vec3::from(v.position)), vs.map(|v| Vec2::from(v.uv)));
                let (e1, e2, d1, d2) = (p[1] - p[0], p[2] - p[0], uv[1] - uv[0], uv[2] - uv[0]);
                let det = d1.x * d2.y - d2.x * d1.y;
                if det.abs() < 1e-6 {
                    continue;
                }
                let dpdu = (e1 * d2.y - e2 * d1.y) / det;
                for v in vs {
                    let tangent = Vec3::new(v.tangent[0], v.tangent[1], v.tangent[2]);
                    assert!(tangent.dot(dpdu) > 0.0, "{kind:?} triangle {t}: tangent against dP/du");
                }
            }
        }
    }

    #[test]
    fn cube_faces_read_upright_from_outside() {
        // On the +Z face u grows towards +X and v grows towards −Y.
        let mesh = cube();
        let front: Vec<_> = mesh.vertices().iter().filter(|v| v.normal == [0.0, 0.0, 1.0]).collect();
        assert_eq!(front.len(), 4);
        for v in front {
            assert!((v.uv[0] - (v.position[0] + 0.5)).abs() < 1e-6);
            assert!((v.uv[1] - (0.5 - v.position[1])).abs() < 1e-6);
        }
    }

    #[test]
    fn blobs_are_distinct_sized_and_wound_outwards() {
        let a = ShapeKind::Blob { detail: 86, seed: 1 }.mesh();
        let b = ShapeKind::Blob { detail: 86, seed: 2 }.mesh();
        assert_eq!(a.indices().len() / 3, 2 * 86 * 86 - 2 * 86, "about 14,600 triangles at detail 86");
        assert_ne!(a.vertices(), b.vertices(), "seeds give different meshes");
        assert_eq!(
            a.vertices(),
            ShapeKind::Blob { detail: 86, seed: 1 }.mesh().vertices(),
            "and the same seed the same one"
        );
        for mesh in [&a, &b] {
            assert!(mesh.vertices().iter().all(|v| Vec3::from(v.position).length() <= 0.5 + 1e-5));
            for t in 0..mesh.indices().len() / 3 {
                let [p0, p1, p2] = tri(mesh, t).map(|v| Vec3::from(v.position));
                assert!((p1 - p0).cross(p2 - p0).dot(p0 + p1 + p2) > 0.0, "triangle {t} faces inwards");
            }
        }
    }

    #[test]
    fn names_round_trip() {
        for kind in ShapeKind::ALL {
            assert_eq!(ShapeKind::from_name(kind.name()), Some(kind));
        }
        assert_eq!(ShapeKind::from_name("teapot"), None);
    }
}
