// Particle billboards (render/passes/particles.rs): one instance a particle, four
// vertices of a strip each, facing the camera; the sprite times the
// particle's colour, under the scene's fog. A record of size 0 draws nothing.
// SOFT (SOFT_MSAA for a multisampled target): the scene's depth is read, and
// a particle fades out over its layer's soft distance in front of geometry.
// LIT: the colour is the light the particle scatters, a medium with no
// normal: the ambient light plus every light arriving at the fragment's point
// (unshadowed); its point and spot lights from the view's light clusters
// where CLUSTERED, else the Scene block's. TRANSPARENCY_LISTS:
// fs_particle_exact (exact transparency's lists).

#import glint::blocks::{scene, camera, Light}
#import glint::light_clusters::{cluster_at, clustered_light, cluster_word, towards_light, arriving}
#import glint::transparency_out::{Weighted, weighted_sums, append_fragment}

@group(2) @binding(0) var sprite: texture_2d<f32>;
@group(2) @binding(1) var sprite_sampler: sampler;
// x: the soft distance, world units.
@group(2) @binding(2) var<uniform> look: vec4<f32>;

#ifdef SOFT
#ifdef SOFT_MSAA
@group(3) @binding(0) var scene_depth: texture_depth_multisampled_2d;
#else
@group(3) @binding(0) var scene_depth: texture_depth_2d;
#endif

// How far behind the particle's fragment at `clip` the scene's surface is.
fn depth_behind(clip: vec4<f32>, world: vec3<f32>) -> f32 {
    let pixel = vec2<i32>(clip.xy);
    let depth = textureLoad(scene_depth, pixel, 0);
    let size = vec2<f32>(textureDimensions(scene_depth));
    let ndc = vec2<f32>(clip.x / size.x * 2.0 - 1.0, 1.0 - clip.y / size.y * 2.0);
    let surface = camera.inv_view_proj * vec4<f32>(ndc, depth, 1.0);
    let eye = camera.position.xyz;
    return length(surface.xyz / surface.w - eye) - length(world - eye);
}
#endif

struct ParticleIn {
    // xyz: centre; w: side in world units.
    @location(0) center_size: vec4<f32>,
    @location(1) color: vec4<f32>,
}

struct ParticleOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) color: vec4<f32>,
    @location(2) world_position: vec3<f32>,
}

@vertex
fn vs_particle(@builtin(vertex_index) corner: u32, p: ParticleIn) -> ParticleOut {
    let uv = vec2<f32>(f32(corner & 1u), f32(corner >> 1u));
    let offset = (uv - 0.5) * p.center_size.w;
    // The camera's right and up in the world: the view matrix's first two rows.
    let right = vec3<f32>(camera.view[0].x, camera.view[1].x, camera.view[2].x);
    let up = vec3<f32>(camera.view[0].y, camera.view[1].y, camera.view[2].y);
    let world = p.center_size.xyz + right * offset.x + up * offset.y;
    var out: ParticleOut;
    out.clip = camera.view_proj * vec4<f32>(world, 1.0);
    out.uv = vec2<f32>(uv.x, 1.0 - uv.y);
    out.color = p.color;
    out.world_position = world;
    return out;
}

#ifdef LIT
// The light arriving at `p` (the fragment at `pixel`) from every direction.
fn light_at(p: vec3<f32>, pixel: vec2<f32>) -> vec3<f32> {
    var light = scene.ambient.rgb;
    let directional = scene.counts.y;
    for (var i = 0u; i < directional; i++) {
        light += scene.lights[i].color.rgb;
    }
#ifdef CLUSTERED
    let cluster = cluster_at(pixel, p);
    for (var k = 0u; k < cluster.y; k++) {
        let positional = clustered_light(cluster.z, cluster_word(cluster.x + k));
        light += arriving(positional, towards_light(positional, p), 1.0);
    }
#else
    for (var i = directional; i < scene.counts.x; i++) {
        light += arriving(scene.lights[i], towards_light(scene.lights[i], p), 1.0);
    }
#endif
    return light;
}
#endif

@fragment
fn fs_particle(in: ParticleOut) -> @location(0) vec4<f32> {
    let color = particle_color(in);
    // Premultiplied: added as is (additive), or over what is behind (alpha).
    return vec4<f32>(color.rgb * color.a, color.a);
}

// An alpha-blended layer's weighted transparency sums (glint::transparency_out).
@fragment
fn fs_particle_weighted(in: ParticleOut) -> Weighted {
    return weighted_sums(particle_color(in), in.world_position);
}

#ifdef TRANSPARENCY_LISTS
// An alpha-blended layer's fragment into its pixel's list (exact
// transparency), after the depth test; sample 0's alone, as forward.wgsl's
// fs_exact.
@fragment
@early_depth_test(force)
fn fs_particle_exact(in: ParticleOut, @builtin(sample_index) sample: u32) {
    if sample == 0u {
        append_fragment(particle_color(in), in.clip);
    }
}
#endif

// The particle's colour at the fragment, not premultiplied.
fn particle_color(in: ParticleOut) -> vec4<f32> {
    var color = textureSample(sprite, sprite_sampler, in.uv) * in.color;
#ifdef LIT
    color = vec4<f32>(color.rgb * light_at(in.world_position, in.clip.xy), color.a);
#endif
    // Fog thins the particle towards nothing (what is behind already has it).
    let distance = length(camera.position.xyz - in.world_position) * scene.fog.w;
    color.a = color.a * exp(-distance * distance);
#ifdef SOFT
    color.a = color.a * clamp(depth_behind(in.clip, in.world_position) / max(look.x, 1e-4), 0.0, 1.0);
#endif
    return color;
}
