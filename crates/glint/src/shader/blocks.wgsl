// Shader data blocks shared by every glint shader (bind-group convention in
// src/render/mod.rs). Field layouts match the #[repr(C)] twins in render/blocks.rs.

struct Light {
    // xyz: direction the light travels (w = 0) or world position (w = 1).
    position: vec4<f32>,
    // rgb: colour × intensity; w: range (point lights).
    color: vec4<f32>,
}

struct SceneBlock {
    ambient: vec4<f32>,
    sky_top: vec4<f32>,
    sky_bottom: vec4<f32>,
    light_count: u32,
    // Scalars, not a vec3: a vec3<u32> would be 16-aligned and move `lights`.
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
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
