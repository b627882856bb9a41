//! Simulation: cloth as Discrete Elastic Plates, integrated implicitly with
//! Newton's method on a sparse system.

pub mod cloth;
