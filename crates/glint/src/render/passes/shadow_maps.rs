//! Core layer: the shadow maps and what the Scene block (`@group(0)`) tells the
//! shader about them: the 2D depth-map array (cascades and spot lights, binding
//! 2), point lights' cube faces storing distance, six 2D layers a cube (binding 3), the
//! comparison sampler (binding 4) and the Shadow block (binding 1) with each 2D
//! view's matrix. Maps of one kind share the largest size any light asks for.

use crate::gpu::DriverErrors;
use crate::render::error::RenderError;
use crate::render::passes::shadow_views::{ShadowView, ViewTarget};
use crate::render::resources::gpu_array::GpuArray;
use crate::render::resources::pipelines::SHADOW_FORMAT;
use crate::scene::shadow_layout::MAX_2D_VIEWS;
use crate::scene::{ShadowLayout, MAX_SHADOW_MAP_BYTES};

/// Fraction of a cascade over which it blends into the next.
const CASCADE_BLEND: f32 = 0.1;

/// The Shadow block, `@group(0) @binding(1)` (1,296 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct ShadowGpu {
    /// World to clip of each 2D view.
    view_proj: [[f32; 16]; MAX_2D_VIEWS],
    /// Per 2D view: x texel size (world units; per unit of distance for
    /// perspective views), y the cascade's end distance (0: not a cascade),
    /// z the soft shadows' penumbra scale (0: the 3×3 filter).
    info: [[f32; 4]; MAX_2D_VIEWS],
    /// x: 1 / 2D map size, y: 1 / cube map size, z: cascade blend fraction.
    params: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<ShadowGpu>() == 1296);

impl ShadowGpu {
    /// The block for a frame's views, with maps of these sizes.
    pub(crate) fn new(views: &[ShadowView], size_2d: u32, size_cube: u32) -> Self {
        let mut block = Self {
            view_proj: [[0.0; 16]; MAX_2D_VIEWS],
            info: [[0.0; 4]; MAX_2D_VIEWS],
            params: [1.0 / size_2d as f32, 1.0 / size_cube as f32, CASCADE_BLEND, 0.0],
        };
        for v in views {
            if let ViewTarget::Layer(layer) = v.target {
                block.view_proj[layer as usize] = v.view_proj().to_cols_array();
                block.info[layer as usize] = [v.texel, v.split, v.penumbra, 0.0];
            }
        }
        block
    }
}

/// What the adapter allows the shadow maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct ShadowSupport {
    /// The device is on wgpu's GL backend (see [`ShadowMaps::new`]).
    pub gl: bool,
}

impl ShadowSupport {
    /// The 2D layers and cubes allocated for `layers` and `cubes` in use (see
    /// [`ShadowMaps::new`]): at least one of each, and two 2D layers on GL.
    pub(crate) fn allocated(self, layers: u32, cubes: u32) -> (u32, u32) {
        let least = if self.gl { 2 } else { 1 };
        (layers.max(least), cubes.max(1))
    }
}

/// The shadow-map textures, one attachment view per layer, and the sampler.
pub(crate) struct ShadowMaps {
    pub support: ShadowSupport,
    pub size_2d: u32,
    pub layers: u32,
    pub size_cube: u32,
    pub cubes: u32,
    maps: wgpu::TextureView,
    cube_maps: wgpu::TextureView,
    /// Render-attachment views: one per 2D layer.
    pub layer_views: Vec<wgpu::TextureView>,
    /// Render-attachment views: one per cube face (`6 · cube + face`).
    pub face_views: Vec<wgpu::TextureView>,
    pub sampler: wgpu::Sampler,
}

fn depth_texture(device: &wgpu::Device, label: &str, size: u32, layers: u32) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width: size, height: size, depth_or_array_layers: layers },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: SHADOW_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    })
}

/// The view group 0 samples: every layer of `texture`, as a 2D array.
fn array_view(texture: &wgpu::Texture) -> wgpu::TextureView {
    texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}

fn layer_views(texture: &wgpu::Texture, layers: u32) -> Vec<wgpu::TextureView> {
    (0..layers)
        .map(|layer| {
            texture.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: layer,
                array_layer_count: Some(1),
                ..Default::default()
            })
        })
        .collect()
}

