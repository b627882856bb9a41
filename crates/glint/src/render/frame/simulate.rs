//! Core layer: the frame's simulate stage. A simulation that runs on the GPU
//! ([`GpuSimulation`]: particles, `sim/particles`; the school, `sim/school`)
//! is part of the frame's input ([`FrameInput::simulate`](crate::render::FrameInput::simulate))
//! and records its compute passes into the frame's encoder before the frame's
//! views ([`Renderer::simulate`]), so what it writes (a particle layer's
//! billboards) is drawn in the same submission, never read back. The outline
//! shows it as `frame N › simulate`.

use crate::gpu::GpuSimulation;
use crate::render::frame::Frame;
use crate::render::Renderer;

impl Renderer {
    /// Stage 1 of the frame: record `simulations`' compute passes into the
    /// frame's encoder, before any view, under the debug group "simulate".
    /// Where the device has no compute shaders ([`computes`](Self::computes)
    /// is false) simulations step on the CPU instead, and give none.
    pub(crate) fn simulate(&mut self, frame: &mut Frame, simulations: &mut [&mut dyn GpuSimulation]) {
        if simulations.is_empty() {
            return;
        }
        self.outline.enter(&mut frame.encoder, "simulate");
        self.outline.pass("simulate", crate::render::debug::explain::PassType::Compute, &[]);
        for simulation in simulations {
            simulation.encode(&self.device, &self.queue, &mut frame.encoder);
        }
        self.outline.leave(&mut frame.encoder);
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
