//! Core layer: bind-group layouts (one per block of the convention in
//! `render/mod.rs`), the shared pipeline layout, and the pipeline cache.
//!
//! A forward pipeline is identified by its [`PipelineKey`]: the shader variant
//! (macro set and light counts), the vertex layout, the four render-state objects and the target
//! formats. Shader modules are cached per variant, pipelines per key; a key's
//! index in the cache is its id in sort keys.

use crate::gpu::{sampler_entry, texture_entry, DriverErrors, TargetFormat, COLOR_FORMAT, DEPTH_FORMAT};
use crate::render::resources::gpu_array;
use crate::scene::{BlendState, Compare, Cull, DepthState, Mesh, RenderStates, SkinVertex, StencilOp, Vertex};
use crate::shader::{LightCounts, ShaderError, ShaderFeatures};
use std::collections::HashMap;

/// Shadow maps are 32-bit float depth.
pub(crate) const SHADOW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Ambient occlusion's pre-pass target: octahedral view-space normal (xy), distance as a half
/// float (z) plus what it rounded away (w); 0 where nothing was drawn.
pub(crate) const PREPASS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// One vertex buffer of a mesh: the interleaved [`Vertex`] stream, or one of
/// the optional ones, in this order (a layout's streams are buffer slots 0, 1, ...).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Stream {
    /// [`Vertex`]: position, normal, uv, tangent (`@location(0..=3)`).
    Base,
    /// Linear RGBA colour (`@location(4)`).
    Color,
    /// Second texture coordinate (`@location(5)`).
    Uv1,
    /// Joints and weights, [`SkinVertex`] (`@location(6)`, `@location(7)`).
    Skin,
}

impl Stream {
    /// Bytes per vertex.
    pub(crate) fn stride(self) -> u32 {
        match self {
            Self::Base => std::mem::size_of::<Vertex>() as u32,
            Self::Color => 16,
            Self::Uv1 => 8,
            Self::Skin => std::mem::size_of::<SkinVertex>() as u32,
        }
    }

    fn attributes(self) -> &'static [wgpu::VertexAttribute] {
        const BASE: [wgpu::VertexAttribute; 4] =
            wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32x4];
        const COLOR: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![4 => Float32x4];
        const UV1: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![5 => Float32x2];
        const SKIN: [wgpu::VertexAttribute; 2] = wgpu::vertex_attr_array![6 => Uint16x4, 7 => Float32x4];
        match self {
            Self::Base => &BASE,
            Self::Color => &COLOR,
            Self::Uv1 => &UV1,
            Self::Skin => &SKIN,
        }
    }

    /// This stream's bytes in `mesh` (empty when the mesh lacks it).
    pub(crate) fn bytes(self, mesh: &Mesh) -> &[u8] {
        match self {
            Self::Base => bytemuck::cast_slice(mesh.vertices()),
            Self::Color => mesh.colors().map_or(&[], bytemuck::cast_slice),
            Self::Uv1 => mesh.uv1().map_or(&[], bytemuck::cast_slice),
            Self::Skin => mesh.skin().map_or(&[], bytemuck::cast_slice),
        }
    }
}

/// What a draw reads besides its material: which vertex streams its mesh has
/// (the base stream always; a pipeline reads exactly these, and each optional
/// one sets its shader feature bit), and how its instances are stored.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub(crate) struct VertexLayout {
    /// Vertex colours ([`ShaderFeatures::VERTEX_COLOR`]).
    pub colors: bool,
    /// A second uv set ([`ShaderFeatures::UV1`]).
    pub uv1: bool,
    /// Joints and weights ([`ShaderFeatures::SKINNED`]).
    pub skin: bool,
    /// Compact instances, 16 bytes each ([`ShaderFeatures::COMPACT`]).
    pub compact: bool,
    /// Levels of detail in a frame that cross-fades them
    /// ([`ShaderFeatures::LOD_FADE`]; a shape without keeps its early depth test).
    pub levels: bool,
}

impl VertexLayout {
    /// The layout a mesh's streams need (its instances stored in full, no levels yet).
    pub(crate) fn of(mesh: &Mesh) -> Self {
        let (colors, uv1, skin) = (mesh.colors().is_some(), mesh.uv1().is_some(), mesh.skin().is_some());
        Self { colors, uv1, skin, compact: false, levels: false }
    }

