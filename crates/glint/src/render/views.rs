//! Core layer: the GPU state a view keeps between frames ([`ViewGpu`]): its
//! Camera block (`@group(1)`) — the camera at record 0, then each shadow view —
//! in one uniform buffer bound with a dynamic offset, and its forward and shadow
//! draw lists. Records and lists are written only where their bytes change, so
//! a view that did not change uploads nothing, however many views a frame has.

use crate::render::clusters::Binned;
use crate::render::frame::input::{ViewKey, KEEP_VIEW_FRAMES};
use crate::render::gpu_driven::draw_list::{DrawList, ListPaths};
use crate::render::gpu_driven::light_binning::GpuBins;
use crate::render::passes::accumulate::Accumulation;
use crate::render::passes::ambient_occlusion::OcclusionTargets;
use crate::render::passes::post::PostParams;
use crate::render::passes::shadow_maps::{ShadowGpu, ShadowMaps};
use crate::render::passes::shadow_views::MAX_SHADOW_VIEWS;
use crate::render::passes::transparency::TransparencyTargets;
use crate::render::resources::blocks::CameraGpu;
use crate::render::resources::blocks::{SceneGpu, UniformBlock};
use crate::render::resources::buffers::InstanceBuffer;
use crate::render::resources::gpu_array::GpuArray;
use crate::render::resources::pipelines::Pipelines;
use std::collections::HashMap;

/// Records the buffer holds: the camera and up to [`MAX_SHADOW_VIEWS`] shadow views.
const RECORDS: usize = 1 + MAX_SHADOW_VIEWS;
/// Bytes between records: the dynamic-offset alignment every device accepts.
pub(crate) const RECORD_STRIDE: u64 = 256;

/// The view records and the bind group over them.
pub(crate) struct ViewBlocks {
    buffer: wgpu::Buffer,
    pub bind_group: wgpu::BindGroup,
    last: Vec<Option<CameraGpu>>,
}

impl ViewBlocks {
    pub(crate) fn new(device: &wgpu::Device, layout: &wgpu::BindGroupLayout) -> Self {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("camera block: view records"),
            size: RECORD_STRIDE * RECORDS as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("camera block (group 1)"),
            layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: Self::binding(&buffer) }],
        });
        Self { buffer, bind_group, last: vec![None; RECORDS] }
    }

    /// The records as a group's binding 0, one record at a time (picked by
    /// [`offset`](Self::offset)): in the Camera block's group, and in exact
    /// transparency's group beside the fragment lists.
    pub(crate) fn camera(&self) -> wgpu::BindingResource<'_> {
        Self::binding(&self.buffer)
    }

    fn binding(buffer: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer,
            offset: 0,
            size: std::num::NonZeroU64::new(std::mem::size_of::<CameraGpu>() as u64),
        })
    }

    /// Write record `index` (0: the camera, 1 + k: shadow view k) if it changed;
    /// returns bytes written.
    pub(crate) fn update(&mut self, queue: &wgpu::Queue, index: usize, value: CameraGpu) -> u64 {
        if self.last[index] == Some(value) {
            return 0;
        }
        queue.write_buffer(&self.buffer, RECORD_STRIDE * index as u64, bytemuck::bytes_of(&value));
        self.last[index] = Some(value);
        std::mem::size_of::<CameraGpu>() as u64
    }

    /// The dynamic offset that selects record `index`.
    pub(crate) fn offset(index: usize) -> u32 {
        (RECORD_STRIDE * index as u64) as u32
    }
}

/// What every view's GPU state points at: the shared instance buffer and
/// shadow maps, with the generations that say when they were replaced.
pub(crate) struct Shared<'a> {
    pub device: &'a wgpu::Device,
    pub pipelines: &'a Pipelines,
    pub instances: &'a InstanceBuffer,
    pub shadow_maps: &'a ShadowMaps,
    pub shadow_maps_generation: u64,
    pub environment: &'a crate::render::passes::environment::EnvironmentMaps,
    /// A 1 × 1 white texture: the ambient occlusion of a view without it.
    pub white: &'a wgpu::TextureView,
}

