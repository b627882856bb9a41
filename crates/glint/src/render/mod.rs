//! Core layer: the [`Renderer`], which turns the entities submitted for a frame
//! into GPU commands, following DESIGN.md's data flow.
//!
//! ## Bind-group convention (shader data blocks)
//! | group | block | written when | holds |
//! | --- | --- | --- | --- |
//! | 0 | Scene | lights or environment change | ambient, sky colours, light count, `lights[64]` |
//! | 1 | Camera | the camera, target aspect or scene time changes | view, view-projection, its inverse, eye position, scene time and wind (shadow passes bind it too) |
//! | 2 | Material | a material is added or edited | `materials: array<MaterialBlock>` (the table, indexed by material id), one texture set: diffuse / normal / specular maps, sampler, metallic-roughness / occlusion / emissive maps |
//! | 3 | Renderer | instances: where entities changed; draw indices: when the visible set changed, one write | `instances: array<Instance>` (transform rows + material index, persistent; a compact entity's 16-byte instances four to a record), `draw_indices: array<u32>` (an identity ramp for whole tiles, then visible instances in draw order) |
//!
//! Where vertex shaders cannot read storage buffers (WebGL2, some GLES drivers;
//! [`Gpu::vertex_storage`](crate::Gpu::vertex_storage)), the material table and
//! both Renderer-block arrays are data textures instead (`gpu_array.rs`), read
//! record by record in `forward.wgsl`'s `DATA_TEXTURES` variant; everything else
//! is the same.
//!
//! Every pipeline shares one layout with these four groups, so groups 0, 1 and 3
//! are bound once per pass and group 2 changes only between texture sets (materials
//! with the same maps share a bind group; untextured materials all share one).
//! Each instance names its material, and shapes share the buffers of the mesh pool,
//! so a run of batches with one pipeline, texture set and pool page is a single
//! `multi_draw_indexed_indirect` call: one indirect command per batch.

pub mod batch;
pub mod cull;
mod debug;
mod error;
mod frame;
mod frame_variant;
mod gpu_driven;
mod passes;
pub mod queue;
mod resources;
mod view;
mod views;

pub use crate::gpu::{GpuSimulation, ParticleGpu, MAX_LAYER_PARTICLES};
pub use crate::scene::{ShadowLayout, MAX_CUBES, MAX_SHADOW_MAP_BYTES};
pub use debug::explain::{BatchCall, DrawCall, FrameCalls, PassCalls, PassType};
pub use debug::stats::{FrameStats, PassStats, Passes, StageTimes, UploadStats};
pub use debug::timer::GpuTimes;
pub use error::RenderError;
pub use frame::naive::MAX_NAIVE_DRAWS;
pub use frame::{FrameInput, FrameOutput, Shadows, ViewKey, KEEP_VIEW_FRAMES};
pub use gpu_driven::gpu_cull::SKIP_UNPAID_OCCLUSION;
pub use passes::particles::{ParticleBlend, ParticleLook, ParticlesId};
pub use resources::mesh_pool::MeshTooLarge;
pub use resources::registry::Registry;

use crate::gpu::{Gpu, SubmitQueue};
use crate::scene::Texture;
use crate::scene::{Entity, Material, MaterialId, Mesh, RenderTargetId, ShapeId, TextureId};
use frame::visible::Visible;
use frame_variant::FrameVariant;
use gpu_driven::draw_list::ListPaths;
use passes::shadow_maps::{ShadowMaps, ShadowSupport};
use resources::buffers::InstanceBuffer;
use resources::instances::InstanceStore;
use views::ViewGpu;
use web_time::Instant;

/// An entity as submitted this frame: its store slot and what it draws with.
struct Submitted {
    slot: usize,
    shape: ShapeId,
    material: MaterialId,
    render_order: Option<u8>,
    cast_shadows: bool,
    /// Its instances.
    instances: u64,
    /// The fraction of each tile drawn: the entity's density times the renderer's.
    density: f32,
}

/// How a frame is built.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FrameMode {
    /// Culled, sorted, batched, uploading only what changed.
    #[default]
    Optimized,
    /// The pre-upgrade way, kept as a baseline for `glint bench`: one draw per
    /// instance in submission order, no culling and no sorting, the material block
    /// and the draw's instance index written before every draw, and every state
    /// bound again for every draw.
    Naive,
}