impl ShadowMaps {
    /// Maps of at least `layers` 2D layers of `size_2d`² texels and `cubes` cubes
    /// of `size_cube`² (at least one of each, so the bind group always has them).
    ///
    /// On wgpu's GL backend at least two 2D layers, and one spare layer after
    /// the cube faces: GL fixes a texture's binding type when it is made, and
    /// wgpu guesses it from the layers, taking one layer for a plain 2D texture
    /// and a square multiple of six for cubes. Bound as a 2D array, such a
    /// texture samples wrongly (a lone spot light's shadow was lost; the cube
    /// faces, sampled as 2D layers, shadowed the wrong side).
    pub(crate) fn new(
        device: &wgpu::Device,
        support: ShadowSupport,
        size_2d: u32,
        layers: u32,
        size_cube: u32,
        cubes: u32,
    ) -> Self {
        let (layers, cubes) = support.allocated(layers, cubes);
        let maps = depth_texture(device, "shadow maps (2D array)", size_2d, layers);
        let spare = u32::from(support.gl);
        let cube_maps = depth_texture(device, "shadow maps (cube faces)", size_cube, 6 * cubes + spare);
        Self {
            support,
            size_2d,
            layers,
            size_cube,
            cubes,
            maps: array_view(&maps),
            cube_maps: array_view(&cube_maps),
            layer_views: layer_views(&maps, layers),
            face_views: layer_views(&cube_maps, 6 * cubes),
            sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("shadow maps: comparison sampler"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                compare: Some(wgpu::CompareFunction::LessEqual),
                ..Default::default()
            }),
        }
    }

    /// [`ShadowMaps::new`] for a frame's lights: refused before anything is
    /// allocated when the maps would take more than [`MAX_SHADOW_MAP_BYTES`], and
    /// an error (not a panic) when the device cannot make them.
    pub(crate) fn checked(
        device: &wgpu::Device,
        support: ShadowSupport,
        size_2d: u32,
        layers: u32,
        size_cube: u32,
        cubes: u32,
    ) -> Result<Self, RenderError> {
        let (layers, cubes) = support.allocated(layers, cubes);
        let bytes = ShadowLayout { size_2d, size_cube, layers, cubes, first: Vec::new() }.bytes();
        if bytes > MAX_SHADOW_MAP_BYTES {
            let limit_name = "MAX_SHADOW_MAP_BYTES: lower the lights' shadow_map_size";
            return Err(RenderError::TooLarge {
                what: "the shadow maps",
                bytes,
                limit: MAX_SHADOW_MAP_BYTES,
                limit_name,
            });
        }
        let scope = DriverErrors::watch(device);
        let maps = Self::new(device, support, size_2d, layers, size_cube, cubes);
        match scope.finish() {
            Some(error) => Err(RenderError::Device { what: "the shadow maps", message: error.to_string() }),
            None => Ok(maps),
        }
    }

    /// Whether these maps can hold a frame with these needs (sizes exactly, layers at least).
    pub(crate) fn fits(&self, size_2d: u32, layers: u32, size_cube: u32, cubes: u32) -> bool {
        self.size_2d == size_2d && self.size_cube == size_cube && self.layers >= layers && self.cubes >= cubes
    }

    /// The Scene block's bind group over `scene` and `shadow` blocks, these
    /// maps, `environment`'s, the view's ambient `occlusion` and its light
    /// `clusters`.
    pub(crate) fn scene_group(
        &self,
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        (scene, shadow): (&wgpu::Buffer, &wgpu::Buffer),
        (environment, occlusion): (&crate::render::passes::environment::EnvironmentMaps, &wgpu::TextureView),
        clusters: &GpuArray,
    ) -> wgpu::BindGroup {
        let entries = [
            wgpu::BindGroupEntry { binding: 0, resource: scene.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: shadow.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(&self.maps) },
            wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(&self.cube_maps) },
            wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::Sampler(&self.sampler) },
            wgpu::BindGroupEntry { binding: 9, resource: wgpu::BindingResource::TextureView(occlusion) },
            wgpu::BindGroupEntry { binding: 10, resource: clusters.binding() },
        ];
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("renderer: scene block (group 0)"),
            layout,
            entries: &entries.into_iter().chain(environment.entries()).collect::<Vec<_>>(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shadow_block_mirrors_its_wgsl_struct() {
        use crate::shader::layout::assert_mirrors;
        assert_mirrors!(ShadowGpu, &crate::shader::forward_for_layouts(), "ShadowBlock", [view_proj, info, params]);
    }
}
