//! Core layer: the [`Renderer`], split by owner: the [`Resources`] frames
//! draw with, each view's GPU state by its key ([`ViewStates`]), and what
//! the next frame starts from ([`NextFrame`]); its frame is
//! [`render_frame`](Renderer::render_frame) (`frame/mod.rs`), the seed's calls
//! are `frame/beginner.rs`. Here: making one, adding to its registry, its
//! settings, and submitting entities.

use crate::gpu::TargetFormat;
use crate::gpu::{Gpu, ParticleGpu};
use crate::render::clusters::Clusters;
use crate::render::debug::explain::{FrameCalls, Tape};
use crate::render::debug::inspect::read_list;
use crate::render::debug::stats::FrameStats;
use crate::render::debug::timer::{GpuTimer, GpuTimes};
use crate::render::error::RenderError;
use crate::render::frame::input::FrameMode;
use crate::render::frame::prepare::prepare_environment;
use crate::render::frame::stages::submit;
use crate::render::frame::state::NextFrame;
use crate::render::frame_variant::FrameVariant;
use crate::render::passes::particles::{ParticleLook, ParticlesId};
use crate::render::resources::registry::Registry;
use crate::render::resources::Resources;
use crate::render::views::ViewStates;
use crate::scene::Lighting;
use crate::scene::{Entity, Material, MaterialId, Mesh, RenderTargetId, ShapeId, Texture, TextureId};

/// The renderer, three owners: `res`, what frames draw with and keep (its
/// [`Registry`] of shapes, materials, textures, render targets and pipelines,
/// the instances kept on the GPU, the passes' maps); `views`, each view's GPU
/// state (blocks, draw lists) by the caller's key; `next`, what the next frame
/// starts from. The scene is not its own: each frame is given the entities, the [`Lighting`]
/// (lights and environment) and the views.
///
/// Program structure (Tiny Graphics): create shapes, materials and entities once;
/// each frame update them and draw them with
/// [`render_frame`](Self::render_frame): the entities, views, lighting and GPU
/// simulations of one frame in a [`FrameInput`](crate::render::FrameInput). The seed's calls are a thin
/// layer over it: [`submit`](Self::submit) every entity to draw, ask for the
/// shadow maps ([`shadow_pass`](Self::shadow_pass)), then
/// [`flush`](Self::flush) with the view (or camera), lighting and shadows;
/// [`render`](Self::render) is those calls for one view,
/// [`render_views`](Self::render_views) for several.
pub struct Renderer {
    /// What frames draw with, kept between them.
    pub(crate) res: Resources,
    /// Each view's GPU state, by the caller's key.
    pub(crate) views: ViewStates,
    /// What the next frame starts from: its number, the entities submitted so far.
    pub(crate) next: NextFrame,
}

impl Renderer {
    /// Create a renderer on `gpu`'s device.
    pub fn new(gpu: &Gpu) -> Self {
        let (res, views, next) = (Resources::new(gpu), ViewStates::default(), NextFrame::new(gpu.debug_groups()));
        Self { res, views, next }
    }

    /// The shapes, materials, textures and render targets added so far.
    pub fn registry(&self) -> &Registry {
        &self.res.registry
    }

    /// The registry, to add what a placed asset uses (`world/place.rs`).
    pub(crate) fn registry_mut(&mut self) -> &mut Registry {
        &mut self.res.registry
    }

    /// Add an environment image ([`Registry::add_environment`]).
    pub fn add_environment(&mut self, image: &crate::scene::EnvironmentImage) -> crate::scene::EnvironmentId {
        self.res.registry.add_environment(image)
    }

    /// Add a shape ([`Registry::add_shape`]).
    pub fn add_shape(&mut self, mesh: Mesh) -> ShapeId {
        self.res.registry.add_shape(mesh)
    }

    /// Replace a shape's mesh ([`Registry::update_shape`]).
    pub fn update_shape(&mut self, id: ShapeId, mesh: Mesh) -> bool {
        self.res.registry.update_shape(id, mesh)
    }

    /// The mesh of a shape ([`Registry::shape`]).
    pub fn shape(&self, id: ShapeId) -> Option<&Mesh> {
        self.res.registry.shape(id)
    }

    /// Add a texture ([`Registry::add_texture`]).
    pub fn add_texture(&mut self, texture: Texture) -> TextureId {
        self.res.registry.add_texture(texture)
    }

    /// Add a render target and the texture that shows it ([`Registry::add_render_target`]).
    pub fn add_render_target(
        &mut self,
        width: u32,
        height: u32,
        hdr: bool,
    ) -> Result<(RenderTargetId, TextureId), RenderError> {
        self.res.registry.add_render_target(width, height, hdr)
    }

    /// Add a material ([`Registry::add_material`]).
    pub fn add_material(&mut self, material: Material) -> MaterialId {
        self.res.registry.add_material(material)
    }

