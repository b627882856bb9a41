//! Core layer: the twins that draw blended materials for weighted and exact
//! transparency (`render/passes/transparency.rs`), beside the forward
//! pipelines they twin: the layout exact twins bind their fragment lists
//! with, and the formats and blend of the weighted targets they (and the
//! particles' weighted pipelines) draw into.

use crate::gpu::{storage_entry, COLOR_FORMAT};
use crate::render::resources::pipelines::{uniform_entry, PassKind, PipelineKey, Pipelines};
use crate::scene::{BlendState, DepthState, RenderStates, Transparency};
use crate::shader::{ShaderError, ShaderFeatures};

/// Weighted transparency's targets: the sums and revealage, the weights.
pub(crate) const WEIGHTED_FORMATS: [wgpu::TextureFormat; 2] =
    [wgpu::TextureFormat::Rgba16Float, wgpu::TextureFormat::R16Float];

/// The blend of both weighted targets: colour summed, alpha multiplied by
/// 1 − the fragment's alpha.
pub(crate) const WEIGHTED_BLEND: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
    alpha: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::Zero,
        dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
        operation: wgpu::BlendOperation::Add,
    },
};

impl Pipelines {
    /// The key of the pipeline drawing what `forward` draws for
    /// `transparency`; `None` where it is not alpha-blended (additive and
    /// multiplying materials, and those using the stencil, stay in the
    /// forward pass) or `transparency` is sorted. The twin tests depth as
    /// `forward` does and writes none.
    fn transparency_key(forward: PipelineKey, transparency: Transparency) -> Option<PipelineKey> {
        let blended = forward.pass == PassKind::Forward
            && forward.features.contains(ShaderFeatures::ALPHA_BLEND)
            && forward.states.blend == BlendState::Alpha
            && forward.states.stencil == Default::default();
        let depth = DepthState { compare: forward.states.depth.compare, write: false };
        let states = RenderStates { depth, raster: forward.states.raster, ..Default::default() };
        let twin = PipelineKey { states, ..forward };
        match transparency {
            Transparency::Sorted => None,
            Transparency::Weighted => {
                Some(PipelineKey { pass: PassKind::Weighted, color_format: WEIGHTED_FORMATS[0], ..twin })
            }
            Transparency::Exact => Some(PipelineKey {
                pass: PassKind::Exact,
                features: twin.features | ShaderFeatures::TRANSPARENCY_LISTS,
                color_format: COLOR_FORMAT,
                ..twin
            }),
        }
        .filter(|_| blended)
    }

    /// The twin of forward pipeline `forward` for `transparency` (see
    /// [`transparency_key`](Self::transparency_key)), built on first use;
    /// returns how many pipelines were built now.
    pub(crate) fn transparency_id(
        &mut self,
        device: &wgpu::Device,
        forward: u16,
        transparency: Transparency,
    ) -> Result<(Option<u16>, u32), ShaderError> {
        if let Some(&id) = self.transparency_of.get(&(forward, transparency)) {
            return Ok((id, 0));
        }
        let key = Self::transparency_key(self.key_of(forward), transparency);
        if key.is_some_and(|k| k.pass == PassKind::Exact) {
            self.lists_layout(device);
        }
        let (id, built) = match key {
            Some(key) => self.forward_id(device, key).map(|(id, built)| (Some(id), u32::from(built)))?,
            None => (None, 0),
        };
        self.transparency_of.insert((forward, transparency), id);
        Ok((id, built))
    }

    /// The twin of forward pipeline `forward` for `transparency`, once
    /// [`transparency_id`](Self::transparency_id) made it (`None`: the
    /// forward pass draws it itself).
    pub(crate) fn transparency_of(&self, forward: u16, transparency: Transparency) -> Option<u16> {
        self.transparency_of.get(&(forward, transparency)).copied().flatten()
    }

    /// Group 1 of exact twins: the Camera block (binding 0, as every
    /// forward layout has it), the list heads (1), the nodes (2) and the
    /// lists' size (3); made once.
    pub(crate) fn lists_layout(&mut self, device: &wgpu::Device) -> &wgpu::BindGroupLayout {
        let (group, _) = self.lists.get_or_insert_with(|| {
            let fragment = wgpu::ShaderStages::FRAGMENT;
            let group = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("renderer: camera block and fragment lists layout (group 1)"),
                entries: &[
                    uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT, true),
                    storage_entry(1, false),
                    storage_entry(2, false),
                    uniform_entry(3, fragment, false),
                ],
            });
            let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("renderer: exact transparency pipeline layout"),
                bind_group_layouts: &[
                    Some(&self.scene_layout),
                    Some(&group),
                    Some(&self.material_layout),
                    Some(&self.instance_layout),
                ],
                immediate_size: 0,
            });
            (group, layout)
        });
        group
    }
}
