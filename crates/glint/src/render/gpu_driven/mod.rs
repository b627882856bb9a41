//! Core layer: the GPU-driven path: a view's draw lists (indirect commands
//! built from sorted batches), culled on the GPU by compute passes, with
//! two-phase occlusion culling against a depth pyramid, and the view's
//! lights binned into its clusters.

pub(crate) mod commands;
pub(crate) mod cull_pipelines;
pub(crate) mod draw_list;
pub(crate) mod gpu_cull;
pub(crate) mod light_binning;
pub(crate) mod occlusion;
