// Shader data blocks shared by every glint shader (bind-group convention in
// src/render/mod.rs). Field layouts match the #[repr(C)] twins in render/resources/blocks.rs.
#define_import_path glint::blocks

#import glint::equirect::equirect_uv

struct Light {
    // xyz: direction the light travels (w = 0) or world position (w = 1).
    position: vec4<f32>,
    // rgb: colour × intensity; w: range (point and spot lights).
    color: vec4<f32>,
    // Spot cone: xyz axis, w scale; cone factor saturate(dot(axis, -l) * scale + offset)^2.
    spot: vec4<f32>,
    // x: the cone's offset (1 with scale 0 for lights without a cone);
    // y: first shadow view (cascades, spot: a layer of shadow_maps; point: a cube
    // of shadow_cubes), -1 without shadows; z: depth bias, w: normal bias (texels).
    params: vec4<f32>,
}

struct SceneBlock {
    // rgb: ambient light; w: sun glare (0: none; sky.wgsl fs_glare).
    ambient: vec4<f32>,
    sky_top: vec4<f32>,
    sky_bottom: vec4<f32>,
    // rgb: fog colour; w: density (0: no fog).
    fog: vec4<f32>,
    // x: lights in `lights` (at most 64; a clustered frame's other point and spot
    // lights are in its light clusters only); y: directional lights (first in
    // `lights`); z: a light
    // cluster tile's side in pixels; w: depth slices (render/clusters.rs).
    counts: vec4<u32>,
    // Image-based lighting (render/passes/environment.rs): x: intensity (0: none);
    // y, z: cos and sin of the environment's turn about +Y; w: the specular
    // map's last level (roughness 1).
    environment: vec4<f32>,
    // x: the specular level the sky is drawn from (its blur); y: 1 draws the
    // heat map of lights per light cluster (forward.wgsl cluster_heat), else 0;
    // z, w: the soft-shadow filter grid's offset for this sub-frame of an
    // accumulated still, in taps (0 for a frame of its own).
    environment_sky: vec4<f32>,
    // Light clusters (render/clusters.rs): x, y: tiles across and down; a
    // fragment's slice is floor(ln(view depth) · z + w), clamped.
    clusters: vec4<f32>,
    lights: array<Light, 64>,
}

struct CameraBlock {
    view_proj: mat4x4<f32>,
    view: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    position: vec4<f32>,
    // x: the scene time in seconds; y: wind strength; zw: wind direction (x, z),
    // unit (here rather than in the Scene block: shadow passes bind no Scene block).
    motion: vec4<f32>,
    // xyz: the eye far fields are measured from (a shadow view's: its camera
    // view's); w: 1 when far fields are on (scene/far_field.rs).
    far_eye: vec4<f32>,
}

// Directional lights' cascades (src/scene/light.rs CASCADES).
const CASCADES: u32 = 4u;

struct ShadowBlock {
    // World to clip of each 2D shadow view (cascades and spot lights).
    view_proj: array<mat4x4<f32>, 16>,
    // x: texel size (world units; per unit of distance for spot views);
    // y: the camera distance where a cascade ends (0: not a cascade); z: soft
    // shadows' penumbra width in uv per unit of NDC depth from blocker to
    // receiver (0: the 3×3 filter; shadow_lookup.wgsl soft_shadow).
    info: array<vec4<f32>, 16>,
    // x: 1 / 2D map size; y: 1 / cube map size; z: cascade blend fraction.
    params: vec4<f32>,
}

@group(0) @binding(0) var<uniform> scene: SceneBlock;
@group(0) @binding(1) var<uniform> shadows: ShadowBlock;
@group(0) @binding(2) var shadow_maps: texture_depth_2d_array;
// Point lights' cubes: cube c's faces are layers 6c..6c+5 (+X −X +Y −Y +Z −Z, each
// oriented as a cube map's face), sampled as 2D layers (shadow_lookup.wgsl cube_face):
// lavapipe's process grew every frame a shader holding a cube-map lookup drew.
@group(0) @binding(3) var shadow_cubes: texture_depth_2d_array;
@group(0) @binding(4) var shadow_sampler: sampler_comparison;
// The environment (render/passes/environment.rs; 1 × 1 stand-ins without one): the
// specular map (equirectangular, a level per roughness step), the diffuse
// light's nine spherical-harmonic coefficients (texels 0..9 of row 0), the
// split-sum BRDF table (x: n·v, y: roughness) and their sampler.
@group(0) @binding(5) var environment_specular: texture_2d<f32>;
@group(0) @binding(6) var environment_irradiance: texture_2d<f32>;
@group(0) @binding(7) var environment_brdf: texture_2d<f32>;
@group(0) @binding(8) var environment_sampler: sampler;
// The view's screen-space ambient occlusion at half its resolution
// (render/passes/ambient_occlusion.rs; a 1 × 1 white stand-in without it).
@group(0) @binding(9) var ambient_occlusion: texture_2d<f32>;
@group(1) @binding(0) var<uniform> camera: CameraBlock;

// The environment's radiance toward world direction `d`, from specular level
// `level` (fractional levels blend), times its intensity. The environment is
// turned as glam's Mat3::from_rotation_y(rotation) turns it: looked up turned back.
fn environment_sample(d: vec3<f32>, level: f32) -> vec3<f32> {
    let c = scene.environment.y;
    let s = scene.environment.z;
    let own = vec3<f32>(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
    let uv = equirect_uv(own);
    return textureSampleLevel(environment_specular, environment_sampler, uv, level).rgb * scene.environment.x;
}
