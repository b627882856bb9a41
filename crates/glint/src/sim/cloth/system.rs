//! The sparse linear system of a Newton step: a fixed pattern over the free
//! degrees of freedom (the lower triangle of the 3×3 blocks between the nodes
//! of each edge and hinge, and of each node with itself), filled anew when the
//! Jacobian is refreshed, and factorised ([`super::factor`]). Each entry's slot
//! in the matrix, the fill-reducing ordering and the symbolic Cholesky
//! factorisation are computed once; the numeric factor lives in a buffer reused
//! every time, so one factorisation can serve several solves.

use super::factor::{Cholesky, Lu};
use faer::sparse::{Pair, SparseColMat, SparseColMatRef, SymbolicSparseColMat};

/// Why a linear solve failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SolveFailed;

pub use crate::scene::cloth::{BYTES_PER_PATTERN_ENTRY, MAX_SYSTEM_BYTES};

/// An LU factor's size over the Cholesky factor's, for the memory check before
/// an LU factorisation: partial pivoting fills in far more than Cholesky (a
/// 257 × 257 static sheet's LU reached 5.25 GB, about 16 times its Cholesky
/// factor).
const LU_OVER_CHOLESKY: u64 = 16;

/// Why [`SparseSystem::new`] could not build a system.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SystemError {
    /// The Cholesky factor would take this many bytes, more than [`MAX_SYSTEM_BYTES`].
    TooLarge(u64),
    /// faer could not build the pattern or its symbolic factorisation.
    Failed,
}

/// The factor the last factorisation produced.
enum Factor {
    None,
    Cholesky,
    Lu,
}

/// A sparse symmetric system over `n` unknowns with a fixed pattern (lower triangle).
pub struct SparseSystem {
    n: usize,
    symbolic: SymbolicSparseColMat<usize>,
    /// Where each pattern entry's value goes among the matrix's (deduplicated) values.
    slots: Vec<usize>,
    /// The matrix's values in column order, duplicates summed.
    matrix_values: Vec<f64>,
    /// One value per pattern entry, in pattern order.
    pub values: Vec<f64>,
    cholesky: Cholesky,
    lu: Lu,
    factor: Factor,
    #[cfg(test)]
    pattern: Vec<(usize, usize)>,
}

