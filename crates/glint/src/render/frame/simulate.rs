//! Core layer: the frame's simulate stage. A simulation that runs on the GPU
//! ([`GpuSimulation`]: particles, `sim/particles`; the school, `sim/school`)
//! is part of the frame's input ([`FrameInput::simulate`](crate::render::FrameInput::simulate))
//! and records its compute passes into the frame's encoder before the frame's
//! views (`simulate`): its steps, then the instance records of the entities
//! it draws ([`GpuSimulation::place`], into the instance store where
//! [`compact_store`](super::stages::compact_store) left their ranges, and
//! the vertices of shapes it deforms into the mesh pool), so what it writes
//! (a particle layer's billboards, the school's fish, a cloth) is drawn
//! in the same submission, never read back. The outline shows it as
//! `frame N › simulate`.

use crate::gpu::{GpuSimulation, PlaceTargets};
use crate::render::debug::explain::PassType;
use crate::render::frame::state::Frame;
use crate::render::resources::Resources;
use crate::render::RenderError;

/// The frame's simulate stage: record `simulations`' compute passes into the
/// frame's encoder, after the instance store is compacted and before any
/// view, under the debug group "simulate": every simulation's steps, then
/// every simulation's placing of what it draws (where one writes shapes'
/// vertices, every shape the frame draws is put in the mesh pool first). Where the device has no compute shaders
/// ([`Renderer::computes`](crate::Renderer::computes) is false) simulations
/// step on the CPU instead, and give none. Errors when a shape cannot be
/// put in the mesh pool.
pub(crate) fn simulate(
    res: &mut Resources,
    frame: &mut Frame,
    simulations: &mut [&mut dyn GpuSimulation],
) -> Result<(), RenderError> {
    if simulations.is_empty() {
        return Ok(());
    }
    let written: Vec<_> = simulations.iter().flat_map(|s| s.shapes()).collect();
    if !written.is_empty() {
        // Every shape the frame draws goes into the mesh pool now, so that no
        // page grows (into a new buffer) after the place passes wrote into it.
        for shape in written.into_iter().chain(frame.submitted.iter().map(|s| s.shape)) {
            frame.mesh_bytes += res.registry.mesh_range(shape)?.1;
        }
    }
    let (device, queue) = (&res.device, &res.queue);
    frame.outline.enter(&mut frame.encoder, "simulate");
    frame.outline.pass("simulate", PassType::Compute, &[]);
    for simulation in simulations.iter_mut() {
        simulation.encode(device, queue, &mut frame.encoder);
    }
    // Where views cull on the GPU the store keeps boxes, and its records are a storage buffer.
    if let (Some(bounds), Some(records)) = (res.instances.bounds(), res.instances.array().buffer()) {
        let range_of = |entity: u64| res.store.gpu_range(entity, frame.index);
        let vertices_of = |shape| res.registry.vertex_target(shape);
        let targets = PlaceTargets { records, bounds, range_of: &range_of, vertices_of: &vertices_of };
        for simulation in simulations.iter_mut() {
            simulation.place(device, queue, &mut frame.encoder, &targets);
        }
    }
    frame.outline.leave(&mut frame.encoder);
    Ok(())
}
