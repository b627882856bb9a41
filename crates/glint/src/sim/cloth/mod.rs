//! Discrete Elastic Plates cloth.

pub mod energy;
pub mod mesh;

pub use mesh::{ClothMesh, ClothMeshError, Topology};
mod dynamics;
mod system;

pub use dynamics::{Cloth, ClothParams, Integrator, StepError, StepStats, MAX_HALVINGS};
