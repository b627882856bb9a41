// Shader data blocks shared by every glint shader (bind-group convention in
// src/render/mod.rs). Field layouts match the #[repr(C)] twins in render/blocks.rs.
#define_import_path glint::blocks

struct Light {
    // xyz: direction the light travels (w = 0) or world position (w = 1).
    position: vec4<f32>,
    // rgb: colour × intensity; w: range (point and spot lights).
    color: vec4<f32>,
    // Spot cone: xyz axis, w scale; cone factor saturate(dot(axis, -l) * scale + offset)^2.
    spot: vec4<f32>,
    // x: the cone's offset (1 with scale 0 for lights without a cone).
    spot_offset: vec4<f32>,
}

struct SceneBlock {
    ambient: vec4<f32>,
    sky_top: vec4<f32>,
    sky_bottom: vec4<f32>,
    // rgb: fog colour; w: density (0: no fog).
    fog: vec4<f32>,
    // x: number of lights; y, z, w: reserved.
    counts: vec4<u32>,
    lights: array<Light, 64>,
}

struct CameraBlock {
    view_proj: mat4x4<f32>,
    view: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    position: vec4<f32>,
}

@group(0) @binding(0) var<uniform> scene: SceneBlock;
@group(1) @binding(0) var<uniform> camera: CameraBlock;
