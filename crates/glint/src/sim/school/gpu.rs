//! [`GpuSchool`]: a [`School`] stepped by compute shaders (`shader/school.wgsl`),
//! its state kept on the GPU between steps and read back on request. A step
//! is deterministic: the fish are sorted by cell with a stable radix sort
//! ([`GpuRadixSort`]), by number inside a cell as the CPU sorts them, not in
//! the order atomics ran, so the same start gives the same bits on the same
//! device.

use super::place::{Placer, SchoolDrawing};
use super::{School, SchoolParams, Swimmer};
use crate::gpu::GpuError;
use crate::gpu::{GpuSimulation, PlaceTargets};
use crate::sim::radix::{GpuRadixSort, RadixGroup};
use crate::sim::scan::{GpuScan, ScanGroup};
use crate::Gpu;

/// Obstacles the GPU's parameter block holds.
pub const MAX_GPU_OBSTACLES: usize = crate::scene::school::MAX_OBSTACLES;
const WORKGROUP: u32 = 256;

// Every school's fish fit one radix sort.
const _: () = assert!(crate::scene::school::MAX_FISH as u32 <= crate::sim::radix::MAX_PAIRS);

/// The uniform block `Params` of `shader/school.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ParamsGpu {
    origin: [f32; 3],
    cell: f32,
    dims: [u32; 3],
    count: u32,
    bounds_min: [f32; 3],
    radius: f32,
    bounds_max: [f32; 3],
    cos_half: f32,
    weights: [f32; 4],
    more: [f32; 4],
    speed: [f32; 4],
    hunter: [f32; 4],
    flags: [u32; 4],
    obstacles: [[f32; 4]; MAX_GPU_OBSTACLES],
}

/// One fish as `shader/school.wgsl` stores it (32 bytes).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct FishGpu {
    position: [f32; 3],
    phase: f32,
    velocity: [f32; 3],
    pad: f32,
}

impl From<&Swimmer> for FishGpu {
    fn from(f: &Swimmer) -> Self {
        Self { position: f.position.into(), phase: f.phase, velocity: f.velocity.into(), pad: 0.0 }
    }
}

impl From<&FishGpu> for Swimmer {
    fn from(f: &FishGpu) -> Self {
        Self { position: f.position.into(), velocity: f.velocity.into(), phase: f.phase }
    }
}

/// The predator's `Hunt` state (48 bytes with the nearest fish's search:
/// its squared distance's bits at 28, where a fish keeps its padding, and
/// its number).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct HuntGpu {
    position: [f32; 3],
    phase: f32,
    velocity: [f32; 3],
    nearest_bits: u32,
    nearest: u32,
    pad: [u32; 3],
}

impl From<&Swimmer> for HuntGpu {
    fn from(f: &Swimmer) -> Self {
        let FishGpu { position, phase, velocity, .. } = FishGpu::from(f);
        Self { position, phase, velocity, nearest_bits: 0, nearest: 0, pad: [0; 3] }
    }
}

/// The passes of one step before the scan, and after it.
const BEFORE_SCAN: [&str; 2] = ["clear", "count"];
const AFTER_SCAN: [&str; 3] = ["gather", "steer", "hunt"];

/// A school whose steps run as compute passes. Needs compute shaders and
/// eight storage buffers a stage ([`Gpu::culls_on_gpu`]); elsewhere (GL,
/// WebGL2) [`GpuSchool::new`] says so and the CPU [`School`] steps instead.
pub struct GpuSchool {
    params: SchoolParams,
    block: ParamsGpu,
    uniform: wgpu::Buffer,
    fish: [wgpu::Buffer; 2],
    hunt: wgpu::Buffer,
    /// Bind groups reading fish buffer 0 then 1.
    groups: [wgpu::BindGroup; 2],
    pipelines: Vec<wgpu::ComputePipeline>,
    scan: GpuScan,
    scan_group: ScanGroup,
    sort: GpuRadixSort,
    sort_group: RadixGroup,
    /// Which fish buffer holds the current state.
    current: usize,
    cells: u32,
    /// Steps [`GpuSimulation::encode`] records next.
    pending: u32,
    /// The entities drawing it in place, once [`draw_in_place`](Self::draw_in_place) is called.
    placer: Option<Placer>,
}

