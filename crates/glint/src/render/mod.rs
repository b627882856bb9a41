//! Core layer: the [`Renderer`], which turns the entities submitted for a frame
//! into GPU commands, following DESIGN.md's data flow.
//!
//! ## Bind-group convention (shader data blocks)
//! | group | block | written when | holds |
//! | --- | --- | --- | --- |
//! | 0 | Scene | lights or environment change | ambient, sky colours, light count, `lights[64]` |
//! | 1 | Camera | the camera or target aspect changes | view, view-projection, its inverse, eye position |
//! | 2 | Material | a material is added or edited | `materials: array<MaterialBlock>` (the table, indexed by material id), one texture set: diffuse / normal / specular maps, sampler, metallic-roughness / occlusion / emissive maps |
//! | 3 | Renderer | instances: where entities changed; draw indices: when the visible set changed, one write | `instances: array<Instance>` (transform rows + material index, persistent), `draw_indices: array<u32>` (visible instances in draw order) |
//!
//! Every pipeline shares one layout with these four groups, so groups 0, 1 and 3
//! are bound once per pass and group 2 changes only between texture sets (materials
//! with the same maps share a bind group; untextured materials all share one).
//! Each instance names its material, and shapes share the buffers of the mesh pool,
//! so a run of batches with one pipeline, texture set and pool page is a single
//! `multi_draw_indexed_indirect` call: one indirect command per batch.

pub mod batch;
mod blocks;
pub mod cull;
mod draw_list;
mod encode;
mod frame_variant;
mod instances;
mod materials;
mod mesh_pool;
mod pipelines;
pub mod queue;
mod resources;
mod shadow_maps;
mod shadow_pass;
mod shadow_views;
mod stats;
mod timer;
mod view;
mod views;
mod visible;

pub use mesh_pool::MeshTooLarge;
pub use shadow_maps::{ShadowLayout, MAX_CUBES, MAX_SHADOW_MAP_BYTES};
pub use shadow_pass::Shadows;
pub use stats::{FrameStats, PassStats, Passes, StageTimes, UploadStats};
pub use timer::GpuTimes;

use crate::asset::Texture;
use crate::gpu::{Gpu, OffscreenTarget};
use crate::scene::{
    Background, Entity, Environment, Light, Material, MaterialId, Mesh, ShapeId, TextureId, View, Viewport, MAX_LIGHTS,
};
use batch::Batch;
use blocks::{SceneGpu, UniformBlock};
use draw_list::DrawList;
use frame_variant::FrameVariant;
use glam::Vec3A;
use instances::InstanceStore;
use mesh_pool::{MeshPool, MeshRange};
use pipelines::{Pipelines, VertexLayout};
use queue::{DrawItem, Queue};
use resources::{InstanceBuffer, MaterialTable, TextureUploader};
use shadow_maps::{ShadowGpu, ShadowMaps, ShadowSupport};
use shadow_pass::ShadowsDrawn;
use std::time::Instant;
use view::ViewFrame;
use views::ViewBlocks;
use visible::Visible;

/// Errors from [`Renderer::flush`].
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// More lights than the Scene block holds.
    #[error("{0} lights given, but a frame can use at most {MAX_LIGHTS}")]
    TooManyLights(usize),
    /// An entity names a shape this renderer never created.
    #[error("unknown shape id {0:?}: shapes come from this renderer's add_shape")]
    UnknownShape(ShapeId),
    /// An entity names a material this renderer never created.
    #[error("unknown material id {0:?}: materials come from this renderer's add_material")]
    UnknownMaterial(MaterialId),
    /// One of glint's own shaders failed to compose (a bug in glint).
    #[error(transparent)]
    Shader(#[from] crate::shader::ShaderError),
    /// A shape too large for one GPU buffer.
    #[error("shape {shape:?}: {source}")]
    MeshTooLarge {
        /// The shape.
        shape: ShapeId,
        /// Its size and the limit.
        source: MeshTooLarge,
    },
    /// A GPU resource the frame needs is larger than glint or the adapter allows.
    #[error("{what} needs {bytes} bytes, more than the {limit}-byte limit ({limit_name})")]
    TooLarge {
        /// The resource.
        what: &'static str,
        /// What it needs.
        bytes: u64,
        /// The most allowed.
        limit: u64,
        /// Which limit that is.
        limit_name: &'static str,
    },
    /// A texture wider or taller than the adapter allows.
    #[error("texture '{name}' is {width} x {height}, larger than this adapter's {side} texels a side (max_texture_dimension_2d)")]
    TextureTooLarge {
        /// The texture's name.
        name: String,
        /// Its size.
        width: u32,
        /// Its size.
        height: u32,
        /// The adapter's largest side.
        side: u32,
    },
    /// The device refused to create a resource (out of memory, or a limit). The
    /// renderer may hold a broken resource afterwards: make a new one.
    #[error("the GPU could not create {what}: {message}")]
    Device {
        /// The resource.
        what: &'static str,
        /// What wgpu said.
        message: String,
    },
    /// A flush was given shadow maps drawn for an earlier frame.
    #[error("the shadow maps given to flush were drawn for an earlier frame: call shadow_pass again each frame")]
    StaleShadows,
    /// A flush was given shadow maps drawn for another view or other lights.
    #[error("the shadow maps given to flush were drawn for another view or other lights")]
    ShadowsForOtherView,
    /// A view's viewport is empty or reaches outside the target.
    #[error("viewport {0:?} is not a non-empty rectangle inside 0..1")]
    BadViewport(Viewport),
    /// A material names a texture this renderer never created.
    #[error("material '{material}' uses unknown texture id {texture:?}")]
    UnknownTexture {
        /// The material's name.
        material: String,
        /// The bad id.
        texture: TextureId,
    },
}

