//! Discrete Elastic Plates cloth.

pub mod contact;
pub mod energy;
pub mod mesh;
pub mod pins;
pub mod view;

pub use contact::Collider;
pub use mesh::{ClothMesh, ClothMeshError, Topology};
pub use pins::{PinMotion, PinSelector};
pub use view::ClothView;
mod dynamics;
mod factor;
mod system;

pub use dynamics::{
    realtime, Cloth, ClothParams, Integrator, Solve, StepError, StepStats, MAX_HALVINGS, MAX_STATIC_ITERATIONS,
};
pub use system::MAX_SYSTEM_BYTES;
