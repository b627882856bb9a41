// Weighted blended transparency's composite (render/passes/transparency.rs,
// after McGuire and Bavoil 2013): the view's sums, drawn by forward.wgsl's
// fs_weighted, over what the opaque stages drew. Blended One +
// OneMinusSrcAlpha: the average colour covers 1 - revealage of the pixel.
//
// Bindings: the sums (rgb: colour × alpha × weight; a: revealage, the
// product of 1 - alpha) and the weights (r: the sum of alpha × weight),
// resolved to one sample.

#import glint::full_screen::full_screen_clip

@group(0) @binding(0) var sums: texture_2d<f32>;
@group(0) @binding(1) var weights: texture_2d<f32>;

@vertex
fn vs_composite(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    return full_screen_clip(index, 0.0);
}

@fragment
fn fs_composite(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let p = vec2<i32>(position.xy);
    let sum = textureLoad(sums, p, 0);
    // Nothing transparent here: the pixel stays as it was.
    if sum.a >= 1.0 {
        discard;
    }
    let color = sum.rgb / max(textureLoad(weights, p, 0).r, 1e-5);
    let coverage = 1.0 - sum.a;
    return vec4<f32>(color * coverage, coverage);
}
