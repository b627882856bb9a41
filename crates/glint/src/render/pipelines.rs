//! Core layer: bind-group layouts (one per block of the convention in
//! `render/mod.rs`), the shared pipeline layout, and the pipeline cache.

use crate::gpu::{COLOR_FORMAT, DEPTH_FORMAT};
use crate::scene::{AlphaMode, Material, Vertex};
use std::collections::HashMap;

/// What makes one forward pipeline differ from another.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) struct PipelineKey {
    /// Alpha blending on, depth writes off.
    pub blend: bool,
    /// Back faces drawn (no culling).
    pub double_sided: bool,
    /// MSAA samples of the target.
    pub samples: u32,
}

impl PipelineKey {
    pub(crate) fn for_material(material: &Material, samples: u32) -> Self {
        Self { blend: material.alpha_mode == AlphaMode::Blend, double_sided: material.double_sided, samples }
    }
}

/// Layouts, shader modules and every pipeline built so far.
pub(crate) struct Pipelines {
    pub scene_layout: wgpu::BindGroupLayout,
    pub camera_layout: wgpu::BindGroupLayout,
    pub material_layout: wgpu::BindGroupLayout,
    pub instance_layout: wgpu::BindGroupLayout,
    layout: wgpu::PipelineLayout,
    forward: wgpu::ShaderModule,
    sky: wgpu::ShaderModule,
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

impl Pipelines {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let all = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries })
        };
        let scene_layout = layout("renderer: scene block layout (group 0)", &[uniform_entry(0, all)]);
        let camera_layout = layout("renderer: camera block layout (group 1)", &[uniform_entry(0, all)]);
        let material_layout = layout(
            "renderer: material block layout (group 2)",
            &[uniform_entry(0, all), texture_entry(1), texture_entry(2), texture_entry(3), sampler_entry(4)],
        );
        let storage = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::VERTEX,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let instance_layout = layout("renderer: renderer block layout (group 3)", &[storage(0), storage(1)]);
        // One layout for every pass: the sky uses groups 0–1 of it, so switching
        // between sky and forward pipelines never disturbs bound groups.
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
        let module = |label, source: String| {
            device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            })
        };
        Self {
            forward: module("renderer: forward shader", crate::shader::forward()),
            sky: module("renderer: sky shader", crate::shader::sky()),
            scene_layout,
            camera_layout,
            material_layout,
            instance_layout,
            layout: pipeline_layout,
            forward_cache: Vec::new(),
            forward_index: HashMap::new(),
            sky_cache: HashMap::new(),
        }
    }

    /// The id of the forward pipeline for `key`, building it on first use.
    /// Returns whether it was built now.
    pub(crate) fn forward_id(&mut self, device: &wgpu::Device, key: PipelineKey) -> (u16, bool) {
        if let Some(&id) = self.forward_index.get(&key) {
            return (id, false);
        }
        let pipeline = self.build_forward(device, key);
        let id = self.forward_cache.len() as u16;
        self.forward_cache.push((key, pipeline));
        self.forward_index.insert(key, id);
        (id, true)
    }

    pub(crate) fn forward(&self, id: u16) -> &wgpu::RenderPipeline {
        &self.forward_cache[id as usize].1
    }

    /// The sky pipeline for `samples`, if [`Self::sky`] built it.
    pub(crate) fn sky_built(&self, samples: u32) -> Option<&wgpu::RenderPipeline> {
        self.sky_cache.get(&samples)
    }

    /// The sky pipeline for `samples`, building it on first use.
    pub(crate) fn sky(&mut self, device: &wgpu::Device, samples: u32) -> &wgpu::RenderPipeline {
        let (layout, module) = (&self.layout, &self.sky);
        self.sky_cache.entry(samples).or_insert_with(|| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("renderer: sky pipeline"),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module,
                    entry_point: Some("vs_sky"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: Some(depth_state(false, wgpu::CompareFunction::LessEqual)),
                multisample: wgpu::MultisampleState { count: samples, ..Default::default() },
                fragment: Some(wgpu::FragmentState {
                    module,
                    entry_point: Some("fs_sky"),
                    compilation_options: Default::default(),
                    targets: &[Some(COLOR_FORMAT.into())],
                }),
                multiview_mask: None,
                cache: None,
            })
        })
    }

    fn build_forward(&self, device: &wgpu::Device, key: PipelineKey) -> wgpu::RenderPipeline {
        const ATTRIBUTES: [wgpu::VertexAttribute; 4] =
            wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32x4];
        let label = format!(
            "renderer: forward pipeline ({}, {}, {}x)",
            if key.blend { "blend" } else { "opaque" },
            if key.double_sided { "double-sided" } else { "back-face culled" },
            key.samples
        );
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(&label),
            layout: Some(&self.layout),
            vertex: wgpu::VertexState {
                module: &self.forward,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<Vertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &ATTRIBUTES,
                })],
            },
            primitive: wgpu::PrimitiveState {
                front_face: wgpu::FrontFace::Ccw,
                cull_mode: if key.double_sided { None } else { Some(wgpu::Face::Back) },
                ..Default::default()
            },
            depth_stencil: Some(depth_state(!key.blend, wgpu::CompareFunction::Less)),
            multisample: wgpu::MultisampleState { count: key.samples, ..Default::default() },
            fragment: Some(wgpu::FragmentState {
                module: &self.forward,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: COLOR_FORMAT,
                    blend: key.blend.then_some(wgpu::BlendState::ALPHA_BLENDING),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        })
    }
}

fn depth_state(write: bool, compare: wgpu::CompareFunction) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(write),
        depth_compare: Some(compare),
        stencil: Default::default(),
        bias: Default::default(),
    }
}