    /// How many layouts there are ([`VertexLayout::index`] is below this).
    pub(crate) const COUNT: usize = 32;

    /// A dense number for the layout, for per-layout tables.
    pub(crate) fn index(self) -> usize {
        usize::from(self.colors)
            | usize::from(self.uv1) << 1
            | usize::from(self.skin) << 2
            | usize::from(self.compact) << 3
            | usize::from(self.levels) << 4
    }

    /// The streams, in buffer-slot order.
    pub(crate) fn streams(self) -> impl Iterator<Item = Stream> {
        [(true, Stream::Base), (self.colors, Stream::Color), (self.uv1, Stream::Uv1), (self.skin, Stream::Skin)]
            .into_iter()
            .filter_map(|(on, s)| on.then_some(s))
    }
}

/// Slope-scaled depth bias of 2D shadow maps (the per-light biases are added
/// where the map is read).
const SHADOW_SLOPE_BIAS: f32 = 1.5;

/// The full-screen passes of the sky shader: the gradient sky or the
/// environment, drawn behind what the opaque stages drew, and the sun glare,
/// added over everything.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum SkyPass {
    Gradient,
    Environment,
    Glare,
}

/// What a pipeline draws into.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum PassKind {
    /// The forward pass: colour and depth of the target.
    Forward,
    /// A 2D shadow map: depth only, slope-scaled bias, both sides drawn.
    ShadowDepth,
    /// A cube-map face: the distance to the light over its range as depth.
    ShadowDistance,
    /// A view's depth pre-pass for ambient occlusion: normal and distance
    /// (`fs_prepass`) into its target, depth into the view's (or its own).
    Prepass,
    /// Weighted transparency's accumulation (`fs_weighted`): the sums into
    /// the view's two half-float targets, depth tested, not written.
    Weighted,
    /// Exact transparency's fragment lists (`fs_exact`): no colour target,
    /// depth tested before the shader, not written.
    Exact,
}

/// Everything that makes one pipeline differ from another.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) struct PipelineKey {
    pub pass: PassKind,
    pub features: ShaderFeatures,
    pub lights: LightCounts,
    pub vertex_layout: VertexLayout,
    pub states: RenderStates,
    pub color_format: wgpu::TextureFormat,
    pub depth_format: wgpu::TextureFormat,
    pub samples: u32,
}

/// Layouts, shader modules and every pipeline built so far.
pub(crate) struct Pipelines {
    pub scene_layout: wgpu::BindGroupLayout,
    pub camera_layout: wgpu::BindGroupLayout,
    pub material_layout: wgpu::BindGroupLayout,
    pub instance_layout: wgpu::BindGroupLayout,
    layout: wgpu::PipelineLayout,
    shadow_layout: wgpu::PipelineLayout,
    sky_layout: wgpu::PipelineLayout,
    /// Whether the forward shader reads its arrays from storage buffers (else
    /// from data textures).
    vertex_storage: bool,
    modules: HashMap<(ShaderFeatures, LightCounts), wgpu::ShaderModule>,
    sky_module: Option<wgpu::ShaderModule>,
    /// Forward and shadow pipelines; a key's index is its id in sort keys.
    forward_cache: Vec<(PipelineKey, wgpu::RenderPipeline)>,
    forward_index: HashMap<PipelineKey, u16>,
    /// Each forward pipeline's pre-pass twin (drawing into the view target's
    /// depth, or into its own), once asked for.
    prepass_of: HashMap<(u16, bool), Option<u16>>,
    /// Each forward pipeline's twin testing a shared pre-pass's depth for equality.
    equal_of: HashMap<u16, u16>,
    /// The sky shader's pipelines by target and pass.
    sky_cache: HashMap<(TargetFormat, SkyPass), wgpu::RenderPipeline>,
    /// Each forward pipeline's twin drawing it for weighted or exact
    /// transparency, once asked for (`resources/transparency_twins.rs`).
    pub(super) transparency_of: HashMap<(u16, crate::scene::Transparency), Option<u16>>,
    /// Group 1 with the fragment lists beside the Camera block, and the
    /// forward layout with it: made with the first exact twin.
    pub(super) lists: Option<(wgpu::BindGroupLayout, wgpu::PipelineLayout)>,
}

