//! Core layer: WGSL sources and shader variants.
//!
//! Shaders import shared modules (`glint::blocks`: groups 0 and 1;
//! `glint::equirect`; `glint::full_screen`, the full-screen triangle) with
//! `#import`, in the subset of naga_oil's syntax that `build.rs` reads. The
//! forward shader has a variant per [`ShaderFeatures`] set: each bit is a
//! shader def that `forward.wgsl` tests with `#ifdef`, so a material pays only
//! for what it uses, and each set is compiled once. The composition happens
//! when glint is built (`build.rs`, [`assemble`]), with no composer at run
//! time; tests check it against naga_oil's composition, and every Rust struct
//! that mirrors a WGSL struct against naga's layout of it (`layout.rs`).

mod assemble;
#[cfg(test)]
mod composed_tests;
#[cfg(test)]
pub(crate) mod layout;

use crate::scene::{AlphaMode, Environment, Light, LightKind, Material, ShadingModel};
use assemble::{assemble, Defs};

bitflags::bitflags! {
    /// The macro set of a forward-shader variant. The bits, and the shader def each sets:
    ///
    /// | bit | def | effect |
    /// | --- | --- | --- |
    /// | 0 | `DIFFUSE_MAP` | multiply the base colour by the diffuse map |
    /// | 1 | `NORMAL_MAP` | perturb the normal with the tangent-space normal map |
    /// | 2 | `SPECULAR_MAP` | scale specular by the specular map's red channel |
    /// | 3 | `ALPHA_MASK` | discard fragments below the alpha cutoff |
    /// | 4 | `ALPHA_BLEND` | write alpha out (blended materials) |
    /// | 5 | `UNLIT` | skip lighting: the shading model is the base colour |
    /// | 6 | `FOG` | fade to the environment's fog colour with distance |
    /// | 7 | `VERTEX_COLOR` | multiply the base colour by the mesh's vertex colour (set by the mesh, not the material) |
    /// | 8 | `METALLIC_ROUGHNESS` | glTF's metallic-roughness BRDF instead of Blinn-Phong |
    /// | 9 | `METALLIC_ROUGHNESS_MAP` | scale roughness (green) and metalness (blue) by the map |
    /// | 10 | `OCCLUSION_MAP` | darken ambient light by the map's red channel |
    /// | 11 | `EMISSIVE_MAP` | multiply the emissive colour by the map |
    /// | 12 | `UV1` | read the mesh's second uv set for the maps the material names (set by the mesh) |
    /// | 13 | `SKINNED` | move vertices by the weighted sum of four joint matrices (set by the mesh) |
    /// | 14 | `SHADOWS` | look up the shadow maps (set by the frame, only when it has drawn some: untaken, the lookups still cost llvmpipe four times the rest of a simple frame) |
    /// | 15 | `SHADOW_CUBES` | look up point lights' shadow cubes too (set by the frame, only when it has drawn some: while a forward shader holding the cube lookup draws, lavapipe's resident memory grows every frame) |
    /// | 16 | `WIND` | bend vertices in the wind with the scene time ([`Motion::Wind`](crate::scene::Motion::Wind)) |
    /// | 17 | `FLAP` | swing vertices far from the YZ plane up and down ([`Motion::Flap`](crate::scene::Motion::Flap)) |
    /// | 18 | `CIRCLE` | walk each instance around a circle ([`Motion::Circle`](crate::scene::Motion::Circle)) |
    /// | 19 | `EDGE_FADE` | fade alpha with the distance from the instance's placed position ([`Material::edge_fade`]) |
    /// | 20 | `COMPACT` | read each instance from a 16-byte compact record, numbered by the draw (set by the entity: [`Entity::with_compact_instances`](crate::Entity::with_compact_instances)) |
    /// | 21 | `SWIM` | swing a fish's tail with its instance's phase ([`Motion::Swim`](crate::scene::Motion::Swim)) |
    /// | 22 | `ENVIRONMENT` | light from the environment (image-based lighting) instead of the ambient colour ([`Environment::light`]) |
    /// | 23 | `AMBIENT_OCCLUSION` | darken ambient and environment light by the view's screen-space ambient occlusion (set by the frame, for a view with [`View::ambient_occlusion`](crate::View::ambient_occlusion); not for blended or unlit materials) |
    /// | 24 | `FAR_FIELD` | draw fewer, wider instances far from the camera ([`Material::far_field`]) |
    /// | 25 | `LOD_FADE` | drop the pixels of a fading instance's other level of detail (set by the frame, for a view with levels of detail on; not for blended materials or compact instances: `render/lod.rs`) |
    /// | 26 | `CLUSTERED` | point and spot lights from the view's light clusters (set by the frame: `render/clusters.rs`) |
    /// | 27 | `SOFT_SHADOWS` | percentage-closer soft shadows for 2D shadow views whose light has a size (set by the frame, only when one has: [`ShadowSettings::light_size`](crate::scene::ShadowSettings::light_size)) |
    ///
    /// | 28 | `TRANSPARENCY_LISTS` | `fs_exact`: append each fragment to its pixel's list (set by the frame, for the exact transparency twins of blended materials: `render/passes/transparency.rs`) |
    ///
    /// Bits 29–31 are free for more (shadow receiving comes with shadow maps).
    /// The motion bits stay in shadow passes' variants, so shadows move too.
    ///
    /// One def follows from the bits rather than being one: `TEXCOORDS`, set with
    /// any map ([`MAPS`](Self::MAPS)), passes texture coordinates to the fragment
    /// shader (tangents come with `NORMAL_MAP`).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
    pub struct ShaderFeatures: u32 {
        /// `DIFFUSE_MAP`.
        const DIFFUSE_MAP = 1 << 0;
        /// `NORMAL_MAP`.
        const NORMAL_MAP = 1 << 1;
        /// `SPECULAR_MAP`.
        const SPECULAR_MAP = 1 << 2;
        /// `ALPHA_MASK`.
        const ALPHA_MASK = 1 << 3;
        /// `ALPHA_BLEND`.
        const ALPHA_BLEND = 1 << 4;
        /// `UNLIT`.
        const UNLIT = 1 << 5;
        /// `FOG`.
        const FOG = 1 << 6;
        /// `VERTEX_COLOR`.
        const VERTEX_COLOR = 1 << 7;
        /// `METALLIC_ROUGHNESS`.
        const METALLIC_ROUGHNESS = 1 << 8;
        /// `METALLIC_ROUGHNESS_MAP`.
        const METALLIC_ROUGHNESS_MAP = 1 << 9;
        /// `OCCLUSION_MAP`.
        const OCCLUSION_MAP = 1 << 10;
        /// `EMISSIVE_MAP`.
        const EMISSIVE_MAP = 1 << 11;
        /// `UV1`.
        const UV1 = 1 << 12;
        /// `SKINNED`.
        const SKINNED = 1 << 13;
        /// `SHADOWS`.
        const SHADOWS = 1 << 14;
        /// `SHADOW_CUBES`.
        const SHADOW_CUBES = 1 << 15;
        /// `WIND`.
        const WIND = 1 << 16;
        /// `FLAP`.
        const FLAP = 1 << 17;
        /// `CIRCLE`.
        const CIRCLE = 1 << 18;
        /// `EDGE_FADE`.
        const EDGE_FADE = 1 << 19;
        /// `COMPACT`.
        const COMPACT = 1 << 20;
        /// `SWIM`.
        const SWIM = 1 << 21;
        /// `ENVIRONMENT`.
        const ENVIRONMENT = 1 << 22;
        /// `AMBIENT_OCCLUSION`.
        const AMBIENT_OCCLUSION = 1 << 23;
        /// `FAR_FIELD`.
        const FAR_FIELD = 1 << 24;
        /// `LOD_FADE`.
        const LOD_FADE = 1 << 25;
        /// `CLUSTERED`: point and spot lights from the view's light clusters
        /// (`render/clusters.rs`) instead of a loop over every one.
        const CLUSTERED = 1 << 26;
        /// `SOFT_SHADOWS`.
        const SOFT_SHADOWS = 1 << 27;
        /// `TRANSPARENCY_LISTS`.
        const TRANSPARENCY_LISTS = 1 << 28;
    }
}

