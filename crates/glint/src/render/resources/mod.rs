//! Core layer: what frames draw with and keep between them: the registry
//! (shapes in the mesh pool, materials, textures, render targets), the
//! pipelines and their layouts, the persistent instance store, the data
//! blocks' GPU twins, and the pool of transient targets.

pub(crate) mod blocks;
pub(crate) mod buffers;
pub(crate) mod gpu_array;
pub(crate) mod instances;
pub(crate) mod materials;
pub(crate) mod mesh_pool;
pub(crate) mod pipelines;
pub(crate) mod registry;
pub(crate) mod target_pool;