pub(crate) fn uniform_entry(binding: u32, visibility: wgpu::ShaderStages, dynamic: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: dynamic,
            min_binding_size: None,
        },
        count: None,
    }
}

fn compare(c: Compare) -> wgpu::CompareFunction {
    match c {
        Compare::Never => wgpu::CompareFunction::Never,
        Compare::Less => wgpu::CompareFunction::Less,
        Compare::LessEqual => wgpu::CompareFunction::LessEqual,
        Compare::Equal => wgpu::CompareFunction::Equal,
        Compare::GreaterEqual => wgpu::CompareFunction::GreaterEqual,
        Compare::Greater => wgpu::CompareFunction::Greater,
        Compare::NotEqual => wgpu::CompareFunction::NotEqual,
        Compare::Always => wgpu::CompareFunction::Always,
    }
}

fn stencil_op(op: StencilOp) -> wgpu::StencilOperation {
    match op {
        StencilOp::Keep => wgpu::StencilOperation::Keep,
        StencilOp::Zero => wgpu::StencilOperation::Zero,
        StencilOp::Replace => wgpu::StencilOperation::Replace,
        StencilOp::IncrementClamp => wgpu::StencilOperation::IncrementClamp,
        StencilOp::DecrementClamp => wgpu::StencilOperation::DecrementClamp,
        StencilOp::Invert => wgpu::StencilOperation::Invert,
    }
}

fn blend(b: BlendState) -> Option<wgpu::BlendState> {
    let c = |src, dst| wgpu::BlendComponent { src_factor: src, dst_factor: dst, operation: wgpu::BlendOperation::Add };
    use wgpu::BlendFactor as F;
    match b {
        BlendState::Replace => None,
        BlendState::Alpha => Some(wgpu::BlendState::ALPHA_BLENDING),
        BlendState::Additive => Some(wgpu::BlendState { color: c(F::SrcAlpha, F::One), alpha: c(F::Zero, F::One) }),
        BlendState::Multiply => Some(wgpu::BlendState { color: c(F::Dst, F::Zero), alpha: c(F::Zero, F::One) }),
    }
}

pub(crate) fn depth_stencil(states: &RenderStates, format: wgpu::TextureFormat) -> wgpu::DepthStencilState {
    let s = &states.stencil;
    let face = wgpu::StencilFaceState {
        compare: compare(s.compare),
        fail_op: stencil_op(s.fail),
        depth_fail_op: stencil_op(s.depth_fail),
        pass_op: stencil_op(s.pass),
    };
    wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(states.depth.write),
        depth_compare: Some(compare(states.depth.compare)),
        stencil: wgpu::StencilState {
            front: face,
            back: face,
            read_mask: s.read_mask.into(),
            write_mask: s.write_mask.into(),
        },
        bias: wgpu::DepthBiasState {
            constant: states.raster.depth_bias,
            slope_scale: f32::from_bits(states.raster.slope_bias_bits),
            clamp: 0.0,
        },
    }
}

/// The features a depth-only variant of a forward variant with `features`
/// keeps: those that move vertices, and for an alpha-tested material those its
/// test reads (with `tested`, more of them).
fn depth_features(features: ShaderFeatures, tested: ShaderFeatures) -> ShaderFeatures {
    let moving = ShaderFeatures::SKINNED | ShaderFeatures::COMPACT | ShaderFeatures::MOTION;
    let read = ShaderFeatures::ALPHA_MASK
        | ShaderFeatures::DIFFUSE_MAP
        | ShaderFeatures::VERTEX_COLOR
        | ShaderFeatures::UV1
        | tested;
    features & if features.contains(ShaderFeatures::ALPHA_MASK) { moving | read } else { moving }
}

impl Pipelines {
    /// Whether the shaders' arrays are storage buffers (else data textures).
    pub(crate) fn vertex_storage(&self) -> bool {
        self.vertex_storage
    }

