//! The two factorisations of a cloth's [`SparseSystem`](super::system::SparseSystem):
//! Cholesky of its symmetric matrix (given as the lower triangle), and LU of the
//! whole matrix for when that is indefinite. Each comes in two builds with the
//! same interface:
//!
//! - [`chosen`] (native): faer's solvers, which pick a supernodal factorisation
//!   (dense kernels over blocks of columns) where the factor is dense enough
//!   for it to pay, as on large sheets, and a simplicial one elsewhere.
//! - [`simplicial`] (wasm32): faer's simplicial factorisations only, with the
//!   same orderings (AMD for Cholesky, COLAMD for LU). faer's supernodal code
//!   and its dense kernels were 64 KB of the gzipped WebGL2 page (1,350,050 ->
//!   1,286,243 B of wasm), which its size target could not afford. The price
//!   is speed on larger sheets: natively, a 33 × 33-node sheet-like system
//!   factorised in 7.4 ms instead of 2.7 ms, a 65 × 65 one in 62 ms instead of 13.
//!
//! Both are compiled natively for the tests, which solve the same systems with
//! each and compare.

#[cfg(not(target_arch = "wasm32"))]
mod chosen;
#[cfg(any(target_arch = "wasm32", test))]
mod simplicial;

#[cfg(not(target_arch = "wasm32"))]
pub use chosen::{Cholesky, Lu};
#[cfg(target_arch = "wasm32")]
pub use simplicial::{Cholesky, Lu};

/// Factorisations run on one thread: on the 2-core reference machine faer's
/// parallel supernodal Cholesky was slower (9.4 s against 8.2 s for 20 steps
/// of a 65 × 65 sheet), its threads contending with rayon's element assembly.
const PAR: faer::Par = faer::Par::Seq;

#[cfg(test)]
mod tests;
