//! Core layer: a scene's emitters as they run. Each draws in a particle layer
//! of its own; it steps with compute shaders in the frame's simulate stage
//! where the renderer computes ([`Renderer::computes`]), else on the CPU (GL,
//! WebGL2), from the same description and seed.

use super::sim_state::{chunks, SimKind, SimRecord};
use crate::asset::EmitterDesc;
use crate::render::{GpuSimulation, ParticleBlend, ParticleLook, ParticlesId};
use crate::scene::SimPath;
use crate::scene::TextureId;
use crate::sim::particles::{GpuParticles, Particle, ParticleKernels, ParticleSystem};
use crate::{FrameStats, RenderError, Renderer};
use glam::Vec3;
use std::sync::Arc;

/// Where an emitter steps.
enum Run {
    Cpu(Box<ParticleSystem>),
    Gpu(Box<GpuParticles>),
}

/// One emitter's run and the layer it draws in; no run for parameters that
/// cannot make an emitter (a description changed after loading:
/// [`SceneDesc::check_pose`](crate::asset::SceneDesc::check_pose) refuses to pose it).
pub(crate) struct EmitterSim {
    run: Option<Run>,
    layer: ParticlesId,
}

impl EmitterSim {
    /// `desc`'s emitter at time 0, with a layer in `renderer` (its sprite one
    /// of the scene's textures, as `textures` placed them), stepped by
    /// `kernels` where the renderer computes. Errors when the device cannot
    /// hold the layer (out of memory: exit 3).
    pub(crate) fn new(
        desc: &EmitterDesc,
        (textures, kernels): (&[TextureId], Option<&Arc<ParticleKernels>>),
        renderer: &mut Renderer,
    ) -> Result<Self, RenderError> {
        let slots = crate::sim::particles::Schedule::new(&desc.params).slots() as u32;
        let texture = desc.texture.and_then(|i| textures.get(i)).copied();
        let layer = renderer
            .add_particles(slots, ParticleLook { blend: desc.blend, texture, soft: desc.soft, lit: desc.lit })?;
        let cpu = || ParticleSystem::new(desc.params.clone(), desc.dt).ok().map(|s| Run::Cpu(Box::new(s)));
        let run = match (kernels, renderer.particle_buffer(layer)) {
            (Some(kernels), Some((buffer, capacity))) => {
                let buffer = buffer.clone();
                let device = renderer.device_and_queue().0;
                let scope = crate::gpu::DriverErrors::watch(device);
                let on_gpu = GpuParticles::new(
                    renderer.device_and_queue(),
                    kernels,
                    desc.params.clone(),
                    desc.dt,
                    (&buffer, capacity),
                    desc.blend,
                );
                if let Some(error) = scope.finish() {
                    return Err(RenderError::Device { what: "an emitter's buffers", message: error.to_string() });
                }
                on_gpu.map_or_else(|_| cpu(), |g| Some(Run::Gpu(Box::new(g))))
            }
            _ => cpu(),
        };
        Ok(Self { run, layer })
    }

    /// On the CPU, step (or restart and step) to `time`; on the GPU the steps
    /// wait for the frame ([`EmitterSim::draw`]).
    pub(crate) fn pose(&mut self, desc: &EmitterDesc, time: f32) {
        if let Some(Run::Cpu(system)) = &mut self.run {
            let target = desc.steps_to(time);
            if system.steps() > target {
                // The parameters made it once: they make it again.
                if let Ok(fresh) = ParticleSystem::new(desc.params.clone(), desc.dt) {
                    **system = fresh;
                }
            }
            while system.steps() < target {
                system.step();
            }
        }
    }

