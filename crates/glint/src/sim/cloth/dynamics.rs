//! [`Cloth`]: the state of a Discrete Elastic Plates sheet and its time steps.
//!
//! Every integrator is one Newton solve on the free degrees of freedom of
//! `s·M (q − q̃) + ∇E(q) − F = 0` with Jacobian `s·M + ∇²E(q)`:
//!
//! | integrator | s | q̃ (predicted position) |
//! | --- | --- | --- |
//! | implicit Euler | 1/dt² | q₀ + dt v₀ |
//! | Newmark-β (β = ¼, γ = ½) | 1/(β dt²) | q₀ + dt v₀ + dt² (½ − β) a₀ |
//! | static equilibrium | 0 | — (the load is applied in steps) |
//!
//! The Jacobian is the exact one, factorised by Cholesky. Where it is not
//! positive definite, its positive semi-definite approximation
//! ([`Hessian::Definite`]) is factorised instead, and LU of the exact one is the
//! last resort. A factorisation is reused for the next iteration while full
//! steps at least halve the residual (a chord iteration, much cheaper than a
//! new factorisation), and refreshed as soon as they do not.
//!
//! A step that does not converge, or that produces a NaN or a collapsed
//! triangle, is retried as two steps of half the size, down to dt / 2¹⁰.
//!
//! That is the converged solve ([`Solve::Converged`]); [`realtime`] is the other,
//! on a fixed budget per step.

use super::contact::Contact;
use super::energy::{
    bend_energy, bend_gradient, bend_hessian, hinge_angle, stretch_energy, stretch_gradient, stretch_hessian_block,
    Hessian,
};
use super::pins::PinMotion;
use super::system::{SparseSystem, SystemError, MAX_SYSTEM_BYTES};
use super::{ClothMesh, ClothMeshError, Topology};
use crate::scene::cloth::Collider;
pub use crate::scene::cloth::{ClothParams, ClothSetup, Integrator, Solve};
use glam::DVec3;
use p3_maybe_rayon::prelude::*;

#[cfg(test)]
mod conditioning;
pub mod gpu;
pub mod realtime;
mod surface;

/// Newmark's β (average acceleration: unconditionally stable, no numerical damping).
const NEWMARK_BETA: f64 = 0.25;
/// Newmark's γ.
const NEWMARK_GAMMA: f64 = 0.5;
/// Most Newton iterations (fresh or reused factorisations) in one solve.
const MAX_NEWTON: usize = 40;
/// A step is split in halves at most this many times.
pub const MAX_HALVINGS: u32 = 10;
/// Load steps of a static solve, when each converges: the load grows by
/// 1/`LOAD_STEPS` of the full load at a time, and by half as much again after a
/// failed increment (down to 2^-[`MAX_HALVINGS`] of that).
const LOAD_STEPS: usize = 10;
/// Most Newton iterations a static solve may take over all its load
/// increments before it is refused as not converging: what `STATIC_STEPS` in
/// the posing budget pays for. The large-deflection test plate takes 886 over
/// 40 increments; a 65 × 65 sheet that would not converge ran 25–30 s before.
pub const MAX_STATIC_ITERATIONS: u32 = 2_000;
/// A triangle whose area falls below this fraction of its rest area has collapsed.
const COLLAPSED_AREA: f64 = 1e-3;
/// Contact stiffness per node, in units of the node's weight over the contact
/// distance: a resting node sinks this fraction of the contact distance.
const CONTACT_STIFFNESS: f64 = 100.0;

/// Why a step could not be taken (the cloth is left as it was).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum StepError {
    /// Newton's method did not converge even at the smallest step (or load increment).
    #[error("Newton's method did not converge, even with the time step (or static load increment) halved {MAX_HALVINGS} times")]
    NotConverged,
    /// A static solve took more Newton iterations than it may.
    #[error("the static solve did not converge within {MAX_STATIC_ITERATIONS} Newton iterations")]
    StaticBudget,
}

/// What the last [`Cloth::step`] took.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepStats {
    /// Newton iterations over all sub-steps.
    pub newton_iterations: u32,
    /// Jacobian factorisations over all sub-steps (iterations that reuse one do not count).
    pub factorizations: u32,
    /// Sub-steps taken (1 unless the step was halved); for a static solve, the
    /// load increments.
    pub substeps: u32,
}

