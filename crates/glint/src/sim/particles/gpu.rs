//! [`GpuParticles`]: an emitter's slots on the GPU, stepped by compute
//! passes in the frame's encoder ([`FrameInput::simulate`](crate::FrameInput::simulate))
//! and written into a particle layer as billboards, back to front for
//! alpha blending (a counting sort by distance, `shader/particles_step.wgsl`)
//! unless the view draws transparency in any order.

use super::{EmitterParams, Schedule, SpawnShape};
use crate::gpu::GpuSimulation;
use crate::scene::ParticleBlend;
use crate::sim::scan::{GpuScan, ScanGroup};
use glam::Vec3;
use std::sync::Arc;

const WORKGROUP: u32 = 256;
/// Distance buckets of the depth sort.
const BUCKETS: u32 = 4096;
/// Bytes between steps' blocks in the step buffer (the dynamic-offset alignment).
const STEP_STRIDE: u64 = 256;
/// Steps one frame records at most (a 25.6 MB step buffer).
const MAX_STEPS_PER_FRAME: u64 = crate::scene::MAX_POSE_STEPS;
/// Step blocks the step buffer holds to begin with (it grows to a frame's steps).
const FIRST_STEP_BLOCKS: u64 = 64;

/// `shader/particles_step.wgsl`'s `Emitter` block.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct EmitterGpu {
    origin: [f32; 3],
    shape: u32,
    axis: [f32; 3],
    seed: u32,
    across: [f32; 3],
    stream_slots: u32,
    other: [f32; 3],
    burst: u32,
    shape_size: [f32; 4],
    gravity: [f32; 3],
    drag: f32,
    color: [f32; 4],
    color_end: [f32; 4],
    motion: [f32; 4],
    timing: [f32; 4],
    look: [f32; 4],
    ground: [f32; 4],
}

/// `shader/particles_step.wgsl`'s `Step` block.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct StepGpu {
    times: [f32; 4],
    counts: [u32; 4],
    eye: [f32; 4],
}

/// The compute pipelines every GPU emitter on one device shares: made once
/// ([`ParticleKernels::new`]), not once an emitter (a thousand emitters each
/// compiling its own ran a machine out of memory).
pub struct ParticleKernels {
    layout: wgpu::BindGroupLayout,
    update: wgpu::ComputePipeline,
    write: wgpu::ComputePipeline,
    sort: [wgpu::ComputePipeline; 3],
    scan: GpuScan,
}

impl ParticleKernels {
    /// Compile `shader/particles_step.wgsl`'s kernels and the scan's for `device`.
    pub fn new(device: &wgpu::Device) -> Self {
        // The emitter and step blocks, the slots, the layer's records, the
        // sort's keys, counts and starts.
        let layout = crate::gpu::buffers_layout(device, "particles", 7, 2, Some(1));
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("particles_step.wgsl"),
            source: wgpu::ShaderSource::Wgsl(crate::shader::PARTICLES_STEP.into()),
        });
        let pipeline = |entry| crate::gpu::compute_pipeline(device, &module, entry, &[Some(&layout)]);
        Self {
            update: pipeline("update"),
            write: pipeline("write"),
            sort: [pipeline("clear"), pipeline("count"), pipeline("scatter")],
            scan: GpuScan::new(device),
            layout,
        }
    }
}

/// An emitter stepped on the GPU into a particle layer's buffer.
pub struct GpuParticles {
    params: EmitterParams,
    schedule: Schedule,
    blend: ParticleBlend,
    dt: f32,
    slots: u32,
    /// Steps recorded so far, and steps asked for.
    steps: u64,
    target: u64,
    /// Where alpha-blended particles are sorted from (`None`: not sorted).
    eye: Option<Vec3>,
    state: wgpu::Buffer,
    /// The buffers bound besides the step blocks, in binding order.
    bound: [wgpu::Buffer; 6],
    step_buffer: wgpu::Buffer,
    group: wgpu::BindGroup,
    kernels: Arc<ParticleKernels>,
    scan_group: ScanGroup,
}

