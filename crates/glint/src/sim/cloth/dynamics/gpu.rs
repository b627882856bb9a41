//! [`GpuCloth`]: a [`Cloth`] whose time steps run as compute passes
//! (`shader/cloth.wgsl`), by Vertex Block Descent (Chen et al., SIGGRAPH
//! 2024) on the same Discrete Elastic Plates energy, contact and pins as the
//! CPU's Newton solve, which stays the reference and the fallback where the
//! device has no compute.
//!
//! Each step minimises the step's incremental potential (the one
//! [`Cloth::step_objective`] measures) node by node: the free nodes are
//! coloured so that no two of a colour share an edge or hinge
//! ([`super::super::colour`]), and each of the step's iterations gives every
//! colour in turn one pass in which each of its nodes takes a 3×3 Newton step
//! on its own terms, shortened until they fall, so that without acceleration
//! the potential never rises (Chebyshev's acceleration between sweeps, on by
//! default, trades that for speed); how close a fixed number of sweeps comes
//! to Newton's answer is
//! measured (`tests/cloth_gpu.rs`, `docs/cloth.md`). Everything runs in single
//! precision, and a step has a fixed cost: no step is halved or refused, as
//! the CPU solves do, since that would need the state read back.
//!
//! A step is deterministic: each node reads only nodes of other colours and
//! writes only itself, so the same start gives the same bits on the same device.

use super::surface::SurfacePlacer;
use super::{contact_stiffness, Cloth, Integrator, NEWMARK_BETA, NEWMARK_GAMMA};
use crate::gpu::{GpuError, GpuSimulation, PlaceTargets};
use crate::scene::ShapeId;
use crate::sim::cloth::colour::colour_nodes;
use crate::Gpu;
use glam::DVec3;

/// Colliders the parameter block holds: every collider a `.scn` cloth may have.
pub const MAX_GPU_COLLIDERS: usize = crate::scene::cloth::MAX_COLLIDERS;
/// Iterations of a step when a scene or command does not say.
pub const DEFAULT_ITERATIONS: u32 = 60;
/// Most iterations a step may take.
pub const MAX_ITERATIONS: u32 = 10_000;
/// Chebyshev's ρ when a scene or command does not say.
pub const DEFAULT_ACCELERATION: f64 = 0.95;
/// Sweeps over which Chebyshev's ω changes; later ones use the last.
const CHEBYSHEV_BLOCKS: u32 = 32;

/// How a [`GpuCloth`] solves each step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpuSolve {
    /// Sweeps over the node colours a step, 1..=[`MAX_ITERATIONS`].
    pub iterations: u32,
    /// Chebyshev's estimate ρ of how much each sweep shrinks the error, in
    /// 0..1: the sweeps are accelerated by it (Wang 2015), and the step's
    /// potential may then rise between sweeps; 0 turns acceleration off, and
    /// the potential falls at every node's move.
    pub acceleration: f64,
}

impl Default for GpuSolve {
    fn default() -> Self {
        Self { iterations: DEFAULT_ITERATIONS, acceleration: DEFAULT_ACCELERATION }
    }
}
const WORKGROUP: u32 = 64;
/// Smallest storage buffer made: one element of the largest array (`Hinge`).
const MIN_BUFFER_BYTES: u64 = std::mem::size_of::<HingeGpu>() as u64;
/// Bytes between the colours' blocks (the dynamic-offset alignment).
const STRIDE: u64 = 256;

/// The uniform block `Params` of `shader/cloth.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ParamsGpu {
    nodes: u32,
    integrator: u32,
    colliders: u32,
    pad: u32,
    dt: f32,
    inertia: f32,
    drag: f32,
    kappa: f32,
    gravity: [f32; 3],
    bend_k: f32,
    pin_velocity: [f32; 3],
    contact_distance: f32,
    pin_spin: [f32; 3],
    contact_per_kg: f32,
    pin_centre: [f32; 3],
    start_time: f32,
    collider_a: [[f32; 4]; MAX_GPU_COLLIDERS],
    collider_b: [[f32; 4]; MAX_GPU_COLLIDERS],
}