struct ShapeSlot {
    mesh: Mesh,
    layout: VertexLayout,
    /// Where the mesh lives in the pool, once uploaded.
    gpu: Option<MeshRange>,
    /// The vertices changed in place since they were uploaded.
    rewrite: bool,
}

struct MaterialSlot {
    material: Material,
    /// Set by `add_material` / `material_mut`; cleared when the block is written.
    dirty: bool,
    gpu: Option<MaterialGpuTwin>,
}

/// What a material uses on the GPU, and what that was chosen for.
struct MaterialGpuTwin {
    /// Index of its texture set (`Renderer::texture_sets`).
    texture_set: u16,
    /// Forward pipeline id per vertex layout (by `VertexLayout as usize`), built on
    /// first use with a mesh of that layout.
    pipelines: [Option<u16>; VertexLayout::COUNT],
    /// Shadow pipeline ids per vertex layout: 2D depth maps, then cube distance maps.
    shadow_pipelines: [[Option<u16>; 2]; VertexLayout::COUNT],
    samples: u32,
    /// Whether the environment had fog when the pipelines were chosen.
    fog: bool,
    /// What the frame added to the variant when the pipelines were chosen.
    frame: FrameVariant,
}

/// The maps of a material in texture-set binding order: diffuse, normal,
/// specular, metallic-roughness, occlusion, emissive.
type Maps = [Option<TextureId>; 6];

/// A bind group of the Material block for one combination of maps.
struct TextureSet {
    maps: Maps,
    bind_group: wgpu::BindGroup,
}

struct TextureSlot {
    /// Pixels waiting for their first use; dropped once uploaded.
    pending: Option<Texture>,
    view: Option<wgpu::TextureView>,
}

/// An entity as submitted this frame: its store slot and what it draws with.
struct Submitted {
    slot: usize,
    shape: ShapeId,
    material: MaterialId,
    render_order: Option<u8>,
    cast_shadows: bool,
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

/// 1×1 textures bound where a material has no map.
struct DefaultMaps {
    white_srgb: wgpu::TextureView,
    flat_normal: wgpu::TextureView,
    white_linear: wgpu::TextureView,
}

/// The renderer: owns the GPU twins of shapes, materials and textures, and draws
/// the entities submitted each frame.
///
/// Program structure (Tiny Graphics): create shapes, materials and entities once;
/// each frame update them, [`submit`](Self::submit) every entity to draw, draw
/// the shadow maps ([`shadow_pass`](Self::shadow_pass)), then
/// [`flush`](Self::flush) with the view (or camera), lights and shadow maps.
/// [`render`](Self::render) is those calls for one view,
/// [`render_views`](Self::render_views) for several.
pub struct Renderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    pipelines: Pipelines,
    uploader: TextureUploader,
    sampler: wgpu::Sampler,
    defaults: DefaultMaps,
    shapes: Vec<ShapeSlot>,
    mesh_pool: MeshPool,
    materials: Vec<MaterialSlot>,
    material_table: MaterialTable,
    texture_sets: Vec<TextureSet>,
    textures: Vec<TextureSlot>,
    environment: Environment,
    scene_block: UniformBlock<SceneGpu>,
    scene_group: wgpu::BindGroup,
    views: ViewBlocks,
    instances: InstanceBuffer,
    /// The forward view's draws.
    forward: DrawList,
    shadow_maps: ShadowMaps,
    shadow_block: UniformBlock<ShadowGpu>,
    /// Every shadow view's draws.
    shadow_list: DrawList,
    /// Whether this frame's forward pipelines look up shadow maps (the `SHADOWS`
    /// variant): set by `shadow_pass` when a light casts shadows, and by `flush`
    /// when that pass drew maps for its lights.
    frame_variant: FrameVariant,
    store: InstanceStore,
    mode: FrameMode,
    frame_index: u64,
    /// The first bad id submitted this frame, reported by `flush`.
    submit_error: Option<RenderError>,
    gpu_timer: Option<timer::GpuTimer>,
    // Per-frame lists, kept to reuse their allocations.
    submitted: Vec<Submitted>,
    instances_submitted: u64,
    visible: Visible,
    /// Targets of views that draw into part of the output, by size and samples,
    /// with the frame each was last used in.
    view_targets: Vec<(OffscreenTarget, u64)>,
}

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

