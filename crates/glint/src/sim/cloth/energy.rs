//! The two elastic energies of Discrete Elastic Plates, with their exact
//! gradients and Hessians: edge stretching and hinge bending.
//!
//! - Stretching of edge (xᵢ, xⱼ): `E = ½ k ε²`, `ε = |xⱼ − xᵢ| / l̄ − 1`.
//! - Bending of hinge (x₀, x₁; x₂, x₃), edge x₀x₁ shared by triangles (x₀, x₁, x₂)
//!   and (x₀, x₁, x₃): `E = ½ k (θ − θ̄)²` with θ the signed dihedral angle,
//!   `e = x₁ − x₀`, `n₁ = e × (x₂ − x₀)`, `n₂ = (x₃ − x₀) × e`,
//!   `θ = atan2(ê · (n₁ × n₂), n₁ · n₂)` (the same as `sign(e · (n₁ × n₂)) ·
//!   atan2(|n₁ × n₂|, n₁ · n₂)`, as both normals are perpendicular to e).
//!
//! The gradient of θ is the classic one: each wing moves along its face normal,
//! `∂θ/∂x₂ = −|e| n₁ / |n₁|²`, `∂θ/∂x₃ = −|e| n₂ / |n₂|²`, and the edge's ends
//! take the wings' gradients weighted by where each wing projects onto the edge.
//! The Hessian of θ is the exact directional derivative of that gradient, by the
//! product rule, along each of the twelve coordinates.

use glam::DVec3;

/// Stretching energy of one edge with rest length `rest` and stiffness `k`.
pub fn stretch_energy(xi: DVec3, xj: DVec3, rest: f64, k: f64) -> f64 {
    let strain = (xj - xi).length() / rest - 1.0;
    0.5 * k * strain * strain
}

/// Gradient of [`stretch_energy`] with respect to `xj` (the one for `xi` is its negative).
pub fn stretch_gradient(xi: DVec3, xj: DVec3, rest: f64, k: f64) -> DVec3 {
    let d = xj - xi;
    let length = d.length();
    k * (length / rest - 1.0) / (rest * length) * d
}

/// Which Hessian [`stretch_hessian_block`] and [`bend_hessian`] form.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hessian {
    /// The exact second derivative (may be indefinite).
    Exact,
    /// A positive semi-definite approximation: a compressed edge's negative
    /// sideways stiffness is dropped, and so is the hinge term
    /// `k (θ − θ̄) ∇²θ`, leaving `k ∇θ ∇θᵀ` (Gauss–Newton).
    Definite,
}

/// The 3×3 block `K` of [`stretch_energy`]'s Hessian (rows, then columns):
/// the 6×6 Hessian over (xi, xj) is `[[K, −K], [−K, K]]`.
pub fn stretch_hessian_block(xi: DVec3, xj: DVec3, rest: f64, k: f64, kind: Hessian) -> [[f64; 3]; 3] {
    let d = xj - xi;
    let length = d.length();
    let u = d / length;
    let along = k / (rest * rest);
    let across = k * (length / rest - 1.0) / (rest * length);
    let across = if kind == Hessian::Definite { across.max(0.0) } else { across };
    let mut block = [[0.0; 3]; 3];
    for (r, row) in block.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            let identity = if r == c { 1.0 } else { 0.0 };
            *v = along * u[r] * u[c] + across * (identity - u[r] * u[c]);
        }
    }
    block
}

/// Signed dihedral angle of the hinge `x` = [x₀, x₁, x₂, x₃] (0 when flat).
pub fn hinge_angle(x: &[DVec3; 4]) -> f64 {
    let e = x[1] - x[0];
    let n1 = e.cross(x[2] - x[0]);
    let n2 = (x[3] - x[0]).cross(e);
    (e.normalize().dot(n1.cross(n2))).atan2(n1.dot(n2))
}

/// The hinge quantities ∇θ is built from, computed once so that the Hessian's
/// twelve directional derivatives share them.
struct HingeFrame {
    e: DVec3,
    a: DVec3,
    b: DVec3,
    n1: DVec3,
    n2: DVec3,
    length: f64,
    a1: f64,
    a2: f64,
    t2: f64,
    t3: f64,
    /// ∇θ per node.
    gradient: [DVec3; 4],
}

