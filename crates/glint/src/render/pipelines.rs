//! Core layer: bind-group layouts (one per block of the convention in
//! `render/mod.rs`), the shared pipeline layout, and the pipeline cache.
//!
//! A forward pipeline is identified by its [`PipelineKey`]: the shader variant
//! (macro set), the vertex layout, the four render-state objects and the target
//! formats. Shader modules are cached per macro set, pipelines per key; a key's
//! index in the cache is its id in sort keys.

use crate::gpu::{COLOR_FORMAT, DEPTH_FORMAT};
use crate::scene::{BlendState, Compare, Cull, Mesh, RenderStates, StencilOp, Vertex};
use crate::shader::{ShaderError, ShaderFeatures, ShaderLibrary};
use std::borrow::Cow;
use std::collections::HashMap;

/// Vertex buffer layouts a pipeline can read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum VertexLayout {
    /// [`Vertex`]: position, normal, uv, tangent in one interleaved buffer.
    Standard,
    /// [`Vertex`] in buffer 0 and a linear RGBA colour (`@location(4)`) in buffer 1.
    Colored,
}

impl VertexLayout {
    /// The layout a mesh's streams need.
    pub(crate) fn of(mesh: &Mesh) -> Self {
        if mesh.colors().is_some() {
            Self::Colored
        } else {
            Self::Standard
        }
    }

    /// Bytes per vertex of each stream (vertex buffer slot).
    pub(crate) fn strides(self) -> &'static [u32] {
        const VERTEX: u32 = std::mem::size_of::<Vertex>() as u32;
        match self {
            Self::Standard => &[VERTEX],
            Self::Colored => &[VERTEX, 16],
        }
    }
}

/// Everything that makes one forward pipeline differ from another.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) struct PipelineKey {
    pub features: ShaderFeatures,
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
    sky_layout: wgpu::PipelineLayout,
    library: ShaderLibrary,
    modules: HashMap<ShaderFeatures, wgpu::ShaderModule>,
    sky_module: Option<wgpu::ShaderModule>,
    /// Forward pipelines; a key's index is its id in sort keys.
    forward_cache: Vec<(PipelineKey, wgpu::RenderPipeline)>,
    forward_index: HashMap<PipelineKey, u16>,
    /// Sky pipelines by sample count.
    sky_cache: HashMap<u32, wgpu::RenderPipeline>,
}

fn uniform_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A fragment-stage, filterable 2D texture binding.
pub(crate) fn texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// A fragment-stage filtering sampler binding.
pub(crate) fn sampler_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
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