/// The renderer: its [`Registry`] holds the GPU resources (shapes, materials,
/// textures, render targets, pipelines); the rest is what frames reuse (the
/// instances kept on the GPU, the blocks, draw lists and shadow maps). The scene
/// is not its own: each frame is given the entities, the [`Lighting`](crate::Lighting)
/// (lights and environment) and the views.
///
/// Program structure (Tiny Graphics): create shapes, materials and entities once;
/// each frame update them and draw them with
/// [`render_frame`](Self::render_frame): the entities, views, lighting and GPU
/// simulations of one frame in a [`FrameInput`]. The seed's calls are a thin
/// layer over it: [`submit`](Self::submit) every entity to draw, ask for the
/// shadow maps ([`shadow_pass`](Self::shadow_pass)), then
/// [`flush`](Self::flush) with the view (or camera), lighting and shadows;
/// [`render`](Self::render) is those calls for one view,
/// [`render_views`](Self::render_views) for several.
pub struct Renderer {
    /// Errors the device reported outside glint's scopes, returned by the frame.
    uncaptured: crate::gpu::UncapturedErrors,
    device: wgpu::Device,
    queue: SubmitQueue,
    /// The shapes, materials, textures, render targets and pipelines.
    registry: Registry,
    instances: InstanceBuffer,
    /// Each view's GPU state, by the caller's key, with the last frame that
    /// drew it: kept between frames, given back once unused for a while.
    views: std::collections::HashMap<ViewKey, (ViewGpu, u64)>,
    /// How views' draw lists draw (indirect, storage, GPU culling).
    paths: ListPaths,
    /// The keys of the last frame's views, in the order given.
    last_keys: Vec<ViewKey>,
    /// The debug groups open in the frame's encoder, and the last frame's.
    outline: debug::outline::Outline,
    /// The queue's submission count when the last flush ended.
    submits_counted: u64,
    shadow_maps: ShadowMaps,
    /// How many times the shadow maps were replaced (each view's Scene bind
    /// group points at one generation).
    shadow_maps_generation: u64,
    /// The environment's prefiltered maps (image-based lighting).
    environment: passes::environment::EnvironmentMaps,
    store: InstanceStore,
    mode: FrameMode,
    /// The number of the frame being recorded: frames so far.
    frame_index: u64,
    /// The first bad id submitted this frame, reported by `flush`.
    submit_error: Option<RenderError>,
    gpu_timer: Option<debug::timer::GpuTimer>,
    // Per-frame lists, kept to reuse their allocations.
    submitted: Vec<Submitted>,
    visible: Visible,
    /// Transient targets: views' own and the post chain's images.
    targets: resources::target_pool::TargetPool,
    post: passes::post::PostChain,
    /// Samples of a post-processed view's HDR target: the output's where the
    /// adapter multisamples the HDR format, else 1.
    hdr_msaa: bool,
    /// Whether indexed draws take a base vertex ([`Gpu::base_vertex`]).
    base_vertex: bool,
    /// The GPU culling passes, where views can cull on the GPU ([`Gpu::culls_on_gpu`]).
    cull_pipelines: Option<gpu_driven::gpu_cull::CullPipelines>,
    /// The last prepared table and what it was made for.
    last_prepared: Option<(frame::prepare::PrepareKey, Vec<frame::prepare::Prepared>)>,
    /// Every tiled entity's density is multiplied by this ([`Renderer::set_density`]).
    density: f32,
    /// Particle layers ([`Renderer::add_particles`]), drawn in every view.
    particle_layers: Vec<passes::particles::ParticleLayer>,
    /// The soft round spot the layers without a sprite show, added once.
    particle_spot: Option<crate::scene::TextureId>,
    particle_pipelines: passes::particles::ParticlePipelines,
    /// Ambient occlusion's passes reading a single-sample pre-pass (0) and a
    /// multisampled one (1), each made with the first view that needs it.
    ambient_occlusion_pipelines: [Option<passes::ambient_occlusion::AmbientOcclusionPipelines>; 2],
}

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// The CPU time of consecutive stages: each [`Laps::next`] is the time since
/// the last (or since [`Laps::start`]), in milliseconds.
struct Laps(Instant);

