//! Discrete Elastic Plates cloth.

pub mod energy;