impl Renderer {
    /// Create a renderer on `gpu`'s device.
    pub fn new(gpu: &Gpu) -> Self {
        let device = gpu.device.clone();
        let queue = gpu.queue.clone();
        let shadows = ShadowSupport { gl: gpu.info().backend == wgpu::Backend::Gl };
        let pipelines = Pipelines::new(&device);
        let scene_block = UniformBlock::new(&device, "renderer: scene block");
        let shadow_block = UniformBlock::new(&device, "renderer: shadow block");
        let shadow_maps = ShadowMaps::new(&device, shadows, 1, 1, 1, 1);
        let scene_group =
            shadow_maps.scene_group(&device, &pipelines.scene_layout, &scene_block.buffer, &shadow_block.buffer);
        let views = ViewBlocks::new(&device, &pipelines.camera_layout);
        let uploader = TextureUploader::new(&device);
        let pixel = |name: &str, rgba: [u8; 4], srgb| {
            let texture = Texture::new(name, image::RgbaImage::from_pixel(1, 1, image::Rgba(rgba)), srgb);
            uploader.upload(&device, &queue, &texture).0
        };
        let defaults = DefaultMaps {
            white_srgb: pixel("default diffuse (white)", [255; 4], true),
            flat_normal: pixel("default normal (flat)", [128, 128, 255, 255], false),
            white_linear: pixel("default specular (white)", [255; 4], false),
        };
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("renderer: material sampler (repeat, trilinear)"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            address_mode_w: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            anisotropy_clamp: gpu.max_anisotropy(),
            ..Default::default()
        });
        let instances = InstanceBuffer::new(&device);
        let forward = DrawList::new(
            &device,
            "renderer block: forward draw indices",
            &pipelines.instance_layout,
            instances.buffer(),
            gpu.draws_indirect(),
        );
        let shadow_list = DrawList::new(
            &device,
            "renderer block: shadow draw indices",
            &pipelines.instance_layout,
            instances.buffer(),
            gpu.draws_indirect(),
        );
        let mesh_pool = MeshPool::new(&device);
        let material_table = MaterialTable::new(&device);
        Self {
            device,
            queue,
            pipelines,
            uploader,
            sampler,
            defaults,
            shapes: Vec::new(),
            mesh_pool,
            materials: Vec::new(),
            material_table,
            texture_sets: Vec::new(),
            textures: Vec::new(),
            environment: Environment::default(),
            scene_block,
            scene_group,
            views,
            instances,
            forward,
            shadow_maps,
            shadow_block,
            shadow_list,
            frame_variant: FrameVariant::default(),
            store: InstanceStore::default(),
            mode: FrameMode::Optimized,
            frame_index: 0,
            submit_error: None,
            gpu_timer: None,
            submitted: Vec::new(),
            instances_submitted: 0,
            visible: Visible::default(),
            view_targets: Vec::new(),
        }
    }

    /// Add a shape; its buffers are created the first time an entity using it is drawn.
    pub fn add_shape(&mut self, mesh: Mesh) -> ShapeId {
        self.shapes.push(ShapeSlot { layout: VertexLayout::of(&mesh), mesh, gpu: None, rewrite: false });
        ShapeId(self.shapes.len() as u32 - 1)
    }

    /// Replace a shape's mesh (e.g. with morph targets applied). A mesh with the
    /// same streams, vertex count and indices as the old one is written over it
    /// (only the base vertex stream is uploaded); any other goes to a new place in
    /// the mesh pool. Entities drawing the shape pick up its new bounds. Returns
    /// false (and changes nothing) when `id` is not this renderer's.
    pub fn update_shape(&mut self, id: ShapeId, mesh: Mesh) -> bool {
        let Some(slot) = self.shapes.get_mut(id.0 as usize) else { return false };
        let same = VertexLayout::of(&mesh) == slot.layout
            && mesh.vertices().len() == slot.mesh.vertices().len()
            && mesh.indices() == slot.mesh.indices();
        if same {
            slot.rewrite = slot.gpu.is_some();
        } else {
            (slot.layout, slot.gpu, slot.rewrite) = (VertexLayout::of(&mesh), None, false);
        }
        slot.mesh = mesh;
        true
    }

    /// The mesh of a shape (for its bounds), if `id` is this renderer's.
    pub fn shape(&self, id: ShapeId) -> Option<&Mesh> {
        self.shapes.get(id.0 as usize).map(|s| &s.mesh)
    }

    /// Add a texture; it is uploaded (and its mipmaps made) on first use.
    /// An empty (0-pixel) image is replaced by one white pixel.
    pub fn add_texture(&mut self, mut texture: Texture) -> TextureId {
        if texture.image.width() == 0 || texture.image.height() == 0 {
            log::warn!("texture '{}' is empty; using one white pixel", texture.name);
            texture.image = image::RgbaImage::from_pixel(1, 1, image::Rgba([255; 4]));
        }
        self.textures.push(TextureSlot { pending: Some(texture), view: None });
        TextureId(self.textures.len() as u32 - 1)
    }

    /// Add a material; its material-table entry is written on first use.
    pub fn add_material(&mut self, material: Material) -> MaterialId {
        self.materials.push(MaterialSlot { material, dirty: true, gpu: None });
        MaterialId(self.materials.len() as u32 - 1)
    }

    /// Read a material.
    pub fn material(&self, id: MaterialId) -> Option<&Material> {
        self.materials.get(id.0 as usize).map(|s| &s.material)
    }

    /// Edit a material: marks it dirty, so its table entry is rewritten before the next frame.
    pub fn material_mut(&mut self, id: MaterialId) -> Option<&mut Material> {
        self.materials.get_mut(id.0 as usize).map(|s| {
            s.dirty = true;
            &mut s.material
        })
    }

    /// Set the background and ambient light.
    pub fn set_environment(&mut self, environment: Environment) {
        self.environment = environment;
    }

    /// The current background and ambient light.
    pub fn environment(&self) -> &Environment {
        &self.environment
    }

    /// Time the shadow and forward passes on the GPU with timestamp queries, when
    /// the device has them; returns whether timing is on. Read each frame's times
    /// with [`Renderer::read_gpu_times`].
    pub fn enable_gpu_timing(&mut self) -> bool {
        if self.gpu_timer.is_none() {
            self.gpu_timer = timer::GpuTimer::new(&self.device, &self.queue);
        }
        self.gpu_timer.is_some()
    }

    /// GPU time of the last frame's passes, waiting for the GPU to finish them;
    /// `None` when timing is off or unsupported, or the frame was already read.
    pub fn read_gpu_times(&mut self) -> Option<GpuTimes> {
        self.gpu_timer.as_mut()?.read(&self.device)
    }

    /// Build frames the optimized way (the default) or the naive way, for comparison.
    pub fn set_mode(&mut self, mode: FrameMode) {
        self.mode = mode;
    }

    /// Queue `entity` for the next [`flush`](Self::flush). Its transforms are kept
    /// on the GPU between frames and copied again only when its version changed
    /// (see [`Entity::transforms_mut`]). A shape id that is not this renderer's is
    /// reported by the next flush.
    pub fn submit(&mut self, entity: &Entity) {
        let Some(shape) = self.shapes.get(entity.shape.0 as usize) else {
            self.submit_error.get_or_insert(RenderError::UnknownShape(entity.shape));
            return;
        };
        let slot = self.store.submit(entity, shape.mesh.aabb(), self.frame_index);
        self.instances_submitted += entity.transforms().len() as u64;
        self.submitted.push(Submitted {
            slot,
            shape: entity.shape,
            material: entity.material,
            render_order: entity.render_order,
            cast_shadows: entity.cast_shadows,
        });
    }

    /// One whole frame of `entities` seen by `view` (or a camera), the seed's
    /// calls in order: [`submit`](Self::submit) each,
    /// [`shadow_pass`](Self::shadow_pass), then [`flush`](Self::flush). The
    /// statistics include the shadow pass's; the shadow pass's error comes first.
    pub fn render<'e>(
        &mut self,
        entities: impl IntoIterator<Item = &'e Entity>,
        view: impl Into<View>,
        lights: &[Light],
        target: &mut OffscreenTarget,
    ) -> Result<FrameStats, RenderError> {
        let view = view.into();
        for entity in entities {
            self.submit(entity);
        }
        // Flush even after a failed shadow pass, so the submitted entities are dropped.
        let shadows = self.shadow_pass(view, lights, target);
        let frame = self.flush(view, lights, shadows.as_ref().unwrap_or(&Shadows::none()), target);
        shadows.and(frame)
    }

    /// One frame of several `views` of `entities` into `target`, in order, each
    /// culled, shadowed and drawn on its own ([`render`](Self::render) per view);
    /// a later view draws over an earlier one where their viewports overlap.
    /// When the first view does not cover the whole target, the target is
    /// cleared to black first. Returns each view's statistics.
    pub fn render_views<'e, E>(
        &mut self,
        entities: E,
        views: &[View],
        lights: &[Light],
        target: &mut OffscreenTarget,
    ) -> Result<Vec<FrameStats>, RenderError>
    where
        E: IntoIterator<Item = &'e Entity> + Clone,
    {
        if views.first().is_some_and(|v| {
            v.viewport.pixels(target.width(), target.height())[2..] != [target.width(), target.height()]
        }) {
            self.clear(target);
        }
        views.iter().map(|view| self.render(entities.clone(), *view, lights, target)).collect()
    }

    /// Clear `target` to black.
    fn clear(&self, target: &OffscreenTarget) {
        let mut encoder =
            self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("renderer: clear") });
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("clear the target"),
            color_attachments: &[Some(target.color_attachment(wgpu::Color::BLACK))],
            ..Default::default()
        });
        self.queue.submit([encoder.finish()]);
    }

    /// Draw everything submitted since the last flush, seen by `view` (or a
    /// camera, for the whole target), lit by `lights`, into its viewport of
    /// `target`, and return what the frame cost. `shadows` are the maps this
    /// frame's [`shadow_pass`](Self::shadow_pass) drew for the same view and
    /// lights ([`Shadows::none`] draws without shadows).
    ///
    /// The frame of one view, one stage per line ([`Renderer::draw_view`]):
    /// 1. prepare — GPU twins for new shapes, textures, materials and pipelines; edited materials rewritten
    /// 2. cull — each entity's world box, then its instances', against the view's frustum
    /// 3. queue — one draw item with a 64-bit sort key per visible run (per instance when blended)
    /// 4. sort — radix sort by key
    /// 5. batch — equal (stage, pipeline, material, shape) runs merged into instanced draws, one indirect command each
    /// 6. upload — Scene and Camera blocks if changed, changed instances, draw indices and indirect commands if changed
    /// 7. encode — one pass: opaque → alpha-test → sky → transparent (or as `render_order` says);
    ///    batches sharing pipeline, texture set and mesh page go in one multi-draw-indirect call
    /// 8. submit
    ///
    /// A view of part of the target is drawn into a target of its own (kept for
    /// the next frames) and copied into its rectangle.
    ///
    /// Errors (the submitted entities are dropped): more than [`MAX_LIGHTS`]
    /// lights, an id that is not this renderer's, a viewport outside the
    /// target, or shadow maps drawn for another frame, view or lights.
    pub fn flush(
        &mut self,
        view: impl Into<View>,
        lights: &[Light],
        shadows: &Shadows,
        target: &mut OffscreenTarget,
    ) -> Result<FrameStats, RenderError> {
        let start = Instant::now();
        let view = view.into();
        let result = match self.submit_error.take() {
            Some(e) => Err(e),
            None => self.draw_view(&view, lights, shadows, target),
        };
        self.submitted.clear();
        self.instances_submitted = 0;
        self.frame_index += 1;
        result.map(|mut stats| {
            stats.cpu_ms.total = ms_since(start);
            if let Some(shadow) = &shadows.drawn {
                stats.shadow_views = shadow.views;
                stats.passes.shadow = shadow.cost;
                stats.pipelines_compiled += shadow.prepared.pipelines_compiled;
                stats.bytes_uploaded.add(&shadow.prepared.bytes_uploaded);
            }
            stats
        })
    }

    /// [`flush`](Self::flush)'s frame: into `target` itself when `view` covers
    /// it, else into a view target of the viewport's size, then copied there.
    fn draw_view(
        &mut self,
        view: &View,
        lights: &[Light],
        shadows: &Shadows,
        target: &OffscreenTarget,
    ) -> Result<FrameStats, RenderError> {
        if !view.viewport.is_valid() {
            return Err(RenderError::BadViewport(view.viewport));
        }
        let drawn = match &shadows.drawn {
            Some(drawn) => drawn.first_views(self.frame_index, view, lights).map(|_| Some(drawn))?,
            None => None,
        };
        let [x, y, width, height] = view.viewport.pixels(target.width(), target.height());
        let frame = ViewFrame::new(view, width, height);
        if (width, height) == (target.width(), target.height()) {
            return self.run_frame(&frame, lights, drawn, target);
        }
        let own = self.take_view_target(width, height, target.samples());
        let stats = self.run_frame(&frame, lights, drawn, &own);
        let mut encoder = self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("renderer: view into its viewport"),
        });
        encoder.copy_texture_to_texture(
            own.color_texture().as_image_copy(),
            wgpu::TexelCopyTextureInfo {
                origin: wgpu::Origin3d { x, y, z: 0 },
                ..target.color_texture().as_image_copy()
            },
            wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        );
        self.queue.submit([encoder.finish()]);
        self.view_targets.push((own, self.frame_index));
        stats
    }

    /// A view target of this size and sample count: one kept from an earlier
    /// frame, or a new one. Targets unused for more than a frame are dropped.
    fn take_view_target(&mut self, width: u32, height: u32, samples: u32) -> OffscreenTarget {
        let now = self.frame_index;
        let fits = |t: &OffscreenTarget| (t.width(), t.height(), t.samples()) == (width, height, samples);
        if let Some(k) = self.view_targets.iter().position(|(t, _)| fits(t)) {
            return self.view_targets.swap_remove(k).0;
        }
        // A window being resized asks for a new size every frame: keep only recent ones.
        self.view_targets.retain(|(_, used)| used + 2 >= now);
        OffscreenTarget::on_device(&self.device, width, height, samples)
    }

    fn run_frame(
        &mut self,
        frame: &ViewFrame,
        lights: &[Light],
        drawn: Option<&ShadowsDrawn>,
        target: &OffscreenTarget,
    ) -> Result<FrameStats, RenderError> {
        if lights.len() > MAX_LIGHTS {
            return Err(RenderError::TooManyLights(lights.len()));
        }
        let mut stats = FrameStats {
            entities_submitted: self.submitted.len() as u32,
            instances_submitted: self.instances_submitted,
            ..Default::default()
        };
        let t = Instant::now();
        self.frame_variant = FrameVariant::after(drawn, lights);
        self.prepare(target.samples(), &mut stats)?;
        stats.cpu_ms.prepare = ms_since(t);

        let mut visible = std::mem::take(&mut self.visible);
        if self.mode == FrameMode::Naive {
            let t = Instant::now();
            self.naive_batches(&mut stats);
            stats.cpu_ms.batch = ms_since(t);
        } else {
            let t = Instant::now();
            self.cull(frame, &mut visible, &mut stats);
            stats.cpu_ms.cull = ms_since(t);

            let t = Instant::now();
            self.forward.clear();
            self.build_queue(frame, &visible);
            stats.cpu_ms.queue = ms_since(t);

            let t = Instant::now();
            queue::sort(&mut self.forward.items);
            stats.cpu_ms.sort = ms_since(t);

            let t = Instant::now();
            let shapes = &self.shapes;
            self.forward.build(0, &visible.instances, |b| shapes[b.shape.0 as usize].gpu.expect("prepared"));
            stats.cpu_ms.batch = ms_since(t);
        }
        self.visible = visible;

        let t = Instant::now();
        let shadowed = drawn.map_or(&[][..], |d| d.first_view.as_slice());
        self.upload(frame, lights, shadowed, &mut stats)?;
        stats.cpu_ms.upload = ms_since(t);

        let t = Instant::now();
        let commands = self.encode(target, &mut stats);
        stats.cpu_ms.encode = ms_since(t);

        let t = Instant::now();
        self.queue.submit([commands]);
        stats.cpu_ms.submit = ms_since(t);
        stats.bytes_uploaded.finish();
        Ok(stats)
    }

    /// Build, before the first frame, everything drawing `entities` lit by `lights`
    /// into a target of `samples` samples needs: mesh buffers, textures, material
    /// blocks and every pipeline variant (with shadow lookups where a light casts
    /// shadows), so that the first frame compiles nothing. Returns the number of
    /// pipelines compiled.
    pub fn precompile(&mut self, entities: &[&Entity], lights: &[Light], samples: u32) -> Result<u32, RenderError> {
        if lights.len() > MAX_LIGHTS {
            return Err(RenderError::TooManyLights(lights.len()));
        }
        self.frame_variant = FrameVariant::expected(lights);
        let mut stats = FrameStats::default();
        let uses: Vec<_> = entities.iter().map(|e| (e.shape, e.material)).collect();
        self.prepare_uses(&uses, samples, &mut stats)?;
        Ok(stats.pipelines_compiled)
    }

    /// Stage 1: make sure everything the submitted entities use exists on the GPU,
    /// and compact the instance store when it holds more garbage than data.
    fn prepare(&mut self, samples: u32, stats: &mut FrameStats) -> Result<(), RenderError> {
        if let Some(remap) = self.store.compact_if_wasteful(self.frame_index) {
            for s in &mut self.submitted {
                s.slot = remap[s.slot];
            }
        }
        let uses: Vec<_> = self.submitted.iter().map(|s| (s.shape, s.material)).collect();
        self.prepare_uses(&uses, samples, stats)
    }

    fn prepare_uses(
        &mut self,
        uses: &[(ShapeId, MaterialId)],
        samples: u32,
        stats: &mut FrameStats,
    ) -> Result<(), RenderError> {
        if self.material_table.reserve(&self.device, self.materials.len())? {
            // A new table: every entry is written again, every texture set rebound to it.
            for slot in &mut self.materials {
                slot.dirty = true;
            }
            for k in 0..self.texture_sets.len() {
                self.texture_sets[k].bind_group = self.texture_set_group(self.texture_sets[k].maps);
            }
        }
        for &(shape, material) in uses {
            let slot = self.shapes.get_mut(shape.0 as usize).ok_or(RenderError::UnknownShape(shape))?;
            if slot.gpu.is_none() {
                let scope = crate::gpu::DriverErrors::watch(&self.device);
                let added = self.mesh_pool.add(&self.device, &self.queue, &slot.mesh);
                if let Some(error) = scope.finish() {
                    return Err(RenderError::Device { what: "the mesh pool", message: error.to_string() });
                }
                let (range, bytes) = added.map_err(|source| RenderError::MeshTooLarge { shape, source })?;
                slot.gpu = Some(range);
                stats.bytes_uploaded.meshes += bytes;
            }
            if let (true, Some(range)) = (std::mem::take(&mut slot.rewrite), slot.gpu) {
                stats.bytes_uploaded.meshes += self.mesh_pool.rewrite_vertices(&self.queue, range, &slot.mesh);
            }
            let layout = slot.layout;
            self.prepare_material(material, layout, samples, stats)?;
        }
        if matches!(self.environment.background, Background::Gradient { .. }) {
            stats.pipelines_compiled += u32::from(self.pipelines.build_sky(&self.device, samples)?);
        }
        Ok(())
    }

    /// Stage 3: one draw item per visible run, or per visible instance for blended
    /// materials so that they can be sorted far to near one by one. Depth is the
    /// view distance of the run's (or instance's) box centre over the far plane.
    fn build_queue(&mut self, frame: &ViewFrame, visible: &Visible) {
        let far = frame.camera.far();
        let depth = |center: Vec3A| -frame.view.transform_point3a(center).z / far;
        for run in &visible.runs {
            let s = &self.submitted[run.entry];
            let material = &self.materials[s.material.0 as usize];
            let pipeline = self.pipeline_of(s);
            let texture_set = material.gpu.as_ref().expect("prepared").texture_set;
            let queue = match material.material.alpha_mode {
                crate::scene::AlphaMode::Opaque => Queue::Opaque,
                crate::scene::AlphaMode::Mask { .. } => Queue::AlphaTest,
                crate::scene::AlphaMode::Blend => Queue::Transparent,
            };
            let stage = s.render_order.unwrap_or(queue.stage());
            let blended = queue == Queue::Transparent;
            let item = |first, count, depth| DrawItem {
                key: queue::sort_key(stage, blended, pipeline, texture_set, s.material, s.shape, depth),
                pipeline,
                material: s.material,
                shape: s.shape,
                first,
                count,
            };
            if blended {
                for k in run.start..run.start + run.len {
                    let instance = visible.instances[k as usize] as usize;
                    self.forward.items.push(item(k, 1, depth(self.store.bounds.center(instance))));
                }
            } else {
                let center = self.store.slot(s.slot).bounds.map_or(Vec3A::ZERO, |(c, _)| c);
                self.forward.items.push(item(run.start, run.len, depth(center)));
            }
        }
    }

    /// The naive baseline's batches: every valid instance of every submitted entity,
    /// in submission order, one draw each, nothing culled or sorted.
    fn naive_batches(&mut self, stats: &mut FrameStats) {
        self.forward.clear();
        for s in &self.submitted {
            let slot = self.store.slot(s.slot);
            stats.instances_invalid += u64::from(slot.invalid);
            let pipeline = self.pipeline_of(s);
            let range = slot.first as usize..(slot.first + slot.count) as usize;
            for i in range {
                if self.store.bounds.is_valid(i) {
                    self.forward.batches.push(Batch {
                        stage: Queue::Opaque.stage(),
                        pipeline,
                        material: s.material,
                        shape: s.shape,
                        first_instance: self.forward.draw_indices.len() as u32,
                        instance_count: 1,
                    });
                    self.forward.draw_indices.push(i as u32);
                }
            }
        }
    }

    /// The forward pipeline a submitted entity draws with (prepared).
    fn pipeline_of(&self, s: &Submitted) -> u16 {
        let layout = self.shapes[s.shape.0 as usize].layout;
        let twin = self.materials[s.material.0 as usize].gpu.as_ref().expect("prepared");
        twin.pipelines[layout.index()].expect("prepared")
    }

    /// Stage 6: write the blocks that changed, the instances that changed, and this
    /// frame's draw indices and indirect commands where they differ from the last frame's.
    /// `shadowed` is each light's first shadow view (empty: no shadows).
    fn upload(
        &mut self,
        frame: &ViewFrame,
        lights: &[Light],
        shadowed: &[Option<u32>],
        stats: &mut FrameStats,
    ) -> Result<(), RenderError> {
        let bytes = &mut stats.bytes_uploaded;
        let scene = SceneGpu::new(&self.environment, lights, shadowed);
        bytes.scene += self.scene_block.update(&self.queue, scene);
        bytes.camera += self.views.update(&self.queue, 0, frame.camera.to_gpu(frame.aspect));
        self.upload_instances(bytes)?;
        let naive = self.mode == FrameMode::Naive;
        if naive {
            // Every draw's material entry written before it, one small write each.
            for b in &self.forward.batches {
                let block = self.materials[b.material.0 as usize].material.to_gpu();
                bytes.material += self.material_table.write(&self.queue, b.material.0, &block);
            }
        }
        let layout = &self.pipelines.instance_layout;
        let written = self.forward.upload(&self.device, &self.queue, (layout, self.instances.buffer()), naive)?;
        bytes.draw_indices += written.draw_indices;
        bytes.indirect += written.indirect;
        stats.instances_drawn = self.forward.draw_indices.len() as u64;
        Ok(())
    }

    /// Write the instances that changed (all of them when the buffer grew, and
    /// then every draw list is bound to the new buffer).
    fn upload_instances(&mut self, bytes: &mut UploadStats) -> Result<(), RenderError> {
        if self.instances.reserve(&self.device, self.store.len())? {
            self.store.mark_all_dirty();
            self.forward.rebind(&self.device, &self.pipelines.instance_layout, self.instances.buffer());
            self.shadow_list.rebind(&self.device, &self.pipelines.instance_layout, self.instances.buffer());
        }
        for range in self.store.take_dirty() {
            let data = &self.store.instances[range.start as usize..range.end as usize];
            bytes.instances += self.instances.write(&self.queue, range.start, data);
        }
        Ok(())
    }
}

