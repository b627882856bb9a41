//! Core layer: two-phase occlusion culling of a view culled on the GPU (past
//! seed 003, which lists it as future work).
//!
//! 1. Early: the cull pass keeps only what the view saw last frame (a flag per
//!    candidate, [`LatePhase::hidden`]) inside the frustum; the forward pass
//!    draws the opaque and alpha-tested stages of that.
//! 2. The [`DepthPyramid`] is built from the depth buffer with compute
//!    (`shader/pyramid.wgsl`): conservative at every size, as its level 0 (at
//!    half the buffer's resolution, each texel the farthest of its 2 × 2
//!    pixels) is padded to powers of two with the far plane.
//! 3. Late: every candidate is tested against frustum and pyramid; its flag is
//!    written for the next frame, and what is visible now but was not drawn
//!    early goes into the late commands, drawn by a second forward pass (which
//!    then draws the sky and the stages after it).
//!
//! What is visible is always drawn in one phase or the other, so the picture is
//! the frustum-only picture: only the work behind occluders goes. A new or
//! changed set of candidates starts with every flag clear (all drawn early).

use crate::render::error::RenderError;
use crate::render::gpu_driven::commands::{Placed, Run, COMMAND_BYTES};
use crate::render::resources::gpu_array::GrowBuffer;

/// The pyramid's compute pipelines.
pub(crate) struct PyramidPipelines {
    layouts: [wgpu::BindGroupLayout; 3],
    first: wgpu::ComputePipeline,
    first_multisampled: wgpu::ComputePipeline,
    down: wgpu::ComputePipeline,
}

impl PyramidPipelines {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty,
            count: None,
        };
        let level = entry(
            1,
            wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format: wgpu::TextureFormat::R32Float,
                view_dimension: wgpu::TextureViewDimension::D2,
            },
        );
        let texture = |binding, sample_type, multisampled| {
            entry(
                binding,
                wgpu::BindingType::Texture {
                    sample_type,
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled,
                },
            )
        };
        let layout = |label, input| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries: &[input, level],
            })
        };
        let unfilterable = wgpu::TextureSampleType::Float { filterable: false };
        let layouts = [
            layout("depth pyramid: level 0", texture(0, wgpu::TextureSampleType::Depth, false)),
            layout("depth pyramid: level 0 (multisampled)", texture(2, wgpu::TextureSampleType::Depth, true)),
            layout("depth pyramid: level k + 1", texture(3, unfilterable, false)),
        ];
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("pyramid.wgsl"),
            source: wgpu::ShaderSource::Wgsl(crate::shader::PYRAMID.into()),
        });
        let pipeline = |entry, layout| crate::gpu::compute_pipeline(device, &module, entry, &[Some(layout)]);
        Self {
            first: pipeline("first", &layouts[0]),
            first_multisampled: pipeline("first_multisampled", &layouts[1]),
            down: pipeline("down", &layouts[2]),
            layouts,
        }
    }
}

/// A view's depth pyramid: R32Float, level 0 half the depth buffer's size
/// rounded up to powers of two, down to one texel.
pub(crate) struct DepthPyramid {
    /// The depth buffer's size and samples it was made for.
    depth: (u32, u32, u32),
    /// All levels, for the late cull pass.
    pub view: wgpu::TextureView,
    levels: Vec<(wgpu::TextureView, (u32, u32))>,
}

impl DepthPyramid {
    pub(crate) fn new(device: &wgpu::Device, (width, height, samples): (u32, u32, u32)) -> Self {
        let size = (width.div_ceil(2).next_power_of_two(), height.div_ceil(2).next_power_of_two());
        let count = 32 - size.0.max(size.1).leading_zeros();
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("depth pyramid"),
            size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
            mip_level_count: count,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R32Float,
            usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let levels = (0..count)
            .map(|k| {
                let view = texture.create_view(&wgpu::TextureViewDescriptor {
                    base_mip_level: k,
                    mip_level_count: Some(1),
                    ..Default::default()
                });
                (view, ((size.0 >> k).max(1), (size.1 >> k).max(1)))
            })
            .collect();
        Self { depth: (width, height, samples), view: texture.create_view(&Default::default()), levels }
    }

