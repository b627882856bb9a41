//! The sparse linear system of a Newton step: a fixed pattern over the free
//! degrees of freedom (3×3 blocks between the nodes of each edge and hinge, plus
//! the diagonal), filled anew each iteration and factorised with faer. The
//! pattern's sort order and symbolic factorisation are computed once.

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, Lu, SymbolicLlt, SymbolicLu};
use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat};
use faer::Side;

/// Why a linear solve failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SolveFailed;

/// A sparse symmetric system over `n` unknowns with a fixed pattern.
pub struct SparseSystem {
    n: usize,
    symbolic: SymbolicSparseColMat<usize>,
    argsort: Argsort<usize>,
    /// One value per pattern entry (duplicates summed by faer), in pattern order.
    pub values: Vec<f64>,
    llt: Option<SymbolicLlt<usize>>,
    lu: Option<SymbolicLu<usize>>,
    #[cfg(test)]
    pattern: Vec<(usize, usize)>,
}

impl SparseSystem {
    /// A system whose entries are `pattern`'s (row, column) pairs, in that order.
    pub fn new(n: usize, pattern: &[(usize, usize)]) -> Self {
        let pairs: Vec<Pair<usize, usize>> = pattern.iter().map(|&(row, col)| Pair { row, col }).collect();
        let (symbolic, argsort) =
            SymbolicSparseColMat::try_new_from_indices(n, n, &pairs).expect("pattern indices are below n");
        Self {
            n,
            symbolic,
            argsort,
            values: vec![0.0; pattern.len()],
            llt: None,
            lu: None,
            #[cfg(test)]
            pattern: pattern.to_vec(),
        }
    }

    /// The matrix as dense rows (duplicates summed), for tests.
    #[cfg(test)]
    pub fn dense(&self) -> Vec<Vec<f64>> {
        let mut m = vec![vec![0.0; self.n]; self.n];
        for (&(r, c), v) in self.pattern.iter().zip(&self.values) {
            m[r][c] += v;
        }
        m
    }

    /// Solve `A x = rhs` in place, `A` the matrix of [`SparseSystem::values`]:
    /// Cholesky when `A` is positive definite, LU otherwise.
    pub fn solve(&mut self, rhs: &mut [f64]) -> Result<(), SolveFailed> {
        let matrix = SparseColMat::new_from_argsort(self.symbolic.clone(), &self.argsort, &self.values)
            .map_err(|_| SolveFailed)?;
        let rhs_view = faer::MatMut::from_column_major_slice_mut(rhs, self.n, 1);
        let llt_symbolic = match &self.llt {
            Some(s) => s.clone(),
            None => {
                let s = SymbolicLlt::try_new(matrix.symbolic(), Side::Lower).map_err(|_| SolveFailed)?;
                self.llt.insert(s).clone()
            }
        };
        if let Ok(llt) = Llt::try_new_with_symbolic(llt_symbolic, matrix.as_ref(), Side::Lower) {
            llt.solve_in_place(rhs_view);
            return Ok(());
        }
        let lu_symbolic = match &self.lu {
            Some(s) => s.clone(),
            None => {
                let s = SymbolicLu::try_new(matrix.symbolic()).map_err(|_| SolveFailed)?;
                self.lu.insert(s).clone()
            }
        };
        let lu = Lu::try_new_with_symbolic(lu_symbolic, matrix.as_ref()).map_err(|_| SolveFailed)?;
        lu.solve_in_place(rhs_view);
        if rhs.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(SolveFailed)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_positive_definite_and_indefinite_systems() {
        // [[4, 1], [1, 3]] (duplicates summed: 4 = 3 + 1) and then an indefinite one.
        let pattern = [(0, 0), (0, 0), (0, 1), (1, 0), (1, 1)];
        let mut system = SparseSystem::new(2, &pattern);
        system.values.copy_from_slice(&[3.0, 1.0, 1.0, 1.0, 3.0]);
        let mut x = [1.0, 2.0];
        system.solve(&mut x).unwrap();
        assert!((4.0 * x[0] + x[1] - 1.0).abs() < 1e-12 && (x[0] + 3.0 * x[1] - 2.0).abs() < 1e-12, "{x:?}");
        system.values.copy_from_slice(&[0.5, 0.5, 2.0, 2.0, -1.0]);
        let mut x = [1.0, 2.0];
        system.solve(&mut x).unwrap();
        assert!((x[0] + 2.0 * x[1] - 1.0).abs() < 1e-12 && (2.0 * x[0] - x[1] - 2.0).abs() < 1e-12, "{x:?}");
    }
}
