//! Discrete Elastic Plates against the published hinge model's own numbers: the
//! shell cantilever on its "equilateral mesh 40" (generated here, node for node
//! and triangle for triangle), static at two Young's moduli and in time with
//! implicit Euler.

use glam::{DMat3, DVec3};
use glint::sim::cloth::{Cloth, ClothMesh, ClothParams, Integrator};
use rand::{Rng, SeedableRng};

/// Columns and rows of the published mesh.
const COLUMNS: usize = 41;
const ROWS: usize = 11;
/// Edge length, metres.
const EDGE: f64 = 0.0025;

/// Node `11·c + r` (0-based) of the published mesh: column `c`, row `r`.
fn node(c: usize, r: usize) -> u32 {
    (ROWS * c + r) as u32
}

/// "Equilateral mesh 40": 451 nodes in 41 columns of 11, odd rows shifted half an
/// edge to the right; 800 equilateral triangles between neighbouring rows and 9
/// that straighten the ends, all counter-clockwise seen from +z.
fn published_mesh() -> ClothMesh {
    let row_gap = EDGE * 3f64.sqrt() / 2.0;
    let mut nodes = Vec::with_capacity(COLUMNS * ROWS);
    for c in 0..COLUMNS {
        for r in 0..ROWS {
            let shift = if r % 2 == 1 { EDGE / 2.0 } else { 0.0 };
            nodes.push(DVec3::new(EDGE * c as f64 + shift, r as f64 * row_gap, 0.0));
        }
    }
    let mut triangles = Vec::new();
    for r in 0..ROWS - 1 {
        for c in 0..COLUMNS - 1 {
            if r % 2 == 0 {
                // Row r + 1 sits half an edge to the right of row r.
                triangles.push([node(c, r), node(c + 1, r), node(c, r + 1)]);
                triangles.push([node(c + 1, r), node(c + 1, r + 1), node(c, r + 1)]);
            } else {
                triangles.push([node(c, r), node(c + 1, r), node(c + 1, r + 1)]);
                triangles.push([node(c, r), node(c + 1, r + 1), node(c, r + 1)]);
            }
        }
    }
    for r in (1..ROWS - 1).step_by(2) {
        triangles.push([node(0, r - 1), node(0, r), node(0, r + 1)]);
    }
    for r in (2..ROWS - 1).step_by(2) {
        let last = COLUMNS - 1;
        triangles.push([node(last, r - 1), node(last, r + 1), node(last, r)]);
    }
    ClothMesh::new(nodes, triangles).expect("the published mesh")
}

/// The published cantilever with Young's modulus `young`: h = 1 mm,
/// ρ = 1200 kg/m³, g = 9.81 m/s² along −z, clamped where x ≤ 0.01 m.
fn cantilever(young: f64) -> Cloth {
    let params =
        ClothParams { thickness: 1e-3, young, poisson: 0.5, density: 1200.0, gravity: DVec3::new(0.0, 0.0, -9.81) };
    let mesh = published_mesh();
    let pinned: Vec<bool> = mesh.nodes.iter().map(|p| p.x <= 0.01 + 1e-9).collect();
    Cloth::new(mesh, params, &pinned).expect("cloth")
}

/// The tip: node 441 (1-based), at (0.1, 0, 0).
const TIP: usize = 440;

#[test]
fn the_published_mesh_has_its_counts_and_winding() {
    let cloth = cantilever(2e10);
    let mesh = cloth.mesh();
    assert_eq!((mesh.nodes.len(), mesh.triangles.len()), (451, 809));
    let topology = cloth.topology();
    assert_eq!((topology.edges.len(), topology.hinges.len()), (1259, 1168));
    for t in &mesh.triangles {
        let p = t.map(|i| mesh.nodes[i as usize]);
        assert!((p[1] - p[0]).cross(p[2] - p[0]).z > 0.0, "{t:?} is counter-clockwise from +z");
    }
    assert!(mesh.nodes[TIP].distance(DVec3::new(0.1, 0.0, 0.0)) < 1e-12);
    assert_eq!((0..451).filter(|&i| cloth.is_pinned(i)).count(), 50);
    let free_weight: f64 = (0..451).filter(|&i| !cloth.is_pinned(i)).map(|i| cloth.masses()[i] * 9.81).sum();
    assert!((free_weight - 2.3066e-2).abs() < 1e-6, "free weight {free_weight} N");
}