impl ShaderFeatures {
    /// Every map bit: a variant with any of them reads texture coordinates.
    pub const MAPS: Self = Self::DIFFUSE_MAP
        .union(Self::NORMAL_MAP)
        .union(Self::SPECULAR_MAP)
        .union(Self::METALLIC_ROUGHNESS_MAP)
        .union(Self::OCCLUSION_MAP)
        .union(Self::EMISSIVE_MAP);

    /// The variant `material` needs in `environment`.
    pub fn for_material(material: &Material, environment: &Environment) -> Self {
        let mut f = Self::empty();
        f.set(Self::DIFFUSE_MAP, material.diffuse_map.is_some());
        f.set(Self::NORMAL_MAP, material.normal_map.is_some());
        f.set(Self::SPECULAR_MAP, material.specular_map.is_some());
        f.set(Self::ALPHA_MASK, matches!(material.alpha_mode, AlphaMode::Mask { .. }));
        f.set(Self::ALPHA_BLEND, material.alpha_mode == AlphaMode::Blend);
        f.set(Self::UNLIT, material.shading == ShadingModel::Unlit);
        let pbr = material.shading == ShadingModel::MetallicRoughness;
        f.set(Self::METALLIC_ROUGHNESS, pbr);
        f.set(Self::METALLIC_ROUGHNESS_MAP, pbr && material.metallic_roughness_map.is_some());
        f.set(Self::OCCLUSION_MAP, material.occlusion_map.is_some());
        f.set(Self::EMISSIVE_MAP, material.emissive_map.is_some());
        f.set(Self::FOG, material.fog && environment.fog.is_some());
        f.set(Self::EDGE_FADE, material.edge_fade.is_some());
        f.set(Self::FAR_FIELD, material.far_field.is_some());
        f.set(Self::ENVIRONMENT, environment.light.is_some() && material.shading != ShadingModel::Unlit);
        f |= match material.motion {
            None => Self::empty(),
            Some(crate::scene::Motion::Wind { .. }) => Self::WIND,
            Some(crate::scene::Motion::Flap { .. }) => Self::FLAP,
            Some(crate::scene::Motion::Circle { .. }) => Self::CIRCLE,
            Some(crate::scene::Motion::Swim { .. }) => Self::SWIM,
        };
        f
    }

