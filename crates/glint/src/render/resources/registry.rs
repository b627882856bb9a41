//! Core layer: the [`Registry`], the GPU resources a renderer keeps between
//! frames: shapes and the mesh pool they live in, materials and their table,
//! textures and render targets, texture sets and pipelines. Resources are added
//! here as plain data and get their GPU twins on first use (stage 1 of the frame,
//! [`Registry::prepare_uses`]).

use crate::gpu::{Gpu, OffscreenTarget, TargetFormat};
use crate::render::error::RenderError;
use crate::render::frame_variant::FrameVariant;
use crate::render::resources::buffers::{MaterialTable, TextureUploader};
use crate::render::resources::instances::Reach;
use crate::render::resources::mesh_pool::{MeshPool, MeshRange};
use crate::render::resources::pipelines::{Pipelines, VertexLayout};
use crate::scene::Texture;
use crate::scene::{Material, MaterialId, Mesh, RenderTargetId, ShapeId, TextureId};

pub(crate) struct ShapeSlot {
    pub(crate) mesh: Mesh,
    /// Its name where it came from a scene or model ("cube", "fish.obj: body"),
    /// else "shape N".
    pub(crate) name: String,
    pub(crate) layout: VertexLayout,
    /// Where the mesh lives in the pool, once uploaded.
    pub(crate) gpu: Option<MeshRange>,
    /// The vertices changed in place since they were uploaded.
    pub(crate) rewrite: bool,
    /// Its vertices change (morph targets, a cloth): levels of detail made from
    /// one shape would not fit the next, so it is drawn at full detail.
    pub(crate) deforms: bool,
}

pub(crate) struct MaterialSlot {
    pub(crate) material: Material,
    /// Set by `add_material` / `material_mut`; cleared when the block is written.
    pub(crate) dirty: bool,
    pub(crate) gpu: Option<MaterialGpuTwin>,
}

/// What a material uses on the GPU, and what that was chosen for.
pub(crate) struct MaterialGpuTwin {
    /// Index of its texture set (`Registry::texture_sets`).
    pub(crate) texture_set: u16,
    /// Forward pipeline id per vertex layout (by `VertexLayout as usize`), built on
    /// first use with a mesh of that layout.
    pub(crate) pipelines: [Option<u16>; VertexLayout::COUNT],
    /// Shadow pipeline ids per vertex layout: 2D depth maps, then cube distance maps.
    pub(crate) shadow_pipelines: [[Option<u16>; 2]; VertexLayout::COUNT],
    /// The target they draw into.
    pub(crate) target: crate::gpu::TargetFormat,
    /// Whether the environment had fog when the pipelines were chosen.
    pub(crate) fog: bool,
    /// What the frame added to the variant when the pipelines were chosen.
    pub(crate) frame: FrameVariant,
}

/// The maps of a material in texture-set binding order: diffuse, normal,
/// specular, metallic-roughness, occlusion, emissive.
pub(crate) type Maps = [Option<TextureId>; 6];

/// A bind group of the Material block for one combination of maps.
pub(crate) struct TextureSet {
    pub(crate) maps: Maps,
    pub(crate) bind_group: wgpu::BindGroup,
}

pub(crate) struct TextureSlot {
    /// Pixels waiting for their first use; dropped once uploaded.
    pub(crate) pending: Option<Texture>,
    pub(crate) view: Option<wgpu::TextureView>,
}

/// 1×1 textures bound where a material has no map.
pub(crate) struct DefaultMaps {
    pub(crate) white_srgb: wgpu::TextureView,
    pub(crate) flat_normal: wgpu::TextureView,
    pub(crate) white_linear: wgpu::TextureView,
}

