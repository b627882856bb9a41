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
mod error;
mod forward;
mod frame;
mod frame_variant;
mod instances;
mod materials;
mod mesh_pool;
mod pipelines;
mod post;
mod prepare;
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

pub use error::RenderError;
pub use mesh_pool::MeshTooLarge;
pub use post::MAX_POST_EFFECTS;
pub use shadow_maps::{ShadowLayout, MAX_CUBES, MAX_SHADOW_MAP_BYTES};
pub use shadow_pass::Shadows;
pub use stats::{FrameStats, PassStats, Passes, StageTimes, UploadStats};
pub use timer::GpuTimes;

use crate::asset::Texture;
use crate::gpu::{Gpu, OffscreenTarget, TargetFormat};
use crate::scene::{Entity, Environment, Material, MaterialId, Mesh, RenderTargetId, ShapeId, TextureId};
use blocks::{SceneGpu, UniformBlock};
use draw_list::DrawList;
use frame_variant::FrameVariant;
use instances::InstanceStore;
use mesh_pool::{MeshPool, MeshRange};
use pipelines::{Pipelines, VertexLayout};
use resources::{InstanceBuffer, MaterialTable, TextureUploader};
use shadow_maps::{ShadowGpu, ShadowMaps, ShadowSupport};
use std::time::Instant;
use views::ViewBlocks;
use visible::Visible;

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
    /// The target they draw into.
    target: crate::gpu::TargetFormat,
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
    /// Render targets (`add_render_target`), each with the texture that shows it.
    render_targets: Vec<(OffscreenTarget, TextureId)>,
    post: post::PostChain,
    /// Samples of a post-processed view's HDR target: the output's where the
    /// adapter multisamples the HDR format, else 1.
    hdr_msaa: bool,
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
            render_targets: Vec::new(),
            post: post::PostChain::new(&gpu.device),
            hdr_msaa: {
                let flags = gpu.adapter.get_texture_format_features(crate::gpu::HDR_FORMAT).flags;
                flags.sample_count_supported(4) && flags.contains(wgpu::TextureFormatFeatureFlags::MULTISAMPLE_RESOLVE)
            },
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

    /// Add a `width` × `height` render target (half floats when `hdr`, else
    /// 8-bit sRGB), and the texture that shows it: a view with
    /// [`View::output`](crate::View::output) draws into it, a material map with the
    /// texture samples it, in the same frame after that view (see
    /// [`render_views`](Self::render_views)). Fails when a side is 0 or above
    /// the adapter's texture limit.
    pub fn add_render_target(
        &mut self,
        width: u32,
        height: u32,
        hdr: bool,
    ) -> Result<(RenderTargetId, TextureId), RenderError> {
        let side = self.device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width.max(height) > side {
            let name = format!("render target {}", self.render_targets.len());
            return Err(RenderError::TextureTooLarge { name, width, height, side });
        }
        let color = if hdr { crate::gpu::HDR_FORMAT } else { crate::gpu::COLOR_FORMAT };
        let target = OffscreenTarget::on_device(&self.device, width, height, TargetFormat { color, samples: 1 });
        self.textures.push(TextureSlot { pending: None, view: Some(target.color_view().clone()) });
        let texture = TextureId(self.textures.len() as u32 - 1);
        self.render_targets.push((target, texture));
        Ok((RenderTargetId(self.render_targets.len() as u32 - 1), texture))
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
}