impl HingeFrame {
    fn new(x: &[DVec3; 4]) -> Self {
        let (e, a, b) = (x[1] - x[0], x[2] - x[0], x[3] - x[0]);
        let (n1, n2) = (e.cross(a), b.cross(e));
        let length = e.length();
        let (a1, a2) = (n1.length_squared(), n2.length_squared());
        // Wings: g = −(L / A) n.
        let (g2, g3) = (-(length / a1) * n1, -(length / a2) * n2);
        // Where each wing projects onto the edge, as a fraction t of it from x₀.
        let l2 = length * length;
        let (t2, t3) = (a.dot(e) / l2, b.dot(e) / l2);
        let g1 = -(t2 * g2 + t3 * g3);
        let g0 = -((1.0 - t2) * g2 + (1.0 - t3) * g3);
        Self { e, a, b, n1, n2, length, a1, a2, t2, t3, gradient: [g0, g1, g2, g3] }
    }

    /// The derivative of ∇θ along `dx` (the Hessian of θ times `dx`).
    fn derivative(&self, dx: &[DVec3; 4]) -> [DVec3; 4] {
        let Self { e, a, b, n1, n2, length, a1, a2, t2, t3, gradient: [_, _, g2, g3] } = *self;
        let (de, da, db) = (dx[1] - dx[0], dx[2] - dx[0], dx[3] - dx[0]);
        let dn1 = de.cross(a) + e.cross(da);
        let dn2 = db.cross(e) + b.cross(de);
        let d_length = e.dot(de) / length;
        let (da1, da2) = (2.0 * n1.dot(dn1), 2.0 * n2.dot(dn2));
        let wing = |n: DVec3, dn: DVec3, area2: f64, d_area2: f64| {
            let ds = d_length / area2 - length * d_area2 / (area2 * area2);
            -(ds * n + (length / area2) * dn)
        };
        let (dg2, dg3) = (wing(n1, dn1, a1, da1), wing(n2, dn2, a2, da2));
        let l2 = length * length;
        let fraction = |t: f64, w: DVec3, dw: DVec3| (dw.dot(e) + w.dot(de)) / l2 - 2.0 * t * d_length / length;
        let (dt2, dt3) = (fraction(t2, a, da), fraction(t3, b, db));
        let dg1 = -(dt2 * g2 + t2 * dg2 + dt3 * g3 + t3 * dg3);
        let dg0 = -(-dt2 * g2 + (1.0 - t2) * dg2 - dt3 * g3 + (1.0 - t3) * dg3);
        [dg0, dg1, dg2, dg3]
    }
}

/// Bending energy of a hinge with rest angle `rest` and stiffness `k`.
pub fn bend_energy(x: &[DVec3; 4], rest: f64, k: f64) -> f64 {
    let d = hinge_angle(x) - rest;
    0.5 * k * d * d
}

/// Gradient of [`bend_energy`], per hinge node.
pub fn bend_gradient(x: &[DVec3; 4], rest: f64, k: f64) -> [DVec3; 4] {
    let s = k * (hinge_angle(x) - rest);
    HingeFrame::new(x).gradient.map(|v| s * v)
}