/// The GPU resources of a [`Renderer`](crate::render::Renderer), by id: what
/// [`add_shape`](Self::add_shape), [`add_material`](Self::add_material),
/// [`add_texture`](Self::add_texture) and
/// [`add_render_target`](Self::add_render_target) return indexes these lists.
/// It holds no scene (entities, lights, environment) and no view.
pub struct Registry {
    pub(crate) device: wgpu::Device,
    pub(crate) queue: crate::gpu::SubmitQueue,
    pub(crate) pipelines: Pipelines,
    pub(crate) uploader: TextureUploader,
    pub(crate) sampler: wgpu::Sampler,
    pub(crate) defaults: DefaultMaps,
    pub(crate) shapes: Vec<ShapeSlot>,
    pub(crate) mesh_pool: MeshPool,
    pub(crate) materials: Vec<MaterialSlot>,
    pub(crate) material_table: MaterialTable,
    pub(crate) texture_sets: Vec<TextureSet>,
    /// Mip-level blits of textures uploaded since the last frame's submission,
    /// which runs them first.
    pub(crate) mip_blits: Vec<wgpu::CommandBuffer>,
    pub(crate) textures: Vec<TextureSlot>,
    /// Render targets (`add_render_target`), each with the texture that shows it.
    pub(crate) render_targets: Vec<(OffscreenTarget, TextureId)>,
    /// Whether the device occlusion-culls (render targets' depth is then readable).
    pub(crate) occlusion: bool,
    /// Where large meshes' levels of detail are kept between runs (none: made each run).
    pub(crate) level_cache: Option<crate::scene::level_cache::LevelCache>,
    /// Environment images ([`add_environment`](Self::add_environment)), uploaded.
    environments:
        std::collections::HashMap<crate::scene::EnvironmentId, crate::render::passes::environment::SourceImage>,
}