/// What one view keeps on the GPU between frames: a split screen's views, or a
/// view into a render target, each draw from their own records, lists and
/// Shadow block (views are told apart by their [`ViewKey`]).
pub(crate) struct ViewGpu {
    /// The camera's and the shadow views' Camera-block records.
    pub blocks: ViewBlocks,
    /// The forward pass's draws.
    pub forward: DrawList,
    /// Every shadow view's draws.
    pub shadows: DrawList,
    /// The Scene block: lights, environment and each light's first shadow view.
    pub scene_block: UniformBlock<SceneGpu>,
    /// The Shadow block: this view's cascade and spot-light matrices.
    pub shadow_block: UniformBlock<ShadowGpu>,
    /// The Scene bind group over this view's Scene and Shadow blocks and the
    /// shared shadow maps.
    pub scene_group: wgpu::BindGroup,
    /// Its post chain's pass parameters.
    pub post_params: PostParams,
    /// Its ambient occlusion's textures, from its first frame with it.
    pub occlusion: Option<OcclusionTargets>,
    /// Its running mean, from its first accumulated still.
    pub accumulation: Option<Accumulation>,
    /// Its weighted sums or fragment lists, while it draws transparency so
    /// and has something to draw (`frame/transparency.rs`).
    pub transparency: Option<TransparencyTargets>,
    /// Its light clusters' arrays, and this frame's clusters until uploaded
    /// (`render/frame/lights.rs`).
    pub clusters: ClusterArrays,
    /// The instance buffer, shadow maps and environment maps generations the bind groups point at.
    generations: (u64, u64, u64),
}

impl ViewGpu {
    /// A new view's state over `shared`, its lists drawing as `paths` say.
    pub(crate) fn new(shared: &Shared, paths: ListPaths) -> Self {
        let Shared { device, pipelines, instances, .. } = *shared;
        let list = |label| DrawList::new(device, label, &pipelines.instance_layout, instances.array(), paths);
        let scene_block = UniformBlock::new(device, "renderer: scene block");
        let shadow_block = UniformBlock::new(device, "renderer: shadow block");
        let clusters = ClusterArrays::new(device, pipelines.vertex_storage());
        Self {
            blocks: ViewBlocks::new(device, &pipelines.camera_layout),
            forward: list("renderer block: forward draw indices"),
            shadows: list("renderer block: shadow draw indices"),
            scene_group: scene_group(shared, (&scene_block, &shadow_block), None, &clusters),
            clusters,
            post_params: PostParams::new(device),
            occlusion: None,
            accumulation: None,
            transparency: None,
            scene_block,
            shadow_block,
            generations: (instances.generation(), shared.shadow_maps_generation, shared.environment.generation()),
        }
    }

    /// Point the bind groups at the instance buffer, shadow maps and
    /// environment maps of `shared` where any was replaced since they were made.
    pub(crate) fn refresh(&mut self, shared: &Shared) {
        let (instances, maps) = (shared.instances.generation(), shared.shadow_maps_generation);
        let environment = shared.environment.generation();
        if self.generations.0 != instances {
            let layout = &shared.pipelines.instance_layout;
            self.forward.rebind(shared.device, layout, shared.instances.array());
            self.shadows.rebind(shared.device, layout, shared.instances.array());
        }
        if (self.generations.1, self.generations.2) != (maps, environment) {
            self.rebind_scene(shared);
        }
        self.generations = (instances, maps, environment);
    }

    /// Give the view ambient-occlusion textures `occlusion` (new ones: its
    /// size changed), its Scene bind group pointed at them.
    pub(crate) fn set_occlusion(&mut self, shared: &Shared, occlusion: OcclusionTargets) {
        self.occlusion = Some(occlusion);
        self.rebind_scene(shared);
    }

    /// Point the Scene bind group at the view's current arrays and textures
    /// (after one was replaced).
    pub(crate) fn rebind_scene(&mut self, shared: &Shared) {
        let occlusion = self.occlusion.as_ref().map(|o| &o.blurred);
        let blocks = (&self.scene_block, &self.shadow_block);
        self.scene_group = scene_group(shared, blocks, occlusion, &self.clusters);
    }
}

/// The Scene bind group over a view's blocks, the shared maps, its ambient
/// occlusion (white without) and its light clusters.
fn scene_group(
    shared: &Shared,
    (scene, shadow): (&UniformBlock<SceneGpu>, &UniformBlock<ShadowGpu>),
    occlusion: Option<&wgpu::TextureView>,
    clusters: &ClusterArrays,
) -> wgpu::BindGroup {
    let layout = &shared.pipelines.scene_layout;
    let blocks = (&scene.buffer, &shadow.buffer);
    let occlusion = occlusion.unwrap_or(shared.white);
    shared.shadow_maps.scene_group(shared.device, layout, blocks, (shared.environment, occlusion), &clusters.data)
}

