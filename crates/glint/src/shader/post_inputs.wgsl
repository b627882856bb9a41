// What every pass of a post chain (render/passes/post.rs) reads, in
// post.wgsl and smaa.wgsl: the pass's input, a second input (bloom's
// blurred light, SMAA's blending weights), a linear clamping sampler and the
// pass's parameters; and what the full-screen triangle hands each fragment.

#define_import_path glint::post_inputs

struct Params {
    // Per pass: bright: x threshold. blur: xy direction in texels. bloom_add: x
    // intensity. tonemap: x exposure (EV), y operator (0 none, 1 Reinhard, 2 ACES,
    // 3 AgX). edges: xyz colour, w threshold. vignette: x strength. SMAA's
    // passes: x luma threshold, y most search steps, z most diagonal search
    // steps (0: none), w the share of a corner's blending kept (1: no corner
    // detection).
    a: vec4<f32>,
    // xy: one texel of the input in uv units, zw: the input's size in pixels.
    texel: vec4<f32>,
}

@group(0) @binding(0) var source: texture_2d<f32>;
@group(0) @binding(1) var extra: texture_2d<f32>;
@group(0) @binding(2) var linear_clamp: sampler;
@group(0) @binding(3) var<uniform> params: Params;

struct Varyings {
    @builtin(position) position: vec4<f32>,
    @location(0) uv: vec2<f32>,
}