impl Laps {
    fn start() -> Self {
        Self(Instant::now())
    }

    fn next(&mut self) -> f64 {
        ms_since(std::mem::replace(&mut self.0, Instant::now()))
    }
}

impl Renderer {
    /// Create a renderer on `gpu`'s device.
    pub fn new(gpu: &Gpu) -> Self {
        let device = gpu.device.clone();
        let queue = SubmitQueue::new(gpu.queue.clone());
        let shadows = ShadowSupport { gl: gpu.info().backend == wgpu::Backend::Gl };
        let registry = Registry::new(gpu, queue.clone());
        let pipelines = &registry.pipelines;
        let shadow_maps = ShadowMaps::new(&device, shadows, 1, 1, 1, 1);
        let instances = InstanceBuffer::new(&device, gpu.vertex_storage(), gpu.culls_on_gpu());
        let environment = passes::environment::EnvironmentMaps::new(&device);
        let paths =
            ListPaths { indirect: gpu.draws_indirect(), storage: gpu.vertex_storage(), gpu_cull: gpu.culls_on_gpu() };
        let layouts = (&pipelines.scene_layout, &pipelines.camera_layout);
        let particle_pipelines = passes::particles::ParticlePipelines::new(&device, layouts, gpu.occlusion_culls());
        Self {
            particle_layers: Vec::new(),
            particle_spot: None,
            particle_pipelines,
            ambient_occlusion_pipelines: [None, None],
            submits_counted: queue.submits(),
            uncaptured: gpu.uncaptured(),
            device,
            queue,
            registry,
            instances,
            views: std::collections::HashMap::new(),
            paths,
            last_keys: Vec::new(),
            outline: debug::outline::Outline::new(gpu.debug_groups()),
            shadow_maps,
            shadow_maps_generation: 0,
            environment,
            store: InstanceStore::default(),
            mode: FrameMode::Optimized,
            frame_index: 0,
            submit_error: None,
            gpu_timer: None,
            submitted: Vec::new(),
            visible: Visible::default(),
            targets: resources::target_pool::TargetPool::default(),
            post: passes::post::PostChain::new(&gpu.device),
            last_prepared: None,
            density: 1.0,
            cull_pipelines: gpu
                .culls_on_gpu()
                .then(|| gpu_driven::gpu_cull::CullPipelines::new(&gpu.device, gpu.occlusion_culls())),
            base_vertex: gpu.base_vertex(),
            hdr_msaa: {
                let flags = gpu.adapter.get_texture_format_features(crate::gpu::HDR_FORMAT).flags;
                flags.sample_count_supported(4) && flags.contains(wgpu::TextureFormatFeatureFlags::MULTISAMPLE_RESOLVE)
            },
        }
    }