/// Append the visible instances of the entity in `slot`. Its world box decides
/// at once when wholly inside or outside; a box crossing a plane has its tiles
/// decided the same way, and only tiles crossing a plane have their instances
#[cfg(test)]
mod tests {
    use super::*;
    use crate::asset::ShapeKind;
    use crate::scene::Camera;
    use glam::{Mat4, Vec3};

    fn gpu() -> Option<Gpu> {
        match Gpu::headless() {
            Ok(gpu) => Some(gpu),
            Err(e) if std::env::var("GLINT_REQUIRE_ADAPTER").as_deref() == Ok("1") => panic!("{e}"),
            Err(e) => {
                eprintln!("skipping GPU test: {e}");
                None
            }
        }
    }

    #[test]
    fn errors_while_pipelines_are_made_are_caught_not_left_to_panic() {
        let Some(gpu) = gpu() else { return };
        let scope = crate::gpu::DriverErrors::watch(&gpu.device);
        // Invalid on every adapter: anisotropy must be at least 1.
        let _sampler =
            gpu.device.create_sampler(&wgpu::SamplerDescriptor { anisotropy_clamp: 0, ..Default::default() });
        let error = scope.finish().expect("the error is caught");
        assert!(matches!(error, wgpu::Error::Validation { .. }), "{error}");
        let clean = crate::gpu::DriverErrors::watch(&gpu.device);
        let _sampler = gpu.device.create_sampler(&wgpu::SamplerDescriptor::default());
        assert!(clean.finish().is_none(), "nothing to catch");
    }

