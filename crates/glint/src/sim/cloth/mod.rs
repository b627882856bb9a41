//! Discrete Elastic Plates cloth.

mod colour;
pub mod contact;
pub mod energy;
pub mod view;

pub use crate::scene::cloth::{pins, ClothMesh, ClothMeshError, Collider, PinMotion, PinSelector, Topology};
pub use view::ClothView;
mod dynamics;
mod factor;
mod system;

pub use dynamics::gpu::{GpuCloth, GpuSolve, MAX_ITERATIONS as MAX_GPU_ITERATIONS};
pub use dynamics::{
    realtime, Cloth, ClothParams, ClothSetup, Integrator, Solve, StepError, StepStats, MAX_HALVINGS,
    MAX_STATIC_ITERATIONS,
};
pub use system::MAX_SYSTEM_BYTES;