/// A cloth: its mesh and elastic constants, pins, and positions and velocities.
pub struct Cloth {
    mesh: ClothMesh,
    topology: Topology,
    params: ClothParams,
    rest_lengths: Vec<f64>,
    stretch_k: Vec<f64>,
    rest_angles: Vec<f64>,
    bend_k: f64,
    rest_areas: Vec<f64>,
    /// Largest `k / l̄²` of the edges: the stiffness that sets the residual's rounding floor.
    stiffest_edge: f64,
    /// Lumped mass per node, kg.
    mass: Vec<f64>,
    /// First free degree of freedom of each node (`None` when pinned).
    dof: Vec<Option<usize>>,
    free_dofs: usize,
    /// How many of the system's values each element owns (edges, then hinges, in
    /// pattern order); each free node's own 3×3 block follows them.
    element_lengths: Vec<usize>,
    /// For each element value, its (row, column) in the element's own Hessian
    /// (node-major, 3 coordinates per node).
    element_slots: Vec<[u8; 2]>,
    pin_motion: PinMotion,
    contact: Contact,
    /// Mass-proportional damping c, 1/s: each free node feels `−c·m·v`.
    damping: f64,
    system: SparseSystem,
    /// Node positions, metres.
    pub positions: Vec<DVec3>,
    /// Node velocities, m/s.
    pub velocities: Vec<DVec3>,
    accelerations: Vec<DVec3>,
    /// Simulated time, seconds.
    pub time: f64,
    /// What the last step took.
    pub last_step: StepStats,
    solve: Solve,
}

impl Cloth {
    /// A fresh simulation of `setup`, at rest.
    pub fn start(setup: &ClothSetup) -> Result<Self, ClothMeshError> {
        let mut cloth = Cloth::new(setup.mesh.clone(), setup.params, &setup.pinned)?;
        cloth.set_pin_motion(setup.pin_motion);
        cloth.set_colliders(setup.colliders.clone(), setup.contact_distance);
        cloth.set_damping(setup.damping);
        cloth.set_solve(setup.solve);
        Ok(cloth)
    }