impl GpuParticles {
    /// `params`' emitter stepping `dt` seconds at a time into `records` (a
    /// particle layer's buffer, [`Renderer::particle_buffer`](crate::Renderer::particle_buffer),
    /// of at least [`Schedule::slots`] records), blended as `blend`, by
    /// `kernels` (shared with the device's other emitters).
    /// Errors with [`EmitterParams::check`]'s reason, or when the layer is too small.
    pub fn new(
        (device, queue): (&wgpu::Device, &wgpu::Queue),
        kernels: &Arc<ParticleKernels>,
        params: EmitterParams,
        dt: f32,
        (records, capacity): (&wgpu::Buffer, u32),
        blend: ParticleBlend,
    ) -> Result<Self, String> {
        params.check()?;
        let schedule = Schedule::new(&params);
        let slots = schedule.slots() as u32;
        if capacity < slots {
            return Err(format!("the layer holds {capacity} particles, the emitter needs {slots}"));
        }
        let storage = |label: &str, size: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(16),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let state = storage("particles: slots", 32 * u64::from(slots));
        let keys = storage("particles: depth keys", 8 * u64::from(slots));
        let counts = storage("particles: per bucket", 4 * u64::from(BUCKETS + 1));
        let starts = storage("particles: first per bucket", 4 * u64::from(BUCKETS + 1));
        let uniform = |label: &str, size: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let emitter = uniform("particles: emitter", std::mem::size_of::<EmitterGpu>() as u64);
        queue.write_buffer(&emitter, 0, bytemuck::bytes_of(&emitter_block(&params, &schedule)));
        let bound = [emitter, state.clone(), records.clone(), keys, counts.clone(), starts.clone()];
        let step_buffer = step_buffer(device, FIRST_STEP_BLOCKS);
        let group = bind_group(device, &kernels.layout, &bound, &step_buffer);
        let scan_group = kernels.scan.group((device, queue), &counts, &starts, BUCKETS + 1);
        Ok(Self {
            kernels: kernels.clone(),
            params,
            schedule,
            blend,
            dt,
            slots,
            steps: 0,
            target: 0,
            eye: None,
            state,
            bound,
            step_buffer,
            group,
            scan_group,
        })
    }

    /// Its parameters.
    pub fn params(&self) -> &EmitterParams {
        &self.params
    }

    /// When its particles spawn.
    pub fn schedule(&self) -> &Schedule {
        &self.schedule
    }

    /// Its slots: the records its layer draws.
    pub fn slots(&self) -> u32 {
        self.slots
    }

    /// Step on to `time` seconds in the next frame's simulate stage (from the
    /// start again, all slots emptied, for an earlier time), with alpha-blended
    /// particles sorted from `eye` (`None`: written in slot order, as
    /// additive ones are, for transparency drawn in any order).
    pub fn advance_to(&mut self, queue: &wgpu::Queue, time: f32, eye: Option<Vec3>) {
        let target = (f64::from(time.max(0.0)) / f64::from(self.dt)).round() as u64;
        if target < self.steps {
            let empty = vec![0u8; 32 * self.slots as usize];
            queue.write_buffer(&self.state, 0, &empty);
            self.steps = 0;
        }
        self.target = target;
        self.eye = eye;
    }

    /// The frame its steps were recorded in failed and dropped them: start
    /// again from time 0 at the next [`advance_to`](Self::advance_to).
    pub(crate) fn frame_failed(&mut self) {
        self.steps = u64::MAX;
    }

    /// The state of every slot (waiting for the GPU), for tests.
    pub fn read_slots(&self, gpu: &crate::Gpu) -> Result<Vec<super::Particle>, crate::GpuError> {
        Ok(bytemuck::pod_collect_to_vec(&gpu.read_buffer(&self.state)?))
    }

