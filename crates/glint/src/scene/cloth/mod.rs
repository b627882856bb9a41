//! A cloth as a scene describes it ([`ClothSetup`]): its mesh at rest
//! ([`ClothMesh`]: nodes and triangles, checked, and their topology: unique
//! edges and the hinges of interior edges), its material, which nodes are
//! pinned and how they move ([`pins`]), what it collides with ([`Collider`]),
//! and what its linear system would cost ([`ClothSetup::check`]).
//! `sim::cloth` simulates it; `asset` reads it from `.scn` blocks and mesh files.

mod collider;
pub mod pins;

pub use collider::Collider;
pub use pins::{PinMotion, PinSelector, MAX_PIN_TERMS};

use glam::DVec3;
use std::collections::HashMap;

/// Most bytes one cloth's linear system may hold: its pattern and the numeric
/// Cholesky factor (estimated from the pattern before either is allocated), or
/// an LU factor. Chosen from measurements on the 23 GiB, 2-core reference
/// machine (see `docs/limits.md`): a 257 × 257 sheet's system takes about
/// 0.3 GiB, while a 1025 × 1025 sheet would need over 8 GiB.
pub const MAX_SYSTEM_BYTES: u64 = 2 << 30;

/// Most colliders one cloth may have: each node is tested against each in every
/// Newton iteration (10,000 colliders on a 17 × 17 cloth took over 30 s to
/// pose a second), and 64 stay below the cost of the solve itself (and fit
/// the GPU solve's parameter block).
pub const MAX_COLLIDERS: usize = 64;

/// Bytes per pattern entry while a system is built: the entry itself (16), its
/// faer index pair (16) and the sort faer does on them (16), its value (8)
/// and slot (8), and the element's local index (2), rounded up.
pub const BYTES_PER_PATTERN_ENTRY: u64 = 72;

/// The plate's material and the world it hangs in (SI units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClothParams {
    /// Thickness h, metres.
    pub thickness: f64,
    /// Young's modulus E, pascals.
    pub young: f64,
    /// Poisson's ratio ν. Recorded for reference: the DEP constants used here
    /// (`k_s = (√3/2) E h l̄`, `k_b = (2/√3) E h³ / 12`) do not depend on it.
    pub poisson: f64,
    /// Density ρ, kg/m³.
    pub density: f64,
    /// Gravity, m/s².
    pub gravity: DVec3,
}

/// How the simulation (`sim::cloth::Cloth::step`) advances time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// Backward Euler: stable at any step, loses energy.
    ImplicitEuler,
    /// Newmark-β with β = ¼, γ = ½: keeps energy much better.
    Newmark,
    /// No time: each step solves for the equilibrium under the full load.
    Static,
}

/// How the simulation (`sim::cloth::Cloth::step`) solves each time step's
/// implicit equations (a static solve always converges).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Solve {
    /// Newton's method to convergence every step: the reference.
    #[default]
    Converged,
    /// A fixed budget per step for interactive use, with the same energies: at
    /// most three Newton iterations on the definite Jacobian with a cut-short
    /// line search (see `sim::cloth::realtime`). Its error against the converged solve is measured in
    /// `tests/cloth_realtime.rs` and `docs/cloth.md`.
    Realtime,
    /// Vertex Block Descent on compute shaders (`sim::cloth::GpuCloth`), drawn
    /// from its buffers, where a renderer has the compute path; elsewhere (GL,
    /// WebGL2, a static solve, the debug view) the converged solve, with a
    /// warning. The CPU's `Cloth` solves it as [`Converged`](Self::Converged).
    Gpu,
}

/// What a cloth starts from.
#[derive(Clone, Debug)]
pub struct ClothSetup {
    /// The rest mesh, placed in the world (`origin`, `angles`).
    pub mesh: ClothMesh,
    /// Material and gravity.
    pub params: ClothParams,
    /// Which nodes are pinned.
    pub pinned: Vec<bool>,
    /// How the pinned nodes move (`pin_velocity`, `pin_spin` about `origin`).
    pub pin_motion: PinMotion,
    /// Rigid obstacles (`colliders`).
    pub colliders: Vec<Collider>,
    /// Contact distance δ, metres.
    pub contact_distance: f64,
    /// Mass-proportional damping, 1/s.
    pub damping: f64,
    /// How each step is solved (`solve`: `converged` or `realtime`).
    pub solve: Solve,
}