/// `Edge` of `shader/cloth.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct EdgeGpu {
    nodes: [u32; 2],
    rest: f32,
    k: f32,
}

/// `Hinge` of `shader/cloth.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct HingeGpu {
    nodes: [u32; 4],
    rest: f32,
    pad: [f32; 3],
}

/// `Chebyshev` of `shader/cloth.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ChebyshevGpu {
    omega: f32,
    record: u32,
    pad: [u32; 2],
}

/// `Colour` of `shader/cloth.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ColourGpu {
    first: u32,
    count: u32,
    pad: [u32; 2],
}

/// A cloth stepped on the GPU. Needs the renderer's compute path
/// ([`Gpu::culls_on_gpu`]: compute shaders, eight storage buffers a stage and
/// indirect drawing, not GL's backend), where the scene's simulations step;
/// elsewhere (GL, WebGL2) [`GpuCloth::new`] says so and the CPU solve steps instead.
pub struct GpuCloth {
    nodes: u32,
    /// Position, velocity, acceleration (each xyz of a `vec4<f32>` per node).
    state: [wgpu::Buffer; 3],
    /// Steps taken since the upload (`State` of the shader).
    steps_buffer: wgpu::Buffer,
    /// Bind groups 0 (every pass), 1 (predict and finish) and 2 (the solve).
    groups: [wgpu::BindGroup; 3],
    /// Chebyshev's blocks and positions one and two sweeps back (group 3),
    /// when the sweeps are accelerated.
    chebyshev: Option<wgpu::BindGroup>,
    predict: wgpu::ComputePipeline,
    solve: wgpu::ComputePipeline,
    accelerate: wgpu::ComputePipeline,
    finish: wgpu::ComputePipeline,
    /// Nodes per colour.
    colours: Vec<u32>,
    settings: GpuSolve,
    dt: f64,
    start_time: f64,
    /// Steps recorded since the upload.
    recorded: u64,
    /// Steps the next [`encode`](Self::encode) records.
    pending: u32,
    /// The pass writing its surface shape in place, once drawn so.
    surface: Option<SurfacePlacer>,
}

impl GpuCloth {
    /// Upload `cloth`'s state to step it by `dt` seconds with `integrator`,
    /// each step solved as `settings` says. Errors where the device has no
    /// compute path, for a static solve (it has no time to step: the CPU
    /// solves it), or for settings out of their ranges.
    pub fn new(
        gpu: &Gpu,
        cloth: &Cloth,
        dt: f64,
        integrator: Integrator,
        settings: GpuSolve,
    ) -> Result<Self, GpuError> {
        if !gpu.culls_on_gpu() {
            return Err(GpuError::Failed(format!(
                "the GPU cloth solve needs the renderer's compute path (compute shaders, 8 storage buffers a stage \
                 and indirect drawing, not GL), which {} ({:?}) lacks; solve the cloth on the CPU",
                gpu.info().name,
                gpu.info().backend
            )));
        }
        Self::on_device((&gpu.device, &gpu.queue), cloth, (dt, integrator), settings)
    }

