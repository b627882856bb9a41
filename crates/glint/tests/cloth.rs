//! Discrete Elastic Plates against physical laws: plate rigidity on a cylinder,
//! energy behaviour of the integrators, contact, pins, damping, and a large sheet
//! under a huge time step (the published cantilever is in `cloth_published.rs`).

use glam::DVec3;
use glint::sim::cloth::{Cloth, ClothMesh, ClothParams, Collider, Integrator, PinMotion, PinSelector};

/// An equilateral mesh of `width` × `height` with edges of `edge`: rows
/// `edge·√3/2` apart, odd rows shifted by half an edge (with a node at each
/// end so the plate is rectangular), neighbouring rows zipped into triangles.
fn equilateral_plate(width: f64, height: f64, edge: f64) -> ClothMesh {
    let row_gap = edge * 3f64.sqrt() / 2.0;
    let rows = (height / row_gap).round() as usize;
    let columns = (width / edge).round() as usize;
    let mut nodes = Vec::new();
    let mut row_nodes: Vec<Vec<u32>> = Vec::new();
    for j in 0..=rows {
        let y = j as f64 * row_gap;
        let mut xs: Vec<f64> = (0..=columns).map(|i| i as f64 * edge).collect();
        if j % 2 == 1 {
            xs = std::iter::once(0.0).chain((0..columns).map(|i| (i as f64 + 0.5) * edge)).chain([width]).collect();
        }
        row_nodes.push(
            xs.iter()
                .map(|&x| {
                    nodes.push(DVec3::new(x, y, 0.0));
                    (nodes.len() - 1) as u32
                })
                .collect(),
        );
    }
    let mut triangles = Vec::new();
    for pair in row_nodes.windows(2) {
        let (low, high) = (&pair[0], &pair[1]);
        let (mut i, mut k) = (0, 0);
        while i + 1 < low.len() || k + 1 < high.len() {
            let x = |v: u32| nodes[v as usize].x;
            let advance_low = k + 1 >= high.len() || (i + 1 < low.len() && x(low[i + 1]) <= x(high[k + 1]));
            if advance_low {
                triangles.push([low[i], low[i + 1], high[k]]);
                i += 1;
            } else {
                triangles.push([low[i], high[k + 1], high[k]]);
                k += 1;
            }
        }
    }
    ClothMesh::new(nodes, triangles).expect("a valid plate")
}

/// A 1 mm sheet of density 200 kg/m³ under gravity along −Z, Young's modulus `young`.
fn fabric(young: f64) -> ClothParams {
    ClothParams { thickness: 1e-3, young, poisson: 0.3, density: 200.0, gravity: DVec3::new(0.0, 0.0, -9.81) }
}

/// A 0.2 m square sheet hinged along one edge, released horizontally.
fn swinging_sheet() -> Cloth {
    let params =
        ClothParams { thickness: 5e-4, young: 1e7, poisson: 0.3, density: 500.0, gravity: DVec3::new(0.0, 0.0, -9.81) };
    let mesh = ClothMesh::sheet(0.2, 0.2, 9, 9);
    let pinned: Vec<bool> = mesh.nodes.iter().map(|p| p.x <= 1e-9).collect();
    Cloth::new(mesh, params, &pinned).expect("cloth")
}