    #[test]
    fn blended_instances_are_drawn_far_to_near_and_render_order_overrides_queues() {
        let Some(gpu) = gpu() else { return };
        let mut r = Renderer::new(&gpu);
        r.set_environment(Environment {
            background: Background::Gradient { top: Vec3::Z, bottom: Vec3::ONE },
            ..Environment::default()
        });
        let sphere = r.add_shape(ShapeKind::Sphere.mesh());
        let glass = r.add_material(Material { alpha_mode: crate::AlphaMode::Blend, ..Material::default() });
        let solid = r.add_material(Material::default());
        // Instances at view distances 4, 10, 7, 12, 5 (camera at z = 10 looking down −z), scrambled.
        let zs = [6.0, 0.0, 3.0, -2.0, 5.0];
        let glass_entity =
            Entity::instanced(sphere, glass, zs.iter().map(|&z| Mat4::from_translation(Vec3::Z * z)).collect());
        let ground = Entity::new(sphere, solid, Mat4::from_translation(Vec3::Y * -2.0)).with_render_order(Some(200));
        let front = Entity::new(sphere, solid, Mat4::from_translation(Vec3::X * 2.0));
        let camera = Camera::perspective(60.0, 0.1, 100.0).looking_at(Vec3::Z * 10.0, Vec3::ZERO);
        let mut target = OffscreenTarget::new(&gpu, 32, 32, 1).expect("target");
        r.submit(&ground);
        r.submit(&glass_entity);
        r.submit(&front);
        let stats = r.flush(camera, &[], &Shadows::none(), &mut target).expect("frame");
        // Drawn order: `front` (opaque), sky, the five glass instances far to near, then the ground (200).
        let stages: Vec<u8> = r.forward.batches.iter().map(|b| b.stage).collect();
        assert_eq!(stages, vec![64, 192, 200]);
        let glass_batch = r.forward.batches[1];
        assert_eq!(glass_batch.instance_count, 5, "one entity's instances merge into one draw once sorted");
        let order: Vec<f32> = r.forward.draw_indices[glass_batch.first_instance as usize..][..5]
            .iter()
            .map(|&i| r.store.instances[i as usize].transform().w_axis.z)
            .collect();
        assert_eq!(order, vec![-2.0, 0.0, 3.0, 5.0, 6.0], "far (low z) to near");
        assert_eq!(stats.draws, 4, "front, sky, glass, ground");
    }
}