    /// Its slots as the GPU keeps them and the steps they took (waiting for
    /// the GPU), for a simulation cache; `None` while steps are pending.
    pub(crate) fn save(
        &self,
        (device, queue): (&wgpu::Device, &wgpu::Queue),
    ) -> Result<Option<(Vec<u8>, u64)>, crate::GpuError> {
        if self.target != self.steps {
            return Ok(None);
        }
        Ok(Some((crate::gpu::read_buffer(device, queue, &self.state)?, self.steps)))
    }

    /// Go on from slots [`save`](Self::save)d after `steps` steps.
    pub(crate) fn load(&mut self, queue: &wgpu::Queue, slots: &[u8], steps: u64) -> Result<(), String> {
        crate::gpu::refill(queue, &[(&self.state, slots, "particles")])?;
        (self.steps, self.target) = (steps, steps);
        Ok(())
    }

    /// The step block of step `n` (from 0), sorting from the eye.
    fn step_block(&self, n: u64) -> StepGpu {
        let t = |n: u64| (n as f64 * f64::from(self.dt)) as f32;
        let (t0, t1) = (t(n), t(n + 1));
        let (stream, bursts) = self.schedule.counts_at(t1);
        StepGpu {
            times: [t0, t1, self.dt, self.sort_distance()],
            counts: [stream.min(u64::from(u32::MAX)) as u32, bursts.min(u64::from(u32::MAX)) as u32, 0, 0],
            eye: self.eye.unwrap_or(Vec3::ZERO).extend(1.0).into(),
        }
    }

    /// The farthest a living particle can be from the eye, for the buckets.
    fn sort_distance(&self) -> f32 {
        let p = &self.params;
        let life = self.schedule.life_max();
        let shape = match p.shape {
            SpawnShape::Point => 0.0,
            SpawnShape::Sphere(r) | SpawnShape::Cone(r) => r,
            SpawnShape::Box(half) => half.length(),
        };
        let reach = shape + p.speed.1 * life + 0.5 * (p.gravity.length() + p.noise) * life * life;
        self.eye.unwrap_or(Vec3::ZERO).distance(p.origin) + reach.max(1e-3)
    }
}

impl GpuSimulation for GpuParticles {
    fn encode(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, encoder: &mut wgpu::CommandEncoder) {
        // A longer jump (the API's; scenes' poses are capped alike) goes on next frame.
        let steps = self.target.saturating_sub(self.steps).min(MAX_STEPS_PER_FRAME) as u32;
        // Every step's block, and the last one again for the sort.
        if self.step_buffer.size() < STEP_STRIDE * u64::from(steps + 1) {
            self.step_buffer = step_buffer(device, u64::from(steps + 1).next_power_of_two());
            self.group = bind_group(device, &self.kernels.layout, &self.bound, &self.step_buffer);
        }
        let blocks: Vec<u8> = (0..=steps)
            .flat_map(|k| {
                let mut block = vec![0u8; STEP_STRIDE as usize];
                let n = self.steps + u64::from(k.min(steps.max(1) - 1));
                block[..std::mem::size_of::<StepGpu>()].copy_from_slice(bytemuck::bytes_of(&self.step_block(n)));
                block
            })
            .collect();
        queue.write_buffer(&self.step_buffer, 0, &blocks);
        let groups = self.slots.div_ceil(WORKGROUP);
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("particles"), timestamp_writes: None });
        let kernels = &self.kernels;
        pass.set_pipeline(&kernels.update);
        for k in 0..steps {
            pass.set_bind_group(0, &self.group, &[(u64::from(k) * STEP_STRIDE) as u32]);
            pass.dispatch_workgroups(groups, 1, 1);
        }
        let last = [(u64::from(steps) * STEP_STRIDE) as u32];
        pass.set_bind_group(0, &self.group, &last);
        match (self.blend, self.eye) {
            (ParticleBlend::Additive, _) | (ParticleBlend::Alpha, None) => {
                pass.set_pipeline(&kernels.write);
                pass.dispatch_workgroups(groups, 1, 1);
            }
            (ParticleBlend::Alpha, Some(_)) => {
                let [clear, count, scatter] = &kernels.sort;
                pass.set_pipeline(clear);
                pass.dispatch_workgroups(groups.max((BUCKETS + 1).div_ceil(WORKGROUP)), 1, 1);
                pass.set_pipeline(count);
                pass.dispatch_workgroups(groups, 1, 1);
                kernels.scan.encode(&mut pass, &self.scan_group);
                pass.set_bind_group(0, &self.group, &last);
                pass.set_pipeline(scatter);
                pass.dispatch_workgroups(groups, 1, 1);
            }
        }
        drop(pass);
        self.steps += u64::from(steps);
    }
}

