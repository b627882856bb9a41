//! Cholesky and LU with faer's simplicial factorisations only, which the web
//! page's module links instead of [`super`]'s supernodal ones. The orderings
//! are faer's own (AMD, COLAMD) and the matrix is permuted as faer's solvers
//! do it, so the factors differ from theirs only by rounding.

use super::PAR;
use crate::sim::cloth::system::{SolveFailed, SystemError, MAX_SYSTEM_BYTES};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::perm::PermRef;
use faer::prelude::Reborrow;
use faer::sparse::linalg::cholesky::simplicial::{
    factorize_simplicial_numeric_llt, factorize_simplicial_numeric_llt_scratch, factorize_simplicial_symbolic_cholesky,
    factorize_simplicial_symbolic_cholesky_scratch, prefactorize_symbolic_cholesky, SimplicialLltRef,
    SymbolicSimplicialCholesky,
};
use faer::sparse::linalg::lu::simplicial::{
    factorize_simplicial_numeric_lu, factorize_simplicial_numeric_lu_scratch, solve_in_place_scratch, SimplicialLu,
};
use faer::sparse::linalg::{amd, colamd};
use faer::sparse::utils::{permute_self_adjoint_scratch, permute_self_adjoint_to_unsorted};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Side};

/// A Cholesky factorisation of matrices with one pattern: the AMD ordering
/// and the symbolic factor computed once, the permuted matrix and the numeric
/// factor in buffers reused by every [`Cholesky::factorize`].
pub struct Cholesky {
    /// The ordering: row `i` of the permuted matrix is row `order[i]` of the matrix.
    order: Vec<usize>,
    order_inv: Vec<usize>,
    /// The permuted matrix's upper triangle (faer's simplicial factorisation reads that one).
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    permuted: Vec<f64>,
    symbolic: SymbolicSimplicialCholesky<usize>,
    values: Vec<f64>,
    /// The right-hand side in the ordering's order while it is solved.
    x: Vec<f64>,
    scratch: MemBuffer,
}

impl Cholesky {
    /// The ordering and symbolic factorisation of the symmetric matrix whose
    /// lower triangle is `lower`. Fails with [`SystemError::TooLarge`] when
    /// `other_bytes`, the permuted matrix, the numeric factor and the scratch
    /// space together would take more than [`MAX_SYSTEM_BYTES`] (checked
    /// before the numeric factor is allocated).
    pub fn new(lower: SymbolicSparseColMatRef<'_, usize>, other_bytes: u64) -> Result<Self, SystemError> {
        let (n, nnz) = (lower.nrows(), lower.compute_nnz());
        let scratch_size = StackReq::any_of(&[
            amd::order_maybe_unsorted_scratch::<usize>(n, nnz),
            permute_self_adjoint_scratch::<usize>(n),
            factorize_simplicial_symbolic_cholesky_scratch::<usize>(n),
            factorize_simplicial_numeric_llt_scratch::<usize, f64>(n),
        ]);
        let mut scratch = MemBuffer::try_new(scratch_size).map_err(|_| SystemError::Failed)?;
        let (mut order, mut order_inv) = (vec![0; n], vec![0; n]);
        let stack = MemStack::new(&mut scratch);
        amd::order_maybe_unsorted(&mut order, &mut order_inv, lower, Default::default(), stack)
            .map_err(|_| SystemError::Failed)?;
        let (mut col_ptr, mut row_idx, mut permuted) = (vec![0; n + 1], vec![0; nnz], vec![0.0; nnz]);
        let zeros = vec![0.0; lower.row_idx().len()];
        let upper = permute_self_adjoint_to_unsorted(
            &mut permuted,
            &mut col_ptr,
            &mut row_idx,
            SparseColMatRef::new(lower, &zeros),
            PermRef::new_checked(&order, &order_inv, n),
            Side::Lower,
            Side::Upper,
            stack,
        );
        let (mut etree, mut col_counts) = (vec![0; n], vec![0; n]);
        let etree = prefactorize_symbolic_cholesky(&mut etree, &mut col_counts, upper.symbolic(), stack);
        let symbolic = factorize_simplicial_symbolic_cholesky(upper.symbolic(), etree, &col_counts, stack)
            .map_err(|_| SystemError::Failed)?;
        let bytes = other_bytes
            .saturating_add(24 * nnz as u64)
            .saturating_add(8 * symbolic.len_val() as u64)
            .saturating_add(scratch_size.size_bytes() as u64);
        if bytes > MAX_SYSTEM_BYTES {
            return Err(SystemError::TooLarge(bytes));
        }
        Ok(Self {
            values: vec![0.0; symbolic.len_val()],
            x: vec![0.0; n],
            order,
            order_inv,
            col_ptr,
            row_idx,
            permuted,
            symbolic,
            scratch,
        })
    }