    /// [`new`](Self::new) on a device known to compute.
    pub(crate) fn on_device(
        (device, queue): (&wgpu::Device, &wgpu::Queue),
        cloth: &Cloth,
        (dt, integrator): (f64, Integrator),
        settings: GpuSolve,
    ) -> Result<Self, GpuError> {
        if integrator == Integrator::Static {
            return Err(GpuError::Failed(
                "the GPU cloth solve steps in time; a static cloth is solved on the CPU".into(),
            ));
        }
        if !(1..=MAX_ITERATIONS).contains(&settings.iterations) {
            return Err(GpuError::Failed(format!("the GPU cloth solve takes 1 to {MAX_ITERATIONS} iterations a step")));
        }
        if !(0.0..1.0).contains(&settings.acceleration) {
            return Err(GpuError::Failed(format!(
                "the GPU cloth solve's acceleration is from 0 up to (not including) 1, not {}",
                settings.acceleration
            )));
        }
        if !(dt.is_finite() && dt > 0.0) {
            return Err(GpuError::Failed(format!("the GPU cloth solve needs a time step above 0, not {dt}")));
        }
        let n = cloth.positions.len();
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let buffer = |label: &str, bytes: &[u8]| {
            let b = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                // At least one element of every array the shader binds (a
                // mesh may have no hinges).
                size: (bytes.len() as u64).max(MIN_BUFFER_BYTES),
                usage: storage,
                mapped_at_creation: false,
            });
            queue.write_buffer(&b, 0, bytes);
            b
        };
        let state = state_bytes(cloth);
        let state = [
            buffer("cloth: positions", &state[0]),
            buffer("cloth: velocities", &state[1]),
            buffer("cloth: accelerations", &state[2]),
        ];
        let zeros = vec![[0f32; 4]; n];
        let solve = buffer("cloth: step's positions", bytemuck::cast_slice(&zeros));
        let target = buffer("cloth: step's targets", bytemuck::cast_slice(&zeros));
        // Rest positions (the pins' starts) and masses, negative when pinned.
        let rest: Vec<[f32; 4]> = (cloth.mesh.nodes.iter().zip(&cloth.mass).enumerate())
            .map(|(i, (p, m))| p.as_vec3().extend(if cloth.is_pinned(i) { -1.0 } else { *m as f32 }).to_array())
            .collect();
        let rest = buffer("cloth: rest positions and masses", bytemuck::cast_slice(&rest));
        let steps_buffer = buffer("cloth: steps taken", &[0; 16]);
        let (starts, adjacency) = adjacency(cloth);
        let edges: Vec<EdgeGpu> = (cloth.topology.edges.iter().zip(&cloth.rest_lengths).zip(&cloth.stretch_k))
            .map(|((e, l), k)| EdgeGpu { nodes: *e, rest: *l as f32, k: *k as f32 })
            .collect();
        let hinges: Vec<HingeGpu> = (cloth.topology.hinges.iter().zip(&cloth.rest_angles))
            .map(|(h, rest)| HingeGpu { nodes: *h, rest: *rest as f32, pad: [0.0; 3] })
            .collect();
        let free: Vec<bool> = (0..n).map(|i| !cloth.is_pinned(i)).collect();
        let colours = colour_nodes(n, &cloth.topology, &free);
        let order: Vec<u32> = colours.iter().flatten().copied().collect();
        let mut blocks = vec![0u8; STRIDE as usize * colours.len().max(1)];
        let mut first = 0;
        for (k, c) in colours.iter().enumerate() {
            let block = ColourGpu { first, count: c.len() as u32, pad: [0; 2] };
            blocks[k * STRIDE as usize..][..16].copy_from_slice(bytemuck::bytes_of(&block));
            first += c.len() as u32;
        }
        let uniform = |label: &str, bytes: &[u8]| {
            let b = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes.len() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            queue.write_buffer(&b, 0, bytes);
            b
        };
        let block = params_block(cloth, dt, integrator)?;
        let params = uniform("cloth: parameters", bytemuck::bytes_of(&block));
        let colour_blocks = uniform("cloth: colours", &blocks);
        // Group 0 every pass reads, group 1 the state between steps, group 2 the solve's.
        let shared_layout = crate::gpu::buffers_layout(device, "cloth", 4, 1, None);
        let state_layout = crate::gpu::buffers_layout(device, "cloth state", 4, 0, None);
        let solve_layout = crate::gpu::buffers_layout(device, "cloth solve", 6, 1, Some(0));
        let group = |label: &str, layout: &wgpu::BindGroupLayout, buffers: &[&wgpu::Buffer]| {
            crate::gpu::bind_buffers(device, label, layout, buffers.iter().map(|b| b.as_entire_binding()))
        };
        let shared_group = group("cloth", &shared_layout, &[&params, &solve, &target, &rest]);
        let [position, velocity, acceleration] = &state;
        let state_group = group("cloth state", &state_layout, &[position, velocity, acceleration, &steps_buffer]);
        let adjacency_start = buffer("cloth: adjacency starts", bytemuck::cast_slice(&starts));
        let adjacency = buffer("cloth: adjacency", bytemuck::cast_slice(&adjacency));
        let edges = buffer("cloth: edges", bytemuck::cast_slice(&edges));
        let hinges = buffer("cloth: hinges", bytemuck::cast_slice(&hinges));
        let order = buffer("cloth: nodes by colour", bytemuck::cast_slice(&order));
        let colour_binding = wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &colour_blocks,
            offset: 0,
            size: wgpu::BufferSize::new(std::mem::size_of::<ColourGpu>() as u64),
        });
        let elements = [&adjacency_start, &adjacency, &edges, &hinges, &order];
        let solve_group = crate::gpu::bind_buffers(
            device,
            "cloth solve",
            &solve_layout,
            std::iter::once(colour_binding).chain(elements.iter().map(|b| b.as_entire_binding())),
        );
        let chebyshev_layout = crate::gpu::buffers_layout(device, "cloth acceleration", 3, 1, Some(0));
        let chebyshev = (settings.acceleration > 0.0).then(|| {
            let blocks = uniform("cloth: chebyshev", &chebyshev_blocks(settings.acceleration));
            let binding = wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: &blocks,
                offset: 0,
                size: wgpu::BufferSize::new(std::mem::size_of::<ChebyshevGpu>() as u64),
            });
            let last = buffer("cloth: positions a sweep back", bytemuck::cast_slice(&zeros));
            let before = buffer("cloth: positions two sweeps back", bytemuck::cast_slice(&zeros));
            let resources = [binding, last.as_entire_binding(), before.as_entire_binding()];
            crate::gpu::bind_buffers(device, "cloth acceleration", &chebyshev_layout, resources)
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("cloth.wgsl"),
            source: wgpu::ShaderSource::Wgsl(crate::shader::CLOTH.into()),
        });
        let pipeline = |entry: &str, layouts: &[Option<&wgpu::BindGroupLayout>]| {
            crate::gpu::compute_pipeline(device, &module, entry, layouts)
        };
        Ok(Self {
            nodes: n as u32,
            predict: pipeline("predict", &[Some(&shared_layout), Some(&state_layout)]),
            solve: pipeline("solve_colour", &[Some(&shared_layout), None, Some(&solve_layout)]),
            accelerate: pipeline("accelerate", &[Some(&shared_layout), None, None, Some(&chebyshev_layout)]),
            finish: pipeline("finish", &[Some(&shared_layout), Some(&state_layout)]),
            state,
            steps_buffer,
            groups: [shared_group, state_group, solve_group],
            chebyshev,
            colours: colours.iter().map(|c| c.len() as u32).collect(),
            settings,
            dt,
            start_time: cloth.time,
            recorded: 0,
            pending: 0,
            surface: None,
        })
    }

    /// Colours the free nodes take (passes per iteration).
    pub fn colours(&self) -> usize {
        self.colours.len()
    }

    /// How each step is solved.
    pub fn settings(&self) -> GpuSolve {
        self.settings
    }

    /// Have the next [`encode`](Self::encode) record `steps` more steps.
    pub fn advance(&mut self, steps: u32) {
        self.pending += steps;
    }

    /// Record the pending steps into `encoder`.
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let node_groups = self.nodes.div_ceil(WORKGROUP);
        for _ in 0..std::mem::take(&mut self.pending) {
            let mut pass = encoder
                .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("cloth step"), timestamp_writes: None });
            pass.set_bind_group(0, &self.groups[0], &[]);
            pass.set_bind_group(1, &self.groups[1], &[]);
            pass.set_pipeline(&self.predict);
            pass.dispatch_workgroups(node_groups, 1, 1);
            let accelerate = |pass: &mut wgpu::ComputePass<'_>, sweep: u32| {
                if let Some(group) = &self.chebyshev {
                    pass.set_pipeline(&self.accelerate);
                    pass.set_bind_group(3, group, &[(u64::from(sweep.min(CHEBYSHEV_BLOCKS)) * STRIDE) as u32]);
                    pass.dispatch_workgroups(node_groups, 1, 1);
                }
            };
            accelerate(&mut pass, 0);
            for sweep in 1..=self.settings.iterations {
                pass.set_pipeline(&self.solve);
                for (k, &count) in self.colours.iter().enumerate() {
                    pass.set_bind_group(2, &self.groups[2], &[(k as u64 * STRIDE) as u32]);
                    pass.dispatch_workgroups(count.div_ceil(WORKGROUP), 1, 1);
                }
                accelerate(&mut pass, sweep);
            }
            pass.set_pipeline(&self.finish);
            pass.dispatch_workgroups(node_groups, 1, 1);
            drop(pass);
            self.recorded += 1;
        }
    }

    /// Start again from `cloth` (the one it was made from, or one like it):
    /// its positions, velocities, accelerations and time, no step pending.
    pub fn restart(&mut self, queue: &wgpu::Queue, cloth: &Cloth) {
        for (buffer, bytes) in self.state.iter().zip(state_bytes(cloth)) {
            queue.write_buffer(buffer, 0, &bytes);
        }
        queue.write_buffer(&self.steps_buffer, 0, &[0; 4]);
        (self.start_time, self.recorded, self.pending) = (cloth.time, 0, 0);
    }

    /// Its positions, velocities, accelerations and steps since the upload
    /// as the GPU keeps them (waiting for the GPU), for a simulation cache;
    /// `None` while steps are pending.
    pub(crate) fn save(&self, gpu: (&wgpu::Device, &wgpu::Queue)) -> Result<Option<Vec<Vec<u8>>>, GpuError> {
        let [p, v, a] = &self.state;
        match self.pending {
            0 => crate::gpu::read_buffers(gpu, &[p, v, a, &self.steps_buffer]).map(Some),
            _ => Ok(None),
        }
    }

    /// Go on from what [`save`](Self::save) read, `recorded` steps after an
    /// upload of `start` (the one it was made from), dropping pending steps.
    pub(crate) fn load(
        &mut self,
        queue: &wgpu::Queue,
        (start, recorded): (&Cloth, u64),
        [p, v, a, steps]: [&[u8]; 4],
    ) -> Result<(), String> {
        let counted = steps.get(..4).map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")));
        if counted.map(u64::from) != Some(recorded) {
            return Err(format!("the GPU counted {counted:?} steps, but the record says {recorded}"));
        }
        let [positions, velocities, accelerations] = &self.state;
        let writes = [
            (positions, p, "positions"),
            (velocities, v, "velocities"),
            (accelerations, a, "accelerations"),
            (&self.steps_buffer, steps, "the step count"),
        ];
        crate::gpu::refill(queue, &writes)?;
        (self.start_time, self.recorded, self.pending) = (start.time, recorded, 0);
        Ok(())
    }

    /// Draw it in place: from the next frame it is a simulation in
    /// ([`GpuSimulation`]), its place pass writes its positions and normals
    /// into `shape`'s vertices, a mesh of one vertex per node of `cloth` (the
    /// one it was made from) such as [`ClothView`](super::super::ClothView)'s surface.
    pub(crate) fn draw_in_place(
        &mut self,
        (device, queue): (&wgpu::Device, &wgpu::Queue),
        cloth: &Cloth,
        shape: ShapeId,
    ) {
        self.surface = Some(SurfacePlacer::new(device, queue, cloth, shape));
    }

    /// Record and submit one step (not waited for).
    pub fn step(&mut self, gpu: &Gpu) {
        self.advance(1);
        let mut encoder =
            gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("cloth step") });
        self.encode(&mut encoder);
        gpu.queue.submit([encoder.finish()]);
    }

    /// Copy the state now into `cloth` (the one it was made from, or one
    /// like it): positions, velocities, accelerations and time, waiting for
    /// the GPU. Errors when the device reported an error since the last
    /// check (a step that did not run), or the reading failed.
    pub fn read_into(&self, gpu: &Gpu, cloth: &mut Cloth) -> Result<(), GpuError> {
        let n = self.nodes as usize;
        let [positions, velocities, accelerations] = [&self.state[0], &self.state[1], &self.state[2]]
            .map(|b| gpu.read_buffer(b).map(|bytes| read_vec3s(&bytes, n)));
        let steps = u32::from_le_bytes(gpu.read_buffer(&self.steps_buffer)?[..4].try_into().expect("4 bytes"));
        gpu.check()?;
        (cloth.positions, cloth.velocities, cloth.accelerations) = (positions?, velocities?, accelerations?);
        cloth.time = self.start_time + f64::from(steps) * self.dt;
        debug_assert_eq!(u64::from(steps), self.recorded);
        Ok(())
    }
}

