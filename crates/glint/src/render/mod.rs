//! Core layer: the [`Renderer`], which turns the entities submitted for a frame
//! into GPU commands, following DESIGN.md's data flow.
//!
//! ## Rooms
//! | folder or file | what it holds |
//! | --- | --- |
//! | `renderer.rs` | the [`Renderer`]: its `Resources`, each view's GPU state by key (`ViewStates`), what the next frame starts from; making one, its registry and settings |
//! | `frame/` | [`Renderer::render_frame`] and the stages it runs, free functions over the resources, the frame and a view's state |
//! | `passes/` | the GPU passes and what they own: shadow maps and views, ambient occlusion, particle layers, environment maps, the post chain |
//! | `gpu_driven/` | draw lists of indirect commands, culled on the GPU, with occlusion culling's depth pyramid |
//! | `resources/` | what frames draw with and keep: registry, mesh pool, instance store, pipelines, data blocks, target pool |
//! | `debug/` | statistics, GPU timing, the debug-group outline, `glint explain`'s calls, read-backs |
//! | `view.rs`, `views.rs` | what the stages read of a view this frame; the GPU state a view keeps |
//! | `batch.rs`, `cull.rs`, `queue.rs` | batching, frustum culling and sort keys, pure CPU code |
//!
//! No two files import each other, even through others (`tests/layers.rs`).
//!
//! ## Bind-group convention (shader data blocks)
//! | group | block | written when | holds |
//! | --- | --- | --- | --- |
//! | 0 | Scene | lights or environment change | ambient, sky colours, light count, `lights[64]` |
//! | 1 | Camera | the camera, target aspect or scene time changes | view, view-projection, its inverse, eye position, scene time and wind (shadow passes bind it too) |
//! | 2 | Material | a material is added or edited | `materials: array<MaterialBlock>` (the table, indexed by material id), one texture set: diffuse / normal / specular maps, sampler, metallic-roughness / occlusion / emissive maps |
//! | 3 | Renderer | instances: where entities changed; draw indices: when the visible set changed, one write | `instances: array<Instance>` (transform rows + material index, persistent; a compact entity's 16-byte instances four to a record), `draw_indices: array<u32>` (an identity ramp for whole tiles, then visible instances in draw order) |
//!
//! Where vertex shaders cannot read storage buffers (WebGL2, some GLES drivers;
//! [`Gpu::vertex_storage`](crate::Gpu::vertex_storage)), the material table and
//! both Renderer-block arrays are data textures instead (`gpu_array.rs`), read
//! record by record in `forward.wgsl`'s `DATA_TEXTURES` variant; everything else
//! is the same.
//!
//! Every pipeline shares one layout with these four groups, so groups 0, 1 and 3
//! are bound once per pass and group 2 changes only between texture sets (materials
//! with the same maps share a bind group; untextured materials all share one).
//! Each instance names its material, and shapes share the buffers of the mesh pool,
//! so a run of batches with one pipeline, texture set and pool page is a single
//! `multi_draw_indexed_indirect` call: one indirect command per batch.

pub mod batch;
pub mod clusters;
pub mod cull;
mod debug;
mod error;
mod frame;
mod frame_variant;
mod gpu_driven;
mod lod;
mod passes;
pub mod queue;
mod renderer;
pub(crate) mod resources;
mod view;
mod views;

pub use crate::gpu::{GpuSimulation, InstanceRange, ParticleGpu, PlaceTargets, VertexTarget, MAX_LAYER_PARTICLES};
pub use crate::scene::{ShadowLayout, MAX_CUBES, MAX_SHADOW_MAP_BYTES};
pub use clusters::Clusters;
pub use debug::explain::{BatchCall, DrawCall, FrameCalls, PassCalls, PassType};
pub use debug::stats::{ClusterStats, FrameStats, ListCounts, PassStats, Passes, StageTimes, UploadStats};
pub use debug::timer::GpuTimes;
pub use error::{MeshTooLarge, RenderError};
pub use frame::input::{FrameInput, FrameMode, FrameOutput, SubFrame, ViewKey, KEEP_VIEW_FRAMES, MAX_SUB_FRAMES};
pub use frame::naive::MAX_NAIVE_DRAWS;
pub use frame::Shadows;
pub use gpu_driven::gpu_cull::SKIP_UNPAID_OCCLUSION;
pub use passes::particles::{ParticleBlend, ParticleLook, ParticlesId};
pub use renderer::Renderer;
pub use resources::registry::Registry;
