use super::{MaterialId, ShapeId};
use glam::Mat4;

/// A thing to draw: a shape, a material and one transform per instance.
///
/// All instances of an entity go in one instanced draw, and entities that share
/// shape and material are merged into that same draw.
#[derive(Clone, Debug, PartialEq)]
pub struct Entity {
    /// The mesh.
    pub shape: ShapeId,
    /// The material.
    pub material: MaterialId,
    /// Object-to-world transform of each instance.
    pub transforms: Vec<Mat4>,
}

impl Entity {
    /// An entity with one instance at `transform`.
    pub fn new(shape: ShapeId, material: MaterialId, transform: Mat4) -> Self {
        Self::instanced(shape, material, vec![transform])
    }

    /// An entity with one instance per transform.
    pub fn instanced(shape: ShapeId, material: MaterialId, transforms: Vec<Mat4>) -> Self {
        Self {
            shape,
            material,
            transforms,
        }
    }
}
