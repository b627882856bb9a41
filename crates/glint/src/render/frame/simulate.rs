//! Core layer: the frame's simulate stage. A simulation that runs on the GPU
//! ([`GpuSimulation`]: particles, `sim/particles`; the school, `sim/school`)
//! is part of the frame's input ([`FrameInput::simulate`](crate::render::FrameInput::simulate))
//! and records its compute passes into the frame's encoder before the frame's
//! views (`simulate`), so what it writes (a particle layer's
//! billboards) is drawn in the same submission, never read back. The outline
//! shows it as `frame N › simulate`.

use crate::gpu::GpuSimulation;
use crate::render::debug::explain::PassType;
use crate::render::frame::state::Frame;

/// Stage 1 of the frame: record `simulations`' compute passes into the
/// frame's encoder, before any view, under the debug group "simulate".
/// Where the device has no compute shaders
/// ([`Renderer::computes`](crate::Renderer::computes) is false) simulations
/// step on the CPU instead, and give none.
pub(crate) fn simulate(
    frame: &mut Frame,
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    simulations: &mut [&mut dyn GpuSimulation],
) {
    if simulations.is_empty() {
        return;
    }
    frame.outline.enter(&mut frame.encoder, "simulate");
    frame.outline.pass("simulate", PassType::Compute, &[]);
    for simulation in simulations {
        simulation.encode(device, queue, &mut frame.encoder);
    }
    frame.outline.leave(&mut frame.encoder);
}
