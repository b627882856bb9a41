//! Core layer: screen-space ambient occlusion of a view with
//! [`View::ambient_occlusion`](crate::View::ambient_occlusion) (camera key `ssao`).
//!
//! Three render passes before the view's forward pass, the same on Vulkan, GL,
//! WebGL2 and WebGPU:
//! 1. **depth pre-pass** — the forward list's opaque and alpha-tested runs, each
//!    with its pipeline's pre-pass twin (`fs_prepass`: [`PassKind::Prepass`](crate::render::resources::pipelines::PassKind)),
//!    write the view-space normal and distance into a target of their own
//!    ([`PREPASS_FORMAT`]) and their depth into the view target's, with its
//!    samples ([`PrepassDepth::Shared`]). The forward pass then loads that
//!    depth and tests it for equality (each run's equal-depth twin), drawing
//!    no depth of its own: depth is drawn once, and each pixel is shaded once.
//!    (Where two surfaces land on the same depth value, as far-off grass can
//!    in a 24-bit depth buffer, the last drawn shows rather than the first:
//!    the meadow with ambient occlusion shows two such pixels of 65,536 at its
//!    horizon with its near plane at 0.05, none with it at 1.)
//!    With occlusion culling the pre-pass draws the early phase, the depth
//!    pyramid and late cull are built from its depth, and a second pre-pass
//!    draws the late phase: what comes into view is occluded in the frame it
//!    appears. Into a multisampled target where the next passes are fragment
//!    passes (GL, WebGL2: they cannot read a multisampled texture), the
//!    pre-pass has one sample and a depth of its own ([`PrepassDepth::Own`]),
//!    drawn before the forward pass draws depth as without ambient occlusion.
//! 2. **occlusion** — `shader/ssao.wgsl`'s ground-truth-style pass at half
//!    resolution (reading the pre-pass's first sample where it has several);
//! 3. **blur** — depth-aware (by the distance the occlusion pass wrote beside
//!    each pixel's occlusion), at half resolution, into the texture the forward
//!    shader's `AMBIENT_OCCLUSION` variant reads (group 0, binding 9), which
//!    darkens ambient and environment light only, never the lights'.
//!
//! Passes 2 and 3 are compute passes where the frame's path has compute (views
//! cull on the GPU: [`Gpu::culls_on_gpu`](crate::Gpu::culls_on_gpu)), full-screen
//! fragment passes otherwise (GL, WebGL2); both run the same functions.
//!
//! GPU time: the shared pre-pass is [`GpuTimes::depth_prepass_ms`](crate::render::GpuTimes::depth_prepass_ms)
//! (the view's depth), occlusion and blur (and a pre-pass with a depth of its
//! own) [`GpuTimes::ambient_occlusion_ms`](crate::render::GpuTimes::ambient_occlusion_ms);
//! the draws are [`Passes::ambient_occlusion`](crate::render::Passes::ambient_occlusion)
//! (the pre-pass's, and one each for occlusion and blur as fragment passes).

use crate::render::resources::blocks::UniformBlock;
use crate::render::resources::pipelines::{PREPASS_FORMAT, SHADOW_FORMAT};
use crate::render::view::ViewFrame;
use crate::scene::{AmbientOcclusion, Projection};

/// The occlusion textures (half resolution), in red: 1 open, 0 wholly
/// occluded; the raw one has the pixel's distance in the other three
/// (`ssao.wgsl`'s `pack_distance`), which the blur weighs its taps by.
const OCCLUSION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// The largest radius searched, in full-resolution pixels (nearer surfaces
/// search no further, so a close-up costs what a distant view does).
const MAX_RADIUS_PIXELS: f32 = 64.0;

/// The occlusion passes' parameters (`Occlusion` in `shader/ssao.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct AmbientOcclusionGpu {
    projection: [f32; 4],
    params: [f32; 4],
}

impl AmbientOcclusionGpu {
    pub(crate) fn new(frame: &ViewFrame, settings: AmbientOcclusion) -> Self {
        let p = frame.projection;
        let orthographic = matches!(frame.camera.projection, Projection::Orthographic { .. });
        Self {
            projection: [p.x_axis.x, p.y_axis.y, f32::from(u8::from(orthographic)), settings.radius],
            params: [settings.intensity, MAX_RADIUS_PIXELS, frame.sample.index as f32, 0.0],
        }
    }
}

/// How the occlusion and blur passes run.
pub(crate) enum Kind {
    Fragment([wgpu::RenderPipeline; 2]),
    Compute([wgpu::ComputePipeline; 2]),
}

/// The occlusion and blur pipelines reading a pre-pass of one sample or of
/// several, made with the first view that needs them.
pub(crate) struct AmbientOcclusionPipelines {
    layouts: [wgpu::BindGroupLayout; 2],
    pub(crate) kind: Kind,
}

