// Post-processing passes on a full-screen triangle: each fragment entry point is
// one pass of a view's post chain (render/passes/post.rs). Colours are linear; a pass
// into the view's output (an sRGB target) is encoded by the hardware.
//
// Bindings and parameters: post_inputs.wgsl.

#import glint::full_screen::{full_screen_clip, full_screen_uv}
#import glint::post_inputs::{Params, Varyings, source, extra, linear_clamp, params}

@vertex
fn vs_post(@builtin(vertex_index) index: u32) -> Varyings {
    return Varyings(full_screen_clip(index, 0.0), full_screen_uv(index));
}

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

fn at(uv: vec2<f32>) -> vec3<f32> {
    return textureSampleLevel(source, linear_clamp, uv, 0.0).rgb;
}

/// The input texel `offset` texels from the one under `uv`, clamped to the edge.
fn texel_at(uv: vec2<f32>, offset: vec2<i32>) -> vec3<f32> {
    let size = vec2<i32>(textureDimensions(source));
    let base = vec2<i32>(floor(uv * vec2<f32>(size)));
    let coords = clamp(base + offset, vec2<i32>(0), size - vec2<i32>(1));
    return textureLoad(source, coords, 0).rgb;
}

// Bloom, 1 of 3: the light above the threshold (a soft knee: the part of each
// pixel's luminance over it).
@fragment
fn fs_bright(in: Varyings) -> @location(0) vec4<f32> {
    let c = at(in.uv);
    let l = luminance(c);
    return vec4<f32>(c * max(l - params.a.x, 0.0) / max(l, 1e-4), 1.0);
}

// Bloom, 2 of 3: a 9-tap Gaussian along one axis (run twice).
@fragment
fn fs_blur(in: Varyings) -> @location(0) vec4<f32> {
    let step = params.a.xy * params.texel.xy;
    var weights = array<f32, 5>(0.227027, 0.1945946, 0.1216216, 0.054054, 0.016216);
    var sum = at(in.uv) * weights[0];
    for (var k = 1; k < 5; k++) {
        let offset = step * f32(k);
        sum += (at(in.uv + offset) + at(in.uv - offset)) * weights[k];
    }
    return vec4<f32>(sum, 1.0);
}

// Bloom, 3 of 3: the blurred light added back.
@fragment
fn fs_bloom_add(in: Varyings) -> @location(0) vec4<f32> {
    let glow = textureSampleLevel(extra, linear_clamp, in.uv, 0.0).rgb;
    return vec4<f32>(at(in.uv) + glow * params.a.x, 1.0);
}

fn aces(x: vec3<f32>) -> vec3<f32> {
    // Narkowicz's fit of the ACES filmic curve.
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), vec3<f32>(0.0), vec3<f32>(1.0));
}

fn agx(x: vec3<f32>) -> vec3<f32> {
    // AgX (Troy Sobotka), in the minimal form of Benjamin Wrensch: inset, log2
    // encoding over [-12.47393, 4.026069] EV, a polynomial sigmoid, outset. The
    // sigmoid gives display values; they are decoded to linear for the sRGB target.
    let inset = mat3x3<f32>(
        vec3<f32>(0.842479062253094, 0.0423282422610123, 0.0423756549057051),
        vec3<f32>(0.0784335999999992, 0.878468636469772, 0.0784336),
        vec3<f32>(0.0792237451477643, 0.0791661274605434, 0.879142973793104),
    );
    let outset = mat3x3<f32>(
        vec3<f32>(1.19687900512017, -0.0528968517574562, -0.0529716355144438),
        vec3<f32>(-0.0980208811401368, 1.15190312990417, -0.0980434501171241),
        vec3<f32>(-0.0990297440797205, -0.0989611768448433, 1.15107367264116),
    );
    let lo = -12.47393;
    let hi = 4.026069;
    var v = inset * max(x, vec3<f32>(1e-10));
    v = clamp((log2(v) - lo) / (hi - lo), vec3<f32>(0.0), vec3<f32>(1.0));
    let v2 = v * v;
    let v4 = v2 * v2;
    v = 15.5 * v4 * v2 - 40.14 * v4 * v + 31.96 * v4 - 6.868 * v2 * v + 0.4298 * v2 + 0.1191 * v - 0.00232;
    v = outset * v;
    return pow(clamp(v, vec3<f32>(0.0), vec3<f32>(1.0)), vec3<f32>(2.2));
}

