//! Core layer: the frame's simulate stage. A simulation that runs on the GPU
//! ([`GpuSimulation`]: particles, `sim/particles`) records its compute passes
//! into the frame's encoder before the frame's views ([`Renderer::simulate`]),
//! so what it writes (a particle layer's billboards) is drawn in the same
//! submission, never read back. The outline shows it as `frame N › simulate`.

use super::Renderer;
use crate::gpu::GpuSimulation;

impl Renderer {
    /// Stage 0 of the next frame: record `sim`'s compute passes into the
    /// frame's encoder, before any view, under the debug group "simulate".
    /// Call it before the frame's [`render_views`](Self::render_views) (or
    /// shadow pass and flush); where the device has no compute shaders
    /// ([`computes`](Self::computes) is false) simulations step on the CPU instead.
    pub fn simulate(&mut self, sim: &mut dyn GpuSimulation) {
        let mut encoder = self.take_encoder();
        self.outline.enter(&mut encoder, "simulate");
        self.outline.pass("simulate", super::explain::PassType::Compute, &[]);
        sim.encode(&self.device, &self.queue, &mut encoder);
        self.outline.leave(&mut encoder);
        self.encoder = Some(encoder);
    }

    /// Whether the device runs compute shaders with storage buffers here
    /// ([`Gpu::culls_on_gpu`](crate::Gpu::culls_on_gpu)): GPU simulations
    /// and culling then run on it.
    pub fn computes(&self) -> bool {
        self.cull_pipelines.is_some()
    }

    /// The device and queue, for GPU simulations' own buffers.
    pub fn device_and_queue(&self) -> (&wgpu::Device, &wgpu::Queue) {
        (&self.device, &self.queue)
    }
}