impl GpuSchool {
    /// Upload `school`'s state. Errors where the device has no compute path,
    /// or the school has more than [`MAX_GPU_OBSTACLES`] obstacles.
    pub fn new(gpu: &Gpu, school: &School) -> Result<Self, GpuError> {
        if !gpu.culls_on_gpu() {
            return Err(GpuError::Failed(format!(
                "GPU schooling needs compute shaders and 8 storage buffers a stage, which {} ({:?}) lacks; step the school on the CPU",
                gpu.info().name,
                gpu.info().backend
            )));
        }
        Self::on_device((&gpu.device, &gpu.queue), school)
    }

    /// [`new`](Self::new) on a device known to compute (a renderer's, where
    /// [`Renderer::computes`](crate::Renderer::computes)).
    pub(crate) fn on_device((device, queue): (&wgpu::Device, &wgpu::Queue), school: &School) -> Result<Self, GpuError> {
        let params = school.params().clone();
        if params.obstacles.len() > MAX_GPU_OBSTACLES {
            return Err(GpuError::Failed(format!("GPU schooling takes at most {MAX_GPU_OBSTACLES} obstacles")));
        }
        let shape = school.grid_shape();
        let cells = shape.cells();
        let n = school.fish().len();
        let block = params_block(&params, shape, n as u32, 0.0);
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let buffer = |label: &str, size: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(16),
                usage: storage,
                mapped_at_creation: false,
            })
        };
        let fish_bytes = 32 * n as u64;
        let fish = [buffer("school: fish a", fish_bytes), buffer("school: fish b", fish_bytes)];
        let fish_data: Vec<FishGpu> = school.fish().iter().map(FishGpu::from).collect();
        queue.write_buffer(&fish[0], 0, bytemuck::cast_slice(&fish_data));
        let sorted = buffer("school: fish by cell", fish_bytes);
        let keys = buffer("school: cell and fish", 8 * n as u64);
        let spare = buffer("school: cell and fish, sorting", 8 * n as u64);
        let counts = buffer("school: fish per cell", 4 * (cells as u64 + 1));
        let starts = buffer("school: first slot per cell", 4 * (cells as u64 + 1));
        let hunt = buffer("school: predator", std::mem::size_of::<HuntGpu>() as u64);
        let predator = school.predator().copied().unwrap_or_default();
        let hunt_data = HuntGpu::from(&predator);
        queue.write_buffer(&hunt, 0, bytemuck::bytes_of(&hunt_data));
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("school: parameters"),
            size: std::mem::size_of::<ParamsGpu>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = crate::gpu::buffers_layout(device, "school", 8, 1, None);
        let group = |from: usize| {
            let buffers = [&uniform, &fish[from], &fish[1 - from], &sorted, &keys, &counts, &starts, &hunt];
            crate::gpu::bind_buffers(device, "school", &layout, buffers.iter().map(|b| b.as_entire_binding()))
        };
        let groups = [group(0), group(1)];
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("school.wgsl"),
            source: wgpu::ShaderSource::Wgsl(crate::shader::SCHOOL.into()),
        });
        let pipelines = BEFORE_SCAN
            .iter()
            .chain(&AFTER_SCAN)
            .map(|entry| crate::gpu::compute_pipeline(device, &module, entry, &[Some(&layout)]))
            .collect();
        let scan = GpuScan::new(device);
        let scan_group = scan.group((device, queue), &counts, &starts, cells + 1);
        let sort = GpuRadixSort::new(device);
        let cell_bits = u32::BITS - cells.saturating_sub(1).leading_zeros();
        let sort_group = sort.group((device, queue), &scan, (&keys, &spare), (n as u32, cell_bits));
        Ok(Self {
            params,
            block,
            uniform,
            fish,
            hunt,
            groups,
            pipelines,
            scan,
            scan_group,
            sort,
            sort_group,
            current: 0,
            cells,
            pending: 0,
            placer: None,
        })
    }

    /// Start again from `school`'s state (the same parameters and fish
    /// count: a scene's school restarted from its seed), dropping pending steps.
    pub(crate) fn restart(&mut self, queue: &wgpu::Queue, school: &School) {
        let fish: Vec<FishGpu> = school.fish().iter().map(FishGpu::from).collect();
        queue.write_buffer(&self.fish[0], 0, bytemuck::cast_slice(&fish));
        let predator = HuntGpu::from(&school.predator().copied().unwrap_or_default());
        queue.write_buffer(&self.hunt, 0, bytemuck::bytes_of(&predator));
        (self.current, self.pending) = (0, 0);
    }

    /// Its fish and predator as the GPU keeps them (waiting for the GPU),
    /// for a simulation cache; `None` while steps are pending.
    pub(crate) fn save(&self, gpu: (&wgpu::Device, &wgpu::Queue)) -> Result<Option<Vec<Vec<u8>>>, GpuError> {
        match self.pending {
            0 => crate::gpu::read_buffers(gpu, &[&self.fish[self.current], &self.hunt]).map(Some),
            _ => Ok(None),
        }
    }

    /// Go on from the fish and predator [`save`](Self::save)d, dropping pending steps.
    pub(crate) fn load(&mut self, queue: &wgpu::Queue, fish: &[u8], hunt: &[u8]) -> Result<(), String> {
        crate::gpu::refill(queue, &[(&self.fish[0], fish, "fish"), (&self.hunt, hunt, "the predator")])?;
        (self.current, self.pending) = (0, 0);
        Ok(())
    }

    /// Draw it in place from now on: after each frame's steps its fish and
    /// predator are written into the instance records of `drawings`'
    /// entities ([`GpuSimulation::place`]). Errors for a drawing with no
    /// part transforms or more than
    /// [`MAX_PART_TRANSFORMS`](super::MAX_PART_TRANSFORMS).
    pub fn draw_in_place(&mut self, device: &wgpu::Device, drawings: Vec<SchoolDrawing>) -> Result<(), GpuError> {
        self.placer = Some(Placer::new(device, drawings)?);
        Ok(())
    }

    /// Record and submit one step of `dt` seconds (not waited for).
    pub fn step(&mut self, gpu: &Gpu, dt: f32) {
        self.advance(&gpu.queue, 1, dt);
        let mut encoder =
            gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("school step") });
        self.encode(&gpu.device, &gpu.queue, &mut encoder);
        gpu.queue.submit([encoder.finish()]);
    }

    /// Have the next [`GpuSimulation::encode`] (a frame's simulate stage,
    /// [`FrameInput::simulate`](crate::FrameInput::simulate)) record `steps` more
    /// steps of `dt` seconds.
    pub fn advance(&mut self, queue: &wgpu::Queue, steps: u32, dt: f32) {
        if self.block.more[3] != dt {
            self.block.more[3] = dt;
            queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&self.block));
        }
        self.pending += steps;
    }

    /// One step's passes into `encoder`, after which the other fish buffer
    /// holds the state.
    fn encode_step(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let fish_groups = (self.block.count).div_ceil(WORKGROUP);
        let cell_groups = (self.cells + 1).div_ceil(WORKGROUP);
        let threads = [cell_groups, fish_groups, fish_groups, fish_groups, 1];
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("school step"), timestamp_writes: None });
        for (k, (pipeline, groups)) in self.pipelines.iter().zip(threads).enumerate() {
            if k == BEFORE_SCAN.len() {
                self.scan.encode(&mut pass, &self.scan_group);
                self.sort.encode(&mut pass, &self.scan, &self.sort_group);
            }
            if k == 0 || k == BEFORE_SCAN.len() {
                pass.set_bind_group(0, &self.groups[self.current], &[]);
            }
            pass.set_pipeline(pipeline);
            pass.dispatch_workgroups(groups, 1, 1);
        }
        drop(pass);
        self.current = 1 - self.current;
    }

    /// The state now, as a CPU [`School`] (waiting for the GPU).
    pub fn read(&self, gpu: &Gpu) -> Result<School, GpuError> {
        let bytes = gpu.read_buffer(&self.fish[self.current])?;
        let fish: Vec<Swimmer> =
            bytemuck::pod_collect_to_vec::<u8, FishGpu>(&bytes).iter().map(Swimmer::from).collect();
        let hunt: HuntGpu =
            bytemuck::pod_read_unaligned(&gpu.read_buffer(&self.hunt)?[..std::mem::size_of::<HuntGpu>()]);
        let hunter = FishGpu { position: hunt.position, phase: hunt.phase, velocity: hunt.velocity, pad: 0.0 };
        let predator = self.params.predator.map(|_| Swimmer::from(&hunter));
        Ok(School::from_state(self.params.clone(), fish, predator))
    }
}

