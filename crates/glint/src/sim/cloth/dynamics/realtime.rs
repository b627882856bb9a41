//! The realtime solve ([`Solve::Realtime`]): a fixed budget per step instead of
//! Newton's method to convergence, for interactive use, with the same energies.
//!
//! - Each step takes at most [`NEWTON_ITERATIONS`] Newton iterations from the
//!   extrapolated start, fewer once the forces balance to 1 % of the weight
//!   (a falling sheet needs none). One, as in Baraff and Witkin's "large steps",
//!   drifted too far: 1.7 cm on average from the converged tablecloth at 2 s,
//!   and it halved a third of its steps.
//! - Each iteration solves the positive semi-definite Jacobian (Gauss–Newton
//!   hinge and edge terms, plus the mass) with a fresh Cholesky factor. Keeping
//!   a factor across iterations and steps as the preconditioner of at most 12
//!   conjugate-gradient iterations (tolerance 10⁻²) was slower at both sizes
//!   measured, as the kept factor went stale within a step or two: 103 against
//!   130 steps/s on the 33 × 33 tablecloth, 5.5 against 8.1 on a 65 × 65 one
//!   (`glint sim cloth --bench`, the commands in `docs/cloth.md`).
//! - A node's move is cut short where it would enter a collider (its penalty
//!   starts only δ off the surface, so an iteration does not see a table top the
//!   node is about to cross), then the move is taken as far as the incremental
//!   potential falls (full, half, … down to an eighth).
//! - When it does not fall, a NaN or a collapsed triangle appears, or the step
//!   gains energy ([`Cloth::step`]), the time step is halved as in the converged
//!   solve.

use super::{Cloth, Hessian, Solve, StepStats};
use glam::DVec3;

/// Most Newton iterations a step takes.
pub const NEWTON_ITERATIONS: usize = 3;

/// A step's forces balance when its residual is this fraction of the weight.
const TOLERANCE: f64 = 1e-2;

/// Halvings of the step's length the line search tries before refusing it.
const LINE_SEARCH_HALVINGS: u32 = 3;

/// Energy a realtime step may gain before it is refused, as a fraction of the
/// cloth's weight times its extent: far below the gains of a step going
/// unstable (a 65 × 65 sheet swinging from two corners gained 0.5 J in one
/// step from −0.18 J), above the noise of an inexact solve.
const ENERGY_SLACK: f64 = 1e-4;

impl Cloth {
    /// The realtime solve from `q` (moved in place) on the residual of
    /// [`Cloth::newton`]: at most [`NEWTON_ITERATIONS`] iterations, fewer once the
    /// forces balance to [`TOLERANCE`] of the weight; `None` when the step must
    /// be halved.
    pub(super) fn realtime_solve(
        &mut self,
        q: &mut [DVec3],
        scale: f64,
        predicted: &[DVec3],
        stats: &mut StepStats,
    ) -> Option<()> {
        debug_assert_eq!(self.solve, Solve::Realtime);
        let weight: f64 = self.mass.iter().sum::<f64>() * self.params.gravity.length();
        for _ in 0..NEWTON_ITERATIONS {
            let (r, norm) = self.residual(q, scale, predicted, 1.0);
            if !norm.is_finite() {
                return None;
            }
            if norm <= TOLERANCE * weight {
                break;
            }
            self.realtime_iteration(q, &r, scale, predicted, stats)?;
        }
        Some(())
    }

    /// Kinetic, elastic, gravitational and contact energy of the cloth at
    /// `positions` moving at `velocities`, joules.
    fn mechanical_energy(&self, positions: &[DVec3], velocities: &[DVec3]) -> f64 {
        let contact: f64 = (positions.iter().enumerate())
            .filter(|(node, _)| self.dof[*node].is_some())
            .map(|(node, x)| self.contact.energy(*x, self.contact_k(node)))
            .sum();
        self.energy_of(positions, velocities) + contact
    }

    /// Whether the cloth would have more energy (beyond rounding) at `positions`
    /// moving at `velocities` than now, with pins that stand still.
    pub(super) fn gains_energy(&self, positions: &[DVec3], velocities: &[DVec3]) -> bool {
        let still = self.pin_motion.velocity == DVec3::ZERO && self.pin_motion.angular_velocity == DVec3::ZERO;
        let weight: f64 = self.mass.iter().sum::<f64>() * self.params.gravity.length().max(1.0);
        let extent = positions.iter().fold(0.0f64, |m, p| m.max(p.abs().max_element())).max(1.0);
        let before = self.mechanical_energy(&self.positions, &self.velocities);
        still && self.mechanical_energy(positions, velocities) > before + ENERGY_SLACK * weight * extent
    }

    /// One iteration from `q` with residual `r`: a fresh factor of the definite
    /// Jacobian, its Newton step cut short at colliders and shortened until the
    /// incremental potential falls; `None` when even an eighth of it raises the
    /// potential.
    fn realtime_iteration(
        &mut self,
        q: &mut [DVec3],
        r: &[f64],
        scale: f64,
        predicted: &[DVec3],
        stats: &mut StepStats,
    ) -> Option<()> {
        self.assemble(q, scale, Hessian::Definite);
        stats.factorizations += 1;
        stats.newton_iterations += 1;
        if !self.system.factorize_cholesky() {
            return None;
        }
        let mut step: Vec<f64> = r.iter().map(|v| -v).collect();
        self.system.solve(&mut step).ok()?;
        for (node, first) in self.dof.iter().enumerate() {
            if let Some(first) = *first {
                let wanted = DVec3::from_slice(&step[first..first + 3]);
                let allowed = self.contact.clamp_motion(q[node], wanted);
                step[first..first + 3].copy_from_slice(&allowed.to_array());
            }
        }
        let potential = self.potential(q, scale, predicted, 1.0);
        let mut alpha = 1.0;
        for _ in 0..=LINE_SEARCH_HALVINGS {
            let trial = self.moved(q, &step, alpha);
            let after = self.potential(&trial, scale, predicted, 1.0);
            if after.is_finite() && after <= potential {
                q.copy_from_slice(&trial);
                return Some(());
            }
            alpha *= 0.5;
        }
        None
    }
}