    /// The layouts and an empty cache; the material table and the Renderer
    /// block are storage buffers when `vertex_storage`, else data textures
    /// (`render/resources/gpu_array.rs`), in the layouts and in the shaders.
    pub(crate) fn new(device: &wgpu::Device, vertex_storage: bool) -> Self {
        let all = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries })
        };
        let fragment = wgpu::ShaderStages::FRAGMENT;
        let array = |binding, visibility| gpu_array::layout_entry(binding, visibility, vertex_storage);
        let depth_texture = |binding, view_dimension| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: fragment,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Depth,
                view_dimension,
                multisampled: false,
            },
            count: None,
        };
        let scene_layout = layout(
            "renderer: scene block layout (group 0)",
            &[
                uniform_entry(0, all, false),
                uniform_entry(1, fragment, false),
                depth_texture(2, wgpu::TextureViewDimension::D2Array),
                depth_texture(3, wgpu::TextureViewDimension::D2Array),
                wgpu::BindGroupLayoutEntry {
                    binding: 4,
                    visibility: fragment,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
                    count: None,
                },
                // The environment's maps (render/passes/environment.rs).
                texture_entry(5),
                texture_entry(6),
                texture_entry(7),
                sampler_entry(8),
                // The view's ambient occlusion (render/passes/ambient_occlusion.rs).
                texture_entry(9),
                // The view's light clusters: its lists and lights (render/frame/lights.rs).
                array(10, fragment),
            ],
        );
        // One record per view, picked by a dynamic offset (render/views.rs).
        let camera_layout = layout("renderer: camera block layout (group 1)", &[uniform_entry(0, all, true)]);
        let material_layout = layout(
            "renderer: material block layout (group 2)",
            &[
                array(0, all),
                texture_entry(1),
                texture_entry(2),
                texture_entry(3),
                sampler_entry(4),
                texture_entry(5),
                texture_entry(6),
                texture_entry(7),
            ],
        );
        let vertex = wgpu::ShaderStages::VERTEX;
        let instance_layout =
            layout("renderer: renderer block layout (group 3)", &[array(0, vertex), array(1, vertex)]);
        // The sky reads groups 0–1 only and gets a layout of just those, so it can be
        // drawn before any material is bound; the forward groups 2–3 are set again after it.
        let sky_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("renderer: sky pipeline layout"),
            bind_group_layouts: &[Some(&scene_layout), Some(&camera_layout)],
            immediate_size: 0,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("renderer: forward pipeline layout"),
            bind_group_layouts: &[
                Some(&scene_layout),
                Some(&camera_layout),
                Some(&material_layout),
                Some(&instance_layout),
            ],
            immediate_size: 0,
        });
        // Shadow pipelines draw into the shadow maps group 0 samples: they go without it.
        let shadow_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("renderer: shadow pipeline layout"),
            bind_group_layouts: &[None, Some(&camera_layout), Some(&material_layout), Some(&instance_layout)],
            immediate_size: 0,
        });
        Self {
            scene_layout,
            camera_layout,
            material_layout,
            instance_layout,
            layout: pipeline_layout,
            shadow_layout,
            sky_layout,
            vertex_storage,
            modules: HashMap::new(),
            sky_module: None,
            forward_cache: Vec::new(),
            forward_index: HashMap::new(),
            prepass_of: HashMap::new(),
            equal_of: HashMap::new(),
            sky_cache: HashMap::new(),
            transparency_of: HashMap::new(),
            lists: None,
        }
    }

    /// The key of the forward pipeline drawing meshes of `vertex_layout` with a
    /// material of these features and states, lit by `lights`, on a glint target.
    /// The layout adds its own feature bits (vertex colours, second uv set, skinning).
    pub(crate) fn key(
        mut features: ShaderFeatures,
        lights: LightCounts,
        vertex_layout: VertexLayout,
        states: RenderStates,
        target: TargetFormat,
    ) -> PipelineKey {
        features.set(ShaderFeatures::VERTEX_COLOR, vertex_layout.colors);
        features.set(ShaderFeatures::UV1, vertex_layout.uv1);
        features.set(ShaderFeatures::SKINNED, vertex_layout.skin);
        features.set(ShaderFeatures::COMPACT, vertex_layout.compact);
        // Compact instances are drawn at full detail, by their number, and
        // blended ones at one level (render/lod.rs).
        let blended = features.contains(ShaderFeatures::ALPHA_BLEND);
        features.set(ShaderFeatures::LOD_FADE, vertex_layout.levels && !vertex_layout.compact && !blended);
        PipelineKey {
            pass: PassKind::Forward,
            features,
            lights,
            vertex_layout,
            states,
            color_format: target.color,
            depth_format: DEPTH_FORMAT,
            samples: target.samples,
        }
    }

    /// The key of the shadow pipeline drawing what `forward` draws into a shadow
    /// map of `pass`: only the features that move vertices, and for an
    /// alpha-tested material those its test reads, stay (so a textured and a
    /// plain material share one shadow pipeline: fewer programs to compile
    /// before a WebGL2 page's first frame); depth writes, one sample, no colour.
    pub(crate) fn shadow_key(forward: PipelineKey, pass: PassKind) -> PipelineKey {
        debug_assert!(matches!(pass, PassKind::ShadowDepth | PassKind::ShadowDistance));
        let states = RenderStates {
            depth: DepthState { compare: Compare::Less, write: true },
            raster: crate::scene::RasterState {
                cull: Cull::None,
                depth_bias: 0,
                // Depth views lean on slope-scaled bias; distance views write their own depth.
                slope_bias_bits: if pass == PassKind::ShadowDepth { SHADOW_SLOPE_BIAS.to_bits() } else { 0 },
            },
            ..Default::default()
        };
        PipelineKey {
            pass,
            features: depth_features(forward.features, ShaderFeatures::empty()),
            // Shadow maps are drawn unlit.
            lights: LightCounts::default(),
            vertex_layout: forward.vertex_layout,
            states,
            color_format: COLOR_FORMAT,
            depth_format: SHADOW_FORMAT,
            samples: 1,
        }
    }

    /// The key of the depth pre-pass pipeline drawing what `forward` draws
    /// (ambient occlusion's: `render/passes/ambient_occlusion.rs`): normal and distance
    /// into its target, and depth with the forward pipeline's own test, bias and
    /// culling, into the view target's depth when `shared` (the forward pass
    /// then tests it for equality), else into one of its own (one sample). An
    /// alpha-tested material keeps what its forward test reads, edge fade too:
    /// both passes drop the same fragments.
    pub(crate) fn prepass_key(forward: PipelineKey, shared: bool) -> PipelineKey {
        let states = RenderStates { depth: forward.states.depth, raster: forward.states.raster, ..Default::default() };
        PipelineKey {
            pass: PassKind::Prepass,
            // A cross-fade drops the same pixels from both passes.
            features: depth_features(forward.features, ShaderFeatures::EDGE_FADE)
                | (forward.features & ShaderFeatures::LOD_FADE),
            lights: LightCounts::default(),
            vertex_layout: forward.vertex_layout,
            states,
            color_format: PREPASS_FORMAT,
            depth_format: if shared { forward.depth_format } else { SHADOW_FORMAT },
            samples: if shared { forward.samples } else { 1 },
        }
    }

    /// The pre-pass pipeline drawing what forward pipeline `forward` draws,
    /// into the view target's depth when `shared` (see
    /// [`prepass_key`](Self::prepass_key)), with the forward twin that then
    /// tests that depth for equality; `None` where `forward` draws nothing into
    /// the pre-pass (blended, not writing depth, testing other than nearer, or
    /// using the stencil: its forward draw keeps its own test, and what it
    /// covers is shaded as without a pre-pass). Built on
    /// first use; returns how many pipelines were built now.
    pub(crate) fn prepass_id(
        &mut self,
        device: &wgpu::Device,
        forward: u16,
        shared: bool,
    ) -> Result<(Option<u16>, u32), ShaderError> {
        if let Some(&id) = self.prepass_of.get(&(forward, shared)) {
            return Ok((id, 0));
        }
        let key = self.key_of(forward);
        let states = key.states;
        let drawn = states.depth.write
            && matches!(states.depth.compare, Compare::Less | Compare::LessEqual)
            && states.stencil == Default::default()
            && states.blend == BlendState::Replace
            && !key.features.contains(ShaderFeatures::ALPHA_BLEND);
        let mut built = 0;
        let id = match drawn {
            true => {
                let (id, b) = self.forward_id(device, Self::prepass_key(key, shared))?;
                built += u32::from(b);
                if shared {
                    let depth = DepthState { compare: Compare::Equal, write: false };
                    let equal = PipelineKey { states: RenderStates { depth, ..states }, ..key };
                    let (twin, b) = self.forward_id(device, equal)?;
                    built += u32::from(b);
                    self.equal_of.insert(forward, twin);
                }
                Some(id)
            }
            false => None,
        };
        self.prepass_of.insert((forward, shared), id);
        Ok((id, built))
    }

    /// The pre-pass pipeline of forward pipeline `forward`, once
    /// [`prepass_id`](Self::prepass_id) made it (`None`: it draws nothing there).
    pub(crate) fn prepass_of(&self, forward: u16, shared: bool) -> Option<u16> {
        self.prepass_of.get(&(forward, shared)).copied().flatten()
    }

    /// The twin of forward pipeline `forward` that tests a shared pre-pass's
    /// depth for equality and writes none, once [`prepass_id`](Self::prepass_id)
    /// made it (`None`: `forward` itself draws, with its own test).
    pub(crate) fn equal_of(&self, forward: u16) -> Option<u16> {
        self.equal_of.get(&forward).copied()
    }

    /// The id of the forward pipeline for `key`, building it (and its shader variant)
    /// on first use. Returns whether it was built now.
    pub(crate) fn forward_id(&mut self, device: &wgpu::Device, key: PipelineKey) -> Result<(u16, bool), ShaderError> {
        if let Some(&id) = self.forward_index.get(&key) {
            return Ok((id, false));
        }
        let label = format!("renderer: forward shader {:?} {:?}", key.features, key.lights);
        let scope = DriverErrors::watch(device);
        let variant = (key.features, key.lights);
        if !self.modules.contains_key(&variant) {
            let wgsl = crate::shader::forward(key.features, key.lights, self.vertex_storage);
            self.modules.insert(variant, shader_module(device, &label, wgsl));
        }
        let pipeline = self.build_forward(device, key);
        if let Some(error) = scope.finish() {
            self.modules.remove(&variant);
            return Err(ShaderError::refused(&label, &error));
        }
        let id = self.forward_cache.len() as u16;
        self.forward_cache.push((key, pipeline));
        self.forward_index.insert(key, id);
        Ok((id, true))
    }

    /// The key a pipeline id was built for.
    pub(crate) fn key_of(&self, id: u16) -> PipelineKey {
        self.forward_cache[id as usize].0
    }

    pub(crate) fn forward(&self, id: u16) -> &wgpu::RenderPipeline {
        &self.forward_cache[id as usize].1
    }

    /// The stencil reference a pipeline's draws use.
    pub(crate) fn stencil_reference(&self, id: u16) -> u32 {
        self.forward_cache[id as usize].0.states.stencil.reference.into()
    }

    /// The sky or glare pipeline for `target`, if [`Self::build_sky`] built it.
    pub(crate) fn sky_built(&self, target: TargetFormat, pass: SkyPass) -> Option<&wgpu::RenderPipeline> {
        self.sky_cache.get(&(target, pass))
    }

    /// Build the sky or glare pipeline for `target` unless it exists; returns
    /// whether it was built now.
    pub(crate) fn build_sky(
        &mut self,
        device: &wgpu::Device,
        target: TargetFormat,
        pass: SkyPass,
    ) -> Result<bool, ShaderError> {
        if self.sky_cache.contains_key(&(target, pass)) {
            return Ok(false);
        }
        let scope = DriverErrors::watch(device);
        if self.sky_module.is_none() {
            self.sky_module = Some(shader_module(device, "renderer: sky shader", crate::shader::sky()));
        }
        let module = self.sky_module.as_ref().expect("built above");
        // The sky behind what was drawn; the glare added over everything.
        let (compare, entry, blend) = match pass {
            SkyPass::Gradient => (Compare::LessEqual, "fs_sky", None),
            SkyPass::Environment => (Compare::LessEqual, "fs_sky_environment", None),
            SkyPass::Glare => {
                let add = wgpu::BlendComponent {
                    src_factor: wgpu::BlendFactor::One,
                    dst_factor: wgpu::BlendFactor::One,
                    operation: wgpu::BlendOperation::Add,
                };
                (Compare::Always, "fs_glare", Some(wgpu::BlendState { color: add, alpha: add }))
            }
        };
        let states = RenderStates { depth: crate::scene::DepthState { compare, write: false }, ..Default::default() };
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(match pass {
                SkyPass::Gradient => "renderer: sky pipeline",
                SkyPass::Environment => "renderer: environment sky pipeline",
                SkyPass::Glare => "renderer: glare pipeline",
            }),
            layout: Some(&self.sky_layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some("vs_sky"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(depth_stencil(&states, DEPTH_FORMAT)),
            multisample: wgpu::MultisampleState { count: target.samples, ..Default::default() },
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: target.color,
                    blend,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        if let Some(error) = scope.finish() {
            self.sky_module = None;
            return Err(ShaderError::refused("renderer: sky shader", &error));
        }
        self.sky_cache.insert((target, pass), pipeline);
        Ok(true)
    }

    fn build_forward(&self, device: &wgpu::Device, key: PipelineKey) -> wgpu::RenderPipeline {
        let buffers: Vec<_> = key
            .vertex_layout
            .streams()
            .map(|s| {
                Some(wgpu::VertexBufferLayout {
                    array_stride: s.stride().into(),
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: s.attributes(),
                })
            })
            .collect();
        let module = &self.modules[&(key.features, key.lights)];
        let label =
            format!("renderer: {:?} pipeline {:?} {:?} {}x", key.pass, key.features, key.states.blend, key.samples);
        let targets = [Some(wgpu::ColorTargetState {
            format: key.color_format,
            blend: blend(key.states.blend),
            write_mask: wgpu::ColorWrites::ALL,
        })];
        let weighted = super::transparency_twins::WEIGHTED_FORMATS.map(|format| {
            Some(wgpu::ColorTargetState {
                format,
                blend: Some(super::transparency_twins::WEIGHTED_BLEND),
                write_mask: wgpu::ColorWrites::ALL,
            })
        });
        let lists = self.lists.as_ref().map(|(_, layout)| layout);
        let alpha_tested = key.features.contains(ShaderFeatures::ALPHA_MASK);
        let (layout, fragment, targets): (_, _, &[_]) = match key.pass {
            PassKind::Forward => (&self.layout, Some("fs_main"), &targets),
            PassKind::ShadowDepth => (&self.shadow_layout, alpha_tested.then_some("fs_shadow_mask"), &[]),
            PassKind::ShadowDistance => (&self.shadow_layout, Some("fs_shadow_distance"), &[]),
            PassKind::Prepass => (&self.shadow_layout, Some("fs_prepass"), &targets),
            PassKind::Weighted => (&self.layout, Some("fs_weighted"), &weighted),
            // Made before any exact twin (else the layout refuses `fs_exact`'s lists).
            PassKind::Exact => (lists.unwrap_or(&self.layout), Some("fs_exact"), &[]),
        };
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(&label),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &buffers,
            },
            primitive: wgpu::PrimitiveState {
                front_face: wgpu::FrontFace::Ccw,
                cull_mode: match key.states.raster.cull {
                    Cull::Back => Some(wgpu::Face::Back),
                    Cull::Front => Some(wgpu::Face::Front),
                    Cull::None => None,
                },
                ..Default::default()
            },
            depth_stencil: Some(depth_stencil(&key.states, key.depth_format)),
            multisample: wgpu::MultisampleState { count: key.samples, ..Default::default() },
            fragment: fragment.map(|entry| wgpu::FragmentState {
                module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    }
}

/// The module of one of the composed shaders' WGSL (`crate::shader`).
pub(crate) fn shader_module(device: &wgpu::Device, label: &str, wgsl: String) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(wgsl.into()),
    })
}
