//! Beginner layer: [`Material`], how a surface looks (Blinn-Phong or
//! metallic-roughness shading, maps, alpha, motion) and how it is drawn (its
//! render states).

use super::states::{BlendState, Compare, Cull, DepthState, RenderStates};
use super::TextureId;
use glam::{Vec2, Vec4};

bitflags::bitflags! {
    /// A set of a material's texture maps (which of them read the second uv set).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
    pub struct MapSlots: u32 {
        /// `diffuse_map`.
        const DIFFUSE = 1 << 0;
        /// `normal_map`.
        const NORMAL = 1 << 1;
        /// `specular_map`.
        const SPECULAR = 1 << 2;
        /// `metallic_roughness_map`.
        const METALLIC_ROUGHNESS = 1 << 3;
        /// `occlusion_map`.
        const OCCLUSION = 1 << 4;
        /// `emissive_map`.
        const EMISSIVE = 1 << 5;
    }
}

/// How a material's alpha is used, which also picks its render queue.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    /// Alpha ignored; drawn in the opaque queue.
    Opaque,
    /// Fragments with alpha below the cutoff are discarded; alpha-test queue.
    Mask {
        /// Alpha below this is cut away (0..1).
        cutoff: f32,
    },
    /// Alpha-blended over what is behind; transparent queue, far to near.
    Blend,
}

/// How a material turns light into colour (a shader variant each).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ShadingModel {
    /// Ambient + Lambert diffuse + Blinn-Phong specular from every light.
    #[default]
    BlinnPhong,
    /// Base colour (and maps) only, ignoring lights: skies, UI, debug views.
    Unlit,
    /// glTF's metallic-roughness BRDF: GGX distribution, height-correlated Smith
    /// visibility, Schlick Fresnel; Lambert diffuse for the non-metal part. Uses
    /// `metallic`, `roughness` and their map; `ambient`, `diffuse`, `specular` and
    /// `smoothness` are Blinn-Phong's and unused.
    MetallicRoughness,
}

