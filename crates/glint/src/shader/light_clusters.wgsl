// A view's light clusters (render/clusters.rs, render/frame/lights.rs), as
// the forward shader and lit particles read them, and the light a point or
// spot light sends to a point.
//
// The clusters are one array of 16-byte texels (one binding: WebGL2 allows 16
// textures a stage): words, four a texel, then the view's point and spot
// lights as Light records of four texels. Word 0 is the texel the records
// begin at; then per cluster two words, the word its entries begin at and
// their count; then the entries (lights' numbers). A data texture where
// DATA_TEXTURES (its rows DATA_WIDTH texels), else a storage buffer.
#define_import_path glint::light_clusters

#import glint::blocks::{scene, camera, Light}

#ifdef DATA_TEXTURES
@group(0) @binding(10) var cluster_texels: texture_2d<u32>;

fn cluster_texel(i: u32) -> vec4<u32> {
    return textureLoad(cluster_texels, vec2<u32>(i % #{DATA_WIDTH}u, i / #{DATA_WIDTH}u), 0);
}
#else
@group(0) @binding(10) var<storage, read> cluster_data: array<vec4<u32>>;

fn cluster_texel(i: u32) -> vec4<u32> {
    return cluster_data[i];
}
#endif

fn cluster_word(i: u32) -> u32 {
    return cluster_texel(i / 4u)[i % 4u];
}

// Light `i` of the view's, its records beginning at texel `at`.
fn clustered_light(at: u32, i: u32) -> Light {
    let first = at + 4u * i;
    return Light(
        bitcast<vec4<f32>>(cluster_texel(first)),
        bitcast<vec4<f32>>(cluster_texel(first + 1u)),
        bitcast<vec4<f32>>(cluster_texel(first + 2u)),
        bitcast<vec4<f32>>(cluster_texel(first + 3u)),
    );
}

// The light cluster of a fragment at `pixel` in the view and world position
// `position` (its pixel's tile and its view depth's slice, the rule of
// render/clusters.rs): x its entries' first word, y their count, z the texel
// the light records begin at.
fn cluster_at(pixel: vec2<f32>, position: vec3<f32>) -> vec3<u32> {
    let tiles = vec2<u32>(scene.clusters.xy);
    let tile = min(vec2<u32>(pixel / f32(scene.counts.z)), tiles - 1u);
    let depth = max(-(camera.view * vec4<f32>(position, 1.0)).z, 1e-6);
    let slice = clamp(floor(log(depth) * scene.clusters.z + scene.clusters.w), 0.0, f32(scene.counts.w - 1u));
    let index = tile.x + tiles.x * (tile.y + tiles.y * u32(slice));
    return vec3<u32>(cluster_word(1u + 2u * index), cluster_word(2u + 2u * index), cluster_word(0u));
}

// From `p` towards a point or spot light: xyz the unit direction, w the distance.
fn towards_light(light: Light, p: vec3<f32>) -> vec4<f32> {
    let to_light = light.position.xyz - p;
    let dist = length(to_light);
    return vec4<f32>(to_light / max(dist, 1e-4), dist);
}

// The light a point or spot light sends along `towards` (towards_light's),
// times `lit` (its shadow): inverse square, windowed to reach exactly zero at
// the range, and the spot's cone.
fn arriving(light: Light, towards: vec4<f32>, lit: f32) -> vec3<f32> {
    let dist = towards.w;
    let x = dist / light.color.w;
    let window = saturate(1.0 - x * x * x * x);
    let cone = saturate(dot(light.spot.xyz, -towards.xyz) * light.spot.w + light.params.x);
    return light.color.rgb * lit * window * window * cone * cone / max(dist * dist, 1e-4);
}