    /// The vertex-animation bits (the far field's widening too): kept in shadow passes.
    pub const MOTION: Self = Self::WIND.union(Self::FLAP).union(Self::CIRCLE).union(Self::SWIM).union(Self::FAR_FIELD);

    /// The shader defs of this set: one per bit that is set, and `TEXCOORDS`
    /// with any map.
    fn shader_defs(self) -> impl Iterator<Item = &'static str> {
        let texcoords = self.intersects(Self::MAPS).then_some("TEXCOORDS");
        self.iter_names().map(|(name, _)| name).chain(texcoords)
    }
}

/// How many lights of each kind a forward variant loops over, compiled in as the
/// defs `DIRECTIONAL_LIGHTS` and `POSITIONAL_LIGHTS` (point and spot lights) beside
/// the [`ShaderFeatures`]: the loops unroll and read each light at a constant
/// index, which made llvmpipe's fragment work on a one-light frame a quarter
/// cheaper than a loop to a count read from the Scene block. A frame with another
/// mix of lights gets (and caches) its own variants.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct LightCounts {
    /// Directional lights (first in the Scene block).
    pub directional: u8,
    /// Point and spot lights (after the directional ones).
    pub positional: u8,
}

impl LightCounts {
    /// The counts of `lights` (at most [`MAX_LIGHTS`](crate::scene::MAX_LIGHTS)).
    pub fn of(lights: &[Light]) -> Self {
        let directional = lights.iter().filter(|l| matches!(l.kind, LightKind::Directional { .. })).count();
        Self { directional: directional as u8, positional: (lights.len() - directional) as u8 }
    }

