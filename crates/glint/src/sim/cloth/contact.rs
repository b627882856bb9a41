//! Contact between cloth nodes and rigid colliders (planes, spheres, boxes).
//!
//! Each node closer to a collider than the contact distance δ (half the
//! cloth's thickness plus a margin) feels the penalty energy
//! `½ k (δ − φ)²`, φ the node's signed distance to the collider. The energy
//! joins the Newton solve like the elastic ones, so contact is implicit and
//! stable at any step. Its Hessian is taken as `k n nᵀ` (the Gauss–Newton
//! part: positive semi-definite, exact for planes and box faces).
//!
//! Contact is frictionless, and nodes only: a collider edge sharper than the
//! mesh spacing can poke between nodes. Cloth does not collide with itself.

use crate::scene::cloth::Collider;
use glam::DVec3;

/// Penalty contact against a set of colliders.
#[derive(Clone, Debug, Default)]
pub struct Contact {
    /// The colliders.
    pub colliders: Vec<Collider>,
    /// Contact distance δ, metres.
    pub distance: f64,
}

impl Contact {
    /// `step` cut short where it would carry a node from outside every collider
    /// into one: the realtime solve's single iterations cannot see a collider
    /// the node is not yet near (its penalty starts δ off the surface), so a
    /// falling node would pass into a table top and leave through the far side.
    /// The motion is sampled at quarters; the node stops at the last sample
    /// still outside.
    pub fn clamp_motion(&self, from: DVec3, step: DVec3) -> DVec3 {
        let inside = |x: DVec3| self.colliders.iter().any(|c| c.distance(x).0 < 0.0);
        if self.colliders.is_empty() || inside(from) {
            return step;
        }
        let safe = [0.25, 0.5, 0.75, 1.0].into_iter().take_while(|t| !inside(from + *t * step)).last();
        step * safe.unwrap_or(0.0)
    }

    /// Penalty energy of one node with stiffness `k`.
    pub fn energy(&self, x: DVec3, k: f64) -> f64 {
        self.colliders.iter().map(|c| self.gap(c, x).map_or(0.0, |(g, _)| 0.5 * k * g * g)).sum()
    }

    /// Penalty gradient (∂E/∂x) and Gauss–Newton Hessian of one node.
    pub fn gradient_and_hessian(&self, x: DVec3, k: f64) -> (DVec3, [[f64; 3]; 3]) {
        let mut gradient = DVec3::ZERO;
        let mut hessian = [[0.0; 3]; 3];
        for c in &self.colliders {
            if let Some((g, n)) = self.gap(c, x) {
                gradient -= k * g * n;
                for (r, row) in hessian.iter_mut().enumerate() {
                    for (col, v) in row.iter_mut().enumerate() {
                        *v += k * n[r] * n[col];
                    }
                }
            }
        }
        (gradient, hessian)
    }

    /// How far `x` is inside the contact distance of `c` (positive), and the normal.
    fn gap(&self, c: &Collider, x: DVec3) -> Option<(f64, DVec3)> {
        let (phi, n) = c.distance(x);
        (phi < self.distance).then_some((self.distance - phi, n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colliders_parse_or_say_what_was_expected() {
        assert_eq!(Collider::parse("plane 0 0 1  0 0 2"), Ok(Collider::Plane { point: DVec3::Z, normal: DVec3::Z }));
        assert_eq!(
            Collider::parse("sphere 1 2 3 0.5"),
            Ok(Collider::Sphere { centre: DVec3::new(1.0, 2.0, 3.0), radius: 0.5 })
        );
        assert_eq!(Collider::parse("box 0 0 0 1 1 1"), Ok(Collider::Box { min: DVec3::ZERO, max: DVec3::ONE }));
        for bad in ["plane 0 0 0 0 0 0", "sphere 0 0 0 -1", "box 0 0 0 1 1 0", "cone 1 2 3", "sphere 0 0 x 1", ""] {
            assert!(Collider::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn signed_distances() {
        let plane = Collider::Plane { point: DVec3::ZERO, normal: DVec3::Z };
        assert_eq!(plane.distance(DVec3::new(3.0, 1.0, -0.5)), (-0.5, DVec3::Z));
        let sphere = Collider::Sphere { centre: DVec3::ONE, radius: 0.5 };
        let (d, n) = sphere.distance(DVec3::new(1.0, 1.0, 2.0));
        assert!((d - 0.5).abs() < 1e-12 && (n - DVec3::Z).length() < 1e-12);
        let table = Collider::Box { min: DVec3::new(-1.0, -1.0, 0.0), max: DVec3::new(1.0, 1.0, 0.1) };
        let (d, n) = table.distance(DVec3::new(0.2, 0.3, 0.3));
        assert!((d - 0.2).abs() < 1e-12 && n == DVec3::Z, "above the top: {d} {n}");
        let (d, n) = table.distance(DVec3::new(0.9, 0.0, 0.09));
        assert!((d + 0.01).abs() < 1e-12 && n == DVec3::Z, "just inside the top: {d} {n}");
        let (d, n) = table.distance(DVec3::new(2.0, 0.0, 1.1));
        assert!((d - 2f64.sqrt()).abs() < 1e-12 && (n - DVec3::new(1.0, 0.0, 1.0).normalize()).length() < 1e-12);
    }

    #[test]
    fn the_gradient_is_the_energys_derivative() {
        let contact = Contact {
            colliders: vec![
                Collider::Sphere { centre: DVec3::ZERO, radius: 1.0 },
                Collider::Plane { point: DVec3::new(0.0, 0.0, 0.9), normal: DVec3::Z },
            ],
            distance: 0.05,
        };
        let x = DVec3::new(0.3, 0.2, 0.9);
        let (g, _) = contact.gradient_and_hessian(x, 100.0);
        assert!(g.length() > 0.0);
        let h = 1e-7;
        for axis in 0..3 {
            let mut step = DVec3::ZERO;
            step[axis] = h;
            let numeric = (contact.energy(x + step, 100.0) - contact.energy(x - step, 100.0)) / (2.0 * h);
            assert!((numeric - g[axis]).abs() < 1e-5, "axis {axis}: {numeric} vs {}", g[axis]);
        }
    }
}
