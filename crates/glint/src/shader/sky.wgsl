// Two-colour gradient sky (or the environment's): one full-screen triangle on the far plane, drawn after
// the opaque queues so the depth test skips every covered pixel. The sun glare:
// the same triangle drawn last, added without a depth test (a sphere around
// the view, bright in the sun's direction).

#import glint::blocks::{scene, camera, environment_sample}
#import glint::full_screen::full_screen_clip

struct SkyOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) ndc: vec2<f32>,
}

@vertex
fn vs_sky(@builtin(vertex_index) index: u32) -> SkyOut {
    let clip = full_screen_clip(index, 1.0);
    return SkyOut(clip, clip.xy);
}

// The unit direction the camera looks along through this pixel.
fn view_ray(ndc: vec2<f32>) -> vec3<f32> {
    let far = camera.inv_view_proj * vec4<f32>(ndc, 1.0, 1.0);
    let near = camera.inv_view_proj * vec4<f32>(ndc, 0.0, 1.0);
    return normalize(far.xyz / far.w - near.xyz / near.w);
}

@fragment
fn fs_sky(in: SkyOut) -> @location(0) vec4<f32> {
    let dir = view_ray(in.ndc);
    // Flat at the horizon (no kink where the ground colour meets the sky).
    let t = smoothstep(0.0, 0.6, dir.y);
    return vec4<f32>(mix(scene.sky_bottom.rgb, scene.sky_top.rgb, t), 1.0);
}

// The sky drawn from the environment (image-based lighting), at the Scene
// block's blur level.
@fragment
fn fs_sky_environment(in: SkyOut) -> @location(0) vec4<f32> {
    return vec4<f32>(environment_sample(view_ray(in.ndc), scene.environment_sky.x), 1.0);
}

// Sun glare, added over everything: the first directional light's colour times
// the Scene block's glare, a bright core and a wide halo around the direction
// to the sun (nothing without a directional light, or below the horizon,
// where the sun's intensity is 0).
@fragment
fn fs_glare(in: SkyOut) -> @location(0) vec4<f32> {
    if scene.counts.y == 0u {
        return vec4<f32>(0.0);
    }
    let sun = scene.lights[0];
    let c = max(dot(view_ray(in.ndc), -normalize(sun.position.xyz)), 0.0);
    let light = scene.ambient.w * (0.6 * pow(c, 256.0) + 0.25 * pow(c, 12.0));
    return vec4<f32>(sun.color.rgb * light, 0.0);
}