    fn shader_defs(self) -> [(&'static str, u32); 2] {
        [("DIRECTIONAL_LIGHTS", self.directional.into()), ("POSITIONAL_LIGHTS", self.positional.into())]
    }
}

/// A pipeline the adapter's driver refused (for example a GLES driver that
/// cannot translate it).
#[derive(Debug, thiserror::Error)]
#[error("shader '{name}' did not build: {message}")]
pub struct ShaderError {
    name: String,
    message: String,
}

impl ShaderError {
    /// The driver refused what `name` built.
    pub(crate) fn refused(name: &str, error: &wgpu::Error) -> Self {
        Self { name: name.into(), message: error.to_string() }
    }
}

/// Texels in a row of the data textures that stand in for storage buffers
/// where vertex shaders cannot read those (`DATA_WIDTH` in `forward.wgsl`, see
/// `render/resources/gpu_array.rs`): WebGL2's guaranteed smallest texture limit.
pub(crate) const DATA_TEXTURE_WIDTH: u32 = 2048;

/// The defs of the forward shader for one feature set and mix of lights,
/// reading its arrays from storage buffers when `vertex_storage` (else from
/// data textures: the `DATA_TEXTURES` def).
fn forward_defs(features: ShaderFeatures, lights: LightCounts, vertex_storage: bool) -> Defs {
    let mut values = vec![("DATA_WIDTH", DATA_TEXTURE_WIDTH)];
    values.extend(lights.shader_defs());
    Defs { set: features.shader_defs().chain((!vertex_storage).then_some("DATA_TEXTURES")).collect(), values }
}

/// The forward shader for one feature set and mix of lights: `vs_main` /
/// `fs_main`, groups 0–3; reading storage buffers when `vertex_storage`.
pub(crate) fn forward(features: ShaderFeatures, lights: LightCounts, vertex_storage: bool) -> String {
    assemble(assemble::FORWARD, &forward_defs(features, lights, vertex_storage))
}

/// A forward shader holding every block the frame's Rust structs mirror
/// (for the layout checks, [`layout`]).
#[cfg(test)]
pub(crate) fn forward_for_layouts() -> String {
    let features = ShaderFeatures::SHADOWS | ShaderFeatures::SHADOW_CUBES;
    forward(features, LightCounts { directional: 1, positional: 1 }, true)
}

/// The gradient sky: `vs_sky` / `fs_sky`, groups 0–1.
pub(crate) fn sky() -> String {
    assemble(assemble::SKY, &Defs::default())
}

/// The environment's prefiltering passes: `vs_full` with `fs_specular`,
/// `fs_irradiance` and `fs_brdf`, its own group 0.
pub(crate) fn prefilter() -> String {
    assemble(assemble::PREFILTER, &Defs::default())
}

/// A variant of the particle billboards' module.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub(crate) struct ParticleShading {
    /// Reading the scene's depth (`SOFT`): multisampled (`SOFT_MSAA`) or not.
    pub soft: Option<bool>,
    /// Lit by the frame's lights (`LIT`): from the view's light clusters
    /// (`CLUSTERED`) or not.
    pub lit: Option<bool>,
    /// The light clusters are a data texture (`DATA_TEXTURES`), where
    /// shaders cannot read storage buffers.
    pub data_textures: bool,
    /// `fs_particle_exact` appends to exact transparency's lists
    /// (`TRANSPARENCY_LISTS`).
    pub lists: bool,
}

/// The defs of the particle billboards' module `variant`.
fn particle_defs(variant: ParticleShading) -> Defs {
    let soft = variant.soft.map(|msaa| std::iter::once("SOFT").chain(msaa.then_some("SOFT_MSAA")));
    let lit = variant.lit.map(|clustered| std::iter::once("LIT").chain(clustered.then_some("CLUSTERED")));
    let set = soft.into_iter().flatten().chain(lit.into_iter().flatten());
    let set = set.chain(variant.data_textures.then_some("DATA_TEXTURES"));
    let set = set.chain(variant.lists.then_some("TRANSPARENCY_LISTS")).collect();
    Defs { set, values: vec![("DATA_WIDTH", DATA_TEXTURE_WIDTH)] }
}

/// The particle billboards' module: `vs_particle` / `fs_particle`, as `variant` says.
pub(crate) fn particles(variant: ParticleShading) -> String {
    assemble(assemble::PARTICLES, &particle_defs(variant))
}