    /// Values in the factor: its size over the matrix's, for memory estimates.
    pub fn len_val(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Factorise the matrix whose lower triangle is `lower` (the pattern given
    /// to [`Cholesky::new`]); false when it is not positive definite.
    pub fn factorize(&mut self, lower: SparseColMatRef<'_, usize, f64>) -> bool {
        let stack = MemStack::new(&mut self.scratch);
        let upper = permute_self_adjoint_to_unsorted(
            &mut self.permuted,
            &mut self.col_ptr,
            &mut self.row_idx,
            lower,
            PermRef::new_checked(&self.order, &self.order_inv, self.x.len()),
            Side::Lower,
            Side::Upper,
            stack,
        );
        factorize_simplicial_numeric_llt(&mut self.values, upper.rb(), Default::default(), &self.symbolic, stack)
            .is_ok()
    }

    /// Solve `A x = rhs` in place with the last successful factorisation.
    pub fn solve(&mut self, rhs: &mut [f64]) {
        for (x, &row) in self.x.iter_mut().zip(&self.order) {
            *x = rhs[row];
        }
        let n = self.x.len();
        SimplicialLltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut self.x, n, 1),
            PAR,
            MemStack::new(&mut self.scratch),
        );
        for (r, &i) in rhs.iter_mut().zip(&self.order_inv) {
            *r = self.x[i];
        }
    }
}

/// An LU factorisation with partial pivoting; its COLAMD column ordering is
/// computed on the first [`Lu::factorize`] and reused.
#[derive(Default)]
pub struct Lu {
    /// The column ordering (forward, inverse), once computed.
    columns: Option<(Vec<usize>, Vec<usize>)>,
    /// The row pivoting of the last factorisation (forward, inverse).
    rows: (Vec<usize>, Vec<usize>),
    lu: Option<SimplicialLu<usize, f64>>,
}

impl Lu {
    /// Factorise `full`, the whole square matrix (each time with the same pattern).
    pub fn factorize(&mut self, full: SparseColMatRef<'_, usize, f64>) -> Result<(), SolveFailed> {
        let n = full.ncols();
        let scratch = StackReq::any_of(&[
            colamd::order_scratch::<usize>(n, n, full.compute_nnz()),
            factorize_simplicial_numeric_lu_scratch::<usize, f64>(n, n),
        ]);
        let mut scratch = MemBuffer::try_new(scratch).map_err(|_| SolveFailed)?;
        let stack = MemStack::new(&mut scratch);
        let (order, order_inv) = match &mut self.columns {
            Some(columns) => columns,
            None => {
                let (mut order, mut order_inv) = (vec![0; n], vec![0; n]);
                colamd::order(&mut order, &mut order_inv, full.symbolic(), Default::default(), stack)
                    .map_err(|_| SolveFailed)?;
                self.columns.insert((order, order_inv))
            }
        };
        self.rows = (vec![0; n], vec![0; n]);
        let mut lu = SimplicialLu::new();
        let columns = PermRef::new_checked(order, order_inv, n);
        self.lu = None;
        factorize_simplicial_numeric_lu(&mut self.rows.0, &mut self.rows.1, &mut lu, full, columns, stack)
            .map_err(|_| SolveFailed)?;
        self.lu = Some(lu);
        Ok(())
    }

    /// Solve `A x = rhs` in place with the last successful factorisation.
    pub fn solve(&mut self, rhs: &mut [f64]) {
        let (Some(lu), Some((order, order_inv))) = (&self.lu, &self.columns) else { return };
        let n = rhs.len();
        let mut scratch = MemBuffer::new(solve_in_place_scratch::<usize, f64>(n, 1, PAR));
        lu.solve_in_place_with_conj(
            PermRef::new_checked(&self.rows.0, &self.rows.1, n),
            PermRef::new_checked(order, order_inv, n),
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, 1),
            PAR,
            MemStack::new(&mut scratch),
        );
    }
}
