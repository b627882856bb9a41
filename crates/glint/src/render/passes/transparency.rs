//! Core layer: order-independent transparency's targets and composites
//! ([`Transparency::Weighted`] and [`Transparency::Exact`]; sorted
//! transparency needs neither). A view's blended materials are left out of
//! its forward pass and drawn, in any order, by their twins
//! (`resources/transparency_twins.rs`) in a pass of their own
//! (`frame/transparency.rs`); the composite then blends the result over the
//! picture, first in the pass that ends the view (particles and glare after).
//!
//! - **Weighted** (McGuire and Bavoil 2013): two half-float targets at the
//!   view's samples, resolved to one: `Rgba16Float` holds Σ colour × alpha ×
//!   weight (rgb) and the revealage Π(1 − alpha) (a); `R16Float` Σ alpha ×
//!   weight. Both take `WEIGHTED_BLEND` (`resources/transparency_twins.rs`,
//!   beside the twins that draw into them): WebGL2 has no blend state per
//!   target. Memory: 10 bytes a pixel a sample, and 10 a pixel resolved.
//! - **Exact**: per-pixel lists in storage buffers. The heads (4 bytes a
//!   pixel, and the count of nodes taken) and the nodes (16 bytes: the colour
//!   as four half floats, the depth, the next node), [`NODES_PER_PIXEL`] a
//!   pixel, as many as one storage binding holds. Under MSAA the shaders run
//!   per sample and sample 0 alone appends (one fragment of a surface a
//!   pixel). The composite sorts each pixel's nearest 32 fragments and
//!   blends them; fragments past the nodes are dropped (the count read back
//!   by `glint explain` says when).

use crate::gpu::{storage_entry, DriverErrors, TargetFormat, DEPTH_FORMAT};
use crate::render::error::RenderError;
use crate::render::resources::pipelines::{shader_module, uniform_entry};
use crate::render::resources::transparency_twins::WEIGHTED_FORMATS;
use crate::scene::Transparency;
use std::collections::HashMap;

/// Nodes a view's lists hold per pixel on average (fewer where one storage
/// binding cannot hold them).
pub(crate) const NODES_PER_PIXEL: u64 = 8;

/// Bytes of one list node.
const NODE_BYTES: u64 = 16;

/// What the device can draw, and the composites built so far.
pub(crate) struct TransparencyPasses {
    /// Weighted at one sample, and at four.
    weighted: [bool; 2],
    /// Exact ([`Gpu::fragment_lists`](crate::Gpu::fragment_lists)).
    exact: bool,
    /// The largest storage binding: what the nodes may take.
    max_binding: u64,
    /// Each composite's group 0 (weighted's textures, exact's lists), made
    /// with its first pipeline.
    layouts: HashMap<Transparency, (wgpu::BindGroupLayout, wgpu::PipelineLayout, wgpu::ShaderModule)>,
    pipelines: HashMap<(TargetFormat, Transparency), wgpu::RenderPipeline>,
}

impl TransparencyPasses {
    /// Nothing built yet; what `gpu` can draw.
    pub(crate) fn new(gpu: &crate::Gpu) -> Self {
        let msaa = WEIGHTED_FORMATS.iter().all(|&format| {
            let flags = gpu.adapter.get_texture_format_features(format).flags;
            flags.sample_count_supported(4) && flags.contains(wgpu::TextureFormatFeatureFlags::MULTISAMPLE_RESOLVE)
        });
        let weighted = gpu.blends_half_floats();
        Self {
            weighted: [weighted, weighted && msaa],
            exact: gpu.fragment_lists(),
            max_binding: gpu.device.limits().max_storage_buffer_binding_size,
            layouts: HashMap::new(),
            pipelines: HashMap::new(),
        }
    }

    /// How a view asking for `wanted` into a target of `samples` draws here:
    /// weighted stays sorted where half floats do not blend (or not at those
    /// samples); exact is an error where fragment shaders cannot keep lists.
    pub(crate) fn way(&self, wanted: Transparency, samples: u32) -> Result<Transparency, RenderError> {
        match wanted {
            Transparency::Weighted if !self.weighted[usize::from(samples > 1)] => Ok(Transparency::Sorted),
            Transparency::Exact if !self.exact => Err(RenderError::Unavailable {
                what: "exact transparency",
                why: "it keeps per-pixel lists in storage buffers, which fragment shaders here cannot write \
                      (the WebGL2 path, and WebGPU in browsers); use weighted or sorted",
            }),
            way => Ok(way),
        }
    }