/// Mip blit shader: `vs_blit` / `fs_blit`, its own group 0.
pub(crate) const BLIT: &str = assemble::BLIT;
/// The post-processing passes (render/passes/post.rs).
pub(crate) const POST: &str = assemble::POST;
/// SMAA's three passes, in the post chain (render/passes/post.rs).
pub(crate) const SMAA: &str = assemble::SMAA;
/// Accumulated stills' fold and copy (render/passes/accumulate.rs).
pub(crate) const ACCUMULATE: &str = assemble::ACCUMULATE;
/// Weighted transparency's composite (render/passes/transparency.rs).
pub(crate) const TRANSPARENCY: &str = assemble::TRANSPARENCY;
/// Exact transparency's composite: each pixel's list sorted and blended.
pub(crate) const TRANSPARENCY_LISTS: &str = assemble::TRANSPARENCY_LISTS;
/// GPU frustum culling of a draw list (`render/gpu_driven/gpu_cull.rs`).
pub(crate) const CULL: &str = assemble::CULL;
/// The depth pyramid of occlusion culling (`render/gpu_driven/occlusion.rs`).
pub(crate) const PYRAMID: &str = assemble::PYRAMID;
/// The defs of the ambient occlusion passes' module: `PREPASS_MSAA` where the
/// pre-pass they read is `multisampled`.
fn ssao_defs(multisampled: bool) -> Defs {
    Defs { set: multisampled.then_some("PREPASS_MSAA").into_iter().collect(), values: Vec::new() }
}

/// Screen-space ambient occlusion (`render/passes/ambient_occlusion.rs`): its
/// fragment passes, reading a `multisampled` pre-pass or not.
pub(crate) fn ssao(multisampled: bool) -> String {
    assemble(assemble::SSAO, &ssao_defs(multisampled))
}

/// Its compute passes, appended to [`ssao`].
pub(crate) const SSAO_COMPUTE: &str = assemble::SSAO_COMPUTE;
/// Particles stepped on the GPU (`sim/particles/gpu.rs`).
pub(crate) const PARTICLES_STEP: &str = assemble::PARTICLES_STEP;
/// Fish schooling on the GPU (`sim/school/gpu.rs`).
pub(crate) const SCHOOL: &str = assemble::SCHOOL;
/// The school's fish written into the instance store (`sim/school/gpu.rs`).
pub(crate) const SCHOOL_PLACE: &str = assemble::SCHOOL_PLACE;
/// The running sum of the GPU's counting sorts (`sim/scan.rs`).
pub(crate) const SCAN: &str = assemble::SCAN;
/// The stable radix sort of key-value pairs (`sim/radix.rs`).
pub(crate) const RADIX: &str = assemble::RADIX;
/// Cloth stepped by Vertex Block Descent (`sim/cloth/dynamics/gpu.rs`).
pub(crate) const CLOTH: &str = assemble::CLOTH;
/// The GPU cloth's surface written into the mesh pool (`sim/cloth/dynamics/surface.rs`).
pub(crate) const CLOTH_PLACE: &str = assemble::CLOTH_PLACE;
/// A view's lights binned into its clusters (`render/gpu_driven/light_binning.rs`).
pub(crate) const BIN_LIGHTS: &str = assemble::BIN_LIGHTS;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn light_counts_split_directional_from_point_and_spot_lights() {
        use crate::scene::{Light, LightKind};
        let sun = Light::directional(glam::Vec3::NEG_Y, glam::Vec3::ONE, 1.0);
        let lamp = Light { kind: LightKind::Point { position: glam::Vec3::Y, range: 5.0 }, ..sun };
        let spot = Light {
            kind: LightKind::Spot {
                position: glam::Vec3::Y,
                direction: glam::Vec3::NEG_Y,
                range: 5.0,
                inner_angle: 0.2,
                outer_angle: 0.4,
            },
            ..sun
        };
        assert_eq!(LightCounts::of(&[]), LightCounts::default());
        assert_eq!(LightCounts::of(&[lamp, sun, spot, sun]), LightCounts { directional: 2, positional: 2 });
    }

    #[test]
    fn features_follow_the_material_and_environment() {
        let mut m = Material::default();
        assert_eq!(ShaderFeatures::for_material(&m, &Environment::default()), ShaderFeatures::empty());
        m.alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
        m.shading = ShadingModel::Unlit;
        let foggy =
            Environment { fog: Some(crate::scene::Fog { color: glam::Vec3::ONE, density: 0.1 }), ..Default::default() };
        assert_eq!(
            ShaderFeatures::for_material(&m, &foggy),
            ShaderFeatures::ALPHA_MASK | ShaderFeatures::UNLIT | ShaderFeatures::FOG
        );
        m.fog = false;
        assert!(!ShaderFeatures::for_material(&m, &foggy).contains(ShaderFeatures::FOG));
        assert_eq!(ShaderFeatures::FOG.shader_defs().collect::<Vec<_>>(), vec!["FOG"]);
    }
}