impl GpuSimulation for GpuSchool {
    fn encode(&mut self, _: &wgpu::Device, _: &wgpu::Queue, encoder: &mut wgpu::CommandEncoder) {
        for _ in 0..std::mem::take(&mut self.pending) {
            self.encode_step(encoder);
        }
    }

    fn place(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        instances: &PlaceTargets<'_>,
    ) {
        if let Some(placer) = &mut self.placer {
            let state = (&self.fish[self.current], &self.hunt, self.block.count);
            placer.encode((device, queue), encoder, state, instances);
        }
    }
}

/// `params` for `count` fish on grid `shape`, stepping `dt` seconds.
fn params_block(params: &SchoolParams, shape: super::GridShape, count: u32, dt: f32) -> ParamsGpu {
    let w = params.weights;
    let mut obstacles = [[0.0; 4]; MAX_GPU_OBSTACLES];
    for (slot, o) in obstacles.iter_mut().zip(&params.obstacles) {
        *slot = [o.center.x, o.center.y, o.center.z, o.radius];
    }
    let hunter = params.predator.map_or([0.0; 4], |h| [h.speed, h.accel, h.fear, 1.0]);
    ParamsGpu {
        origin: shape.origin.into(),
        cell: shape.cell,
        dims: shape.dims.into(),
        count,
        bounds_min: params.bounds.min.into(),
        radius: params.radius,
        bounds_max: params.bounds.max.into(),
        cos_half: params.cos_half_view(),
        weights: [w.separation, w.alignment, w.cohesion, w.bounds],
        more: [w.avoid, w.flee, params.max_accel, dt],
        speed: [params.min_speed, params.max_speed, params.beat_rate, params.floor.unwrap_or(0.0)],
        hunter,
        flags: [
            u32::from(params.floor.is_some()),
            params.obstacles.len() as u32,
            shape.cells(),
            super::MAX_NEIGHBOUR_TESTS,
        ],
        obstacles,
    }
}

#[cfg(test)]
mod layout_tests {
    use super::*;
    use crate::shader::layout::{assert_layout, assert_mirrors};

    #[test]
    fn the_school_blocks_mirror_their_wgsl_structs() {
        let wgsl = crate::shader::SCHOOL;
        assert_mirrors!(
            ParamsGpu,
            wgsl,
            "Params",
            [
                origin, cell, dims, count, bounds_min, radius, bounds_max, cos_half, weights, more, speed, hunter,
                flags, obstacles
            ]
        );
        assert_mirrors!(FishGpu, wgsl, "Fish", [position, phase, velocity, pad]);
        // The WGSL's tail padding is implicit.
        let fields = [
            ("position", std::mem::offset_of!(HuntGpu, position)),
            ("phase", std::mem::offset_of!(HuntGpu, phase)),
            ("velocity", std::mem::offset_of!(HuntGpu, velocity)),
            ("nearest_bits", std::mem::offset_of!(HuntGpu, nearest_bits)),
            ("nearest", std::mem::offset_of!(HuntGpu, nearest)),
        ];
        assert_layout(wgsl, "Hunt", std::mem::size_of::<HuntGpu>(), &fields);
    }
}
