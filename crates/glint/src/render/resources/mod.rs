//! Core layer: what frames draw with and keep between them: the registry
//! (shapes in the mesh pool, materials, textures, render targets), the
//! pipelines and their layouts, the persistent instance store, the data
//! blocks' GPU twins, and the pool of transient targets.

pub(crate) mod blocks;
pub(crate) mod buffers;
pub(crate) mod gpu_array;
pub(crate) mod instances;
pub(crate) mod materials;
pub(crate) mod mesh_pool;
pub(crate) mod pipelines;
pub(crate) mod registry;
pub(crate) mod target_pool;
pub(crate) mod transparency_twins;

use crate::gpu::{Gpu, SubmitQueue, UncapturedErrors};
use crate::render::debug::timer::GpuTimer;
use crate::render::frame::input::FrameMode;
use crate::render::gpu_driven::cull_pipelines::CullPipelines;
use crate::render::gpu_driven::draw_list::ListPaths;
use crate::render::gpu_driven::light_binning::LightBinning;
use crate::render::passes::ambient_occlusion::AmbientOcclusionPipelines;
use crate::render::passes::environment::EnvironmentMaps;
use crate::render::passes::particles::Particles;
use crate::render::passes::post::PostChain;
use crate::render::passes::shadow_maps::{ShadowMaps, ShadowSupport};
use crate::render::views::Shared;
use buffers::InstanceBuffer;
use instances::InstanceStore;
use registry::Registry;
use target_pool::TargetPool;

/// What every frame draws with, owned by the renderer and kept between
/// frames: the device, the [`Registry`] (shapes, materials, textures, render
/// targets, pipelines), the instance store and its GPU buffer, the passes'
/// pipelines and images (shadow maps, environment maps, post chain, ambient
/// occlusion, particle layers, GPU culling), the pool of transient targets,
/// and the settings frames are built with. The frame's stages take it as
/// their first argument.
pub(crate) struct Resources {
    pub device: wgpu::Device,
    pub queue: SubmitQueue,
    /// Errors the device reported outside glint's scopes, returned by the frame.
    pub uncaptured: UncapturedErrors,
    /// The queue's submission count when the last frame ended.
    pub submits_counted: u64,
    /// The shapes, materials, textures, render targets and pipelines.
    pub registry: Registry,
    /// Every submitted entity's instances, kept between frames.
    pub store: InstanceStore,
    /// The store's GPU twin.
    pub instances: InstanceBuffer,
    /// How views' draw lists draw (indirect, storage, GPU culling).
    pub paths: ListPaths,
    pub shadow_maps: ShadowMaps,
    /// How many times the shadow maps were replaced (each view's Scene bind
    /// group points at one generation).
    pub shadow_maps_generation: u64,
    /// The environment's prefiltered maps (image-based lighting).
    pub environment: EnvironmentMaps,
    /// Transient targets: views' own and the post chain's images.
    pub targets: TargetPool,
    pub post: PostChain,
    /// Accumulated stills' passes, made with the first still.
    pub accumulate: Option<crate::render::passes::accumulate::AccumulatePipelines>,
    /// The GPU culling passes, where views can cull on the GPU ([`Gpu::culls_on_gpu`]).
    pub cull_pipelines: Option<CullPipelines>,
    /// The light binning pass, where views can cull on the GPU.
    pub light_binning: Option<LightBinning>,
    /// Particle layers, drawn in every view.
    pub particles: Particles,
    /// Order-independent transparency's composites, and what the device can draw.
    pub transparency: crate::render::passes::transparency::TransparencyPasses,
    /// Ambient occlusion's passes reading a single-sample pre-pass (0) and a
    /// multisampled one (1), each made with the first view that needs it.
    pub ambient_occlusion_pipelines: [Option<AmbientOcclusionPipelines>; 2],
    /// Timestamp queries, once timing is on.
    pub gpu_timer: Option<GpuTimer>,
    /// Samples of a post-processed view's HDR target: the output's where the
    /// adapter multisamples the HDR format, else 1.
    pub hdr_msaa: bool,
    /// Whether indexed draws take a base vertex ([`Gpu::base_vertex`]).
    pub base_vertex: bool,
    /// How frames are built.
    pub mode: FrameMode,
    /// Whether views draw levels of detail (else every mesh at full detail).
    pub levels_of_detail: bool,
    /// Whether views shade their point and spot lights from clusters.
    pub clusters: crate::render::clusters::Clusters,
    /// Whether clustered views draw the heat map of lights per cluster instead of their shading.
    pub cluster_heat_map: bool,
    /// Every tiled entity's density is multiplied by this.
    pub density: f32,
}

impl Resources {
    /// Everything frames draw with on `gpu`'s device, made once.
    pub(crate) fn new(gpu: &Gpu) -> Self {
        let device = gpu.device.clone();
        let queue = SubmitQueue::new(gpu.queue.clone());
        let shadows = ShadowSupport { gl: gpu.info().backend == wgpu::Backend::Gl };
        let registry = Registry::new(gpu, queue.clone());
        let pipelines = &registry.pipelines;
        let layouts = (&pipelines.scene_layout, &pipelines.camera_layout);
        let particles = Particles::new(&device, layouts, (gpu.occlusion_culls(), !gpu.vertex_storage()));
        let flags = gpu.adapter.get_texture_format_features(crate::gpu::HDR_FORMAT).flags;
        Self {
            submits_counted: queue.submits(),
            uncaptured: gpu.uncaptured(),
            instances: InstanceBuffer::new(&device, gpu.vertex_storage(), gpu.culls_on_gpu()),
            paths: ListPaths {
                indirect: gpu.draws_indirect(),
                storage: gpu.vertex_storage(),
                gpu_cull: gpu.culls_on_gpu(),
            },
            shadow_maps: ShadowMaps::new(&device, shadows, 1, 1, 1, 1),
            shadow_maps_generation: 0,
            environment: EnvironmentMaps::new(&device),
            store: InstanceStore::default(),
            targets: TargetPool::default(),
            post: PostChain::new(&device),
            accumulate: None,
            cull_pipelines: gpu.culls_on_gpu().then(|| CullPipelines::new(&device, gpu.occlusion_culls())),
            light_binning: gpu.culls_on_gpu().then(|| LightBinning::new(&device)),
            particles,
            transparency: crate::render::passes::transparency::TransparencyPasses::new(gpu),
            ambient_occlusion_pipelines: [None, None],
            gpu_timer: None,
            hdr_msaa: flags.sample_count_supported(4)
                && flags.contains(wgpu::TextureFormatFeatureFlags::MULTISAMPLE_RESOLVE),
            base_vertex: gpu.base_vertex(),
            mode: FrameMode::Optimized,
            levels_of_detail: true,
            clusters: Default::default(),
            cluster_heat_map: false,
            density: 1.0,
            registry,
            device,
            queue,
        }
    }

    /// What every view's GPU state points at.
    pub(crate) fn shared(&self) -> Shared<'_> {
        Shared {
            device: &self.device,
            pipelines: &self.registry.pipelines,
            instances: &self.instances,
            shadow_maps: &self.shadow_maps,
            shadow_maps_generation: self.shadow_maps_generation,
            environment: &self.environment,
            white: &self.registry.defaults.white_linear,
        }
    }
}