impl Registry {
    /// An empty registry on `gpu`'s device, with its 1×1 default maps.
    pub(crate) fn new(gpu: &Gpu, queue: crate::gpu::SubmitQueue) -> Self {
        let device = gpu.device.clone();
        let uploader = TextureUploader::new(&device);
        let pixel = |name: &str, rgba: [u8; 4], srgb| {
            let texture = Texture::new(name, image::RgbaImage::from_pixel(1, 1, image::Rgba(rgba)), srgb);
            uploader.upload(&device, &queue, &texture).0 // one level: no blits
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
        Self {
            occlusion: gpu.occlusion_culls(),
            level_cache: None,
            pipelines: Pipelines::new(&device, gpu.vertex_storage()),
            mesh_pool: MeshPool::new(&device, gpu.culls_on_gpu()),
            material_table: MaterialTable::new(&device, gpu.vertex_storage()),
            uploader,
            sampler,
            defaults,
            shapes: Vec::new(),
            materials: Vec::new(),
            texture_sets: Vec::new(),
            mip_blits: Vec::new(),
            textures: Vec::new(),
            render_targets: Vec::new(),
            environments: Default::default(),
            device,
            queue,
        }
    }

    /// Add a shape; its buffers are created the first time an entity using it is drawn.
    pub fn add_shape(&mut self, mesh: Mesh) -> ShapeId {
        let name = format!("shape {}", self.shapes.len());
        self.add_named_shape(mesh, name)
    }

    /// [`add_shape`](Self::add_shape), named (as `glint explain` shows it).
    pub(crate) fn add_named_shape(&mut self, mesh: Mesh, name: String) -> ShapeId {
        self.add_shape_slot(mesh, name, false)
    }

    /// [`add_named_shape`](Self::add_named_shape) for a mesh whose vertices
    /// [`update_shape`](Self::update_shape) will change: drawn at full detail.
    pub(crate) fn add_deforming_shape(&mut self, mesh: Mesh, name: String) -> ShapeId {
        self.add_shape_slot(mesh, name, true)
    }

    fn add_shape_slot(&mut self, mesh: Mesh, name: String, deforms: bool) -> ShapeId {
        let layout = VertexLayout::of(&mesh);
        self.shapes.push(ShapeSlot { layout, mesh, name, gpu: None, rewrite: false, deforms });
        ShapeId(self.shapes.len() as u32 - 1)
    }

    /// Replace a shape's mesh (e.g. with morph targets applied). A mesh with the
    /// same streams, vertex count and indices as the old one is written over it
    /// (only the base vertex stream is uploaded); any other goes to a new place in
    /// the mesh pool. Entities drawing the shape pick up its new bounds, and it
    /// is drawn at full detail from then on (its levels of detail were made for
    /// the old vertices). Returns false (and changes nothing) when `id` is not
    /// this renderer's.
    pub fn update_shape(&mut self, id: ShapeId, mesh: Mesh) -> bool {
        let Some(slot) = self.shapes.get_mut(id.0 as usize) else { return false };
        slot.deforms = true;
        if let Some(range) = &mut slot.gpu {
            range.levels.count = 1;
        }
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

    /// Add an environment image for image-based lighting
    /// ([`EnvironmentSource::Image`](crate::scene::EnvironmentSource::Image) of
    /// its id): uploaded now (halved until it fits the adapter and
    /// 2048 texels a side), prefiltered when a frame first uses it. Adding the
    /// same image again does nothing.
    pub fn add_environment(&mut self, image: &crate::scene::EnvironmentImage) -> crate::scene::EnvironmentId {
        let side =
            self.device.limits().max_texture_dimension_2d.min(crate::render::passes::environment::MAX_SOURCE_SIDE);
        let (device, queue) = (&self.device, &self.queue);
        (self.environments.entry(image.id()))
            .or_insert_with(|| crate::render::passes::environment::SourceImage::upload(device, queue, image, side));
        image.id()
    }

    /// The uploaded environment image `id`.
    pub(crate) fn environment(
        &self,
        id: crate::scene::EnvironmentId,
    ) -> Option<&crate::render::passes::environment::SourceImage> {
        self.environments.get(&id)
    }

    /// Add a `width` × `height` render target (half floats when `hdr`, else
    /// 8-bit sRGB), and the texture that shows it: a view with
    /// [`View::output`](crate::View::output) draws into it, a material map with the
    /// texture samples it, in the same frame after that view (see
    /// [`Renderer::render_views`](crate::render::Renderer::render_views)). Fails when a side is 0 or above
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
        // A render target's views are culled as any other: its depth readable where the device occlusion-culls.
        let format = TargetFormat { color, samples: 1 };
        let target = OffscreenTarget::on_device(&self.device, width, height, format, self.occlusion);
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

    /// How far an instance of `shape` drawn with `material` reaches from its
    /// transform: the shape's box, widened by the material's far field and
    /// then its motion. `None` for a shape that is not this registry's.
    pub(crate) fn reach(&self, shape: ShapeId, material: MaterialId) -> Option<Reach> {
        let shape = self.shapes.get(shape.0 as usize)?;
        let (motion, far_field) = self.material(material).map_or((None, None), |m| (m.motion, m.far_field));
        // Widened in the far field first, then moved.
        let local = far_field.map_or(shape.mesh.aabb(), |f| f.reach(shape.mesh.aabb()));
        let (local, walk) = motion.map_or((local, 0.0), |m| m.reach(local));
        Some(Reach { local, walk })
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

    /// The shadow pipeline for `pass` of `material` drawn as `prepared` says:
    /// cached in the material's twin per vertex layout, built (from its forward
    /// pipeline's variant) on first use.
    pub(crate) fn shadow_pipeline(
        &mut self,
        material: MaterialId,
        prepared: &crate::render::frame::prepared::Prepared,
        pass: crate::render::resources::pipelines::PassKind,
        stats: &mut crate::render::debug::stats::FrameStats,
    ) -> Result<u16, RenderError> {
        let (layout, kind) = (
            prepared.layout.index(),
            usize::from(pass == crate::render::resources::pipelines::PassKind::ShadowDistance),
        );
        let cached = self.materials.get(material.0 as usize).and_then(|m| m.gpu.as_ref());
        if let Some(id) = cached.and_then(|t| t.shadow_pipelines[layout][kind]) {
            return Ok(id);
        }
        let key = Pipelines::shadow_key(self.pipelines.key_of(prepared.pipeline), pass);
        let (id, built) = self.pipelines.forward_id(&self.device, key)?;
        stats.pipelines_compiled += u32::from(built);
        if let Some(twin) = self.materials.get_mut(material.0 as usize).and_then(|m| m.gpu.as_mut()) {
            twin.shadow_pipelines[layout][kind] = Some(id);
        }
        Ok(id)
    }

    /// Whether material `id` blends (its draws are sorted far to near).
    pub(crate) fn blended(&self, id: MaterialId) -> bool {
        self.material(id).is_some_and(|m| m.alpha_mode == crate::scene::AlphaMode::Blend)
    }

    /// The render target `view` draws into and the texture that shows it, if any.
    pub(crate) fn render_target_of(&self, view: &crate::scene::View) -> Option<&(OffscreenTarget, TextureId)> {
        view.output.and_then(|id| self.render_targets.get(id.0 as usize))
    }

    /// Whether material `id` shows `texture` in one of its maps.
    pub(crate) fn shows(&self, id: MaterialId, texture: TextureId) -> bool {
        self.materials.get(id.0 as usize).is_some_and(|m| m.material.maps().contains(&Some(texture)))
    }
}