    /// Build the composite of `way` into `target` unless it exists; returns
    /// how many pipelines were built now.
    pub(crate) fn prepare(
        &mut self,
        device: &wgpu::Device,
        target: TargetFormat,
        way: Transparency,
    ) -> Result<u32, RenderError> {
        if self.pipelines.contains_key(&(target, way)) {
            return Ok(0);
        }
        let scope = DriverErrors::watch(device);
        let (_, layout, module) = self.layouts.entry(way).or_insert_with(|| composite_layout(device, way));
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(match way {
                Transparency::Exact => "transparency: exact composite",
                _ => "transparency: weighted composite",
            }),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some("vs_composite"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            // The pass that ends the view reads the depth: tested by nothing, written never.
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(false),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: wgpu::MultisampleState { count: target.samples, ..Default::default() },
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some("fs_composite"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: target.color,
                    blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        if let Some(error) = scope.finish() {
            self.layouts.remove(&way);
            return Err(RenderError::Device { what: "the transparency composite", message: error.to_string() });
        }
        self.pipelines.insert((target, way), pipeline);
        Ok(1)
    }

    /// A view's targets for `way` (not sorted) at `size` × `samples`, once
    /// [`prepare`](Self::prepare) built its composite; exact's lists read
    /// the Camera block `camera` in their group 1 (`lists_layout`, given for exact).
    pub(crate) fn targets(
        &self,
        device: &wgpu::Device,
        (way, size, samples): (Transparency, (u32, u32), u32),
        (lists_layout, camera): (Option<&wgpu::BindGroupLayout>, wgpu::BindingResource),
    ) -> Result<TransparencyTargets, RenderError> {
        let failed = |message: String| RenderError::Device { what: "a view's transparency targets", message };
        let (composite, ..) = self.layouts.get(&way).ok_or_else(|| failed(format!("no {} composite", way.name())))?;
        let scope = DriverErrors::watch(device);
        let targets = match (way, lists_layout) {
            (Transparency::Exact, Some(lists)) => TransparencyTargets::Exact(FragmentLists::new(
                device,
                (size, samples, self.max_binding),
                (lists, camera, composite),
            )?),
            (Transparency::Exact, None) => return Err(failed("no layout for the fragment lists".into())),
            _ => TransparencyTargets::Weighted(Box::new(WeightedTargets::new(device, composite, size, samples))),
        };
        match scope.finish() {
            Some(error) => Err(failed(error.to_string())),
            None => Ok(targets),
        }
    }

    /// The composite of `way` into `target`, once [`prepare`](Self::prepare) built it.
    pub(crate) fn composite(&self, target: TargetFormat, way: Transparency) -> Option<&wgpu::RenderPipeline> {
        self.pipelines.get(&(target, way))
    }
}

/// The composite's group 0 layout, pipeline layout and shader for `way`.
fn composite_layout(
    device: &wgpu::Device,
    way: Transparency,
) -> (wgpu::BindGroupLayout, wgpu::PipelineLayout, wgpu::ShaderModule) {
    let fragment = wgpu::ShaderStages::FRAGMENT;
    let texture = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: fragment,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    };
    let (entries, source) = match way {
        Transparency::Exact => (
            vec![storage_entry(0, true), storage_entry(1, true), uniform_entry(2, fragment, false)],
            crate::shader::TRANSPARENCY_LISTS,
        ),
        _ => (vec![texture(0), texture(1)], crate::shader::TRANSPARENCY),
    };
    let group = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("transparency: composite layout"),
        entries: &entries,
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("transparency: composite pipeline layout"),
        bind_group_layouts: &[Some(&group)],
        immediate_size: 0,
    });
    let module = shader_module(device, "transparency: composite shader", source.to_string());
    (group, layout, module)
}

/// A view's weighted sums or fragment lists, kept between frames while its
/// size, samples and way stay.
pub(crate) enum TransparencyTargets {
    Weighted(Box<WeightedTargets>),
    Exact(FragmentLists),
}

impl TransparencyTargets {
    /// Whether these are the targets of `way` at `size` × `samples`.
    pub(crate) fn fits(&self, way: Transparency, size: (u32, u32), samples: u32) -> bool {
        match self {
            Self::Weighted(w) => way == Transparency::Weighted && (w.size, w.samples) == (size, samples),
            Self::Exact(l) => way == Transparency::Exact && (l.size, l.samples) == (size, samples),
        }
    }

    /// Which way they draw.
    pub(crate) fn way(&self) -> Transparency {
        match self {
            Self::Weighted(_) => Transparency::Weighted,
            Self::Exact(_) => Transparency::Exact,
        }
    }

    /// The composite's group 0.
    pub(crate) fn composite_group(&self) -> &wgpu::BindGroup {
        match self {
            Self::Weighted(w) => &w.group,
            Self::Exact(l) => &l.composite,
        }
    }
}

