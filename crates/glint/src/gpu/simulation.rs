//! Core layer: what GPU simulations share with the renderer: the
//! [`GpuSimulation`] trait (a simulation whose steps are compute passes in the
//! frame's encoder), the billboard record a simulation writes into a particle
//! layer ([`ParticleGpu`]), and the compute helpers every simulation's and
//! culling's shaders use (bind group layouts of whole buffers, pipelines).
//! The simulations (`sim`) and the renderer (`render`) both build on it, so
//! neither needs the other.

/// A simulation whose steps are compute passes in the frame.
pub trait GpuSimulation {
    /// Record its pending steps into `encoder` (writing their parameters
    /// through `queue`, and making buffers on `device` if it needs more).
    fn encode(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, encoder: &mut wgpu::CommandEncoder);

    /// The shapes whose vertices it writes in place (a cloth's surface):
    /// the frame's simulate stage puts them in the mesh pool before
    /// [`place`](Self::place). None by default.
    fn shapes(&self) -> Vec<crate::scene::ShapeId> {
        Vec::new()
    }

    /// After its steps, record the passes that write what it draws: the
    /// instance records of its entities ([`Entity::with_gpu_instances`](crate::Entity::with_gpu_instances))
    /// and the vertices of its [`shapes`](Self::shapes), where `targets` says
    /// they are this frame. None by default.
    fn place(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        targets: &PlaceTargets<'_>,
    ) {
        let _ = (device, queue, encoder, targets);
    }
}

/// Where a frame's GPU simulations write what they draw: the instance store's
/// buffers and each entity's range in them, and the mesh pool's vertex
/// streams, as the frame's simulate stage hands them to [`GpuSimulation::place`].
pub struct PlaceTargets<'a> {
    /// Every instance record (64 bytes each, `Instance` in `shader/forward.wgsl`).
    pub records: &'a wgpu::Buffer,
    /// Every instance's world box (centre, half extent: two `vec4<f32>`),
    /// which GPU culling and level selection read.
    pub bounds: &'a wgpu::Buffer,
    pub(crate) range_of: &'a dyn Fn(u64) -> Option<InstanceRange>,
    pub(crate) vertices_of: &'a dyn Fn(crate::scene::ShapeId) -> Option<VertexTarget<'a>>,
}

impl<'a> PlaceTargets<'a> {
    /// Where the records of the entity whose [`key`](crate::Entity::key) is
    /// `entity` are this frame (they move when the store is compacted); `None`
    /// when it was not submitted this frame, or the store writes its records
    /// from its transforms.
    pub fn range(&self, entity: u64) -> Option<InstanceRange> {
        (self.range_of)(entity)
    }

    /// Where `shape`'s vertices are this frame, for one of the simulation's
    /// [`shapes`](GpuSimulation::shapes); `None` for a shape not in the mesh pool.
    pub fn vertices(&self, shape: crate::scene::ShapeId) -> Option<VertexTarget<'a>> {
        (self.vertices_of)(shape)
    }
}

/// Where a shape's base vertex stream ([`Vertex`](crate::scene::Vertex),
/// 48 bytes each) is this frame, for a GPU simulation writing it in place
/// (pages move when they grow: look it up each frame).
#[derive(Clone, Copy, Debug)]
pub struct VertexTarget<'a> {
    /// The page's base vertex stream, a storage buffer.
    pub buffer: &'a wgpu::Buffer,
    /// The shape's first vertex in it.
    pub first: u32,
    /// Its vertices.
    pub count: u32,
}

/// One entity's run of instance records, and what each record holds besides
/// its transform and motion phase.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceRange {
    /// Its first record.
    pub first: u32,
    /// Its instances.
    pub count: u32,
    /// The material index every record names.
    pub material: u32,
    /// Whether its records say it receives shadows.
    pub receive_shadows: bool,
    /// Its shape's box, grown by its material's motion: an instance's world
    /// box is this box moved by its transform, then grown by `walk`.
    pub local: crate::scene::Aabb,
    /// How far its material's motion walks each instance from its placed
    /// position, world units (0: none): its world box then reaches that far
    /// around the placed position in x and z, at any heading.
    pub walk: f32,
}

/// Most records one layer holds: one emitter's particles at most
/// ([`MAX_PARTICLES`](crate::scene::emitter::MAX_PARTICLES), 128 MiB of records).
pub const MAX_LAYER_PARTICLES: u32 = crate::scene::emitter::MAX_PARTICLES;

/// One billboard (32 bytes): the per-instance vertex data of the particle
/// pipeline (locations 0 and 1) and what `shader/particles_step.wgsl` writes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ParticleGpu {
    /// xyz: the centre; w: the side, world units (0: not drawn).
    pub center_size: [f32; 4],
    /// Linear RGB and alpha.
    pub color: [f32; 4],
}

/// A compute layout of `count` buffers: bindings below `uniforms` are uniform
/// blocks (binding `dynamic` with a dynamic offset), the rest storage.
pub(crate) fn buffers_layout(
    device: &wgpu::Device,
    label: &str,
    count: u32,
    uniforms: u32,
    dynamic: Option<u32>,
) -> wgpu::BindGroupLayout {
    let entry = |binding: u32| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: match binding < uniforms {
                true => wgpu::BufferBindingType::Uniform,
                false => wgpu::BufferBindingType::Storage { read_only: false },
            },
            has_dynamic_offset: dynamic == Some(binding),
            min_binding_size: None,
        },
        count: None,
    };
    let entries: Vec<_> = (0..count).map(entry).collect();
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries })
}

/// A bind group of `resources` in binding order.
pub(crate) fn bind_buffers<'a>(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    resources: impl IntoIterator<Item = wgpu::BindingResource<'a>>,
) -> wgpu::BindGroup {
    let entries: Vec<_> = resources
        .into_iter()
        .enumerate()
        .map(|(k, resource)| wgpu::BindGroupEntry { binding: k as u32, resource })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(label), layout, entries: &entries })
}

/// The compute pipeline of `module`'s entry point `entry` over bind groups of `layouts`.
pub(crate) fn compute_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    entry: &str,
    layouts: &[Option<&wgpu::BindGroupLayout>],
) -> wgpu::ComputePipeline {
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(entry),
        bind_group_layouts: layouts,
        immediate_size: 0,
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: Some(&layout),
        module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    })
}