    /// Whether it was made for a depth buffer of this size and samples.
    pub(crate) fn fits(&self, depth: (u32, u32, u32)) -> bool {
        self.depth == depth
    }

    /// Levels in all.
    pub(crate) fn levels(&self) -> u32 {
        self.levels.len() as u32
    }

    /// Record its dispatches from `depth` (a depth-only view of the depth buffer).
    pub(crate) fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        pipelines: &PyramidPipelines,
        depth: &wgpu::TextureView,
    ) {
        let multisampled = self.depth.2 > 1;
        let bind = |layout, (binding, input): (u32, &wgpu::TextureView), output: &wgpu::TextureView| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("depth pyramid level"),
                layout,
                entries: &[
                    wgpu::BindGroupEntry { binding, resource: wgpu::BindingResource::TextureView(input) },
                    wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(output) },
                ],
            })
        };
        let groups: Vec<(&wgpu::ComputePipeline, wgpu::BindGroup)> = (0..self.levels.len())
            .map(|k| match k {
                0 if multisampled => {
                    (&pipelines.first_multisampled, bind(&pipelines.layouts[1], (2, depth), &self.levels[0].0))
                }
                0 => (&pipelines.first, bind(&pipelines.layouts[0], (0, depth), &self.levels[0].0)),
                k => (&pipelines.down, bind(&pipelines.layouts[2], (3, &self.levels[k - 1].0), &self.levels[k].0)),
            })
            .collect();
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("depth pyramid"), timestamp_writes: None });
        for ((pipeline, group), (_, (w, h))) in groups.iter().zip(&self.levels) {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
    }
}

/// `cull.wgsl`'s `Occlusion`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct OcclusionGpu {
    view_proj: [[f32; 4]; 4],
    size: [f32; 2],
    levels: u32,
    pad: u32,
}

/// What the late phase of a frame needs to know: the view, its depth buffer's
/// size and samples, and the late commands as the CPU makes them.
pub(crate) struct LateInput<'a> {
    pub view_proj: glam::Mat4,
    pub depth: (u32, u32, u32),
    pub template: &'a [wgpu::util::DrawIndexedIndirectArgs],
    /// How far past the early places the late ones are in the draw indices.
    pub place_offset: u32,
}

/// A list's late phase on the GPU: its commands, the candidates' flags and the pyramid.
pub(crate) struct LatePhase {
    /// The late dispatches' `Params`.
    pub params: wgpu::Buffer,
    occlusion: wgpu::Buffer,
    /// The late commands as the CPU makes them: no instances, places in the late region.
    pub template: GrowBuffer,
    uploaded_template: Vec<wgpu::util::DrawIndexedIndirectArgs>,
    /// The late commands the late pass counts instances into.
    pub args: GrowBuffer,
    /// Each run's non-empty late commands.
    pub drawn_args: GrowBuffer,
    /// Per candidate: 1 when it was not visible last frame; then the late
    /// phase's count of instances it found hidden.
    pub hidden: GrowBuffer,
    /// The flags must be cleared before the next early pass (new candidates).
    pub reset_hidden: bool,
    pub pyramid: Option<DepthPyramid>,
    uploaded_occlusion: OcclusionGpu,
}

impl LatePhase {
    pub(crate) fn new(device: &wgpu::Device, label: &'static str) -> Self {
        use wgpu::BufferUsages as U;
        let uniform = |size| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: U::UNIFORM | U::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let buffer = |usage, bytes| GrowBuffer::new(device, label, usage, bytes);
        Self {
            params: uniform(32),
            occlusion: uniform(std::mem::size_of::<OcclusionGpu>() as u64),
            template: buffer(U::COPY_SRC, 1024),
            uploaded_template: Vec::new(),
            // Copied from only to read back for inspection.
            args: buffer(U::STORAGE | U::INDIRECT | U::COPY_SRC, 1024),
            drawn_args: buffer(U::STORAGE | U::INDIRECT, 1024),
            hidden: buffer(U::STORAGE | U::COPY_SRC, 1024),
            reset_hidden: true,
            pyramid: None,
            uploaded_occlusion: OcclusionGpu::default(),
        }
    }