#[test]
fn implicit_euler_loses_energy_every_step_and_newmark_keeps_it() {
    let mut cloth = swinging_sheet();
    let start = cloth.total_energy();
    let mut last = start;
    for step in 0..20 {
        let stats = cloth.step(0.01, Integrator::ImplicitEuler).expect("step");
        assert!(stats.newton_iterations >= 1);
        let energy = cloth.total_energy();
        assert!(energy <= last + 1e-9 * start.abs().max(1e-6), "step {step}: energy rose from {last} to {energy}");
        last = energy;
    }
    let drop_euler = start - last;
    assert!(drop_euler > 0.0, "implicit Euler damps the swing");

    // Newmark (β = ¼, γ = ½) over the same 0.2 s conserves energy within 2% of
    // the potential energy the swing can release. Its steps must resolve the stiff
    // edges, though: at dt = 0.01 s this sheet's energy grows without bound (the
    // trapezoidal rule is not unconditionally stable for nonlinear springs), so
    // it runs at 0.002 s here.
    let mut cloth = swinging_sheet();
    let released = {
        let lowest = cloth.masses().iter().zip(&cloth.positions).map(|(m, p)| m * 9.81 * (p.z + 0.2)).sum::<f64>();
        lowest.max(1e-9)
    };
    let start = cloth.total_energy();
    let mut worst: f64 = 0.0;
    for _ in 0..100 {
        cloth.step(0.002, Integrator::Newmark).expect("step");
        worst = worst.max((cloth.total_energy() - start).abs());
    }
    eprintln!("energy drift: implicit Euler {drop_euler:.3e} J, Newmark {worst:.3e} J (scale {released:.3e} J)");
    assert!(worst <= 0.02 * released, "Newmark drifted {worst} J against {released} J");
    assert!(worst < drop_euler, "Newmark keeps more energy than implicit Euler");
}

/// The hinge stiffness `k_b = (2/√3) E h³/12` is Seung and Nelson's constant
/// for a triangular lattice: an equilateral sheet wrapped onto a cylinder of
/// radius R stores the continuum plate energy ½ D/R² per area, D = E h³/12.
/// This is why the published cantilever deflects near Euler–Bernoulli's beam
/// (1.16 times, `cloth_published.rs`), not 2 or √3 times.
#[test]
fn hinge_stiffness_gives_the_plate_rigidity_on_a_cylinder() {
    use glint::sim::cloth::energy::{bend_energy, hinge_angle};
    let edge = 2.5e-3;
    let mesh = equilateral_plate(0.1, 0.1, edge);
    let topology = mesh.topology().expect("topology");
    let (young, thickness, radius): (f64, f64, f64) = (2e8, 1e-3, 0.5);
    let rigidity = young * thickness.powi(3) / 12.0;
    let k_b = 2.0 / 3f64.sqrt() * rigidity;
    for along_rows in [true, false] {
        let wrapped: Vec<DVec3> = mesh
            .nodes
            .iter()
            .map(|p| {
                let (s, other) = if along_rows { (p.x, p.y) } else { (p.y, p.x) };
                let (a, b) = (radius * (s / radius).sin(), radius * (1.0 - (s / radius).cos()));
                if along_rows {
                    DVec3::new(a, other, b)
                } else {
                    DVec3::new(other, a, b)
                }
            })
            .collect();
        // Interior hinges only: a regular lattice has 1.5 hinges per triangle,
        // so each stands for two thirds of a triangle's area.
        let interior = |p: DVec3| (0.01..0.09).contains(&p.x) && (0.01..0.09).contains(&p.y);
        let (mut energy, mut hinges) = (0.0, 0);
        for hinge in &topology.hinges {
            let rest = hinge.map(|i| mesh.nodes[i as usize]);
            if rest.iter().all(|p| interior(*p)) {
                energy += bend_energy(&hinge.map(|i| wrapped[i as usize]), hinge_angle(&rest), k_b);
                hinges += 1;
            }
        }
        let area = hinges as f64 * (3f64.sqrt() / 4.0 * edge * edge) / 1.5;
        let continuum = 0.5 * rigidity / (radius * radius) * area;
        let ratio = energy / continuum;
        eprintln!(
            "curved {} the rows: {hinges} hinges, energy ratio to the plate {ratio:.5}",
            if along_rows { "along" } else { "across" }
        );
        assert!((ratio - 1.0).abs() < 0.01, "ratio {ratio}");
    }
}

