// Accumulated stills (render/passes/accumulate.rs): a view's sub-frame folded
// into its running mean, and the mean copied out for its post chain. The mean
// is 32-bit float kept as its bits in a 32-bit unsigned integer image, which
// every backend renders into (GL and WebGL2 cannot render into 32-bit floats).
//
// Bindings: the mean so far (bits), the sub-frame as drawn (HDR), the fold's weight.

#import glint::full_screen::full_screen_clip

struct Fold {
    // x: 1 / (k + 1) for sub-frame k; 1 replaces the mean with the sub-frame.
    weight: vec4<f32>,
}

@group(0) @binding(0) var mean: texture_2d<u32>;
@group(0) @binding(1) var sub_frame: texture_2d<f32>;
@group(0) @binding(2) var<uniform> fold: Fold;

@vertex
fn vs_accumulate(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    return full_screen_clip(index, 0.0);
}

fn mean_at(p: vec2<i32>) -> vec4<f32> {
    return bitcast<vec4<f32>>(textureLoad(mean, p, 0));
}

// The mean of sub-frames 0..=k: mean + (x - mean) / (k + 1).
@fragment
fn fs_fold(@builtin(position) position: vec4<f32>) -> @location(0) vec4<u32> {
    let p = vec2<i32>(position.xy);
    let x = textureLoad(sub_frame, p, 0);
    if fold.weight.x >= 1.0 {
        return bitcast<vec4<u32>>(x);
    }
    let m = mean_at(p);
    return bitcast<vec4<u32>>(m + (x - m) * fold.weight.x);
}

// The mean, into the HDR image the post chain reads.
@fragment
fn fs_copy(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    return mean_at(vec2<i32>(position.xy));
}