impl SparseSystem {
    /// A system whose entries are `pattern`'s (row, column) pairs, in that
    /// order, each with row ≥ column: the matrix is their symmetric extension.
    /// Fails when the symbolic factorisation does not fit in memory, or when
    /// the pattern and numeric factor together would take more than
    /// [`MAX_SYSTEM_BYTES`] (checked before the factor is allocated).
    pub fn new(n: usize, pattern: &[(usize, usize)]) -> Result<Self, SystemError> {
        debug_assert!(pattern.iter().all(|(r, c)| r >= c), "lower triangle only");
        let pairs: Vec<Pair<usize, usize>> = pattern.iter().map(|&(row, col)| Pair { row, col }).collect();
        let (symbolic, _) =
            SymbolicSparseColMat::try_new_from_indices(n, n, &pairs).map_err(|_| SystemError::Failed)?;
        drop(pairs);
        let slots = pattern
            .iter()
            .map(|&(row, col)| {
                let rows = symbolic.row_idx_of_col_raw(col);
                rows.binary_search(&row).map(|i| symbolic.col_ptr()[col] + i).map_err(|_| SystemError::Failed)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let cholesky = Cholesky::new(symbolic.as_ref(), pattern.len() as u64 * BYTES_PER_PATTERN_ENTRY)?;
        Ok(Self {
            n,
            matrix_values: vec![0.0; symbolic.row_idx().len()],
            symbolic,
            slots,
            values: vec![0.0; pattern.len()],
            cholesky,
            lu: Lu::default(),
            factor: Factor::None,
            #[cfg(test)]
            pattern: pattern.to_vec(),
        })
    }

    /// The matrix as dense rows (duplicates summed, mirrored), for tests.
    #[cfg(test)]
    pub fn dense(&self) -> Vec<Vec<f64>> {
        let mut m = vec![vec![0.0; self.n]; self.n];
        for (&(r, c), v) in self.pattern.iter().zip(&self.values) {
            m[r][c] += v;
            if r != c {
                m[c][r] += v;
            }
        }
        m
    }

    /// Sum [`SparseSystem::values`] into the matrix's values, each into its slot.
    fn fill_matrix(&mut self) {
        self.matrix_values.fill(0.0);
        for (&slot, &v) in self.slots.iter().zip(&self.values) {
            self.matrix_values[slot] += v;
        }
    }

    /// Cholesky-factorise the matrix of [`SparseSystem::values`]; false (and no
    /// factor) when it is not positive definite.
    pub fn factorize_cholesky(&mut self) -> bool {
        self.factor = Factor::None;
        self.fill_matrix();
        let matrix = SparseColMatRef::new(self.symbolic.as_ref(), &self.matrix_values);
        let ok = self.cholesky.factorize(matrix);
        if ok {
            self.factor = Factor::Cholesky;
        }
        ok
    }

    /// LU-factorise the (symmetric, perhaps indefinite) matrix.
    /// Refused (as a failed factorisation) when its estimated size is over
    /// [`MAX_SYSTEM_BYTES`], before anything is allocated.
    pub fn factorize_lu(&mut self) -> Result<(), SolveFailed> {
        self.factor = Factor::None;
        if (8 * self.cholesky.len_val() as u64).saturating_mul(LU_OVER_CHOLESKY) > MAX_SYSTEM_BYTES {
            return Err(SolveFailed);
        }
        self.fill_matrix();
        let (n, lower) = (self.n, SparseColMatRef::new(self.symbolic.as_ref(), &self.matrix_values));
        // LU needs the whole matrix: the lower triangle plus its mirror.
        let mut triplets = Vec::with_capacity(2 * lower.compute_nnz());
        for (col, (rows, values)) in (0..n).map(|c| (c, (lower.row_idx_of_col_raw(c), lower.val_of_col(c)))) {
            for (&row, &v) in rows.iter().zip(values) {
                triplets.push(faer::sparse::Triplet::new(row, col, v));
                if row != col {
                    triplets.push(faer::sparse::Triplet::new(col, row, v));
                }
            }
        }
        let full = SparseColMat::try_new_from_triplets(self.n, self.n, &triplets).map_err(|_| SolveFailed)?;
        self.lu.factorize(full.as_ref())?;
        self.factor = Factor::Lu;
        Ok(())
    }

    /// Solve `A x = rhs` in place with the last factorisation.
    pub fn solve(&mut self, rhs: &mut [f64]) -> Result<(), SolveFailed> {
        match self.factor {
            Factor::None => return Err(SolveFailed),
            Factor::Cholesky => self.cholesky.solve(rhs),
            Factor::Lu => self.lu.solve(rhs),
        }
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
        let pattern = [(0, 0), (0, 0), (1, 0), (1, 1)];
        let mut system = SparseSystem::new(2, &pattern).unwrap();
        system.values.copy_from_slice(&[3.0, 1.0, 1.0, 3.0]);
        assert!(system.factorize_cholesky());
        let mut x = [1.0, 2.0];
        system.solve(&mut x).unwrap();
        assert!((4.0 * x[0] + x[1] - 1.0).abs() < 1e-12 && (x[0] + 3.0 * x[1] - 2.0).abs() < 1e-12, "{x:?}");
        // A second right-hand side reuses the factor.
        let mut y = [0.0, 1.0];
        system.solve(&mut y).unwrap();
        assert!((4.0 * y[0] + y[1]).abs() < 1e-12 && (y[0] + 3.0 * y[1] - 1.0).abs() < 1e-12, "{y:?}");
        system.values.copy_from_slice(&[0.5, 0.5, 2.0, -1.0]);
        assert!(!system.factorize_cholesky(), "indefinite");
        assert_eq!(system.solve(&mut [1.0, 2.0]), Err(SolveFailed), "no factor after a failure");
        system.factorize_lu().unwrap();
        let mut x = [1.0, 2.0];
        system.solve(&mut x).unwrap();
        assert!((x[0] + 2.0 * x[1] - 1.0).abs() < 1e-12 && (2.0 * x[0] - x[1] - 2.0).abs() < 1e-12, "{x:?}");
    }
}