    /// Before the frame: its billboards into its layer, sorted from `eye`
    /// when alpha-blended and given: written from the CPU, or stepped to `time` by
    /// compute passes in the frame's simulate stage (the simulation returned,
    /// for the frame's input).
    pub(crate) fn draw(
        &mut self,
        desc: &EmitterDesc,
        time: f32,
        eye: Option<Vec3>,
        renderer: &mut Renderer,
    ) -> Option<&mut dyn GpuSimulation> {
        let eye_if_sorted = eye.filter(|_| desc.blend == ParticleBlend::Alpha);
        match &mut self.run {
            None => None,
            Some(Run::Cpu(system)) => {
                renderer.write_particles(self.layer, &system.records(eye_if_sorted));
                None
            }
            Some(Run::Gpu(on_gpu)) => {
                on_gpu.advance_to(renderer.device_and_queue().1, time, eye_if_sorted);
                renderer.set_particle_count(self.layer, on_gpu.slots());
                Some(on_gpu.as_mut())
            }
        }
    }

    /// Its state for a simulation cache ([`World::sim_state`](super::World::sim_state)),
    /// `None` when it cannot run or has GPU steps pending.
    pub(crate) fn save(&self, gpu: (&wgpu::Device, &wgpu::Queue)) -> Result<Option<SimRecord>, crate::GpuError> {
        let record = |path, steps, slots| SimRecord { kind: SimKind::Emitter, path, steps, chunks: vec![slots] };
        Ok(match &self.run {
            None => None,
            Some(Run::Cpu(system)) => {
                Some(record(SimPath::Cpu, system.steps(), bytemuck::cast_slice(system.slots()).to_vec()))
            }
            Some(Run::Gpu(on_gpu)) => on_gpu.save(gpu)?.map(|(slots, steps)| record(SimPath::Gpu, steps, slots)),
        })
    }

    /// Go on from `record` ([`save`](Self::save)d from the same emitter on
    /// the same path).
    pub(crate) fn load(&mut self, record: &SimRecord, queue: &wgpu::Queue) -> Result<(), String> {
        let [slots] = chunks::<1>(record)?;
        match &mut self.run {
            None => Err("the emitter cannot run".into()),
            Some(Run::Cpu(system)) => {
                if slots.len() % std::mem::size_of::<Particle>() != 0 {
                    return Err(format!("{} bytes is not a whole number of particles", slots.len()));
                }
                system.resume(bytemuck::pod_collect_to_vec(slots), record.steps)
            }
            Some(Run::Gpu(on_gpu)) => on_gpu.load(queue, slots, record.steps),
        }
    }

    /// The frame that recorded its GPU steps failed: start again at the next frame.
    pub(crate) fn frame_failed(&mut self) {
        if let Some(Run::Gpu(on_gpu)) = &mut self.run {
            on_gpu.frame_failed();
        }
    }

    /// Where it steps; `None` when it cannot run.
    pub(crate) fn path(&self) -> Option<SimPath> {
        self.run.as_ref().map(|run| match run {
            Run::Cpu(_) => SimPath::Cpu,
            Run::Gpu(_) => SimPath::Gpu,
        })
    }

    /// Whether it steps with compute shaders.
    pub(crate) fn on_gpu(&self) -> bool {
        matches!(self.run, Some(Run::Gpu(_)))
    }
}

/// Fill `stats` with the scene's particles alive at `time` and spawned since
/// `previous`, from each emitter's schedule.
pub(crate) fn count(emitters: &[EmitterDesc], (previous, time): (f32, f32), stats: &mut [FrameStats]) {
    let (mut alive, mut spawned) = (0, 0);
    for e in emitters {
        let schedule = crate::sim::particles::Schedule::new(&e.params);
        let snap = |t: f32| (e.steps_to(t) as f64 * f64::from(e.dt)) as f32;
        alive += schedule.alive_at(&e.params, snap(time));
        spawned += schedule.spawned_at(snap(time)).saturating_sub(if previous < 0.0 {
            0
        } else {
            schedule.spawned_at(snap(previous))
        });
    }
    for s in stats {
        (s.particles_alive, s.particles_spawned) = (alive, spawned);
    }
}