/// A buffer of `blocks` step blocks.
fn step_buffer(device: &wgpu::Device, blocks: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("particles: steps"),
        size: STEP_STRIDE * blocks,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// The bind group of `bound` (bindings 0, 2–6) and the step blocks (binding 1).
fn bind_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    bound: &[wgpu::Buffer; 6],
    steps: &wgpu::Buffer,
) -> wgpu::BindGroup {
    let step = wgpu::BufferBinding {
        buffer: steps,
        offset: 0,
        size: wgpu::BufferSize::new(std::mem::size_of::<StepGpu>() as u64),
    };
    let resources = std::iter::once(bound[0].as_entire_binding())
        .chain([wgpu::BindingResource::Buffer(step)])
        .chain(bound[1..].iter().map(|b| b.as_entire_binding()));
    crate::gpu::bind_buffers(device, "particles", layout, resources)
}

/// The `Emitter` block of `params`.
fn emitter_block(params: &EmitterParams, schedule: &Schedule) -> EmitterGpu {
    let axis = params.direction.try_normalize().unwrap_or(Vec3::Y);
    let (across, other) = axis.any_orthonormal_pair();
    let (shape, shape_size) = match params.shape {
        SpawnShape::Point => (0, [0.0; 4]),
        SpawnShape::Sphere(r) => (1, [r, 0.0, 0.0, 0.0]),
        SpawnShape::Box(half) => (2, half.extend(0.0).into()),
        SpawnShape::Cone(r) => (3, [r, 0.0, 0.0, 0.0]),
    };
    let (ground, bounce) = params.ground.unwrap_or((0.0, 0.0));
    let bursts_alive = (schedule.slots() - u64::from(schedule.stream_slots())) / u64::from(params.burst.count.max(1));
    EmitterGpu {
        origin: params.origin.into(),
        shape,
        axis: axis.into(),
        seed: params.seed,
        across: across.into(),
        stream_slots: schedule.stream_slots(),
        other: other.into(),
        burst: params.burst.count,
        shape_size,
        gravity: params.gravity.into(),
        drag: params.drag,
        color: params.color.into(),
        color_end: params.color_end.into(),
        motion: [params.speed.0, params.speed.1, params.spread.min(180.0).to_radians(), params.noise],
        timing: [params.lifetime.0, params.lifetime.1, params.rate, params.burst.every],
        look: [params.size, params.size_end, params.noise_scale, f32::from(u8::from(params.ground.is_some()))],
        ground: [ground, bounce, bursts_alive as f32, schedule.slots() as f32],
    }
}

#[cfg(test)]
mod layout_tests {
    use super::*;
    use crate::shader::layout::assert_mirrors;

    #[test]
    fn the_emitter_blocks_and_records_mirror_their_wgsl_structs() {
        let wgsl = crate::shader::PARTICLES_STEP;
        assert_mirrors!(
            EmitterGpu,
            wgsl,
            "Emitter",
            [
                origin,
                shape,
                axis,
                seed,
                across,
                stream_slots,
                other,
                burst,
                shape_size,
                gravity,
                drag,
                color,
                color_end,
                motion,
                timing,
                look,
                ground
            ]
        );
        assert_mirrors!(StepGpu, wgsl, "Step", [times, counts, eye]);
        assert_mirrors!(super::super::Particle, wgsl, "Particle", [position, age, velocity, id]);
        assert_mirrors!(crate::gpu::ParticleGpu, wgsl, "Record", [center_size, color]);
    }
}