/// A view's light clusters on the GPU (`forward.wgsl`'s `CLUSTERED` array):
/// its cluster words and its point and spot lights' records in one array of
/// 16-byte texels (layout in `render/frame/lights.rs`), a storage buffer or a
/// data texture.
pub(crate) struct ClusterArrays {
    /// The texels.
    pub data: GpuArray,
    /// This frame's clusters, binned and not yet uploaded.
    pub binned: Option<Binned>,
    /// Binning on the GPU, once the view has binned there.
    pub bins: Option<GpuBins>,
    /// What the CPU last wrote into the array, to write again only when it
    /// changes: every texel where the CPU binned; where the GPU did, a marker
    /// texel (the records' texel, `u32::MAX`) and the records.
    pub written: Vec<[u32; 4]>,
}

impl ClusterArrays {
    /// The grid of the clusters the GPU binned last, where the array holds them.
    pub(crate) fn gpu_grid(&self) -> Option<crate::render::clusters::ClusterGrid> {
        let gpu_binned = self.written.first().is_some_and(|t| t[1] == u32::MAX);
        self.bins.as_ref().and_then(|b| b.grid()).filter(|_| gpu_binned)
    }

    fn new(device: &wgpu::Device, storage: bool) -> Self {
        Self {
            data: GpuArray::new(device, "renderer: light clusters", 16, 1, storage),
            binned: None,
            bins: None,
            written: Vec::new(),
        }
    }
}

/// Every view's GPU state, by the caller's key, with the last frame that drew
/// it: kept between frames, given back once unused for
/// [`KEEP_VIEW_FRAMES`] frames.
#[derive(Default)]
pub(crate) struct ViewStates {
    by_key: HashMap<ViewKey, (ViewGpu, u64)>,
    /// The keys of the last frame's views, in the order given.
    last_keys: Vec<ViewKey>,
}

impl ViewStates {
    /// Remember `keys` as the frame's views, in order.
    pub(crate) fn begin_frame(&mut self, keys: impl Iterator<Item = ViewKey>) {
        self.last_keys.clear();
        self.last_keys.extend(keys);
    }

    /// The state kept under `key` (made on its first frame), taken out while
    /// the view is drawn.
    pub(crate) fn take(&mut self, key: ViewKey, shared: &Shared, paths: ListPaths) -> ViewGpu {
        let mut gpu = match self.by_key.remove(&key) {
            Some((gpu, _)) => gpu,
            None => ViewGpu::new(shared, paths),
        };
        gpu.refresh(shared);
        gpu
    }

    /// Keep `gpu` under `key`, drawn in frame `frame`.
    pub(crate) fn put_back(&mut self, key: ViewKey, gpu: ViewGpu, frame: u64) {
        self.by_key.insert(key, (gpu, frame));
    }

    /// Forget the running means of the last frame's views: a failed frame's
    /// commands were dropped, so its sub-frame never reached them, and the
    /// still must start again from sub-frame 0.
    pub(crate) fn forget_stills(&mut self) {
        for key in &self.last_keys {
            if let Some((gpu, _)) = self.by_key.get_mut(key) {
                gpu.accumulation = None;
            }
        }
    }

    /// Give back the state of views not drawn for [`KEEP_VIEW_FRAMES`] frames before `frame`.
    pub(crate) fn drop_unused(&mut self, frame: u64) {
        self.by_key.retain(|_, (_, drawn)| *drawn + KEEP_VIEW_FRAMES >= frame);
    }

    /// The state of the last frame's view `k` (in the order given).
    pub(crate) fn last(&self, k: usize) -> Option<&ViewGpu> {
        self.last_keys.get(k).and_then(|key| self.by_key.get(key)).map(|(gpu, _)| gpu)
    }

    /// The state of the last frame's view `k`, to update.
    pub(crate) fn last_mut(&mut self, k: usize) -> Option<&mut ViewGpu> {
        self.last_keys.get(k).and_then(|key| self.by_key.get_mut(key)).map(|(gpu, _)| gpu)
    }
}