    /// What every view's GPU state points at.
    fn shared(&self) -> views::Shared<'_> {
        views::Shared {
            device: &self.device,
            pipelines: &self.registry.pipelines,
            instances: &self.instances,
            shadow_maps: &self.shadow_maps,
            shadow_maps_generation: self.shadow_maps_generation,
            environment: &self.environment,
            white: &self.registry.defaults.white_linear,
        }
    }

    /// The shapes, materials, textures and render targets added so far.
    pub fn registry(&self) -> &Registry {
        &self.registry
    }

    /// The registry, to add what a placed asset uses (`world/place.rs`).
    pub(crate) fn registry_mut(&mut self) -> &mut Registry {
        &mut self.registry
    }

    /// Add an environment image ([`Registry::add_environment`]).
    pub fn add_environment(&mut self, image: &crate::scene::EnvironmentImage) -> crate::scene::EnvironmentId {
        self.registry.add_environment(image)
    }

    /// Add a shape ([`Registry::add_shape`]).
    pub fn add_shape(&mut self, mesh: Mesh) -> ShapeId {
        self.registry.add_shape(mesh)
    }

    /// Replace a shape's mesh ([`Registry::update_shape`]).
    pub fn update_shape(&mut self, id: ShapeId, mesh: Mesh) -> bool {
        self.registry.update_shape(id, mesh)
    }

    /// The mesh of a shape ([`Registry::shape`]).
    pub fn shape(&self, id: ShapeId) -> Option<&Mesh> {
        self.registry.shape(id)
    }

    /// Add a texture ([`Registry::add_texture`]).
    pub fn add_texture(&mut self, texture: Texture) -> TextureId {
        self.registry.add_texture(texture)
    }

    /// Add a render target and the texture that shows it ([`Registry::add_render_target`]).
    pub fn add_render_target(
        &mut self,
        width: u32,
        height: u32,
        hdr: bool,
    ) -> Result<(RenderTargetId, TextureId), RenderError> {
        self.registry.add_render_target(width, height, hdr)
    }

    /// Add a material ([`Registry::add_material`]).
    pub fn add_material(&mut self, material: Material) -> MaterialId {
        self.registry.add_material(material)
    }

    /// Read a material ([`Registry::material`]).
    pub fn material(&self, id: MaterialId) -> Option<&Material> {
        self.registry.material(id)
    }

    /// Edit a material ([`Registry::material_mut`]).
    pub fn material_mut(&mut self, id: MaterialId) -> Option<&mut Material> {
        self.registry.material_mut(id)
    }

    /// Time the shadow, forward and post passes on the GPU with timestamp
    /// queries, when the device has them; returns whether timing is on. Each
    /// frame's [`FrameStats::gpu`] then carries the newest finished frame's
    /// times; [`Renderer::read_gpu_times`] waits for the last frame's.
    pub fn enable_gpu_timing(&mut self) -> bool {
        if self.gpu_timer.is_none() {
            self.gpu_timer = debug::timer::GpuTimer::new(&self.device, &self.queue);
        }
        self.gpu_timer.is_some()
    }

    /// GPU time of the last timed frame's passes, waiting for the GPU to finish
    /// them; `None` when timing is off or unsupported, or that frame was already read.
    pub fn read_gpu_times(&mut self) -> Option<GpuTimes> {
        self.gpu_timer.as_mut()?.read(&self.device)
    }

    /// Occlusion-cull the views culled on the GPU (the default, where the
    /// device can: [`Gpu::occlusion_culls`]) or not, to compare costs and to
    /// compare GPU and CPU frustum culling; returns whether views will be.
    pub fn set_occlusion_culling(&mut self, on: bool) -> bool {
        match &mut self.cull_pipelines {
            Some(pipelines) => {
                pipelines.occlusion_on = on;
                pipelines.occlusion()
            }
            None => false,
        }
    }

    /// Build frames the optimized way (the default) or the naive way, for comparison.
    pub fn set_mode(&mut self, mode: FrameMode) {
        self.mode = mode;
    }

    /// Multiply every tiled entity's [`density`](Entity::density) by `density`
    /// (clamped to 0..=1; default 1) from the next submission on: a scene-wide
    /// control that changes no GPU data.
    pub fn set_density(&mut self, density: f32) {
        self.density = if density.is_nan() { 1.0 } else { density.clamp(0.0, 1.0) };
    }

    /// Queue `entity` for the next frame ([`flush`](Self::flush) or
    /// [`render_frame`](Self::render_frame)). Its transforms are kept
    /// on the GPU between frames and copied again only when its version changed
    /// (see [`Entity::transforms_mut`]). A shape id that is not this renderer's is
    /// reported by the next flush.
    pub fn submit(&mut self, entity: &Entity) {
        let Some(shape) = self.registry.shapes.get(entity.shape.0 as usize) else {
            self.submit_error.get_or_insert(RenderError::UnknownShape(entity.shape));
            return;
        };
        let motion = self.registry.material(entity.material).and_then(|m| m.motion);
        let (local, walk) = motion.map_or((shape.mesh.aabb(), 0.0), |m| m.reach(shape.mesh.aabb()));
        let slot = self.store.submit(entity, resources::instances::Reach { local, walk }, self.frame_index);
        self.submitted.push(Submitted {
            slot,
            shape: entity.shape,
            material: entity.material,
            render_order: entity.render_order,
            cast_shadows: entity.cast_shadows,
            instances: entity.transforms().len() as u64,
            density: entity.density * self.density,
        });
    }
}