    /// Read a material ([`Registry::material`]).
    pub fn material(&self, id: MaterialId) -> Option<&Material> {
        self.res.registry.material(id)
    }

    /// Edit a material ([`Registry::material_mut`]).
    pub fn material_mut(&mut self, id: MaterialId) -> Option<&mut Material> {
        self.res.registry.material_mut(id)
    }

    /// Time the shadow, forward and post passes on the GPU with timestamp
    /// queries, when the device has them; returns whether timing is on. Each
    /// frame's [`FrameStats::gpu`] then carries the newest finished frame's
    /// times; [`Renderer::read_gpu_times`] waits for the last frame's.
    pub fn enable_gpu_timing(&mut self) -> bool {
        if self.res.gpu_timer.is_none() {
            self.res.gpu_timer = GpuTimer::new(&self.res.device, &self.res.queue);
        }
        self.res.gpu_timer.is_some()
    }

    /// GPU time of the last timed frame's passes, waiting for the GPU to finish
    /// them; `None` when timing is off or unsupported, or that frame was already read.
    pub fn read_gpu_times(&mut self) -> Option<GpuTimes> {
        self.res.gpu_timer.as_mut()?.read(&self.res.device)
    }

    /// Occlusion-cull the views culled on the GPU (the default, where the
    /// device can: [`Gpu::occlusion_culls`]) or not, to compare costs and to
    /// compare GPU and CPU frustum culling; returns whether views will be.
    pub fn set_occlusion_culling(&mut self, on: bool) -> bool {
        match &mut self.res.cull_pipelines {
            Some(pipelines) => {
                pipelines.occlusion_on = on;
                pipelines.occlusion()
            }
            None => false,
        }
    }

    /// Build frames the optimized way (the default) or the naive way, for comparison.
    pub fn set_mode(&mut self, mode: FrameMode) {
        self.res.mode = mode;
    }

    /// How `view` draws its transparency into a target of `samples` here:
    /// as it asks, or sorted where the device cannot draw weighted, where it
    /// cannot draw exact (the frame is then an error), and in the naive
    /// frame ([`Transparency`]).
    pub fn transparency_of(&self, view: &crate::View, samples: u32) -> crate::scene::Transparency {
        match self.res.mode {
            FrameMode::Naive => crate::scene::Transparency::Sorted,
            _ => self.res.transparency.way(view.transparency, samples).unwrap_or_default(),
        }
    }

    /// Draw levels of detail (the default: each instance the coarsest level
    /// whose error its view allows, [`View::lod_error`](crate::scene::View::lod_error))
    /// or every mesh at full detail, to compare.
    pub fn set_levels_of_detail(&mut self, on: bool) {
        self.res.levels_of_detail = on;
    }

    /// Shade point and spot lights from each view's light clusters as
    /// `clusters` says (`render/clusters.rs`; [`Clusters::Auto`] at first).
    pub fn set_clusters(&mut self, clusters: Clusters) {
        self.res.clusters = clusters;
    }

    /// Draw clustered views as a heat map of the lights in each fragment's
    /// cluster (from dark blue, none, a step of the jet scale for each
    /// doubling, to dark red, 255 or more: `forward.wgsl`'s `cluster_heat`),
    /// each tile's edge darkened;
    /// off at first. Views that are not clustered are drawn as ever.
    pub fn set_cluster_heat_map(&mut self, on: bool) {
        self.res.cluster_heat_map = on;
    }

    /// Keep the levels of detail of large meshes in `cache` between runs (see
    /// [`LevelCache`](crate::scene::level_cache::LevelCache); the default is
    /// none: they are made each run). Shapes drawn before keep theirs.
    pub fn set_level_cache(&mut self, cache: Option<crate::scene::level_cache::LevelCache>) {
        self.res.registry.level_cache = cache;
    }

    /// Multiply every tiled entity's [`density`](Entity::density) by `density`
    /// (clamped to 0..=1; default 1) from the next submission on: a scene-wide
    /// control that changes no GPU data.
    pub fn set_density(&mut self, density: f32) {
        self.res.density = if density.is_nan() { 1.0 } else { density.clamp(0.0, 1.0) };
    }

    /// Queue `entity` for the next frame ([`flush`](Self::flush) or
    /// [`render_frame`](Self::render_frame)). Its transforms are kept
    /// on the GPU between frames and copied again only when its version changed
    /// (see [`Entity::transforms_mut`]). A shape id that is not this renderer's is
    /// reported by the next flush.
    pub fn submit(&mut self, entity: &Entity) {
        submit(&mut self.res, &mut self.next, entity);
    }