fn depth_stencil(states: &RenderStates) -> wgpu::DepthStencilState {
    let s = &states.stencil;
    let face = wgpu::StencilFaceState {
        compare: compare(s.compare),
        fail_op: stencil_op(s.fail),
        depth_fail_op: stencil_op(s.depth_fail),
        pass_op: stencil_op(s.pass),
    };
    wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
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

impl Pipelines {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let all = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries })
        };
        let scene_layout = layout("renderer: scene block layout (group 0)", &[uniform_entry(0, all)]);
        let camera_layout = layout("renderer: camera block layout (group 1)", &[uniform_entry(0, all)]);
        let storage = |binding, visibility| wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let material_layout = layout(
            "renderer: material block layout (group 2)",
            &[
                storage(0, all),
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
            layout("renderer: renderer block layout (group 3)", &[storage(0, vertex), storage(1, vertex)]);
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
        Self {
            scene_layout,
            camera_layout,
            material_layout,
            instance_layout,
            layout: pipeline_layout,
            sky_layout,
            library: ShaderLibrary::new(),
            modules: HashMap::new(),
            sky_module: None,
            forward_cache: Vec::new(),
            forward_index: HashMap::new(),
            sky_cache: HashMap::new(),
        }
    }

    /// The key of the forward pipeline drawing meshes of `vertex_layout` with a
    /// material of these features and states on a glint target. The layout adds its
    /// own feature bits (vertex colours).
    pub(crate) fn key(
        mut features: ShaderFeatures,
        vertex_layout: VertexLayout,
        states: RenderStates,
        samples: u32,
    ) -> PipelineKey {
        features.set(ShaderFeatures::VERTEX_COLOR, vertex_layout == VertexLayout::Colored);
        PipelineKey { features, vertex_layout, states, color_format: COLOR_FORMAT, depth_format: DEPTH_FORMAT, samples }
    }

    /// The id of the forward pipeline for `key`, building it (and its shader variant)
    /// on first use. Returns whether it was built now.
    pub(crate) fn forward_id(&mut self, device: &wgpu::Device, key: PipelineKey) -> Result<(u16, bool), ShaderError> {
        if let Some(&id) = self.forward_index.get(&key) {
            return Ok((id, false));
        }
        if !self.modules.contains_key(&key.features) {
            let module = self.library.forward(key.features)?;
            let label = format!("renderer: forward shader {:?}", key.features);
            self.modules.insert(key.features, shader_module(device, &label, module));
        }
        let pipeline = self.build_forward(device, key);
        let id = self.forward_cache.len() as u16;
        self.forward_cache.push((key, pipeline));
        self.forward_index.insert(key, id);
        Ok((id, true))
    }

    pub(crate) fn forward(&self, id: u16) -> &wgpu::RenderPipeline {
        &self.forward_cache[id as usize].1
    }

    /// The stencil reference a pipeline's draws use.
    pub(crate) fn stencil_reference(&self, id: u16) -> u32 {
        self.forward_cache[id as usize].0.states.stencil.reference.into()
    }

    /// The sky pipeline for `samples`, if [`Self::build_sky`] built it.
    pub(crate) fn sky_built(&self, samples: u32) -> Option<&wgpu::RenderPipeline> {
        self.sky_cache.get(&samples)
    }

    /// Build the sky pipeline for `samples` unless it exists; returns whether it was built now.
    pub(crate) fn build_sky(&mut self, device: &wgpu::Device, samples: u32) -> Result<bool, ShaderError> {
        if self.sky_cache.contains_key(&samples) {
            return Ok(false);
        }
        if self.sky_module.is_none() {
            let module = self.library.sky()?;
            self.sky_module = Some(shader_module(device, "renderer: sky shader", module));
        }
        let module = self.sky_module.as_ref().expect("built above");
        let states = RenderStates {
            depth: crate::scene::DepthState { compare: Compare::LessEqual, write: false },
            ..Default::default()
        };
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("renderer: sky pipeline"),
            layout: Some(&self.sky_layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some("vs_sky"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(depth_stencil(&states)),
            multisample: wgpu::MultisampleState { count: samples, ..Default::default() },
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some("fs_sky"),
                compilation_options: Default::default(),
                targets: &[Some(COLOR_FORMAT.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        self.sky_cache.insert(samples, pipeline);
        Ok(true)
    }

    fn build_forward(&self, device: &wgpu::Device, key: PipelineKey) -> wgpu::RenderPipeline {
        const ATTRIBUTES: [wgpu::VertexAttribute; 4] =
            wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32x4];
        const COLOR: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![4 => Float32x4];
        let stream = |stride: u32, attributes| {
            Some(wgpu::VertexBufferLayout {
                array_stride: stride.into(),
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes,
            })
        };
        let strides = key.vertex_layout.strides();
        let buffers = match key.vertex_layout {
            VertexLayout::Standard => vec![stream(strides[0], &ATTRIBUTES[..])],
            VertexLayout::Colored => vec![stream(strides[0], &ATTRIBUTES[..]), stream(strides[1], &COLOR[..])],
        };
        let module = &self.modules[&key.features];
        let label = format!("renderer: forward pipeline {:?} {:?} {}x", key.features, key.states.blend, key.samples);
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(&label),
            layout: Some(&self.layout),
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
            depth_stencil: Some(depth_stencil(&key.states)),
            multisample: wgpu::MultisampleState { count: key.samples, ..Default::default() },
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: key.color_format,
                    blend: blend(key.states.blend),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        })
    }
}

fn shader_module(device: &wgpu::Device, label: &str, module: wgpu::naga::Module) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Naga(Cow::Owned(module)),
    })
}