/// A square of cloth dropped onto a ball on a floor: it drapes over the ball
/// and its corners come down, and no node ends up inside either collider.
#[test]
fn cloth_drapes_over_a_sphere_and_stops_on_the_floor() {
    let params = fabric(1e6);
    let mut mesh = ClothMesh::sheet(0.6, 0.6, 17, 17);
    for p in &mut mesh.nodes {
        *p += DVec3::new(-0.3, -0.3, 0.25);
    }
    let mut cloth = Cloth::new(mesh, params, &[]).expect("cloth");
    let (ball, radius, floor, gap) = (DVec3::ZERO, 0.2, -0.21, 0.005);
    cloth.set_colliders(
        vec![
            Collider::Sphere { centre: ball, radius },
            Collider::Plane { point: DVec3::new(0.0, 0.0, floor), normal: DVec3::Z },
        ],
        gap,
    );
    for _ in 0..60 {
        cloth.step(0.01, Integrator::ImplicitEuler).expect("step");
    }
    let inside_ball = cloth.positions.iter().map(|p| radius - (*p - ball).length()).fold(f64::MIN, f64::max);
    let below_floor = cloth.positions.iter().map(|p| floor - p.z).fold(f64::MIN, f64::max);
    let top = cloth.positions.iter().map(|p| p.z).fold(f64::MIN, f64::max);
    let corner = cloth.positions[0];
    eprintln!("deepest into the ball {inside_ball:.2e} m, below the floor {below_floor:.2e} m, top {top:.4} m, corner {corner}");
    assert!(inside_ball < 0.0 && below_floor < 0.0, "contact holds the nodes outside");
    assert!(top > radius && top < radius + 2.0 * gap, "the cloth rests on top of the ball: {top}");
    assert!(corner.z < 0.0, "the corners fall past the ball's equator: {corner}");
}

/// Pins chosen by a predicate move with their motion, dragging the cloth.
#[test]
fn animated_pins_follow_their_motion() {
    let params = fabric(1e6);
    let mesh = ClothMesh::sheet(0.3, 0.3, 7, 7);
    let pinned = PinSelector::parse("y>=0.3").unwrap().select(&mesh.nodes).unwrap();
    assert_eq!(pinned.iter().filter(|p| **p).count(), 7);
    let mut cloth = Cloth::new(mesh, params, &pinned).expect("cloth");
    let lift = DVec3::new(0.0, 0.0, 0.5);
    cloth.set_pin_motion(PinMotion { velocity: lift, ..PinMotion::default() });
    for _ in 0..20 {
        cloth.step(0.01, Integrator::ImplicitEuler).expect("step");
    }
    for (i, (p, rest)) in cloth.positions.iter().zip(&cloth.mesh().nodes).enumerate() {
        if pinned[i] {
            assert!((*p - (*rest + lift * 0.2)).length() < 1e-9, "pin {i} at {p}");
            assert!((cloth.velocities[i] - lift).length() < 1e-6, "pin {i} moves at {}", cloth.velocities[i]);
        }
    }
    let far_edge = cloth.positions[..7].iter().map(|p| p.z).sum::<f64>() / 7.0;
    assert!(far_edge < 0.0 && far_edge > -0.3, "the free edge hangs below the lifted pins: {far_edge}");
}

#[test]
fn damping_brings_a_falling_sheet_to_its_terminal_velocity() {
    // Drag −c·m·v on a free sheet under gravity: every node falls at g/c in the
    // end, with either integrator (both treat the drag implicitly).
    for integrator in [Integrator::ImplicitEuler, Integrator::Newmark] {
        let params = fabric(1e6);
        let mesh = ClothMesh::sheet(0.2, 0.2, 5, 5);
        let mut cloth = Cloth::new(mesh.clone(), params, &vec![false; mesh.nodes.len()]).unwrap();
        cloth.set_damping(5.0);
        for _ in 0..300 {
            cloth.step(0.01, integrator).unwrap();
        }
        let terminal = 9.81 / 5.0;
        for v in &cloth.velocities {
            assert!((v.z + terminal).abs() < 1e-3 * terminal, "{integrator:?}: {v} against {terminal}");
            // Straight down, to the solver's tolerance (residuals of 10⁻⁶ of the weight).
            let sideways = v.truncate().length();
            assert!(sideways < 1e-6 * terminal, "{integrator:?}: falls straight: {v}");
        }
    }
}