/// The static tip at both moduli, within 10⁻⁷ m of the published values; the
/// pins hold up the free nodes' weight.
#[test]
fn static_tip_matches_the_published_model_at_small_and_large_deflection() {
    for (young, published) in [(2e10, -6.7400112e-5), (2e8, -6.7007433e-3)] {
        let mut cloth = cantilever(young);
        cloth.step(0.0, Integrator::Static).expect("equilibrium");
        let tip = cloth.positions[TIP].z;
        // Euler–Bernoulli for the 0.09 m free span: the hinge model is softer.
        let span: f64 = 0.09;
        let beam = 3.0 * 1200.0 * 9.81 * span.powi(4) / (2.0 * young * 1e-6);
        eprintln!(
            "E = {young:e}: tip z {tip:.7e} m, published {published:.7e} m, {:.4} x Euler-Bernoulli",
            -tip / beam
        );
        assert!((tip - published).abs() <= 1e-7, "E = {young:e}: tip z {tip:e}, published {published:e}");

        // At equilibrium the pins' reactions (the elastic forces ∇E at the pinned
        // nodes, whose own weight rests directly on the clamp) hold up exactly the
        // weight of the free nodes.
        let gravity = DVec3::new(0.0, 0.0, -9.81);
        let gradient = cloth.elastic_gradient(&cloth.positions);
        let (mut reactions, mut weight) = (DVec3::ZERO, DVec3::ZERO);
        for (i, (g, m)) in gradient.iter().zip(cloth.masses()).enumerate() {
            if cloth.is_pinned(i) {
                reactions += *g;
            } else {
                weight += *m * gravity;
            }
        }
        assert!(reactions.z > 0.0, "the pins push up: {reactions:?}");
        assert!((reactions + weight).length() <= 1e-6 * weight.length(), "pins {reactions:?} against {weight:?}");
    }
}

/// Implicit Euler from rest at dt = 0.01 s: the tip's first minimum at t = 0.07 s.
#[test]
fn implicit_euler_tip_at_the_first_minimum_matches_the_published_model() {
    let mut cloth = cantilever(2e8);
    for _ in 0..7 {
        cloth.step(0.01, Integrator::ImplicitEuler).expect("step");
    }
    let (tip, published) = (cloth.positions[TIP].z, -1.0011650e-2);
    eprintln!("t = 0.07 s: tip z {tip:.7e} m, published {published:.7e} m");
    assert!((tip - published).abs() <= 1e-5, "tip z {tip:e}, published {published:e}");
}

/// The model depends on shape only: moving a deformed random mesh rigidly leaves
/// its elastic energy as it was and turns each node's elastic force with it (the
/// Hessians' blocks are checked the same way in `energy.rs`).
#[test]
fn elastic_energy_and_forces_follow_a_rigid_motion_of_a_random_mesh() {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(17);
    let mut jitter = |scale: f64| {
        DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)) * scale
    };
    let mut mesh = ClothMesh::sheet(0.3, 0.2, 9, 7);
    for p in &mut mesh.nodes {
        *p += jitter(0.008);
    }
    let params = ClothParams { thickness: 1e-3, young: 1e7, poisson: 0.3, density: 200.0, gravity: DVec3::ZERO };
    let cloth = Cloth::new(mesh.clone(), params, &vec![false; mesh.nodes.len()]).expect("cloth");
    let deformed: Vec<DVec3> = mesh.nodes.iter().map(|p| *p + jitter(0.01)).collect();
    let (energy, forces) = (cloth.elastic_energy(&deformed), cloth.elastic_gradient(&deformed));
    assert!(energy > 0.0, "the deformed mesh stores energy");
    let largest = forces.iter().map(|f| f.length()).fold(0.0, f64::max);
    for (axis, angle, shift) in
        [(DVec3::Z, 0.7, DVec3::ZERO), (DVec3::new(1.0, -2.0, 0.5), 2.9, DVec3::new(3.0, -1.0, 7.0))]
    {
        let rotation = DMat3::from_axis_angle(axis.normalize(), angle);
        let moved: Vec<DVec3> = deformed.iter().map(|p| rotation * *p + shift).collect();
        let moved_energy = cloth.elastic_energy(&moved);
        assert!((moved_energy - energy).abs() <= 1e-10 * energy, "energy {moved_energy} against {energy}");
        for (f, g) in cloth.elastic_gradient(&moved).iter().zip(&forces) {
            assert!(f.distance(rotation * *g) <= 1e-10 * largest, "force {f} against {}", rotation * *g);
        }
    }
}