impl AmbientOcclusionPipelines {
    /// As compute passes when `compute`, else as fragment passes; reading a
    /// `multisampled` pre-pass or not.
    pub(crate) fn new(device: &wgpu::Device, compute: bool, multisampled: bool) -> Self {
        let visibility = if compute { wgpu::ShaderStages::COMPUTE } else { wgpu::ShaderStages::FRAGMENT };
        let entry = |binding, ty| wgpu::BindGroupLayoutEntry { binding, visibility, ty, count: None };
        let texture = |binding| {
            entry(
                binding,
                wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    // The pre-pass (binding 1).
                    multisampled: multisampled && binding == 1,
                },
            )
        };
        let uniform = entry(
            0,
            wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
        );
        let output = entry(
            3,
            wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format: OCCLUSION_FORMAT,
                view_dimension: wgpu::TextureViewDimension::D2,
            },
        );
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            let entries: Vec<_> = entries.iter().copied().chain(compute.then_some(output)).collect();
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries })
        };
        let layouts = [
            layout("ambient occlusion: occlusion", &[uniform, texture(1)]),
            layout("ambient occlusion: blur", &[uniform, texture(2)]),
        ];
        let source = match compute {
            true => format!("{}{}", crate::shader::ssao(multisampled), crate::shader::SSAO_COMPUTE),
            false => crate::shader::ssao(multisampled),
        };
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("ssao.wgsl"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let kind = match compute {
            true => Kind::Compute([0, 1].map(|k| {
                let entry = ["cs_occlusion", "cs_blur"][k];
                crate::gpu::compute_pipeline(device, &module, entry, &[Some(&layouts[k])])
            })),
            false => Kind::Fragment([0, 1].map(|k| {
                let (label, entry) =
                    [("ambient occlusion: occlusion", "fs_occlusion"), ("ambient occlusion: blur", "fs_blur")][k];
                let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some(label),
                    bind_group_layouts: &[Some(&layouts[k])],
                    immediate_size: 0,
                });
                crate::gpu::full_screen_pipeline(
                    device,
                    label,
                    (&layout, &module),
                    ("vs_full", entry),
                    OCCLUSION_FORMAT,
                )
            })),
        };
        Self { layouts, kind }
    }
}

/// Where a view's depth pre-pass writes its depth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PrepassDepth {
    /// Into the view target's depth, with its samples: the forward pass tests
    /// it for equality and draws no depth of its own; with occlusion culling,
    /// the pre-pass draws each phase (the depth pyramid built between them),
    /// so what the late phase reveals is occluded in the frame it appears.
    Shared,
    /// Into a single-sample depth buffer of its own, thrown away: where the
    /// target is multisampled and the occlusion passes are fragment passes
    /// (GL, WebGL2, which cannot read a multisampled texture). With occlusion
    /// culling it draws the early phase only.
    Own,
}

/// One view's ambient-occlusion textures at its size, and its parameters.
pub(crate) struct OcclusionTargets {
    pub(crate) size: (u32, u32),
    pub(crate) depth_of: PrepassDepth,
    /// With the target's samples where it shares its depth.
    pub(crate) prepass: wgpu::TextureView,
    /// Whether `prepass` has several samples.
    pub(crate) multisampled: bool,
    /// Its own depth ([`PrepassDepth::Own`]).
    pub(crate) depth: Option<wgpu::TextureView>,
    pub(crate) raw: wgpu::TextureView,
    /// What the forward pass reads.
    pub(crate) blurred: wgpu::TextureView,
    pub(crate) block: UniformBlock<AmbientOcclusionGpu>,
    pub(crate) groups: [wgpu::BindGroup; 2],
}

impl OcclusionTargets {
    /// Textures for a view of `size` drawn into a target of `samples`.
    pub(crate) fn new(
        device: &wgpu::Device,
        pipelines: &AmbientOcclusionPipelines,
        ((width, height), samples): ((u32, u32), u32),
        depth_of: PrepassDepth,
    ) -> Self {
        let compute = matches!(pipelines.kind, Kind::Compute(_));
        let texture = |label, (width, height), (format, sample_count), usage| {
            device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
                    mip_level_count: 1,
                    sample_count,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage,
                    view_formats: &[],
                })
                .create_view(&Default::default())
        };
        let read = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let written = match compute {
            true => read | wgpu::TextureUsages::STORAGE_BINDING,
            false => read,
        };
        let full = (width, height);
        let half = (width.div_ceil(2), height.div_ceil(2));
        let samples = if depth_of == PrepassDepth::Shared { samples } else { 1 };
        let prepass = texture("ambient occlusion: pre-pass", full, (PREPASS_FORMAT, samples), read);
        let depth = (depth_of == PrepassDepth::Own).then(|| {
            let format = SHADOW_FORMAT;
            let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
            texture("ambient occlusion: pre-pass depth", full, (format, 1), attachment)
        });
        let raw = texture("ambient occlusion: raw", half, (OCCLUSION_FORMAT, 1), written);
        let blurred = texture("ambient occlusion: blurred", half, (OCCLUSION_FORMAT, 1), written);
        let block = UniformBlock::new(device, "ambient occlusion: parameters");
        // Binding 0 the parameters, 1 the pre-pass (the occlusion's input), 2
        // the raw occlusion and distance (the blur's), 3 the output (compute passes').
        let group = |k: usize, input: &wgpu::TextureView, output: &wgpu::TextureView| {
            let view =
                |binding, view| wgpu::BindGroupEntry { binding, resource: wgpu::BindingResource::TextureView(view) };
            let entries: Vec<_> =
                std::iter::once(wgpu::BindGroupEntry { binding: 0, resource: block.buffer.as_entire_binding() })
                    .chain([view(1 + k as u32, input)])
                    .chain(compute.then(|| view(3, output)))
                    .collect();
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("ambient occlusion: inputs"),
                layout: &pipelines.layouts[k],
                entries: &entries,
            })
        };
        let groups = [group(0, &prepass, &raw), group(1, &raw, &blurred)];
        Self { size: full, depth_of, prepass, multisampled: samples > 1, depth, raw, blurred, block, groups }
    }
}

/// Which of a view's pre-pass passes is recorded: the first clears, the last
/// resolves (several with occlusion culling's phases).
#[derive(Clone, Copy)]
pub(crate) struct PrepassPart {
    pub first: bool,
    pub last: bool,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_occlusion_parameters_mirror_their_wgsl_struct() {
        crate::shader::layout::assert_mirrors!(
            AmbientOcclusionGpu,
            &crate::shader::ssao(false),
            "AmbientOcclusion",
            [projection, params]
        );
    }
}
