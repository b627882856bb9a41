// Two-colour gradient sky: one full-screen triangle on the far plane, drawn after
// the opaque queues so the depth test skips every covered pixel.

#import glint::blocks::{scene, camera}

struct SkyOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) ndc: vec2<f32>,
}

@vertex
fn vs_sky(@builtin(vertex_index) index: u32) -> SkyOut {
    let uv = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    let ndc = uv * 2.0 - 1.0;
    var out: SkyOut;
    out.clip = vec4<f32>(ndc, 1.0, 1.0);
    out.ndc = ndc;
    return out;
}

@fragment
fn fs_sky(in: SkyOut) -> @location(0) vec4<f32> {
    let far = camera.inv_view_proj * vec4<f32>(in.ndc, 1.0, 1.0);
    let near = camera.inv_view_proj * vec4<f32>(in.ndc, 0.0, 1.0);
    let dir = normalize(far.xyz / far.w - near.xyz / near.w);
    // Flat at the horizon (no kink where the ground colour meets the sky).
    let t = smoothstep(0.0, 0.6, dir.y);
    return vec4<f32>(mix(scene.sky_bottom.rgb, scene.sky_top.rgb, t), 1.0);
}