    /// Make room for `candidates` and the commands, write what changed of
    /// `input`; returns (bytes written, whether a buffer the bind groups hold
    /// was replaced).
    pub(crate) fn upload(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        input: &LateInput,
        candidates: u32,
    ) -> Result<(u64, bool), RenderError> {
        let commands = std::mem::size_of_val(input.template) as u64;
        let mut replaced = false;
        for buffer in [&mut self.template, &mut self.args, &mut self.drawn_args] {
            replaced |= buffer.reserve(device, commands)?;
        }
        if self.hidden.reserve(device, 4 * (u64::from(candidates) + 1))? {
            (replaced, self.reset_hidden) = (true, true);
        }
        if replaced {
            self.uploaded_template.clear();
        }
        if !self.pyramid.as_ref().is_some_and(|p| p.fits(input.depth)) {
            self.pyramid = Some(DepthPyramid::new(device, input.depth));
            replaced = true;
        }
        let mut written = 0;
        if bytemuck::cast_slice::<_, u8>(&self.uploaded_template) != bytemuck::cast_slice::<_, u8>(input.template) {
            written += self.template.write(queue, 0, input.template);
            self.uploaded_template = input.template.to_vec();
        }
        let levels = self.pyramid.as_ref().map_or(1, DepthPyramid::levels);
        let (width, height, _) = input.depth;
        let occlusion = OcclusionGpu {
            view_proj: input.view_proj.to_cols_array_2d(),
            size: [width as f32, height as f32],
            levels,
            pad: 0,
        };
        if occlusion != self.uploaded_occlusion || replaced {
            queue.write_buffer(&self.occlusion, 0, bytemuck::bytes_of(&occlusion));
            written += std::mem::size_of::<OcclusionGpu>() as u64;
            self.uploaded_occlusion = occlusion;
        }
        Ok((written, replaced))
    }

    /// The Occlusion group (group 2) of both phases' cull passes.
    pub(crate) fn bind(&self, device: &wgpu::Device, layout: &wgpu::BindGroupLayout) -> wgpu::BindGroup {
        let pyramid = &self.pyramid.as_ref().expect("made by upload").view;
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("occlusion culling"),
            layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: self.hidden.buffer.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(pyramid) },
                wgpu::BindGroupEntry { binding: 2, resource: self.occlusion.as_entire_binding() },
            ],
        })
    }
}

/// The late commands of a list's batches: none of their instances yet, and a
/// GPU-culled batch's places after the early ones (`gpu_region` further on);
/// `placed` says how each batch's instances are placed.
pub(crate) fn late_commands(
    early: &[wgpu::util::DrawIndexedIndirectArgs],
    placed: &[Placed],
    gpu_region: u32,
) -> Vec<wgpu::util::DrawIndexedIndirectArgs> {
    (early.iter().zip(placed))
        .map(|(c, &placed)| wgpu::util::DrawIndexedIndirectArgs {
            instance_count: 0,
            first_instance: match placed {
                Placed::OnGpu => c.first_instance + gpu_region,
                _ => c.first_instance,
            },
            ..*c
        })
        .collect()
}

/// Draw run `k` (`run`) of the late commands.
pub(crate) fn draw_late_run(
    late: &LatePhase,
    counts: &wgpu::Buffer,
    draw_count: bool,
    pass: &mut wgpu::RenderPass<'_>,
    (k, runs): (usize, usize),
    run: &Run,
) {
    let at = u64::from(run.first) * COMMAND_BYTES;
    match draw_count {
        true => {
            pass.multi_draw_indexed_indirect_count(&late.drawn_args.buffer, at, counts, (runs + k) as u64 * 4, run.len)
        }
        false => pass.multi_draw_indexed_indirect(&late.args.buffer, at, run.len),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pyramid_parameters_mirror_their_wgsl_struct() {
        let wgsl = crate::shader::CULL;
        crate::shader::layout::assert_mirrors!(OcclusionGpu, wgsl, "Occlusion", [view_proj, size, levels, pad]);
    }
}