#[test]
fn a_129_by_129_sheet_at_a_large_step_stays_finite_and_comes_to_rest() {
    // 16,641 nodes at dt = 0.1 s, ten times the default: a 1 m sheet tilted
    // 6° lands edge-first on a floor, tips flat and stops. Every step must
    // converge (halving if it has to) and leave every position finite.
    let params = fabric(1e7);
    let mut mesh = ClothMesh::sheet(1.0, 1.0, 129, 129);
    for p in &mut mesh.nodes {
        // Tilt about the x axis (lengths kept): the y = 0 edge is lowest, 2 cm up.
        let (s, c) = 6f64.to_radians().sin_cos();
        *p = DVec3::new(p.x, c * p.y, 0.02 + s * p.y);
    }
    let mut cloth = Cloth::new(mesh.clone(), params, &vec![false; mesh.nodes.len()]).expect("cloth");
    let distance = 1e-3;
    cloth.set_colliders(vec![Collider::Plane { point: DVec3::ZERO, normal: DVec3::Z }], distance);
    let mut substeps = 0;
    for _ in 0..20 {
        substeps += cloth.step(0.1, Integrator::ImplicitEuler).expect("step").substeps;
        assert!(cloth.positions.iter().chain(&cloth.velocities).all(|v| v.is_finite()), "finite at t = {}", cloth.time);
    }
    let fastest = cloth.velocities.iter().map(|v| v.length()).fold(0.0, f64::max);
    assert!(fastest < 1e-3, "at rest after {} s: fastest node {fastest} m/s", cloth.time);
    let (low, high) = cloth.positions.iter().fold((f64::MAX, f64::MIN), |(l, h), p| (l.min(p.z), h.max(p.z)));
    assert!(low > 0.0 && high < distance, "lying on the floor, inside the contact distance: z in {low}..{high}");
    eprintln!("129 x 129 at dt = 0.1: {substeps} sub-steps for 20 steps");
}

#[test]
fn a_large_deflection_static_solve_halves_its_load_steps() {
    // A 0.5 m plate of 5 × 5 nodes clamped by its first two rows: linear theory
    // puts the tip 0.58 m down, more than the 0.375 m that is free, so the
    // plate swings far over. Newton cannot take a tenth of that load at once;
    // the static solve halves the increment where it must and still ends in
    // equilibrium.
    let params = fabric(1e8);
    let mesh = ClothMesh::sheet(0.5, 0.5, 5, 5);
    let pinned: Vec<bool> = mesh.nodes.iter().map(|p| p.y <= 0.13).collect();
    let mut cloth = Cloth::new(mesh, params, &pinned).expect("cloth");
    let stats = cloth.step(1.0, Integrator::Static).expect("equilibrium");
    assert!(stats.substeps > 10, "some load increment was halved: {stats:?}");
    let lowest = cloth.positions.iter().map(|p| p.z).fold(f64::MAX, f64::min);
    assert!((-0.375..-0.2).contains(&lowest), "the free edge hangs far down, but no further than it is long: {lowest}");
    let gradient = cloth.elastic_gradient(&cloth.positions);
    let weight: f64 = cloth.masses().iter().sum::<f64>() * 9.81;
    for (i, (g, m)) in gradient.iter().zip(cloth.masses()).enumerate() {
        if !cloth.is_pinned(i) {
            let residual = *g - *m * params.gravity;
            assert!(residual.length() < 1e-5 * weight, "node {i} out of balance by {residual}");
        }
    }
}