impl ClothSetup {
    /// Why this cloth cannot be simulated, if it cannot: its mesh (see
    /// [`ClothMesh::topology`]), a node beyond single precision's range (it
    /// is drawn in single precision), or a linear system too large for memory
    /// ([`system_bytes`]), checked before anything is allocated.
    pub fn check(&self) -> Result<(), ClothMeshError> {
        let topology = self.mesh.topology()?;
        if let Some(node) = self.mesh.nodes.iter().position(|p| !p.as_vec3().is_finite()) {
            return Err(ClothMeshError::OutOfRange(node));
        }
        let nodes = self.mesh.nodes.len();
        let free: Vec<bool> = (0..nodes).map(|v| !self.pinned.get(v).copied().unwrap_or(false)).collect();
        let bytes = system_bytes(&topology, &free);
        if bytes > MAX_SYSTEM_BYTES {
            return Err(ClothMeshError::TooLarge { nodes, bytes, max: MAX_SYSTEM_BYTES });
        }
        Ok(())
    }
}

/// The bytes a cloth's linear system takes while it is built, from its
/// `topology` and which nodes are `free` (not pinned): its pattern holds the
/// lower triangle of the 3 × 3 blocks between the free nodes of each edge and
/// hinge, and two entries for each free degree of freedom (its node's own block).
pub fn system_bytes(topology: &Topology, free: &[bool]) -> u64 {
    let free_in = |nodes: &[u32]| 3 * nodes.iter().filter(|&&v| free[v as usize]).count() as u64;
    let free_dofs = 3 * free.iter().filter(|&&f| f).count() as u64;
    let entries = (topology.edges.iter().map(|e| free_in(e)))
        .chain(topology.hinges.iter().map(|h| free_in(h)))
        .map(|k| k * (k + 1) / 2)
        .sum::<u64>()
        + 2 * free_dofs;
    entries.saturating_mul(BYTES_PER_PATTERN_ENTRY)
}

/// Nodes (rest positions, metres) and triangles (node indices) of a cloth.
#[derive(Clone, Debug, PartialEq)]
pub struct ClothMesh {
    /// Rest positions.
    pub nodes: Vec<DVec3>,
    /// Triangles as indices into `nodes`.
    pub triangles: Vec<[u32; 3]>,
}

/// Edges and hinges of a [`ClothMesh`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Topology {
    /// Unique triangle edges, lower index first.
    pub edges: Vec<[u32; 2]>,
    /// Interior edges with their opposite nodes: [x₀, x₁, x₂, x₃], x₂ in the
    /// first triangle (x₀, x₁, x₂ in its winding order) and x₃ in the second.
    pub hinges: Vec<[u32; 4]>,
}

/// Why a mesh cannot be simulated.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ClothMeshError {
    /// A triangle names a node past the end.
    #[error("triangle {triangle} names node {node}, but there are {nodes} nodes")]
    NodeOutOfRange {
        /// Triangle index.
        triangle: usize,
        /// The bad node index (0-based).
        node: u32,
        /// Node count.
        nodes: usize,
    },
    /// A triangle with a repeated node or no area.
    #[error("triangle {0} is degenerate (a repeated node or no area)")]
    Degenerate(usize),
    /// An edge shared by more than two triangles (the third is the last number).
    #[error("edge {0}-{1} is shared by more than two triangles")]
    NonManifold(u32, u32, usize),
    /// No triangles at all.
    #[error("the mesh has no triangles")]
    Empty,
    /// The cloth's sparse linear system would take more memory than glint allows
    /// (see `MAX_SYSTEM_BYTES`), checked before it is allocated.
    #[error(
        "a cloth of {nodes} nodes is too large: its linear system would take about {} MiB, more than the {} MiB glint allows",
        bytes.div_ceil(1 << 20),
        max >> 20
    )]
    TooLarge {
        /// Nodes of the mesh.
        nodes: usize,
        /// Estimated bytes of its system.
        bytes: u64,
        /// The limit.
        max: u64,
    },
    /// A position is NaN or infinite.
    #[error("node {0} is not a finite position")]
    NotFinite(usize),
    /// A position beyond single precision's range (the cloth is drawn in it).
    #[error("node {0} lies beyond single precision's range")]
    OutOfRange(usize),
}