@fragment
fn fs_tonemap(in: Varyings) -> @location(0) vec4<f32> {
    let c = at(in.uv) * exp2(params.a.x);
    var mapped: vec3<f32>;
    switch u32(params.a.y) {
        case 1u: { mapped = c / (1.0 + c); }
        case 2u: { mapped = aces(c); }
        case 3u: { mapped = agx(c); }
        default: { mapped = clamp(c, vec3<f32>(0.0), vec3<f32>(1.0)); }
    }
    return vec4<f32>(mapped, 1.0);
}

fn perceived(c: vec3<f32>) -> f32 {
    return sqrt(luminance(clamp(c, vec3<f32>(0.0), vec3<f32>(1.0))));
}

// FXAA (after Lottes' FXAA 3 "console" variant, reduced): where the four
// diagonal neighbours' luma differ, blend along the edge's direction; a flat
// neighbourhood gives no direction and the pixel is left as it is.
@fragment
fn fs_fxaa(in: Varyings) -> @location(0) vec4<f32> {
    let texel = params.texel.xy;
    let m = at(in.uv);
    let nw = perceived(texel_at(in.uv, vec2<i32>(-1, -1)));
    let ne = perceived(texel_at(in.uv, vec2<i32>(1, -1)));
    let sw = perceived(texel_at(in.uv, vec2<i32>(-1, 1)));
    let se = perceived(texel_at(in.uv, vec2<i32>(1, 1)));
    let lm = perceived(m);
    let lo = min(lm, min(min(nw, ne), min(sw, se)));
    let hi = max(lm, max(max(nw, ne), max(sw, se)));
    if hi - lo < max(0.0312, hi * 0.125) {
        return vec4<f32>(m, 1.0);
    }
    var dir = vec2<f32>(-((nw + ne) - (sw + se)), (nw + sw) - (ne + se));
    let reduce = max((nw + ne + sw + se) * 0.25 * (1.0 / 8.0), 1.0 / 128.0);
    let scale = 1.0 / (min(abs(dir.x), abs(dir.y)) + reduce);
    dir = clamp(dir * scale, vec2<f32>(-8.0), vec2<f32>(8.0)) * texel;
    let a = 0.5 * (at(in.uv + dir * (1.0 / 3.0 - 0.5)) + at(in.uv + dir * (2.0 / 3.0 - 0.5)));
    let b = a * 0.5 + 0.25 * (at(in.uv - dir * 0.5) + at(in.uv + dir * 0.5));
    let lb = perceived(b);
    if lb < lo || lb > hi {
        return vec4<f32>(a, 1.0);
    }
    return vec4<f32>(b, 1.0);
}

// Sobel edge detection on luminance (seed 003): a pixel whose gradient is above
// the threshold takes the edge colour.
@fragment
fn fs_edges(in: Varyings) -> @location(0) vec4<f32> {
    var l: array<f32, 9>;
    for (var k = 0; k < 9; k++) {
        l[k] = perceived(texel_at(in.uv, vec2<i32>(k % 3 - 1, k / 3 - 1)));
    }
    let gx = (l[2] + 2.0 * l[5] + l[8]) - (l[0] + 2.0 * l[3] + l[6]);
    let gy = (l[6] + 2.0 * l[7] + l[8]) - (l[0] + 2.0 * l[1] + l[2]);
    let c = texel_at(in.uv, vec2<i32>(0, 0));
    if sqrt(gx * gx + gy * gy) > params.a.w {
        return vec4<f32>(params.a.xyz, 1.0);
    }
    return vec4<f32>(c, 1.0);
}

// Vignette: darker towards the corners, by up to `strength` there.
@fragment
fn fs_vignette(in: Varyings) -> @location(0) vec4<f32> {
    let d = distance(in.uv, vec2<f32>(0.5)) * 1.41421356;
    return vec4<f32>(at(in.uv) * (1.0 - params.a.x * smoothstep(0.4, 1.0, d)), 1.0);
}
