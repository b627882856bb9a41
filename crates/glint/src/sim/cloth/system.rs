//! The sparse linear system of a Newton step: a fixed pattern over the free
//! degrees of freedom (the lower triangle of the 3×3 blocks between the nodes
//! of each edge and hinge, and of each node with itself), filled anew when the
//! Jacobian is refreshed, and factorised with faer. Each entry's slot in the
//! matrix, the fill-reducing ordering and the symbolic Cholesky factorisation are
//! computed once; the numeric factor lives in a buffer reused every time, so
//! one factorisation can serve several solves.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::solvers::Solve;
use faer::matrix_free::conjugate_gradient::{conjugate_gradient, conjugate_gradient_scratch, CgError, CgParams};
use faer::matrix_free::{InitialGuessStatus, LinOp, Precond};
use faer::reborrow::ReborrowMut;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering};
use faer::sparse::linalg::matmul::sparse_dense_matmul;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{Pair, SparseColMat, SparseColMatRef, SymbolicSparseColMat};
use faer::{Accum, Conj, MatMut, MatRef, Par, Side, Spec};

/// Factorisations run on one thread: on the 2-core reference machine faer's
/// parallel supernodal Cholesky was slower (9.4 s against 8.2 s for 20 steps
/// of a 65 × 65 sheet), its threads contending with rayon's element assembly.
const FACTOR_PAR: faer::Par = faer::Par::Seq;

/// Why a linear solve failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SolveFailed;

/// Most bytes one cloth's linear system may hold: its pattern and the numeric
/// Cholesky factor (estimated from the pattern before either is allocated), or
/// an LU factor. Chosen from measurements on the 23 GiB, 2-core reference
/// machine (see `docs/limits.md`): a 257 × 257 sheet's system takes about
/// 0.3 GiB, while a 1025 × 1025 sheet would need over 8 GiB.
pub const MAX_SYSTEM_BYTES: u64 = 2 << 30;

/// Bytes per pattern entry while a system is built: the entry itself (16), its
/// faer index pair (16) and the sort faer does on them (16), its value (8)
/// and slot (8), and the element's local index (2), rounded up.
pub const BYTES_PER_PATTERN_ENTRY: u64 = 72;

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