impl ClothMesh {
    /// A mesh from nodes and triangles, checked: indices in range, no
    /// degenerate triangle, no edge in more than two triangles, finite positions.
    pub fn new(nodes: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Result<Self, ClothMeshError> {
        let mesh = Self { nodes, triangles };
        mesh.topology()?;
        Ok(mesh)
    }

    /// A `width` × `height` sheet in the XY plane (corner at the origin) of
    /// `nx` × `ny` nodes (each at least 2), every quad split into two triangles
    /// with diagonals alternating so the sheet has no preferred direction.
    pub fn sheet(width: f64, height: f64, nx: u32, ny: u32) -> Self {
        let (nx, ny) = (nx.max(2), ny.max(2));
        let nodes = (0..ny)
            .flat_map(|j| {
                (0..nx).map(move |i| {
                    DVec3::new(width * f64::from(i) / f64::from(nx - 1), height * f64::from(j) / f64::from(ny - 1), 0.0)
                })
            })
            .collect();
        let mut triangles = Vec::with_capacity(2 * ((nx - 1) * (ny - 1)) as usize);
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let (a, b, c, d) = (j * nx + i, j * nx + i + 1, (j + 1) * nx + i + 1, (j + 1) * nx + i);
                if (i + j) % 2 == 0 {
                    triangles.extend([[a, b, c], [a, c, d]]);
                } else {
                    triangles.extend([[a, b, d], [b, c, d]]);
                }
            }
        }
        Self { nodes, triangles }
    }

    /// Unique edges and the hinges of edges shared by two triangles.
    pub fn topology(&self) -> Result<Topology, ClothMeshError> {
        if self.triangles.is_empty() {
            return Err(ClothMeshError::Empty);
        }
        if let Some(i) = self.nodes.iter().position(|p| !p.is_finite()) {
            return Err(ClothMeshError::NotFinite(i));
        }
        // Each edge's triangles, as (opposite node, whether the edge runs low→high in it).
        let mut faces: HashMap<[u32; 2], Vec<(u32, bool)>> = HashMap::with_capacity(self.triangles.len() * 3 / 2);
        let mut order = Vec::with_capacity(self.triangles.len() * 3 / 2);
        for (t, tri) in self.triangles.iter().enumerate() {
            if let Some(&node) = tri.iter().find(|&&v| v as usize >= self.nodes.len()) {
                return Err(ClothMeshError::NodeOutOfRange { triangle: t, node, nodes: self.nodes.len() });
            }
            let [a, b, c] = tri.map(|v| self.nodes[v as usize]);
            if (b - a).cross(c - a).length_squared() <= f64::MIN_POSITIVE {
                return Err(ClothMeshError::Degenerate(t));
            }
            for k in 0..3 {
                let (u, v, w) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
                let key = [u.min(v), u.max(v)];
                let list = faces.entry(key).or_insert_with(|| {
                    order.push(key);
                    Vec::new()
                });
                if list.len() == 2 {
                    return Err(ClothMeshError::NonManifold(key[0], key[1], t));
                }
                list.push((w, u < v));
            }
        }
        let mut topology = Topology { edges: order.clone(), hinges: Vec::new() };
        for key in order {
            if let [(x2, forward), (x3, _)] = faces[&key][..] {
                // x₀ → x₁ in the first triangle's winding, so x₂ is on its left.
                let [x0, x1] = if forward { key } else { [key[1], key[0]] };
                topology.hinges.push([x0, x1, x2, x3]);
            }
        }
        Ok(topology)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sheet_edges_and_hinges_are_counted_right() {
        let mesh = ClothMesh::sheet(1.0, 2.0, 4, 3);
        assert_eq!((mesh.nodes.len(), mesh.triangles.len()), (12, 12));
        let topology = mesh.topology().unwrap();
        // Edges: 3·3 horizontal + 4·2 vertical + 6 diagonals; interior ones all but the 10 on the border.
        assert_eq!(topology.edges.len(), 9 + 8 + 6);
        assert_eq!(topology.hinges.len(), 23 - 10);
        for h in &topology.hinges {
            let x: [DVec3; 4] = h.map(|i| mesh.nodes[i as usize]);
            // x₂ left of x₀→x₁ and x₃ right of it, seen from +Z.
            let e = x[1] - x[0];
            assert!(e.cross(x[2] - x[0]).z > 0.0 && e.cross(x[3] - x[0]).z < 0.0, "{h:?}");
        }
    }

    #[test]
    fn bad_meshes_are_errors() {
        let nodes = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0), DVec3::Z];
        assert_eq!(ClothMesh::new(nodes.clone(), vec![]), Err(ClothMeshError::Empty));
        assert_eq!(ClothMesh::new(nodes.clone(), vec![[0, 1, 1]]), Err(ClothMeshError::Degenerate(0)));
        assert!(matches!(ClothMesh::new(nodes.clone(), vec![[0, 1, 9]]), Err(ClothMeshError::NodeOutOfRange { .. })));
        let fan = vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]];
        assert_eq!(ClothMesh::new(nodes, fan), Err(ClothMeshError::NonManifold(0, 1, 2)));
    }
}