/// Weighted transparency's two targets: drawn at the view's samples
/// (render attachments only: GL then makes them renderbuffers, where
/// llvmpipe writes nothing into a second multisampled texture attachment),
/// resolved to one sample for the composite.
pub(crate) struct WeightedTargets {
    size: (u32, u32),
    samples: u32,
    drawn: [wgpu::TextureView; 2],
    resolved: Option<[wgpu::TextureView; 2]>,
    group: wgpu::BindGroup,
}

impl WeightedTargets {
    fn new(device: &wgpu::Device, layout: &wgpu::BindGroupLayout, (width, height): (u32, u32), samples: u32) -> Self {
        let image = |format, samples, usage| {
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("transparency: weighted sums"),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            });
            texture.create_view(&Default::default())
        };
        let read = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let (drawn, resolved) = match samples {
            1 => (WEIGHTED_FORMATS.map(|f| image(f, 1, read)), None),
            n => (
                WEIGHTED_FORMATS.map(|f| image(f, n, wgpu::TextureUsages::RENDER_ATTACHMENT)),
                Some(WEIGHTED_FORMATS.map(|f| image(f, 1, read))),
            ),
        };
        let read = resolved.as_ref().unwrap_or(&drawn);
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("transparency: weighted composite group"),
            layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&read[0]) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&read[1]) },
            ],
        });
        Self { size: (width, height), samples, drawn, resolved, group }
    }

    /// The accumulation pass's colour attachments: cleared to no sums and
    /// full revealage, resolved where multisampled.
    pub(crate) fn attachments(&self) -> [Option<wgpu::RenderPassColorAttachment<'_>>; 2] {
        let clear = [wgpu::Color { r: 0.0, g: 0.0, b: 0.0, a: 1.0 }, wgpu::Color::TRANSPARENT];
        std::array::from_fn(|k| {
            let resolve_target = self.resolved.as_ref().map(|r| &r[k]);
            let store = if resolve_target.is_some() { wgpu::StoreOp::Discard } else { wgpu::StoreOp::Store };
            Some(wgpu::RenderPassColorAttachment {
                view: &self.drawn[k],
                depth_slice: None,
                resolve_target,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(clear[k]), store },
            })
        })
    }
}

/// Exact transparency's per-pixel lists: the heads, the nodes, their width
/// (a uniform), group 1 of the pass that fills them and group 0 of the
/// composite that reads them.
pub(crate) struct FragmentLists {
    size: (u32, u32),
    samples: u32,
    heads: wgpu::Buffer,
    /// How many nodes they hold (node 0 unused).
    pub(crate) nodes: u64,
    /// Group 1 of the list pass: the Camera block and the lists.
    pub group: wgpu::BindGroup,
    composite: wgpu::BindGroup,
}

impl FragmentLists {
    fn new(
        device: &wgpu::Device,
        ((width, height), samples, max_binding): ((u32, u32), u32, u64),
        (lists_layout, camera, composite_layout): (
            &wgpu::BindGroupLayout,
            wgpu::BindingResource,
            &wgpu::BindGroupLayout,
        ),
    ) -> Result<Self, RenderError> {
        let pixels = u64::from(width) * u64::from(height);
        let heads_bytes = (1 + pixels) * 4;
        if heads_bytes > max_binding {
            return Err(RenderError::TooLarge {
                what: "exact transparency's list heads",
                bytes: heads_bytes,
                limit: max_binding,
                limit_name: "max_storage_buffer_binding_size",
            });
        }
        let nodes = (pixels * NODES_PER_PIXEL + 1).min(max_binding / NODE_BYTES);
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
        let buffer = |label, size| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: storage,
                mapped_at_creation: false,
            })
        };
        let heads = buffer("transparency: list heads", heads_bytes);
        let node_buffer = buffer("transparency: list nodes", nodes * NODE_BYTES);
        let block = wgpu::util::DeviceExt::create_buffer_init(
            device,
            &wgpu::util::BufferInitDescriptor {
                label: Some("transparency: lists' width"),
                contents: bytemuck::cast_slice(&[width, height, 0, 0]),
                usage: wgpu::BufferUsages::UNIFORM,
            },
        );
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("transparency: camera block and lists (group 1)"),
            layout: lists_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: camera },
                entry(1, &heads),
                entry(2, &node_buffer),
                entry(3, &block),
            ],
        });
        let composite = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("transparency: exact composite group"),
            layout: composite_layout,
            entries: &[entry(0, &heads), entry(1, &node_buffer), entry(2, &block)],
        });
        Ok(Self { size: (width, height), samples, heads, nodes, group, composite })
    }

    /// Empty every list and the count of nodes taken (before the list pass).
    pub(crate) fn clear(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.clear_buffer(&self.heads, 0, None);
    }

    /// The heads, whose first word counts the nodes the last frame took.
    pub(crate) fn heads(&self) -> &wgpu::Buffer {
        &self.heads
    }
}

/// Binding `binding` to the whole of `buffer`.
fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource: buffer.as_entire_binding() }
}
