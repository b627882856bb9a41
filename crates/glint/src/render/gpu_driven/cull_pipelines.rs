//! Core layer: [`CullPipelines`], the compute pipelines of GPU culling
//! (`shader/cull.wgsl`): the frustum cull and compact passes, and, where the
//! device has storage textures, occlusion culling's early and late passes and
//! its depth pyramid's.

use crate::gpu::compute_pipeline;
use crate::render::gpu_driven::occlusion::PyramidPipelines;

/// The occlusion-culling pipelines: both phases' cull passes and the pyramid.
pub(crate) struct OcclusionPipelines {
    pub layout: wgpu::BindGroupLayout,
    pub early: wgpu::ComputePipeline,
    pub late: wgpu::ComputePipeline,
    pub pyramid: PyramidPipelines,
}

/// The cull and compact compute pipelines, one pair per renderer, and the
/// occlusion culling ones where the device has storage textures.
pub(crate) struct CullPipelines {
    pub cull_layout: wgpu::BindGroupLayout,
    pub compact_layout: wgpu::BindGroupLayout,
    pub cull: wgpu::ComputePipeline,
    pub compact: wgpu::ComputePipeline,
    pub occlusion: Option<OcclusionPipelines>,
    /// Whether runs draw with a count buffer.
    pub draw_count: bool,
    /// Whether views culled on the GPU are occlusion-culled ([`Renderer::set_occlusion_culling`](crate::render::Renderer::set_occlusion_culling)).
    pub occlusion_on: bool,
}

impl CullPipelines {
    /// The pipelines, with occlusion culling's when `occlusion`.
    pub(crate) fn new(device: &wgpu::Device, occlusion: bool) -> Self {
        let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty,
            count: None,
        };
        let storage = |binding, read_only| {
            entry(
                binding,
                wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
            )
        };
        let uniform = wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        };
        let cull_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("gpu culling: candidates"),
            entries: &[
                entry(0, uniform),
                storage(1, true),
                storage(2, true),
                storage(3, true),
                storage(4, false),
                storage(5, false),
                storage(6, false),
            ],
        });
        let compact_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("gpu culling: runs"),
            entries: &[storage(0, true), storage(1, false)],
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("cull.wgsl"),
            source: wgpu::ShaderSource::Wgsl(crate::shader::CULL.into()),
        });
        let pipeline =
            |entry, layouts: &[Option<&wgpu::BindGroupLayout>]| compute_pipeline(device, &module, entry, layouts);
        let occlusion = occlusion.then(|| {
            let texture = wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            };
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("gpu culling: occlusion"),
                entries: &[storage(0, false), entry(1, texture), entry(2, uniform)],
            });
            OcclusionPipelines {
                early: pipeline("cull_early", &[Some(&cull_layout), None, Some(&layout)]),
                late: pipeline("cull_late", &[Some(&cull_layout), None, Some(&layout)]),
                pyramid: PyramidPipelines::new(device),
                layout,
            }
        });
        Self {
            cull: pipeline("cull", &[Some(&cull_layout)]),
            compact: pipeline("compact", &[Some(&cull_layout), Some(&compact_layout)]),
            cull_layout,
            compact_layout,
            occlusion,
            draw_count: device.features().contains(wgpu::Features::MULTI_DRAW_INDIRECT_COUNT),
            occlusion_on: true,
        }
    }

    /// Whether views culled on the GPU are occlusion-culled too.
    pub(crate) fn occlusion(&self) -> bool {
        self.occlusion.is_some() && self.occlusion_on
    }
}