impl GpuSimulation for GpuCloth {
    fn encode(&mut self, _: &wgpu::Device, _: &wgpu::Queue, encoder: &mut wgpu::CommandEncoder) {
        GpuCloth::encode(self, encoder);
    }

    fn shapes(&self) -> Vec<ShapeId> {
        self.surface.iter().map(SurfacePlacer::shape).collect()
    }

    fn place(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        targets: &PlaceTargets<'_>,
    ) {
        if let Some(surface) = &mut self.surface {
            surface.encode((device, queue), encoder, &self.state[0], targets);
        }
    }
}

/// `cloth`'s positions, velocities and accelerations, each xyz of a
/// `vec4<f32>` per node.
fn state_bytes(cloth: &Cloth) -> [Vec<u8>; 3] {
    let vec4s = |v: &[DVec3]| -> Vec<u8> {
        let all: Vec<[f32; 4]> = v.iter().map(|p| p.as_vec3().extend(0.0).to_array()).collect();
        bytemuck::cast_slice(&all).to_vec()
    };
    [vec4s(&cloth.positions), vec4s(&cloth.velocities), vec4s(&cloth.accelerations)]
}

/// Chebyshev's blocks, [`STRIDE`] apart: block 0 records the start, block n
/// (n ≥ 1) holds ω after sweep n for spectral radius `rho`: ω₁ = 1,
/// ω₂ = 2 / (2 − ρ²), ωₙ = 4 / (4 − ρ² ωₙ₋₁).
fn chebyshev_blocks(rho: f64) -> Vec<u8> {
    let mut bytes = vec![0u8; STRIDE as usize * (CHEBYSHEV_BLOCKS as usize + 1)];
    let mut omega = 1.0;
    for n in 0..=CHEBYSHEV_BLOCKS {
        omega = match n {
            0 | 1 => 1.0,
            2 => 2.0 / (2.0 - rho * rho),
            _ => 4.0 / (4.0 - rho * rho * omega),
        };
        let block = ChebyshevGpu { omega: omega as f32, record: u32::from(n == 0), pad: [0; 2] };
        bytes[n as usize * STRIDE as usize..][..16].copy_from_slice(bytemuck::bytes_of(&block));
    }
    bytes
}

