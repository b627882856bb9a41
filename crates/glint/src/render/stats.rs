//! Core layer: [`FrameStats`], the cost of one frame in numbers.

use serde::Serialize;

/// Bytes written to the GPU during a frame, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct UploadStats {
    /// Scene, camera and material uniform blocks.
    pub uniforms: u64,
    /// Per-instance data (transforms).
    pub instances: u64,
    /// Texture pixels (all mip levels come from the GPU, so only level 0 counts).
    pub textures: u64,
    /// Vertex and index buffers of shapes used for the first time.
    pub meshes: u64,
    /// Sum of the above.
    pub total: u64,
}

/// CPU time of each frame stage, in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct StageTimes {
    /// Creating GPU twins of new shapes, textures and materials; writing edited materials.
    pub prepare: f64,
    /// Building one draw item with a sort key per submitted entity.
    pub queue: f64,
    /// Radix-sorting the draw items.
    pub sort: f64,
    /// Merging runs into instanced draws and packing instance data.
    pub batch: f64,
    /// Writing changed blocks and the frame's instance data.
    pub upload: f64,
    /// Recording the render pass.
    pub encode: f64,
    /// Handing the command buffer to the queue.
    pub submit: f64,
    /// The whole of `flush`.
    pub total: f64,
}

/// What one frame cost: returned by [`Renderer::flush`](crate::Renderer::flush).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FrameStats {
    /// Draw calls recorded (the sky counts as one).
    pub draw_calls: u32,
    /// `set_pipeline` calls.
    pub pipelines_bound: u32,
    /// `set_bind_group` calls.
    pub bind_groups_set: u32,
    /// Bytes written to the GPU, by kind.
    pub bytes_uploaded: UploadStats,
    /// Entities submitted since the last flush.
    pub entities_submitted: u32,
    /// Instances submitted since the last flush.
    pub instances_submitted: u64,
    /// Instances drawn.
    pub instances_drawn: u64,
    /// CPU time per stage.
    pub cpu_ms: StageTimes,
}