    /// A particle layer of `capacity` billboards (at most [`MAX_LAYER_PARTICLES`](crate::gpu::MAX_LAYER_PARTICLES)), drawn in
    /// every view from the next frame on; none to draw until written.
    pub fn add_particles(&mut self, capacity: u32, look: ParticleLook) -> Result<ParticlesId, RenderError> {
        let storage = self.res.cull_pipelines.is_some();
        self.res.particles.add(&mut self.res.registry, storage, (capacity, look))
    }

    /// Draw `records` in layer `id` from the next frame on (as many as fit).
    pub fn write_particles(&mut self, id: ParticlesId, records: &[ParticleGpu]) {
        self.res.particles.write(&self.res.queue, id, records);
    }

    /// Layer `id`'s record buffer, for a compute shader to write (it allows
    /// storage where the device computes), and its capacity.
    pub fn particle_buffer(&self, id: ParticlesId) -> Option<(&wgpu::Buffer, u32)> {
        self.res.particles.buffer(id)
    }

    /// Draw the first `count` records of layer `id` (as written by a compute shader).
    pub fn set_particle_count(&mut self, id: ParticlesId, count: u32) {
        self.res.particles.set_count(id, count);
    }

    /// Whether the device runs compute shaders with storage buffers here
    /// ([`Gpu::culls_on_gpu`](crate::Gpu::culls_on_gpu)): GPU simulations
    /// and culling then run on it.
    pub fn computes(&self) -> bool {
        self.res.cull_pipelines.is_some()
    }

    /// The device and queue, for GPU simulations' own buffers.
    pub fn device_and_queue(&self) -> (&wgpu::Device, &wgpu::Queue) {
        (&self.res.device, &self.res.queue)
    }

    /// Write down every pass and draw call of the frames from now on (or stop):
    /// [`explained`](Self::explained) then holds the last submitted frame's.
    /// Explaining costs CPU time per call; it is for tools, not every frame.
    pub fn set_explaining(&mut self, on: bool) {
        self.next.outline.set_tape(on.then(Tape::default));
    }

    /// The last submitted frame's passes and draw calls, while explaining.
    pub fn explained(&self) -> Option<&FrameCalls> {
        self.next.outline.last_calls()
    }

    /// The instances the last frame's first view (that of `render` or
    /// `flush`) drew, as instance-store indices, sorted: the camera's, then
    /// each shadow view's. Culled on the GPU, read back from what the cull pass wrote
    /// (waiting for the GPU); culled on the CPU, from the lists. Store indices
    /// are the renderer's own business, but two renderers given the same
    /// entities in the same order number them alike. Compact instances are
    /// left out.
    #[doc(hidden)]
    pub fn drawn_instances(&self) -> Result<Vec<Vec<u32>>, RenderError> {
        let Some(view) = self.views.last(0) else {
            return Ok(Vec::new());
        };
        let gpu = (&self.res.device, &*self.res.queue);
        let mut views = read_list(gpu, &view.forward)?;
        views.extend(read_list(gpu, &view.shadows)?);
        Ok(views)
    }

    /// Build, before the first frame, everything drawing `entities` under `lighting`
    /// into a glint target (not a post-processed view) of `samples` samples needs: mesh buffers, textures, material
    /// blocks and every pipeline variant (with shadow lookups where a light casts
    /// shadows), so that the first frame compiles nothing. Returns the number of
    /// pipelines compiled.
    pub fn precompile<'l>(
        &mut self,
        entities: &[&Entity],
        lighting: impl Into<Lighting<'l>>,
        samples: u32,
    ) -> Result<u32, RenderError> {
        let lighting = lighting.into();
        self.res.clusters.check(lighting.lights)?;
        // Views fade levels at their default error.
        let clustered = self.res.clusters.applies(lighting.lights);
        let variant = FrameVariant::expected(lighting.lights, false)
            .with_lod_fade(self.res.levels_of_detail)
            .with_clusters(clustered);
        prepare_environment(&mut self.res, &lighting)?;
        let mut stats = FrameStats::default();
        let uses: Vec<_> = entities
            .iter()
            .map(|e| (e.shape, e.material, crate::render::resources::instances::stored_compactly(e)))
            .collect();
        let target = TargetFormat { color: crate::gpu::COLOR_FORMAT, samples };
        self.res.registry.prepare_uses(&uses, target, (&lighting.environment, variant), &mut stats)?;
        Ok(stats.pipelines_compiled)
    }

    /// Prefilter `lighting`'s environment (image-based lighting) now, in a
    /// submission of its own, unless that was done already (a frame does it
    /// otherwise: at load time, so the first frame does not). Returns whether it
    /// prefiltered.
    pub fn prefilter_environment(&mut self, lighting: &Lighting) -> Result<bool, RenderError> {
        let done = prepare_environment(&mut self.res, lighting)?;
        self.res.queue.submit(std::mem::take(&mut self.res.registry.mip_blits));
        Ok(done)
    }
}
