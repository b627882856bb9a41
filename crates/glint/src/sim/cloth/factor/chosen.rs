//! Cholesky and LU as faer chooses them: supernodal where the factor is dense
//! enough, simplicial elsewhere (see [`super`]).

use super::PAR;
use crate::sim::cloth::system::{SolveFailed, SystemError, MAX_SYSTEM_BYTES};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering};
use faer::sparse::linalg::solvers::{Lu as NumericLu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Side, Spec};

/// A Cholesky factorisation of matrices with one pattern: its ordering and
/// symbolic factor computed once, its numeric factor in a buffer reused by
/// every [`Cholesky::factorize`].
pub struct Cholesky {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    scratch: MemBuffer,
}

impl Cholesky {
    /// The symbolic factorisation of the symmetric matrix whose lower triangle
    /// is `lower`. Fails with [`SystemError::TooLarge`] when `other_bytes`, the
    /// numeric factor and the scratch space together would take more than
    /// [`MAX_SYSTEM_BYTES`] (checked before those are allocated).
    pub fn new(lower: SymbolicSparseColMatRef<'_, usize>, other_bytes: u64) -> Result<Self, SystemError> {
        let symbolic = factorize_symbolic_cholesky(lower, Side::Lower, SymmetricOrdering::Amd, Default::default())
            .map_err(|_| SystemError::Failed)?;
        let scratch = symbolic
            .factorize_numeric_llt_scratch::<f64>(PAR, Spec::default())
            .or(symbolic.solve_in_place_scratch::<f64>(1, PAR));
        let bytes =
            other_bytes.saturating_add(8 * symbolic.len_val() as u64).saturating_add(scratch.size_bytes() as u64);
        if bytes > MAX_SYSTEM_BYTES {
            return Err(SystemError::TooLarge(bytes));
        }
        Ok(Self { values: vec![0.0; symbolic.len_val()], symbolic, scratch: MemBuffer::new(scratch) })
    }

    /// Values in the factor: its size over the matrix's, for memory estimates.
    pub fn len_val(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Factorise the matrix whose lower triangle is `lower` (the pattern given
    /// to [`Cholesky::new`]); false when it is not positive definite.
    pub fn factorize(&mut self, lower: SparseColMatRef<'_, usize, f64>) -> bool {
        let stack = MemStack::new(&mut self.scratch);
        self.symbolic
            .factorize_numeric_llt(
                &mut self.values,
                lower,
                Side::Lower,
                Default::default(),
                PAR,
                stack,
                Spec::default(),
            )
            .is_ok()
    }

    /// Solve `A x = rhs` in place with the last successful factorisation.
    pub fn solve(&mut self, rhs: &mut [f64]) {
        let rhs = MatMut::from_column_major_slice_mut(rhs, rhs.len(), 1);
        let stack = MemStack::new(&mut self.scratch);
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(Conj::No, rhs, PAR, stack);
    }
}

/// An LU factorisation with partial pivoting; its column ordering and
/// symbolic factor are computed on the first [`Lu::factorize`] and reused.
#[derive(Default)]
pub struct Lu {
    symbolic: Option<SymbolicLu<usize>>,
    numeric: Option<NumericLu<usize, f64>>,
}

impl Lu {
    /// Factorise `full`, the whole square matrix (each time with the same pattern).
    pub fn factorize(&mut self, full: SparseColMatRef<'_, usize, f64>) -> Result<(), SolveFailed> {
        self.numeric = None;
        let symbolic = match &self.symbolic {
            Some(s) => s.clone(),
            None => self.symbolic.insert(SymbolicLu::try_new(full.symbolic()).map_err(|_| SolveFailed)?).clone(),
        };
        self.numeric = Some(NumericLu::try_new_with_symbolic(symbolic, full).map_err(|_| SolveFailed)?);
        Ok(())
    }

    /// Solve `A x = rhs` in place with the last successful factorisation.
    pub fn solve(&mut self, rhs: &mut [f64]) {
        if let Some(lu) = &self.numeric {
            lu.solve_in_place(MatMut::from_column_major_slice_mut(rhs, rhs.len(), 1));
        }
    }
}