/// The first `n` `vec4<f32>`s of `bytes`, their xyz in double precision.
fn read_vec3s(bytes: &[u8], n: usize) -> Vec<DVec3> {
    let all: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(bytes);
    all[..n].iter().map(|v| DVec3::new(v[0].into(), v[1].into(), v[2].into())).collect()
}

/// Each node's elements, as `shader/cloth.wgsl` reads them: per node the
/// start of its run (and one past the last), and entries `element << 3 |
/// hinge << 2 | slot`.
fn adjacency(cloth: &Cloth) -> (Vec<u32>, Vec<u32>) {
    let n = cloth.positions.len();
    let mut runs: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (e, edge) in cloth.topology.edges.iter().enumerate() {
        for (slot, &node) in edge.iter().enumerate() {
            runs[node as usize].push((e as u32) << 3 | slot as u32);
        }
    }
    for (h, hinge) in cloth.topology.hinges.iter().enumerate() {
        for (slot, &node) in hinge.iter().enumerate() {
            runs[node as usize].push((h as u32) << 3 | 4 | slot as u32);
        }
    }
    let mut starts = Vec::with_capacity(n + 1);
    let mut entries = Vec::new();
    for run in runs {
        starts.push(entries.len() as u32);
        entries.extend(run);
    }
    starts.push(entries.len() as u32);
    (starts, entries)
}

