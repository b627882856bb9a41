//! Core layer: the [`Renderer`], which turns the entities submitted for a frame
//! into GPU commands, following DESIGN.md's data flow.
//!
//! ## Bind-group convention (shader data blocks)
//! | group | block | written when | holds |
//! | --- | --- | --- | --- |
//! | 0 | Scene | lights or environment change | ambient, sky colours, light count, `lights[64]` |
//! | 1 | Camera | the camera or target aspect changes | view, view-projection, its inverse, eye position |
//! | 2 | Material | the material is added or edited | uniform block, diffuse / normal / specular maps, sampler |
//! | 3 | Instances | every frame, one write | `array<mat4x4<f32>>` in draw order (storage buffer) |
//!
//! Every pipeline shares one layout with these four groups, so groups 0, 1 and 3
//! are bound once per pass and only group 2 changes between draws.

mod batch;
mod blocks;
mod pipelines;
pub mod queue;
mod resources;
mod stats;

pub use stats::{FrameStats, StageTimes, UploadStats};

use crate::asset::Texture;
use crate::gpu::{Gpu, OffscreenTarget};
use crate::scene::{
    Background, Camera, Entity, Environment, Light, Material, MaterialId, Mesh, ShapeId, TextureId,
    MAX_LIGHTS,
};
use batch::Batch;
use blocks::{CameraGpu, InstanceGpu, SceneGpu, UniformBlock};
use pipelines::{PipelineKey, Pipelines};
use queue::{DrawItem, Queue};
use resources::{GpuMesh, InstanceBuffer, TextureUploader};
use std::time::Instant;

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
    gpu: Option<GpuMesh>,
}

struct MaterialSlot {
    material: Material,
    /// Set by `add_material` / `material_mut`; cleared when the block is written.
    dirty: bool,
    gpu: Option<MaterialGpuTwin>,
}

/// A material's uniform buffer and bind group, and what they were built from.
struct MaterialGpuTwin {
    uniform: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    maps: [Option<TextureId>; 3],
    /// Forward pipeline id for (this material's states, `samples`).
    pipeline: u16,
    samples: u32,
}

struct TextureSlot {
    /// Pixels waiting for their first use; dropped once uploaded.
    pending: Option<Texture>,
    view: Option<wgpu::TextureView>,
}

/// An entity as submitted: its ids and where its transforms sit this frame.
struct Submitted {
    shape: ShapeId,
    material: MaterialId,
    first: u32,
    count: u32,
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
/// each frame update them, [`submit`](Self::submit) every entity to draw, then
/// [`flush`](Self::flush) with the camera and lights.
pub struct Renderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    pipelines: Pipelines,
    uploader: TextureUploader,
    sampler: wgpu::Sampler,
    defaults: DefaultMaps,
    shapes: Vec<ShapeSlot>,
    materials: Vec<MaterialSlot>,
    textures: Vec<TextureSlot>,
    environment: Environment,
    scene_block: UniformBlock<SceneGpu>,
    camera_block: UniformBlock<CameraGpu>,
    scene_group: wgpu::BindGroup,
    camera_group: wgpu::BindGroup,
    instances: InstanceBuffer,
    // Per-frame lists, kept to reuse their allocations.
    submitted: Vec<Submitted>,
    transforms: Vec<glam::Mat4>,
    items: Vec<DrawItem>,
    batches: Vec<Batch>,
    packed: Vec<InstanceGpu>,
}

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

