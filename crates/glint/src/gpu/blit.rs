//! Core layer: drawing one texture over another with a full-screen triangle
//! through a linear sampler. Mip generation (each level from the one above) and
//! showing frames in a window both use it.

/// The blit shader, its bind group layout (texture, sampler) and sampler; one
/// pipeline per target format comes from [`Blitter::pipeline`].
pub(crate) struct Blitter {
    layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    module: wgpu::ShaderModule,
    sampler: wgpu::Sampler,
}

impl Blitter {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("blit: source layout"),
            entries: &[texture_entry(0), sampler_entry(1)],
        });
        Self {
            pipeline_layout: device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("blit: pipeline layout"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            }),
            layout,
            module: device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("blit: shader"),
                source: wgpu::ShaderSource::Wgsl(crate::shader::BLIT.into()),
            }),
            sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("blit: sampler"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..Default::default()
            }),
        }
    }

    /// A pipeline drawing into targets of `format`.
    pub(crate) fn pipeline(&self, device: &wgpu::Device, format: wgpu::TextureFormat) -> wgpu::RenderPipeline {
        let label = format!("blit: pipeline ({format:?})");
        full_screen_pipeline(device, &label, (&self.pipeline_layout, &self.module), ("vs_blit", "fs_blit"), format)
    }

    /// Record a pass drawing `source` over all of `target` with `pipeline` (made
    /// by [`Blitter::pipeline`] for `target`'s format).
    pub(crate) fn blit(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::RenderPipeline,
        source: &wgpu::TextureView,
        target: &wgpu::TextureView,
    ) {
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("blit: source"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(source) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&self.sampler) },
            ],
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("blit"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
            })],
            ..Default::default()
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.draw(0..3, 0..1);
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

/// A fragment-stage storage buffer binding, read-only or not.
pub(crate) fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
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

/// A pipeline of one full-screen triangle (its `vertex` entry makes it from the
/// vertex index: no vertex buffers) shaded by `fragment` into one target of
/// `format`, without depth or blending: the blits', the post chain's and the
/// environment prefilter's passes.
pub(crate) fn full_screen_pipeline(
    device: &wgpu::Device,
    label: &str,
    shader: (&wgpu::PipelineLayout, &wgpu::ShaderModule),
    entries: (&str, &str),
    format: wgpu::TextureFormat,
) -> wgpu::RenderPipeline {
    full_screen_pipeline_with(device, label, shader, entries, format, None)
}

/// [`full_screen_pipeline`] with a depth-stencil state (SMAA's passes mark
/// and test the pixels on edges in a stencil).
pub(crate) fn full_screen_pipeline_with(
    device: &wgpu::Device,
    label: &str,
    (layout, module): (&wgpu::PipelineLayout, &wgpu::ShaderModule),
    (vertex, fragment): (&str, &str),
    format: wgpu::TextureFormat,
    depth_stencil: Option<wgpu::DepthStencilState>,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(vertex),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fragment),
            compilation_options: Default::default(),
            targets: &[Some(format.into())],
        }),
        multiview_mask: None,
        cache: None,
    })
}