    /// A cloth at rest in `mesh`'s positions with the nodes in `pinned` held fixed.
    pub fn new(mesh: ClothMesh, params: ClothParams, pinned: &[bool]) -> Result<Self, ClothMeshError> {
        let topology = mesh.topology()?;
        let n = mesh.nodes.len();
        let p = |i: u32| mesh.nodes[i as usize];
        let rest_lengths: Vec<f64> = topology.edges.iter().map(|e| (p(e[1]) - p(e[0])).length()).collect();
        // The edge's energy is ½ k_s l̄ ε²: stretch_energy's stiffness is k_s l̄.
        let stretch_k: Vec<f64> =
            rest_lengths.iter().map(|l| 3f64.sqrt() / 2.0 * params.young * params.thickness * l * l).collect();
        let rest_angles = topology.hinges.iter().map(|h| hinge_angle(&h.map(p))).collect();
        let stiffest_edge = stretch_k.iter().zip(&rest_lengths).map(|(k, l)| k / (l * l)).fold(0.0f64, f64::max);
        let bend_k = 2.0 / 3f64.sqrt() * params.young * params.thickness.powi(3) / 12.0;
        let mut mass = vec![0.0; n];
        let rest_areas: Vec<f64> =
            mesh.triangles.iter().map(|t| 0.5 * (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length()).collect();
        for (t, area) in mesh.triangles.iter().zip(&rest_areas) {
            for &v in t {
                mass[v as usize] += params.density * params.thickness * area / 3.0;
            }
        }
        let mut free_dofs = 0;
        let dof: Vec<Option<usize>> = (0..n)
            .map(|i| {
                (!pinned.get(i).copied().unwrap_or(false)).then(|| {
                    free_dofs += 3;
                    free_dofs - 3
                })
            })
            .collect();
        // Refuse a system too large for memory before allocating its pattern
        // (a 1025 × 1025 sheet's alone would be 3.5 GB).
        let free: Vec<bool> = dof.iter().map(Option::is_some).collect();
        let estimate = crate::scene::cloth::system_bytes(&topology, &free);
        if estimate > MAX_SYSTEM_BYTES {
            return Err(ClothMeshError::TooLarge { nodes: n, bytes: estimate, max: MAX_SYSTEM_BYTES });
        }
        // The pattern: each element's entries, then each free node's own block.
        let (mut pattern, mut element_slots) = (Vec::new(), Vec::new());
        let hinges = topology.hinges.iter().map(|h| &h[..]);
        let element_lengths = (topology.edges.iter().map(|e| &e[..]).chain(hinges))
            .map(|nodes| {
                let start = pattern.len();
                for (slot, at) in element_entries(nodes, &dof) {
                    element_slots.push(slot);
                    pattern.push(at);
                }
                pattern.len() - start
            })
            .collect();
        for first in (0..free_dofs).step_by(3) {
            pattern.extend(NODE_BLOCK.iter().map(|(r, c)| (first + r, first + c)));
        }
        let system = SparseSystem::new(free_dofs, &pattern).map_err(|e| match e {
            SystemError::TooLarge(bytes) => ClothMeshError::TooLarge { nodes: n, bytes, max: MAX_SYSTEM_BYTES },
            SystemError::Failed => ClothMeshError::TooLarge { nodes: n, bytes: estimate, max: MAX_SYSTEM_BYTES },
        })?;
        Ok(Self {
            positions: mesh.nodes.clone(),
            velocities: vec![DVec3::ZERO; n],
            // At rest in its rest shape only gravity accelerates it.
            accelerations: dof.iter().map(|d| if d.is_some() { params.gravity } else { DVec3::ZERO }).collect(),
            mesh,
            topology,
            params,
            rest_lengths,
            stretch_k,
            rest_angles,
            bend_k,
            rest_areas,
            stiffest_edge,
            mass,
            dof,
            free_dofs,
            element_lengths,
            element_slots,
            pin_motion: PinMotion::default(),
            contact: Contact::default(),
            damping: 0.0,
            system,
            time: 0.0,
            last_step: StepStats::default(),
            solve: Solve::Converged,
        })
    }

    /// Solve each time step to convergence (the default) or on a fixed budget.
    pub fn set_solve(&mut self, solve: Solve) {
        self.solve = solve;
    }

    /// How time steps are solved.
    pub fn solve(&self) -> Solve {
        self.solve
    }

    /// Move the pinned nodes rigidly: at time t each is at `motion.at(rest, t)`.
    pub fn set_pin_motion(&mut self, motion: PinMotion) {
        self.pin_motion = motion;
    }

    /// Collide the nodes with `colliders`, keeping them `distance` metres off
    /// each surface (see [`super::contact`]).
    pub fn set_colliders(&mut self, colliders: Vec<Collider>, distance: f64) {
        self.contact = Contact { colliders, distance };
    }

    /// Damp motion with a drag `−c·m·v` on every free node (`c` in 1/s, 0 for
    /// none, the default): a stand-in for air and internal friction, so a drape
    /// settles instead of swinging for ever. It is implicit like the rest: the
    /// velocity is the step's end velocity. Negative or non-finite `c` counts as 0.
    pub fn set_damping(&mut self, c: f64) {
        self.damping = if c.is_finite() { c.max(0.0) } else { 0.0 };
    }

    /// The colliders and contact distance.
    pub fn contact(&self) -> &Contact {
        &self.contact
    }

    /// The mesh (rest positions and triangles).
    pub fn mesh(&self) -> &ClothMesh {
        &self.mesh
    }

    /// Edges and hinges.
    pub fn topology(&self) -> &Topology {
        &self.topology
    }

    /// Lumped mass of each node, kg.
    pub fn masses(&self) -> &[f64] {
        &self.mass
    }

    /// Whether node `i` is pinned.
    pub fn is_pinned(&self, i: usize) -> bool {
        self.dof[i].is_none()
    }

    /// Stretching plus bending energy at `positions`, joules.
    pub fn elastic_energy(&self, positions: &[DVec3]) -> f64 {
        let p = |i: u32| positions[i as usize];
        let stretch: f64 = (self.topology.edges.iter().zip(&self.rest_lengths).zip(&self.stretch_k))
            .map(|((e, &l), &k)| stretch_energy(p(e[0]), p(e[1]), l, k))
            .sum();
        let bend: f64 = (self.topology.hinges.iter().zip(&self.rest_angles))
            .map(|(h, &rest)| bend_energy(&h.map(p), rest, self.bend_k))
            .sum();
        stretch + bend
    }

    /// Kinetic + elastic − gravity's work (potential relative to the origin), joules.
    pub fn total_energy(&self) -> f64 {
        self.energy_of(&self.positions, &self.velocities)
    }

    /// [`total_energy`](Self::total_energy) at `positions` moving at `velocities`.
    fn energy_of(&self, positions: &[DVec3], velocities: &[DVec3]) -> f64 {
        let kinetic: f64 = self.mass.iter().zip(velocities).map(|(m, v)| 0.5 * m * v.length_squared()).sum();
        let gravity: f64 = self.mass.iter().zip(positions).map(|(m, x)| -m * self.params.gravity.dot(*x)).sum();
        kinetic + self.elastic_energy(positions) + gravity
    }

    /// ∇E at `positions`, per node.
    pub fn elastic_gradient(&self, positions: &[DVec3]) -> Vec<DVec3> {
        let p = |i: u32| positions[i as usize];
        let mut g = vec![DVec3::ZERO; positions.len()];
        for ((e, &l), &k) in self.topology.edges.iter().zip(&self.rest_lengths).zip(&self.stretch_k) {
            let f = stretch_gradient(p(e[0]), p(e[1]), l, k);
            g[e[0] as usize] -= f;
            g[e[1] as usize] += f;
        }
        for (h, &rest) in self.topology.hinges.iter().zip(&self.rest_angles) {
            for (node, f) in h.iter().zip(bend_gradient(&h.map(p), rest, self.bend_k)) {
                g[*node as usize] += f;
            }
        }
        g
    }

    /// Fill the system with `scale·M + ∇²E(positions)` over the free DOFs.
    fn assemble(&mut self, positions: &[DVec3], scale: f64, kind: Hessian) {
        let p = |i: u32| positions[i as usize];
        let values = &mut self.system.values;
        let blocks_at = values.len() - 2 * self.free_dofs;
        let (elements, blocks) = values.split_at_mut(blocks_at);
        let edges = self.topology.edges.len();
        let mut slots = self.element_slots.as_slice();
        let slot_runs: Vec<&[[u8; 2]]> = (self.element_lengths.iter())
            .map(|&length| {
                let (run, rest) = slots.split_at(length);
                slots = rest;
                run
            })
            .collect();
        let runs = split_runs(elements, &self.element_lengths);
        runs.into_par_iter().zip(slot_runs).enumerate().for_each(|(i, (out, slots))| {
            let at = |s: &[u8; 2]| (usize::from(s[0]), usize::from(s[1]));
            if i < edges {
                let e = self.topology.edges[i];
                let k = stretch_hessian_block(p(e[0]), p(e[1]), self.rest_lengths[i], self.stretch_k[i], kind);
                for (v, (row, col)) in out.iter_mut().zip(slots.iter().map(at)) {
                    let sign = if row / 3 == col / 3 { 1.0 } else { -1.0 };
                    *v = sign * k[row % 3][col % 3];
                }
            } else {
                let h = self.topology.hinges[i - edges];
                let m = bend_hessian(&h.map(p), self.rest_angles[i - edges], self.bend_k, kind);
                for (v, (row, col)) in out.iter_mut().zip(slots.iter().map(at)) {
                    *v = m[row][col];
                }
            }
        });
        for (node, first) in self.dof.iter().enumerate() {
            if let Some(first) = *first {
                let k = contact_stiffness(self.mass[node], &self.params, &self.contact);
                let (_, mut block) = self.contact.gradient_and_hessian(positions[node], k);
                for (r, row) in block.iter_mut().enumerate() {
                    row[r] += scale * self.mass[node];
                }
                for (out, (r, c)) in blocks[2 * first..2 * first + 6].iter_mut().zip(NODE_BLOCK) {
                    *out = block[r][c];
                }
            }
        }
    }

    /// Contact stiffness of `node`.
    fn contact_k(&self, node: usize) -> f64 {
        contact_stiffness(self.mass[node], &self.params, &self.contact)
    }

    /// Residual `s·M (q − q̃) + ∇E(q) − λ·F` over the free DOFs, and its norm.
    fn residual(&self, q: &[DVec3], scale: f64, predicted: &[DVec3], load: f64) -> (Vec<f64>, f64) {
        let g = self.elastic_gradient(q);
        let mut r = vec![0.0; self.free_dofs];
        for (node, first) in self.dof.iter().enumerate() {
            if let Some(first) = *first {
                let m = self.mass[node];
                let (contact, _) = self.contact.gradient_and_hessian(q[node], self.contact_k(node));
                let v = scale * m * (q[node] - predicted[node]) + g[node] + contact - load * m * self.params.gravity;
                r[first..first + 3].copy_from_slice(&v.to_array());
            }
        }
        let norm = r.iter().map(|v| v * v).sum::<f64>().sqrt();
        (r, norm)
    }

    /// The potential whose gradient is the residual: `½ s (q − q̃)ᵀ M (q − q̃) + E(q) − λ Fᵀ q`.
    fn potential(&self, q: &[DVec3], scale: f64, predicted: &[DVec3], load: f64) -> f64 {
        let external: f64 = (self.mass.iter().zip(q).zip(predicted).enumerate())
            .filter(|(node, _)| self.dof[*node].is_some())
            .map(|(node, ((m, x), p))| {
                0.5 * scale * m * (*x - *p).length_squared() - load * m * self.params.gravity.dot(*x)
                    + self.contact.energy(*x, self.contact_k(node))
            })
            .sum();
        external + self.elastic_energy(q)
    }

    /// Newton's method from `q` (modified in place) on the residual above,
    /// counting its work in `stats`. `None` when it does not converge or goes bad.
    fn newton(
        &mut self,
        q: &mut [DVec3],
        scale: f64,
        predicted: &[DVec3],
        load: f64,
        stats: &mut StepStats,
    ) -> Option<()> {
        let weight: f64 = self.mass.iter().sum::<f64>() * self.params.gravity.length() * load;
        let (mut r, mut norm) = self.residual(q, scale, predicted, load);
        // Forces balance to a millionth of the load (and of the start's imbalance),
        // or to the rounding floor of the stiffest edges, whichever is larger.
        let extent = q.iter().fold(0.0f64, |m, p| m.max(p.abs().max_element()));
        let floor = f64::EPSILON * extent * self.stiffest_edge * (self.free_dofs as f64).sqrt();
        let tolerance = (1e-6 * (weight + norm)).max(floor) + 1e-14;
        let mut factored = false;
        for _ in 0..MAX_NEWTON {
            if norm <= tolerance {
                return Some(());
            }
            if !factored {
                self.factorize_jacobian(q, scale)?;
                stats.factorizations += 1;
            }
            stats.newton_iterations += 1;
            let mut step: Vec<f64> = r.iter().map(|v| -v).collect();
            self.system.solve(&mut step).ok()?;
            // Backtrack until the potential or the residual falls. The residual
            // alone is no guide from a flat sheet: bending it stretches the
            // (very stiff) edges to second order, so the first full step raises
            // the residual by orders of magnitude while lowering the potential.
            let potential = self.potential(q, scale, predicted, load);
            let mut alpha = 1.0;
            let trial = loop {
                let trial = self.moved(q, &step, alpha);
                let (tr, tn) = self.residual(&trial, scale, predicted, load);
                let better = tn < norm || self.potential(&trial, scale, predicted, load) <= potential;
                if tn.is_finite() && (better || alpha < 1.0 / 1024.0) {
                    break (trial, tr, tn);
                }
                alpha *= 0.5;
            };
            factored = alpha == 1.0 && trial.2 <= 0.5 * norm;
            q.copy_from_slice(&trial.0);
            (r, norm) = (trial.1, trial.2);
        }
        (norm <= tolerance).then_some(())
    }

    /// Factorise the Jacobian at `q`: the exact one by Cholesky, else its
    /// definite approximation by Cholesky, else the exact one by LU.
    fn factorize_jacobian(&mut self, q: &[DVec3], scale: f64) -> Option<()> {
        self.assemble(q, scale, Hessian::Exact);
        if self.system.factorize_cholesky() {
            return Some(());
        }
        self.assemble(q, scale, Hessian::Definite);
        if self.system.factorize_cholesky() {
            return Some(());
        }
        self.assemble(q, scale, Hessian::Exact);
        self.system.factorize_lu().ok()
    }

    /// Whether a triangle has (nearly) collapsed or a position is not finite.
    fn broken(&self, q: &[DVec3]) -> bool {
        q.iter().any(|p| !p.is_finite())
            || self.mesh.triangles.iter().zip(&self.rest_areas).any(|(t, rest)| {
                let [a, b, c] = t.map(|v| q[v as usize]);
                0.5 * (b - a).cross(c - a).length() < COLLAPSED_AREA * rest
            })
    }

    /// Node accelerations, m/s² (the Newmark integrator's; zero otherwise).
    pub fn accelerations(&self) -> &[DVec3] {
        &self.accelerations
    }

    /// Go on from `positions`, `velocities` and `accelerations` at `time`
    /// seconds (a simulation cache's), when they are as many as its nodes.
    pub fn resume(&mut self, [positions, velocities, accelerations]: [Vec<DVec3>; 3], time: f64) -> Result<(), String> {
        let n = self.positions.len();
        if [&positions, &velocities, &accelerations].iter().any(|v| v.len() != n) {
            return Err(format!("{} node positions, where the cloth has {n} nodes", positions.len()));
        }
        (self.positions, self.velocities, self.accelerations, self.time) = (positions, velocities, accelerations, time);
        Ok(())
    }

    /// Advance by `dt` seconds with `integrator` (a static solve ignores `dt`).
    /// Pinned nodes stay where they are. On failure nothing changes.
    pub fn step(&mut self, dt: f64, integrator: Integrator) -> Result<StepStats, StepError> {
        let mut stats = StepStats::default();
        if integrator == Integrator::Static {
            let mut q = self.positions.clone();
            let unused = q.clone(); // no inertia: the predicted position is never read
            let (full, mut load, mut halvings) = (1.0 / LOAD_STEPS as f64, 0.0, 0);
            while load < 1.0 {
                // The last increment ends exactly at the full load, whatever the rounding.
                let next = load + full / f64::from(1u32 << halvings);
                let next = if next > 1.0 - 1e-9 { 1.0 } else { next };
                let mut trial = q.clone();
                match self.newton(&mut trial, 0.0, &unused, next, &mut stats).filter(|_| !self.broken(&trial)) {
                    _ if stats.newton_iterations > MAX_STATIC_ITERATIONS => return Err(StepError::StaticBudget),
                    Some(()) => (q, load, stats.substeps) = (trial, next, stats.substeps + 1),
                    None if halvings < MAX_HALVINGS => halvings += 1,
                    None => return Err(StepError::NotConverged),
                }
            }
            self.positions = q;
            self.velocities.fill(DVec3::ZERO);
            self.accelerations.fill(DVec3::ZERO);
            self.last_step = stats;
            return Ok(stats);
        }
        self.substep(dt, integrator, 0, &mut stats)?;
        self.last_step = stats;
        Ok(stats)
    }

    /// The inertia term with damping folded in. The end velocity is linear in
    /// the end position, `v₁ = κ (q − q_d)` (implicit Euler: κ = 1/dt, q_d = x₀;
    /// Newmark: κ = γ/(β dt), q_d = q̃ − (v₀ + dt(1−γ)a₀)/κ), so the drag's
    /// residual `c m κ (q − q_d)` and the inertia's `s m (q − q̃)` add up to one
    /// term `s' m (q − q̂)` with `s' = s + cκ` and `q̂ = (s q̃ + cκ q_d)/s'`.
    fn damped(&self, dt: f64, integrator: Integrator, scale: f64, predicted: &[DVec3]) -> (f64, Vec<DVec3>) {
        if self.damping == 0.0 {
            return (scale, predicted.to_vec());
        }
        let kappa = match integrator {
            Integrator::ImplicitEuler => 1.0 / dt,
            _ => NEWMARK_GAMMA / (NEWMARK_BETA * dt),
        };
        let drag = self.damping * kappa;
        let total = scale + drag;
        let target = (0..predicted.len())
            .map(|i| {
                let q_d = match integrator {
                    Integrator::ImplicitEuler => self.positions[i],
                    _ => {
                        let v = self.velocities[i] + dt * (1.0 - NEWMARK_GAMMA) * self.accelerations[i];
                        predicted[i] - v / kappa
                    }
                };
                (scale * predicted[i] + drag * q_d) / total
            })
            .collect();
        (total, target)
    }

    /// The inertia term of a step of `dt` from now: its scale s and the
    /// predicted positions q̃ (the table in the module's documentation).
    fn inertia(&self, dt: f64, integrator: Integrator) -> (f64, Vec<DVec3>) {
        match integrator {
            Integrator::ImplicitEuler => {
                (1.0 / (dt * dt), self.positions.iter().zip(&self.velocities).map(|(x, v)| *x + dt * *v).collect())
            }
            _ => (
                1.0 / (NEWMARK_BETA * dt * dt),
                (self.positions.iter().zip(&self.velocities).zip(&self.accelerations))
                    .map(|((x, v), a)| *x + dt * *v + dt * dt * (0.5 - NEWMARK_BETA) * *a)
                    .collect(),
            ),
        }
    }

    /// What a step of `dt` with `integrator` from now would minimise, at the
    /// end positions `q`: the incremental potential (damping folded in,
    /// contact included), and the norm of its gradient over the free
    /// degrees of freedom (the residual Newton's method drives to zero).
    /// For measuring another solver's answer ([`gpu::GpuCloth`]) against
    /// this one's.
    pub fn step_objective(&self, q: &[DVec3], dt: f64, integrator: Integrator) -> (f64, f64) {
        let (scale, predicted) = self.inertia(dt, integrator);
        let (scale, target) = self.damped(dt, integrator, scale, &predicted);
        (self.potential(q, scale, &target, 1.0), self.residual(q, scale, &target, 1.0).1)
    }

    fn substep(&mut self, dt: f64, integrator: Integrator, depth: u32, stats: &mut StepStats) -> Result<(), StepError> {
        let (scale, predicted) = self.inertia(dt, integrator);
        // Newton starts where the last acceleration would carry each free node
        // (the membrane's forces there are about half those at `predicted`,
        // which ignores acceleration: 2.1 → 3.2 steps/s on the 65 × 65 bench);
        // pinned nodes start, and stay, on their path.
        let q_start = |node: usize| match self.dof[node] {
            Some(_) => self.positions[node] + dt * self.velocities[node] + dt * dt * self.accelerations[node],
            None => self.pin_motion.at(self.mesh.nodes[node], self.time + dt),
        };
        let mut q: Vec<DVec3> = (0..self.positions.len()).map(q_start).collect();
        let (solve_scale, target) = self.damped(dt, integrator, scale, &predicted);
        let solved = match self.solve {
            Solve::Converged | Solve::Gpu => self.newton(&mut q, solve_scale, &target, 1.0, stats),
            Solve::Realtime => self.realtime_solve(&mut q, solve_scale, &target, stats),
        };
        match solved.filter(|_| !self.broken(&q)) {
            Some(()) => {
                let (velocities, accelerations) = self.end_motion(&q, dt, integrator, scale, &predicted);
                // The realtime solve is inexact, and an inexact implicit step can
                // gain energy (still pins cannot give it any): such a step is
                // refused and halved, as a failed one is.
                if self.solve == Solve::Realtime && self.gains_energy(&q, &velocities) {
                    return self.halve(dt, integrator, depth, stats);
                }
                (self.positions, self.velocities, self.accelerations) = (q, velocities, accelerations);
                stats.substeps += 1;
                self.time += dt;
                Ok(())
            }
            None => self.halve(dt, integrator, depth, stats),
        }
    }

    /// Take the sub-step `dt` as two of half its length (a failed or refused one).
    fn halve(&mut self, dt: f64, integrator: Integrator, depth: u32, stats: &mut StepStats) -> Result<(), StepError> {
        match depth {
            depth if depth < MAX_HALVINGS => {
                self.substep(dt / 2.0, integrator, depth + 1, stats)?;
                self.substep(dt / 2.0, integrator, depth + 1, stats)
            }
            _ => Err(StepError::NotConverged),
        }
    }

    /// Velocities and accelerations at the end of a sub-step of `dt` that ends at `q`.
    fn end_motion(
        &self,
        q: &[DVec3],
        dt: f64,
        integrator: Integrator,
        scale: f64,
        predicted: &[DVec3],
    ) -> (Vec<DVec3>, Vec<DVec3>) {
        let (mut velocities, mut accelerations) = (self.velocities.clone(), self.accelerations.clone());
        for node in 0..q.len() {
            if self.dof[node].is_none() {
                velocities[node] = (q[node] - self.positions[node]) / dt;
                continue;
            }
            let a1 = scale * (q[node] - predicted[node]);
            match integrator {
                Integrator::ImplicitEuler => {
                    let v1 = (q[node] - self.positions[node]) / dt;
                    accelerations[node] = (v1 - velocities[node]) / dt;
                    velocities[node] = v1;
                }
                _ => {
                    let a0 = accelerations[node];
                    velocities[node] += dt * ((1.0 - NEWMARK_GAMMA) * a0 + NEWMARK_GAMMA * a1);
                    accelerations[node] = a1;
                }
            }
        }
        (velocities, accelerations)
    }

    /// `q` moved by `alpha` times `step` (per free DOF); pinned nodes stay.
    fn moved(&self, q: &[DVec3], step: &[f64], alpha: f64) -> Vec<DVec3> {
        let mut moved = q.to_vec();
        for (node, first) in self.dof.iter().enumerate() {
            if let Some(first) = *first {
                moved[node] += alpha * DVec3::from_slice(&step[first..first + 3]);
            }
        }
        moved
    }
}

/// Contact stiffness of a node of `mass` (see [`CONTACT_STIFFNESS`]).
fn contact_stiffness(mass: f64, params: &ClothParams, contact: &Contact) -> f64 {
    CONTACT_STIFFNESS * mass * params.gravity.length().max(1.0) / contact.distance.max(1e-6)
}

/// Cut `values` into consecutive runs of the given lengths.
fn split_runs<'v>(mut values: &'v mut [f64], lengths: &[usize]) -> Vec<&'v mut [f64]> {
    lengths
        .iter()
        .map(|&length| {
            let (run, rest) = std::mem::take(&mut values).split_at_mut(length);
            values = rest;
            run
        })
        .collect()
}