impl Renderer {
    /// Create a renderer on `gpu`'s device.
    pub fn new(gpu: &Gpu) -> Self {
        let device = gpu.device.clone();
        let queue = gpu.queue.clone();
        let pipelines = Pipelines::new(&device);
        let scene_block = UniformBlock::new(&device, "renderer: scene block");
        let camera_block = UniformBlock::new(&device, "renderer: camera block");
        let group = |label, layout, buffer: &wgpu::Buffer| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(label),
                layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buffer.as_entire_binding(),
                }],
            })
        };
        let scene_group = group(
            "renderer: scene block (group 0)",
            &pipelines.scene_layout,
            &scene_block.buffer,
        );
        let camera_group = group(
            "renderer: camera block (group 1)",
            &pipelines.camera_layout,
            &camera_block.buffer,
        );
        let uploader = TextureUploader::new(&device);
        let pixel = |name: &str, rgba: [u8; 4], srgb| {
            let texture = Texture::new(
                name,
                image::RgbaImage::from_pixel(1, 1, image::Rgba(rgba)),
                srgb,
            );
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
        let instances = InstanceBuffer::new(&device, &pipelines.instance_layout);
        Self {
            device,
            queue,
            pipelines,
            uploader,
            sampler,
            defaults,
            shapes: Vec::new(),
            materials: Vec::new(),
            textures: Vec::new(),
            environment: Environment::default(),
            scene_block,
            camera_block,
            scene_group,
            camera_group,
            instances,
            submitted: Vec::new(),
            transforms: Vec::new(),
            items: Vec::new(),
            batches: Vec::new(),
            packed: Vec::new(),
        }
    }

    /// Add a shape; its buffers are created the first time an entity using it is drawn.
    pub fn add_shape(&mut self, mesh: Mesh) -> ShapeId {
        self.shapes.push(ShapeSlot { mesh, gpu: None });
        ShapeId(self.shapes.len() as u32 - 1)
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
        self.textures.push(TextureSlot {
            pending: Some(texture),
            view: None,
        });
        TextureId(self.textures.len() as u32 - 1)
    }

    /// Add a material; its uniform block is written on first use.
    pub fn add_material(&mut self, material: Material) -> MaterialId {
        self.materials.push(MaterialSlot {
            material,
            dirty: true,
            gpu: None,
        });
        MaterialId(self.materials.len() as u32 - 1)
    }

    /// Read a material.
    pub fn material(&self, id: MaterialId) -> Option<&Material> {
        self.materials.get(id.0 as usize).map(|s| &s.material)
    }

    /// Edit a material: marks it dirty, so its block is rewritten before the next frame.
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

    /// Queue `entity` for the next [`flush`](Self::flush): its transforms are copied,
    /// so the entity may change right after. Ids are checked at flush.
    pub fn submit(&mut self, entity: &Entity) {
        self.submitted.push(Submitted {
            shape: entity.shape,
            material: entity.material,
            first: self.transforms.len() as u32,
            count: entity.transforms.len() as u32,
        });
        self.transforms.extend_from_slice(&entity.transforms);
    }

    /// Draw everything submitted since the last flush into `target`, seen by
    /// `camera` and lit by `lights`, and return what the frame cost.
    ///
    /// The frame, one stage per line:
    /// 1. prepare — GPU twins for new shapes, textures, materials and pipelines; edited materials rewritten
    /// 2. queue — one draw item with a 64-bit sort key per submitted entity
    /// 3. sort — radix sort by key
    /// 4. batch — equal (pipeline, material, shape) runs merged into instanced draws
    /// 5. upload — Scene and Camera blocks if changed, all instance data in one write
    /// 6. encode — one pass: opaque → alpha-test → sky → transparent
    /// 7. submit
    ///
    /// Errors (the submitted entities are dropped): more than [`MAX_LIGHTS`] lights,
    /// or an id that is not this renderer's.
    pub fn flush(
        &mut self,
        camera: &Camera,
        lights: &[Light],
        target: &mut OffscreenTarget,
    ) -> Result<FrameStats, RenderError> {
        let start = Instant::now();
        let result = self.run_frame(camera, lights, target);
        self.submitted.clear();
        self.transforms.clear();
        result.map(|mut stats| {
            stats.cpu_ms.total = ms_since(start);
            stats
        })
    }

    fn run_frame(
        &mut self,
        camera: &Camera,
        lights: &[Light],
        target: &OffscreenTarget,
    ) -> Result<FrameStats, RenderError> {
        if lights.len() > MAX_LIGHTS {
            return Err(RenderError::TooManyLights(lights.len()));
        }
        let mut stats = FrameStats {
            entities_submitted: self.submitted.len() as u32,
            instances_submitted: self.transforms.len() as u64,
            ..Default::default()
        };
        let t = Instant::now();
        self.prepare(target.samples(), &mut stats)?;
        stats.cpu_ms.prepare = ms_since(t);

        let t = Instant::now();
        self.build_queue(camera);
        stats.cpu_ms.queue = ms_since(t);

        let t = Instant::now();
        queue::sort(&mut self.items);
        stats.cpu_ms.sort = ms_since(t);

        let t = Instant::now();
        batch::merge(
            &self.items,
            &self.transforms,
            &mut self.packed,
            &mut self.batches,
        );
        stats.cpu_ms.batch = ms_since(t);

        let t = Instant::now();
        self.upload(camera, lights, target, &mut stats);
        stats.cpu_ms.upload = ms_since(t);

        let t = Instant::now();
        let commands = self.encode(target, &mut stats);
        stats.cpu_ms.encode = ms_since(t);

        let t = Instant::now();
        self.queue.submit([commands]);
        stats.cpu_ms.submit = ms_since(t);
        stats.bytes_uploaded.total = stats.bytes_uploaded.uniforms
            + stats.bytes_uploaded.instances
            + stats.bytes_uploaded.textures
            + stats.bytes_uploaded.meshes;
        Ok(stats)
    }

    /// Stage 1: make sure everything the submitted entities use exists on the GPU.
    fn prepare(&mut self, samples: u32, stats: &mut FrameStats) -> Result<(), RenderError> {
        for i in 0..self.submitted.len() {
            let (shape, material) = (self.submitted[i].shape, self.submitted[i].material);
            let slot = self
                .shapes
                .get_mut(shape.0 as usize)
                .ok_or(RenderError::UnknownShape(shape))?;
            if slot.gpu.is_none() {
                slot.gpu = Some(GpuMesh::new(&self.device, &slot.mesh, shape.0));
                stats.bytes_uploaded.meshes += slot.mesh.gpu_bytes();
            }
            self.prepare_material(material, samples, stats)?;
        }
        if matches!(self.environment.background, Background::Gradient { .. }) {
            self.pipelines.sky(&self.device, samples);
        }
        Ok(())
    }

    fn prepare_material(
        &mut self,
        id: MaterialId,
        samples: u32,
        stats: &mut FrameStats,
    ) -> Result<(), RenderError> {
        let slot = self
            .materials
            .get(id.0 as usize)
            .ok_or(RenderError::UnknownMaterial(id))?;
        if !slot.dirty && slot.gpu.as_ref().is_some_and(|g| g.samples == samples) {
            return Ok(());
        }
        let material = slot.material.clone();
        let maps = [
            material.diffuse_map,
            material.normal_map,
            material.specular_map,
        ];
        for texture in maps.into_iter().flatten() {
            let tex = self.textures.get_mut(texture.0 as usize).ok_or_else(|| {
                RenderError::UnknownTexture {
                    material: material.name.clone(),
                    texture,
                }
            })?;
            if let Some(pending) = tex.pending.take() {
                let (view, bytes) = self.uploader.upload(&self.device, &self.queue, &pending);
                tex.view = Some(view);
                stats.bytes_uploaded.textures += bytes;
            }
        }
        let (pipeline, _built) = self
            .pipelines
            .forward_id(&self.device, PipelineKey::for_material(&material, samples));
        let slot = &mut self.materials[id.0 as usize];
        let stale_group = slot.gpu.as_ref().is_none_or(|g| g.maps != maps);
        if stale_group {
            let uniform = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(&format!("material '{}': block", material.name)),
                size: std::mem::size_of::<blocks::MaterialGpu>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let view = |map: Option<TextureId>, default| match map {
                Some(t) => self.textures[t.0 as usize].view.as_ref().unwrap_or(default),
                None => default,
            };
            let bind_group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(&format!("material '{}' (group 2)", material.name)),
                layout: &self.pipelines.material_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: uniform.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(view(
                            maps[0],
                            &self.defaults.white_srgb,
                        )),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::TextureView(view(
                            maps[1],
                            &self.defaults.flat_normal,
                        )),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: wgpu::BindingResource::TextureView(view(
                            maps[2],
                            &self.defaults.white_linear,
                        )),
                    },
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: wgpu::BindingResource::Sampler(&self.sampler),
                    },
                ],
            });
            slot.gpu = Some(MaterialGpuTwin {
                uniform,
                bind_group,
                maps,
                pipeline,
                samples,
            });
        }
        let twin = slot.gpu.as_mut().expect("created above");
        twin.pipeline = pipeline;
        twin.samples = samples;
        if slot.dirty {
            let block = material.to_gpu();
            self.queue
                .write_buffer(&twin.uniform, 0, bytemuck::bytes_of(&block));
            stats.bytes_uploaded.uniforms += std::mem::size_of_val(&block) as u64;
            slot.dirty = false;
        }
        Ok(())
    }

    /// Stage 2: one draw item per submitted entity. Its depth is the view distance
    /// of its first instance's bounding-sphere centre over the far plane.
    fn build_queue(&mut self, camera: &Camera) {
        let view = camera.view();
        let far = camera.far();
        self.items.clear();
        for s in self.submitted.iter().filter(|s| s.count > 0) {
            let slot = &self.materials[s.material.0 as usize];
            let twin = slot.gpu.as_ref().expect("prepared");
            let queue = match slot.material.alpha_mode {
                crate::scene::AlphaMode::Opaque => Queue::Opaque,
                crate::scene::AlphaMode::Mask { .. } => Queue::AlphaTest,
                crate::scene::AlphaMode::Blend => Queue::Transparent,
            };
            let center = self.shapes[s.shape.0 as usize]
                .mesh
                .bounding_sphere()
                .center;
            let world = self.transforms[s.first as usize].transform_point3(center);
            let depth = -view.transform_point3(world).z / far;
            self.items.push(DrawItem {
                key: queue::sort_key(queue, twin.pipeline, s.material, s.shape, depth),
                pipeline: twin.pipeline,
                material: s.material,
                shape: s.shape,
                first: s.first,
                count: s.count,
            });
        }
    }

    /// Stage 5: write the blocks that changed and this frame's instances.
    fn upload(
        &mut self,
        camera: &Camera,
        lights: &[Light],
        target: &OffscreenTarget,
        stats: &mut FrameStats,
    ) {
        let aspect = target.width() as f32 / target.height() as f32;
        stats.bytes_uploaded.uniforms += self
            .scene_block
            .update(&self.queue, SceneGpu::new(&self.environment, lights));
        stats.bytes_uploaded.uniforms +=
            self.camera_block.update(&self.queue, camera.to_gpu(aspect));
        stats.bytes_uploaded.instances += self.instances.write(
            &self.device,
            &self.queue,
            &self.pipelines.instance_layout,
            &self.packed,
        );
        stats.instances_drawn = self.packed.len() as u64;
    }

    /// Stage 6: record the forward pass.
    fn encode(&self, target: &OffscreenTarget, stats: &mut FrameStats) -> wgpu::CommandBuffer {
        let clear = match self.environment.background {
            Background::Color(c) | Background::Gradient { bottom: c, .. } => wgpu::Color {
                r: c.x.into(),
                g: c.y.into(),
                b: c.z.into(),
                a: 1.0,
            },
        };
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("renderer: frame"),
            });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("forward pass"),
                color_attachments: &[Some(target.color_attachment(clear))],
                depth_stencil_attachment: Some(target.depth_attachment()),
                ..Default::default()
            });
            pass.set_bind_group(0, &self.scene_group, &[]);
            pass.set_bind_group(1, &self.camera_group, &[]);
            pass.set_bind_group(3, &self.instances.bind_group, &[]);
            stats.bind_groups_set += 3;
            let opaque_end = self.batches.partition_point(|b| b.queue == Queue::Opaque);
            let alpha_end = self
                .batches
                .partition_point(|b| b.queue != Queue::Transparent);
            let mut bound = Bound::default();
            self.draw_batches(
                &mut pass,
                "opaque",
                &self.batches[..opaque_end],
                &mut bound,
                stats,
            );
            self.draw_batches(
                &mut pass,
                "alpha-test",
                &self.batches[opaque_end..alpha_end],
                &mut bound,
                stats,
            );
            if let (Background::Gradient { .. }, Some(sky)) = (
                self.environment.background,
                self.pipelines.sky_built(target.samples()),
            ) {
                pass.push_debug_group("sky");
                pass.set_pipeline(sky);
                pass.draw(0..3, 0..1);
                pass.pop_debug_group();
                bound.pipeline = None;
                stats.pipelines_bound += 1;
                stats.draw_calls += 1;
            }
            self.draw_batches(
                &mut pass,
                "transparent",
                &self.batches[alpha_end..],
                &mut bound,
                stats,
            );
        }
        encoder.finish()
    }

    /// Draw one queue's batches, setting only the state that changes.
    fn draw_batches(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        name: &str,
        batches: &[Batch],
        bound: &mut Bound,
        stats: &mut FrameStats,
    ) {
        if batches.is_empty() {
            return;
        }
        pass.push_debug_group(name);
        for b in batches {
            if bound.pipeline != Some(b.pipeline) {
                pass.set_pipeline(self.pipelines.forward(b.pipeline));
                bound.pipeline = Some(b.pipeline);
                stats.pipelines_bound += 1;
            }
            if bound.material != Some(b.material) {
                let twin = self.materials[b.material.0 as usize]
                    .gpu
                    .as_ref()
                    .expect("prepared");
                pass.set_bind_group(2, &twin.bind_group, &[]);
                bound.material = Some(b.material);
                stats.bind_groups_set += 1;
            }
            let mesh = self.shapes[b.shape.0 as usize]
                .gpu
                .as_ref()
                .expect("prepared");
            if bound.shape != Some(b.shape) {
                pass.set_vertex_buffer(0, mesh.vertices.slice(..));
                pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
                bound.shape = Some(b.shape);
            }
            pass.draw_indexed(
                0..mesh.index_count,
                0,
                b.first_instance..b.first_instance + b.instance_count,
            );
            stats.draw_calls += 1;
        }
        pass.pop_debug_group();
    }
}

/// What the pass has bound, to skip redundant state changes.
#[derive(Default)]
struct Bound {
    pipeline: Option<u16>,
    material: Option<MaterialId>,
    shape: Option<ShapeId>,
}
