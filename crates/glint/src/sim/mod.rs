//! Simulation: cloth as Discrete Elastic Plates, integrated implicitly with
//! Newton's method on a sparse system; fish schooling after Reynolds on a
//! uniform grid, and particles from emitters; the last two on the CPU and
//! with compute shaders.

pub mod cloth;
pub mod particles;
mod radix;
mod scan;
pub mod school;