/// The factor the last [`SparseSystem::factorize`] produced.
enum Factor {
    None,
    Cholesky,
    Lu(Box<Lu<usize, f64>>),
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
    cholesky: SymbolicCholesky<usize>,
    cholesky_values: Vec<f64>,
    scratch: MemBuffer,
    lu: Option<SymbolicLu<usize>>,
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
        let cholesky =
            factorize_symbolic_cholesky(symbolic.as_ref(), Side::Lower, SymmetricOrdering::Amd, Default::default())
                .map_err(|_| SystemError::Failed)?;
        let par = FACTOR_PAR;
        let scratch_layout = cholesky
            .factorize_numeric_llt_scratch::<f64>(par, Spec::default())
            .or(cholesky.solve_in_place_scratch::<f64>(1, par));
        let bytes = (pattern.len() as u64 * BYTES_PER_PATTERN_ENTRY)
            .saturating_add(8 * cholesky.len_val() as u64)
            .saturating_add(scratch_layout.size_bytes() as u64);
        if bytes > MAX_SYSTEM_BYTES {
            return Err(SystemError::TooLarge(bytes));
        }
        let scratch = MemBuffer::new(scratch_layout);
        Ok(Self {
            n,
            cholesky_values: vec![0.0; cholesky.len_val()],
            matrix_values: vec![0.0; symbolic.row_idx().len()],
            symbolic,
            slots,
            values: vec![0.0; pattern.len()],
            cholesky,
            scratch,
            lu: None,
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
        let par = FACTOR_PAR;
        let stack = MemStack::new(&mut self.scratch);
        let ok = self
            .cholesky
            .factorize_numeric_llt(
                &mut self.cholesky_values,
                matrix,
                Side::Lower,
                Default::default(),
                par,
                stack,
                Spec::default(),
            )
            .is_ok();
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
        let symbolic = match &self.lu {
            Some(s) => s.clone(),
            None => self.lu.insert(SymbolicLu::try_new(full.symbolic()).map_err(|_| SolveFailed)?).clone(),
        };
        let lu = Lu::try_new_with_symbolic(symbolic, full.as_ref()).map_err(|_| SolveFailed)?;
        self.factor = Factor::Lu(Box::new(lu));
        Ok(())
    }

    /// Whether a Cholesky factor is kept (from the last successful
    /// [`factorize_cholesky`](Self::factorize_cholesky)).
    pub fn has_cholesky(&self) -> bool {
        matches!(self.factor, Factor::Cholesky)
    }

    /// Solve `A x = rhs` for the matrix of the current [`values`](Self::values)
    /// (which must be positive definite) by conjugate gradients from the guess in
    /// `x`, preconditioned by the kept Cholesky factor of an earlier matrix, for
    /// at most `max_iterations`, or until the residual is `tolerance` times
    /// `rhs`'s norm. Returns the iterations taken; `x` holds the last iterate even
    /// when the budget ran out first. Fails without a kept factor, or when the
    /// matrix or the factor is found not to be positive definite.
    pub fn solve_cg(
        &mut self,
        rhs: &[f64],
        x: &mut [f64],
        max_iterations: usize,
        tolerance: f64,
    ) -> Result<usize, SolveFailed> {
        if !self.has_cholesky() {
            return Err(SolveFailed);
        }
        self.fill_matrix();
        let lower = SparseColMatRef::new(self.symbolic.as_ref(), &self.matrix_values);
        let diagonal: Vec<f64> = (0..self.n)
            .map(|c| {
                let rows = lower.row_idx_of_col_raw(c);
                rows.binary_search(&c).map_or(0.0, |i| lower.val_of_col(c)[i])
            })
            .collect();
        let matrix = Mirrored { lower, diagonal };
        let kept = KeptFactor { factor: LltRef::new(&self.cholesky, &self.cholesky_values) };
        let par = FACTOR_PAR;
        let mut scratch = MemBuffer::new(conjugate_gradient_scratch(&kept, &matrix, 1, par));
        let params = CgParams {
            initial_guess: InitialGuessStatus::MaybeNonZero,
            abs_tolerance: 0.0,
            rel_tolerance: tolerance,
            max_iters: max_iterations,
            ..Default::default()
        };
        let b = MatRef::from_column_major_slice(rhs, self.n, 1);
        let out = MatMut::from_column_major_slice_mut(x, self.n, 1);
        let stack = MemStack::new(&mut scratch);
        let iterations = match conjugate_gradient(out, &kept, &matrix, b, params, |_| {}, par, stack) {
            Ok(info) => info.iter_count,
            Err(CgError::NoConvergence { .. }) => max_iterations,
            Err(_) => return Err(SolveFailed),
        };
        if x.iter().all(|v| v.is_finite()) {
            Ok(iterations)
        } else {
            Err(SolveFailed)
        }
    }

    /// Solve `A x = rhs` in place with the last factorisation.
    pub fn solve(&mut self, rhs: &mut [f64]) -> Result<(), SolveFailed> {
        let view = faer::MatMut::from_column_major_slice_mut(rhs, self.n, 1);
        match &self.factor {
            Factor::None => return Err(SolveFailed),
            Factor::Cholesky => {
                let par = FACTOR_PAR;
                let stack = MemStack::new(&mut self.scratch);
                LltRef::new(&self.cholesky, &self.cholesky_values).solve_in_place_with_conj(Conj::No, view, par, stack);
            }
            Factor::Lu(lu) => lu.solve_in_place(view),
        }
        if rhs.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(SolveFailed)
        }
    }
}

/// The symmetric matrix whose lower triangle (diagonal included) is `lower`, as
/// an operator: `A x = L x + Lᵀ x − D x`.
#[derive(Debug)]
struct Mirrored<'a> {
    lower: SparseColMatRef<'a, usize, f64>,
    diagonal: Vec<f64>,
}