/// A Blinn-Phong material: everything that decides a surface's colour.
///
/// Colours are linear RGB(A). The fragment shader computes
/// `colour = base * vertex_colour * diffuse_map`, then
/// `ambient·env_ambient·colour + Σ lights (diffuse·N·L·colour + specular·spec_map·(N·H)^shininess)`
/// with `shininess = 2^(1 + 11·smoothness)`. Bound at `@group(2)`: binding 0 the
/// material table (this material's entry is indexed by its id), 1 diffuse map,
/// 2 normal map, 3 specular map, 4 sampler; a missing map is bound as a neutral
/// 1×1 texture.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name, for scene files and diagnostics.
    pub name: String,
    /// Base colour and alpha, linear.
    pub base_color: Vec4,
    /// How much environment ambient light the surface reflects.
    pub ambient: f32,
    /// Lambert diffuse coefficient.
    pub diffuse: f32,
    /// Specular coefficient.
    pub specular: f32,
    /// 0 (rough, broad highlight) to 1 (smooth, tight highlight).
    pub smoothness: f32,
    /// Colour texture (sRGB), multiplied into the base colour.
    pub diffuse_map: Option<TextureId>,
    /// Tangent-space normal map (linear, +Y up as in glTF/OpenGL).
    pub normal_map: Option<TextureId>,
    /// Specular intensity map (linear; red channel scales `specular`).
    pub specular_map: Option<TextureId>,
    /// Metalness, 0 (dielectric) to 1 (metal): metallic-roughness shading.
    pub metallic: f32,
    /// Perceptual roughness, 0 (mirror) to 1: metallic-roughness shading.
    pub roughness: f32,
    /// Metallic-roughness map (linear; glTF layout: green = roughness, blue = metalness).
    pub metallic_roughness_map: Option<TextureId>,
    /// Ambient-occlusion map (linear; red channel darkens ambient light).
    pub occlusion_map: Option<TextureId>,
    /// Light the surface gives off, linear RGB, added after lighting (any shading model).
    pub emissive: glam::Vec3,
    /// Emissive map (sRGB), multiplied into `emissive`.
    pub emissive_map: Option<TextureId>,
    /// Alpha handling and render queue.
    pub alpha_mode: AlphaMode,
    /// Draw back faces too (lit with the flipped normal).
    pub double_sided: bool,
    /// Texture repeats across the shape's 0..1 UV range (u, v).
    pub uv_scale: Vec2,
    /// Added to texture coordinates after scale and rotation.
    pub uv_offset: Vec2,
    /// Counter-clockwise rotation of texture coordinates, in radians, after the
    /// scale: `uv' = offset + rotate(rotation) · (scale · uv)`, as glTF's
    /// `KHR_texture_transform` defines it.
    pub uv_rotation: f32,
    /// Maps that read the mesh's second uv set (glTF `texCoord: 1`) instead of the
    /// first; the second falls back to the first on meshes without one.
    pub uv1_maps: MapSlots,
    /// Lighting model.
    pub shading: ShadingModel,
    /// Whether the environment's fog (if any) covers this material.
    pub fog: bool,
    /// Explicit render states; `None` derives them from `alpha_mode` and
    /// `double_sided` (see [`Material::render_states`]).
    pub states: Option<RenderStates>,
    /// Vertex animation with the scene time, if any.
    pub motion: Option<super::Motion>,
    /// Fade to transparent from `inner` to `outer` world units from the
    /// instance's placed position in x and z (the seed's ground, whose edges
    /// blend into the sky): shows with [`AlphaMode::Blend`].
    pub edge_fade: Option<(f32, f32)>,
    /// Fewer, wider instances far from the camera (the meadow's far field):
    /// see [`FarField`](super::FarField).
    pub far_field: Option<super::FarField>,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            base_color: Vec4::new(0.8, 0.8, 0.8, 1.0),
            ambient: 1.0,
            diffuse: 1.0,
            specular: 0.3,
            smoothness: 0.5,
            diffuse_map: None,
            normal_map: None,
            specular_map: None,
            metallic: 0.0,
            roughness: 0.5,
            metallic_roughness_map: None,
            occlusion_map: None,
            emissive: glam::Vec3::ZERO,
            emissive_map: None,
            alpha_mode: AlphaMode::Opaque,
            double_sided: false,
            uv_scale: Vec2::ONE,
            uv_offset: Vec2::ZERO,
            uv_rotation: 0.0,
            uv1_maps: MapSlots::empty(),
            shading: ShadingModel::BlinnPhong,
            fog: true,
            states: None,
            motion: None,
            edge_fade: None,
            far_field: None,
        }
    }
}

impl Material {
    /// A plain opaque material of one linear RGB colour.
    pub fn color(name: &str, r: f32, g: f32, b: f32) -> Self {
        Self { name: name.into(), base_color: Vec4::new(r, g, b, 1.0), ..Self::default() }
    }

    /// Its maps in texture-set binding order: diffuse, normal, specular,
    /// metallic-roughness, occlusion, emissive.
    pub fn maps(&self) -> [Option<TextureId>; 6] {
        [
            self.diffuse_map,
            self.normal_map,
            self.specular_map,
            self.metallic_roughness_map,
            self.occlusion_map,
            self.emissive_map,
        ]
    }

    /// The render states this material draws with: `states` if set, else blending
    /// and no depth writes for [`AlphaMode::Blend`], and no culling when double-sided.
    pub fn render_states(&self) -> RenderStates {
        self.states.unwrap_or_else(|| {
            let blend = self.alpha_mode == AlphaMode::Blend;
            RenderStates {
                blend: if blend { BlendState::Alpha } else { BlendState::Replace },
                depth: DepthState { compare: Compare::Less, write: !blend },
                raster: super::RasterState {
                    cull: if self.double_sided { Cull::None } else { Cull::Back },
                    ..Default::default()
                },
                ..Default::default()
            }
        })
    }
}