/// The lower triangle of a 3×3 block on the diagonal: (row, column) pairs.
const NODE_BLOCK: [(usize, usize); 6] = [(0, 0), (1, 0), (1, 1), (2, 0), (2, 1), (2, 2)];

/// The entries an element contributes to the system's lower triangle, in
/// pattern order: `([row, column] in the element's Hessian, (row, column) in
/// the system)`, for every pair of free element nodes.
fn element_entries<'a>(
    nodes: &'a [u32],
    dof: &'a [Option<usize>],
) -> impl Iterator<Item = ([u8; 2], (usize, usize))> + 'a {
    let free = move |a: usize| dof[nodes[a] as usize];
    (0..3 * nodes.len()).flat_map(move |i| {
        (0..3 * nodes.len()).filter_map(move |j| {
            let (row, col) = (free(i / 3)? + i % 3, free(j / 3)? + j % 3);
            (row >= col).then_some(([i as u8, j as u8], (row, col)))
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn a_system_too_large_for_memory_is_refused_before_it_is_built() {
        let params = ClothParams { thickness: 1e-3, young: 1e7, poisson: 0.3, density: 200.0, gravity: DVec3::ZERO };
        // 1025 × 1025 nodes: about 22 GB of pattern and factor, refused from the counts.
        let mesh = ClothMesh::sheet(1.0, 1.0, 1025, 1025);
        let nodes = mesh.nodes.len();
        match Cloth::new(mesh, params, &[]) {
            Err(ClothMeshError::TooLarge { nodes: n, bytes, max }) => {
                assert_eq!((n, max), (nodes, MAX_SYSTEM_BYTES));
                assert!(bytes > max, "{bytes}");
            }
            Err(e) => panic!("{e}"),
            Ok(_) => panic!("a 1025 × 1025 cloth was built"),
        }
        let small = ClothMesh::sheet(1.0, 1.0, 9, 9);
        assert!(Cloth::new(small, params, &[]).is_ok());
    }

    #[test]
    fn the_assembled_jacobian_is_the_residuals_derivative() {
        let params = ClothParams {
            thickness: 1e-3,
            young: 1e6,
            poisson: 0.3,
            density: 200.0,
            gravity: DVec3::new(0.0, 0.0, -9.81),
        };
        let mesh = ClothMesh::sheet(0.3, 0.2, 4, 3);
        let pinned: Vec<bool> = (0..mesh.nodes.len()).map(|i| i == 0 || i == 3).collect();
        let mut cloth = Cloth::new(mesh, params, &pinned).unwrap();
        // A floor that some of the jittered nodes touch, so contact is checked too.
        cloth.set_colliders(vec![Collider::Plane { point: DVec3::ZERO, normal: DVec3::Z }], 0.01);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
        let q: Vec<DVec3> = cloth
            .positions
            .iter()
            .map(|p| {
                *p + DVec3::new(
                    rng.random_range(-0.01..0.01),
                    rng.random_range(-0.01..0.01),
                    rng.random_range(-0.03..0.03),
                )
            })
            .collect();
        let predicted: Vec<DVec3> = q.iter().map(|p| *p + DVec3::splat(0.001)).collect();
        let scale = 50.0;
        assert!(q.iter().any(|p| p.z < 0.01), "some nodes are in contact");
        cloth.assemble(&q, scale, Hessian::Exact);
        let jacobian = cloth.system.dense();
        let h = 1e-7;
        for (node, first) in cloth.dof.clone().iter().enumerate() {
            let Some(first) = *first else { continue };
            for axis in 0..3 {
                let (mut plus, mut minus) = (q.clone(), q.clone());
                plus[node][axis] += h;
                minus[node][axis] -= h;
                let (rp, _) = cloth.residual(&plus, scale, &predicted, 1.0);
                let (rm, _) = cloth.residual(&minus, scale, &predicted, 1.0);
                for row in 0..rp.len() {
                    let numeric = (rp[row] - rm[row]) / (2.0 * h);
                    let analytic = jacobian[row][first + axis];
                    assert!(
                        (numeric - analytic).abs() <= 1e-4 * (1.0 + analytic.abs()),
                        "({row}, {}): {analytic} vs {numeric}",
                        first + axis
                    );
                }
            }
        }
    }
}