impl LinOp<f64> for Mirrored<'_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }

    fn nrows(&self) -> usize {
        self.diagonal.len()
    }

    fn ncols(&self) -> usize {
        self.diagonal.len()
    }

    fn apply(&self, mut out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, _stack: &mut MemStack) {
        sparse_dense_matmul(out.rb_mut(), Accum::Replace, self.lower, rhs, 1.0, par);
        sparse_dense_matmul(out.rb_mut(), Accum::Add, self.lower.transpose(), rhs, 1.0, par);
        for col in 0..rhs.ncols() {
            for (row, d) in self.diagonal.iter().enumerate() {
                out[(row, col)] -= d * rhs[(row, col)];
            }
        }
    }

    fn conj_apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, stack: &mut MemStack) {
        self.apply(out, rhs, par, stack);
    }
}

/// A Cholesky factor kept from an earlier matrix, applied as `(L Lᵀ)⁻¹`: the
/// preconditioner of [`SparseSystem::solve_cg`].
#[derive(Debug)]
struct KeptFactor<'a> {
    factor: LltRef<'a, usize, f64>,
}

impl LinOp<f64> for KeptFactor<'_> {
    fn apply_scratch(&self, rhs_ncols: usize, par: Par) -> StackReq {
        self.factor.symbolic().solve_in_place_scratch::<f64>(rhs_ncols, par)
    }

    fn nrows(&self) -> usize {
        self.factor.symbolic().nrows()
    }

    fn ncols(&self) -> usize {
        self.factor.symbolic().ncols()
    }

    fn apply(&self, mut out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, stack: &mut MemStack) {
        out.copy_from(rhs);
        self.apply_in_place(out, par, stack);
    }

    fn conj_apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, stack: &mut MemStack) {
        self.apply(out, rhs, par, stack);
    }
}

impl Precond<f64> for KeptFactor<'_> {
    fn apply_in_place_scratch(&self, rhs_ncols: usize, par: Par) -> StackReq {
        self.apply_scratch(rhs_ncols, par)
    }

    fn apply_in_place(&self, rhs: MatMut<'_, f64>, par: Par, stack: &mut MemStack) {
        self.factor.solve_in_place_with_conj(Conj::No, rhs, par, stack);
    }

    fn conj_apply_in_place(&self, rhs: MatMut<'_, f64>, par: Par, stack: &mut MemStack) {
        self.apply_in_place(rhs, par, stack);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conjugate_gradients_solve_a_changed_matrix_with_the_kept_factor() {
        // A 3×3 tridiagonal SPD matrix, factorised, then changed: CG preconditioned
        // by the old factor solves the new one.
        let pattern = [(0, 0), (1, 0), (1, 1), (2, 1), (2, 2)];
        let mut system = SparseSystem::new(3, &pattern).unwrap();
        let mut x = [0.0; 3];
        assert_eq!(system.solve_cg(&[1.0, 2.0, 3.0], &mut x, 10, 1e-12), Err(SolveFailed), "no kept factor");
        system.values.copy_from_slice(&[4.0, 1.0, 4.0, 1.0, 4.0]);
        assert!(system.factorize_cholesky());
        system.values.copy_from_slice(&[5.0, -1.0, 3.0, 2.0, 6.0]);
        let rhs = [1.0, 2.0, 3.0];
        let iterations = system.solve_cg(&rhs, &mut x, 10, 1e-12).unwrap();
        let dense = system.dense();
        for (row, want) in dense.iter().zip(rhs) {
            let got: f64 = row.iter().zip(&x).map(|(a, b)| a * b).sum();
            assert!((got - want).abs() < 1e-10, "A x = {got}, want {want} ({x:?})");
        }
        assert!((1..=3).contains(&iterations), "{iterations} iterations for 3 unknowns");
        // With the factor of this very matrix, one iteration.
        assert!(system.factorize_cholesky());
        let mut y = [0.0; 3];
        assert_eq!(system.solve_cg(&rhs, &mut y, 10, 1e-12).unwrap(), 1);
    }

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