/// Hessian of [`bend_energy`] over the 12 coordinates (node-major: x₀.x, x₀.y, …, x₃.z).
pub fn bend_hessian(x: &[DVec3; 4], rest: f64, k: f64, kind: Hessian) -> [[f64; 12]; 12] {
    let mut h = [[0.0; 12]; 12];
    let frame = HingeFrame::new(x);
    let gradient: [f64; 12] = std::array::from_fn(|i| frame.gradient[i / 3][i % 3]);
    if kind == Hessian::Exact {
        let strain = hinge_angle(x) - rest;
        for col in 0..12 {
            let mut dx = [DVec3::ZERO; 4];
            dx[col / 3][col % 3] = 1.0;
            let dg = frame.derivative(&dx);
            for (row, line) in h.iter_mut().enumerate() {
                line[col] = k * strain * dg[row / 3][row % 3];
            }
        }
    }
    for (line, gr) in h.iter_mut().zip(gradient) {
        for (v, gc) in line.iter_mut().zip(gradient) {
            *v += k * gr * gc;
        }
    }
    // Exact in exact arithmetic; rounding leaves it a hair off symmetric.
    let mut symmetric = h;
    for (row, line) in symmetric.iter_mut().enumerate() {
        for (col, v) in line.iter_mut().enumerate() {
            *v = 0.5 * (h[row][col] + h[col][row]);
        }
    }
    symmetric
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// A hinge near a flat pair of triangles, each coordinate jittered.
    fn random_hinge(rng: &mut rand_pcg::Pcg64) -> [DVec3; 4] {
        let base = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.4, 0.9, 0.0),
            DVec3::new(0.6, -0.8, 0.0),
        ];
        base.map(|p| {
            p + DVec3::new(rng.random_range(-0.3..0.3), rng.random_range(-0.3..0.3), rng.random_range(-0.4..0.4))
        })
    }

    fn flat(x: &[DVec3; 4]) -> [f64; 12] {
        std::array::from_fn(|i| x[i / 3][i % 3])
    }

    fn unflat(v: &[f64; 12]) -> [DVec3; 4] {
        std::array::from_fn(|n| DVec3::new(v[3 * n], v[3 * n + 1], v[3 * n + 2]))
    }

    /// Central differences of `f` at `v`, per coordinate.
    fn numeric<const N: usize>(v: &[f64; 12], f: impl Fn(&[f64; 12]) -> [f64; N]) -> [[f64; N]; 12] {
        let h = 1e-6;
        std::array::from_fn(|i| {
            let (mut plus, mut minus) = (*v, *v);
            plus[i] += h;
            minus[i] -= h;
            let (a, b) = (f(&plus), f(&minus));
            std::array::from_fn(|k| (a[k] - b[k]) / (2.0 * h))
        })
    }

    fn assert_close(analytic: f64, numeric: f64, scale: f64, what: &str) {
        assert!(
            (analytic - numeric).abs() <= 1e-5 * scale.max(1.0),
            "{what}: analytic {analytic} vs numeric {numeric}"
        );
    }

    #[test]
    fn flat_hinge_has_zero_angle_and_folding_up_is_negative() {
        let mut x = [DVec3::ZERO, DVec3::X, DVec3::new(0.5, 1.0, 0.0), DVec3::new(0.5, -1.0, 0.0)];
        assert_eq!(hinge_angle(&x), 0.0);
        x[2].z = 1.0;
        x[3].z = 1.0;
        assert!((hinge_angle(&x) + std::f64::consts::FRAC_PI_2).abs() < 1e-12, "{}", hinge_angle(&x));
    }

    #[test]
    fn bending_gradient_and_hessian_match_finite_differences() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        for _ in 0..50 {
            let x = random_hinge(&mut rng);
            let (rest, k) = (rng.random_range(-0.5..0.5), rng.random_range(0.5..2.0));
            let v = flat(&x);
            let g = flat(&bend_gradient(&x, rest, k));
            let num_g = numeric(&v, |p| [bend_energy(&unflat(p), rest, k)]);
            let h = bend_hessian(&x, rest, k, Hessian::Exact);
            let num_h = numeric(&v, |p| flat(&bend_gradient(&unflat(p), rest, k)));
            let scale = h.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
            for i in 0..12 {
                assert_close(g[i], num_g[i][0], 1.0, &format!("gradient {i}"));
                for j in 0..12 {
                    assert_close(h[i][j], num_h[j][i], scale, &format!("hessian ({i}, {j})"));
                }
            }
        }
    }

    #[test]
    fn stretching_gradient_and_hessian_match_finite_differences() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        for _ in 0..50 {
            let xi = DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            let xj =
                xi + DVec3::new(rng.random_range(0.2..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            let (rest, k) = (rng.random_range(0.3..1.5), rng.random_range(0.5..2.0));
            let mut v = [0.0; 12];
            v[..3].copy_from_slice(&xi.to_array());
            v[3..6].copy_from_slice(&xj.to_array());
            let energy = |p: &[f64; 12]| {
                let (a, b) = (DVec3::from_slice(&p[..3]), DVec3::from_slice(&p[3..6]));
                stretch_energy(a, b, rest, k)
            };
            let gradient = |p: &[f64; 12]| {
                let (a, b) = (DVec3::from_slice(&p[..3]), DVec3::from_slice(&p[3..6]));
                let g = stretch_gradient(a, b, rest, k);
                let mut out = [0.0; 12];
                out[..3].copy_from_slice(&(-g).to_array());
                out[3..6].copy_from_slice(&g.to_array());
                out
            };
            let num_g = numeric(&v, |p| [energy(p)]);
            let g = gradient(&v);
            let num_h = numeric(&v, gradient);
            let block = stretch_hessian_block(xi, xj, rest, k, Hessian::Exact);
            for i in 0..6 {
                assert_close(g[i], num_g[i][0], 1.0, &format!("gradient {i}"));
                for j in 0..6 {
                    let sign = if (i < 3) == (j < 3) { 1.0 } else { -1.0 };
                    assert_close(sign * block[i % 3][j % 3], num_h[j][i], 1.0, &format!("hessian ({i}, {j})"));
                }
            }
        }
    }

    #[test]
    fn energies_gradients_and_hessians_do_not_change_under_rigid_motion() {
        // E(Rx + t) = E(x), ∇E(Rx + t) = R ∇E(x) and ∇²E(Rx + t) = R ∇²E(x) Rᵀ,
        // per node block, for both energies and both Hessians, to rounding.
        let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
        let unit = |rng: &mut rand_pcg::Pcg64| {
            DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
        };
        for _ in 0..50 {
            let rotation = glam::DMat3::from_axis_angle(unit(&mut rng).normalize(), rng.random_range(-3.0..3.0));
            let shift = 10.0 * unit(&mut rng);
            let x = random_hinge(&mut rng);
            let y = x.map(|p| rotation * p + shift);
            let (rest, k) = (rng.random_range(-0.3..0.3), rng.random_range(1.0..2.0));
            let close =
                |a: f64, b: f64, what: &str| assert!((a - b).abs() <= 1e-10 * b.abs().max(1.0), "{what}: {a} vs {b}");
            close(bend_energy(&y, rest, k), bend_energy(&x, rest, k), "bending energy");
            close(stretch_energy(y[0], y[1], 0.8, k), stretch_energy(x[0], x[1], 0.8, k), "stretching energy");
            for (gy, gx) in bend_gradient(&y, rest, k).iter().zip(bend_gradient(&x, rest, k)) {
                assert!(gy.distance(rotation * gx) <= 1e-10 * gx.length().max(1.0), "bending gradient");
            }
            let (sy, sx) = (stretch_gradient(y[0], y[1], 0.8, k), stretch_gradient(x[0], x[1], 0.8, k));
            assert!(sy.distance(rotation * sx) <= 1e-10 * sx.length().max(1.0), "stretching gradient");
            // R·H·Rᵀ per 3×3 block.
            let rotated = |block: glam::DMat3| rotation * block * rotation.transpose();
            let block_of = |h: &[[f64; 12]; 12], i: usize, j: usize| {
                glam::DMat3::from_cols_array_2d(&std::array::from_fn(|c| {
                    std::array::from_fn(|r| h[3 * i + r][3 * j + c])
                }))
            };
            for kind in [Hessian::Exact, Hessian::Definite] {
                let (hy, hx) = (bend_hessian(&y, rest, k, kind), bend_hessian(&x, rest, k, kind));
                let scale = hx.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
                for i in 0..4 {
                    for j in 0..4 {
                        let d = block_of(&hy, i, j) - rotated(block_of(&hx, i, j));
                        assert!(
                            d.to_cols_array().iter().all(|v| v.abs() <= 1e-10 * scale.max(1.0)),
                            "{kind:?} bending Hessian ({i}, {j})"
                        );
                    }
                }
                let as_mat = |b: [[f64; 3]; 3]| {
                    glam::DMat3::from_cols_array_2d(&std::array::from_fn(|c| std::array::from_fn(|r| b[r][c])))
                };
                let by = as_mat(stretch_hessian_block(y[0], y[1], 0.8, k, kind));
                let bx = as_mat(stretch_hessian_block(x[0], x[1], 0.8, k, kind));
                assert!(
                    (by - rotated(bx)).to_cols_array().iter().all(|v| v.abs() <= 1e-10 * k),
                    "{kind:?} stretching Hessian"
                );
            }
        }
    }

    #[test]
    fn definite_hessians_have_no_negative_directions() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        let quadratic = |h: &dyn Fn(usize, usize) -> f64, v: &[f64]| -> f64 {
            (0..v.len()).map(|i| (0..v.len()).map(|j| v[i] * h(i, j) * v[j]).sum::<f64>()).sum()
        };
        let (mut exact_negative, mut checked) = (0, 0);
        for _ in 0..50 {
            let x = random_hinge(&mut rng);
            let rest = rng.random_range(-0.5..0.5);
            let exact = bend_hessian(&x, rest, 1.0, Hessian::Exact);
            let definite = bend_hessian(&x, rest, 1.0, Hessian::Definite);
            // A squeezed edge (length 0.5 of rest 1).
            let block = stretch_hessian_block(DVec3::ZERO, DVec3::new(0.3, 0.4, 0.0), 1.0, 1.0, Hessian::Definite);
            let edge = |i: usize, j: usize| if (i < 3) == (j < 3) { 1.0 } else { -1.0 } * block[i % 3][j % 3];
            for _ in 0..20 {
                let v: [f64; 12] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
                assert!(quadratic(&|i, j| definite[i][j], &v) >= -1e-12);
                assert!(quadratic(&edge, &v[..6]) >= -1e-12);
                exact_negative += usize::from(quadratic(&|i, j| exact[i][j], &v) < 0.0);
                checked += 1;
            }
        }
        assert!(exact_negative > 0, "the exact hinge Hessian is indefinite somewhere ({checked} tries)");
    }
}
