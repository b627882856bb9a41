//! Both builds of the factorisations solve the same systems to the same answers.

use super::{chosen, simplicial};
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, SymbolicCholeskyRaw, SymmetricOrdering};
use faer::sparse::{SparseColMat, Triplet};
use faer::Side;

/// A sheet-like system: the nodes of a `side` × `side` grid, three unknowns
/// each, coupled to their eight neighbours, with `shift` added on the
/// diagonal (positive definite for shift ≥ 0, indefinite well below).
/// Returns its lower triangle and the whole matrix.
fn grid_system(side: usize, shift: f64) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
    let dof = |x: usize, y: usize, k: usize| 3 * (y * side + x) + k;
    let (mut lower, mut full) = (Vec::new(), Vec::new());
    for (y, x) in (0..side).flat_map(|y| (0..side).map(move |x| (y, x))) {
        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1), (-1, 1)] {
            let (nx, ny) = (x as isize + dx, y as isize + dy);
            if nx < 0 || ny < 0 || nx >= side as isize || ny >= side as isize {
                continue;
            }
            for (a, b) in (0..3).flat_map(|a| (0..3).map(move |b| (a, b))) {
                let (i, j) = (dof(nx as usize, ny as usize, a), dof(x, y, b));
                let same = (dx, dy) == (0, 0);
                // Diagonally dominant off the shift: 8 neighbours' 3 entries
                // of at most 0.3 each, against 9 on the diagonal.
                let v = if same && a == b {
                    9.0 + shift
                } else {
                    0.3 * (((i * 7 + j * 13 + (i * j) % 5) % 11) as f64 / 10.0 - 0.5)
                };
                if same && b > a {
                    continue; // each pair within a node once, from its lower triangle
                }
                let (r, c) = if i >= j { (i, j) } else { (j, i) };
                lower.push(Triplet::new(r, c, v));
                full.push(Triplet::new(r, c, v));
                if r != c {
                    full.push(Triplet::new(c, r, v));
                }
            }
        }
    }
    let n = 3 * side * side;
    (
        SparseColMat::try_new_from_triplets(n, n, &lower).unwrap(),
        SparseColMat::try_new_from_triplets(n, n, &full).unwrap(),
    )
}

fn rhs(n: usize) -> Vec<f64> {
    (0..n).map(|i| ((i * 31 % 17) as f64 - 8.0) / 8.0).collect()
}

/// `full * x - b`, largest entry.
fn residual(full: &SparseColMat<usize, f64>, x: &[f64], b: &[f64]) -> f64 {
    let mut ax = vec![0.0; x.len()];
    for (col, &xc) in x.iter().enumerate() {
        for (&row, &v) in full.row_idx_of_col_raw(col).iter().zip(full.val_of_col(col)) {
            ax[row] += v * xc;
        }
    }
    ax.iter().zip(b).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
}

fn max_difference(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
}

#[test]
fn cholesky_builds_agree_on_a_sheet_large_enough_for_supernodes() {
    let side = 40;
    let (lower, full) = grid_system(side, 0.0);
    // faer's own choice here is supernodal, so the two builds really differ.
    let symbolic =
        factorize_symbolic_cholesky(lower.symbolic(), Side::Lower, SymmetricOrdering::Amd, Default::default());
    assert!(matches!(symbolic.unwrap().raw(), SymbolicCholeskyRaw::Supernodal(_)), "faer chose simplicial");
    let mut chosen = chosen::Cholesky::new(lower.symbolic(), 0).unwrap();
    let mut simplicial = simplicial::Cholesky::new(lower.symbolic(), 0).unwrap();
    // The same ordering: the supernodes hold the simplicial factor's entries and some zeros.
    assert!(simplicial.len_val() <= chosen.len_val() && simplicial.len_val() > lower.compute_nnz());
    assert!(chosen.factorize(lower.as_ref()) && simplicial.factorize(lower.as_ref()));
    let b = rhs(3 * side * side);
    let (mut x_chosen, mut x_simplicial) = (b.clone(), b.clone());
    chosen.solve(&mut x_chosen);
    simplicial.solve(&mut x_simplicial);
    assert!(residual(&full, &x_simplicial, &b) < 1e-12, "{}", residual(&full, &x_simplicial, &b));
    assert!(max_difference(&x_chosen, &x_simplicial) < 1e-13, "{}", max_difference(&x_chosen, &x_simplicial));
    // The factor is reused for another right-hand side, and refactorised.
    let c: Vec<f64> = b.iter().map(|v| 1.0 - v).collect();
    let mut y = c.clone();
    simplicial.solve(&mut y);
    assert!(residual(&full, &y, &c) < 1e-12);
    let (indefinite, _) = grid_system(side, -12.0);
    assert!(!chosen.factorize(indefinite.as_ref()) && !simplicial.factorize(indefinite.as_ref()), "not definite");
}

#[test]
fn lu_builds_agree_on_an_indefinite_sheet() {
    let side = 12;
    let (_, full) = grid_system(side, -9.05);
    let b = rhs(3 * side * side);
    let (mut chosen, mut simplicial) = (chosen::Lu::default(), simplicial::Lu::default());
    for round in 0..2 {
        chosen.factorize(full.as_ref()).unwrap();
        simplicial.factorize(full.as_ref()).unwrap();
        let (mut x_chosen, mut x_simplicial) = (b.clone(), b.clone());
        chosen.solve(&mut x_chosen);
        simplicial.solve(&mut x_simplicial);
        let scale = x_chosen.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(residual(&full, &x_simplicial, &b) < 1e-9 * scale, "round {round}");
        assert!(max_difference(&x_chosen, &x_simplicial) < 1e-9 * scale, "round {round}");
    }
}

#[test]
fn memory_limit_counts_what_the_caller_holds() {
    let (lower, _) = grid_system(4, 0.0);
    let limit = crate::sim::cloth::MAX_SYSTEM_BYTES;
    for other in [0, limit] {
        let fits = other == 0;
        assert_eq!(chosen::Cholesky::new(lower.symbolic(), other).is_ok(), fits);
        assert_eq!(simplicial::Cholesky::new(lower.symbolic(), other).is_ok(), fits);
    }
}
