// Blit: the source texture drawn over the whole target through a linear sampler.
// Mip generation draws each level from the one above at half size; a window shows
// a frame at the same size (texel centres land on pixel centres: an exact copy).
// sRGB views decode and re-encode, so filtering is in linear space.

#import glint::full_screen::{full_screen_clip, full_screen_uv}

@group(0) @binding(0) var source: texture_2d<f32>;
@group(0) @binding(1) var source_sampler: sampler;

struct BlitOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
}

@vertex
fn vs_blit(@builtin(vertex_index) index: u32) -> BlitOut {
    return BlitOut(full_screen_clip(index, 0.0), full_screen_uv(index));
}

@fragment
fn fs_blit(in: BlitOut) -> @location(0) vec4<f32> {
    return textureSample(source, source_sampler, in.uv);
}