/// The parameter block of `cloth` stepping by `dt` with `integrator`.
fn params_block(cloth: &Cloth, dt: f64, integrator: Integrator) -> Result<ParamsGpu, GpuError> {
    let colliders = &cloth.contact.colliders;
    if colliders.len() > MAX_GPU_COLLIDERS {
        return Err(GpuError::Failed(format!("the GPU cloth solve takes at most {MAX_GPU_COLLIDERS} colliders")));
    }
    let (inertia, kappa) = match integrator {
        Integrator::Newmark => (1.0 / (NEWMARK_BETA * dt * dt), NEWMARK_GAMMA / (NEWMARK_BETA * dt)),
        _ => (1.0 / (dt * dt), 1.0 / dt),
    };
    let mut collider_a = [[0.0; 4]; MAX_GPU_COLLIDERS];
    let mut collider_b = [[0.0; 4]; MAX_GPU_COLLIDERS];
    for (k, c) in colliders.iter().enumerate() {
        use crate::scene::cloth::Collider;
        let f = |v: DVec3| v.as_vec3().to_array();
        let ([a0, a1, a2], kind, b) = match *c {
            Collider::Plane { point, normal } => (f(point), 0.0, f(normal)),
            Collider::Sphere { centre, radius } => (f(centre), 1.0, [radius as f32, 0.0, 0.0]),
            Collider::Box { min, max } => (f(min), 2.0, f(max)),
        };
        collider_a[k] = [a0, a1, a2, kind];
        collider_b[k] = [b[0], b[1], b[2], 0.0];
    }
    let pins = &cloth.pin_motion;
    Ok(ParamsGpu {
        nodes: cloth.positions.len() as u32,
        integrator: u32::from(integrator == Integrator::Newmark),
        colliders: colliders.len() as u32,
        pad: 0,
        dt: dt as f32,
        inertia: inertia as f32,
        drag: (cloth.damping * kappa) as f32,
        kappa: kappa as f32,
        gravity: cloth.params.gravity.as_vec3().to_array(),
        bend_k: cloth.bend_k as f32,
        pin_velocity: pins.velocity.as_vec3().to_array(),
        contact_distance: cloth.contact.distance as f32,
        pin_spin: pins.angular_velocity.as_vec3().to_array(),
        contact_per_kg: contact_stiffness(1.0, &cloth.params, &cloth.contact) as f32,
        pin_centre: pins.centre.as_vec3().to_array(),
        start_time: cloth.time as f32,
        collider_a,
        collider_b,
    })
}

#[cfg(test)]
mod layout_tests {
    use super::*;
    use crate::shader::layout::assert_mirrors;

    #[test]
    fn the_cloth_blocks_mirror_their_wgsl_structs() {
        let wgsl = crate::shader::CLOTH;
        assert_mirrors!(
            ParamsGpu,
            wgsl,
            "Params",
            [
                nodes,
                integrator,
                colliders,
                pad,
                dt,
                inertia,
                drag,
                kappa,
                gravity,
                bend_k,
                pin_velocity,
                contact_distance,
                pin_spin,
                contact_per_kg,
                pin_centre,
                start_time,
                collider_a,
                collider_b
            ]
        );
        assert_mirrors!(EdgeGpu, wgsl, "Edge", [nodes, rest, k]);
        assert_mirrors!(HingeGpu, wgsl, "Hinge", [nodes, rest, pad]);
        assert_mirrors!(ColourGpu, wgsl, "Colour", [first, count, pad]);
        assert_mirrors!(ChebyshevGpu, wgsl, "Chebyshev", [omega, record, pad]);
    }
}
