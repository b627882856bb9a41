// Screen-space ambient occlusion (render/passes/ambient_occlusion.rs), two passes at
// half the view's resolution over the depth pre-pass, full-screen fragment
// passes here, compute passes with ssao_compute.wgsl appended:
// - fs_occlusion: ground-truth ambient occlusion (Jimenez et al. 2016, "Practical
//   Realtime Strategies for Accurate Indirect Occlusion"): per pixel, SLICES
//   screen directions turned by a per-pixel noise; in each, the highest horizon
//   on either side within the radius, and the cosine-weighted visible arc
//   between them about the projected normal. Each slice's visible arc is divided
//   by its unoccluded arc, so open ground is exactly 1.
// - fs_blur: a 5 × 5 blur whose taps count less the further their depth is
//   from the centre's, so occlusion does not bleed across silhouettes. The
//   occlusion pass writes each pixel's distance beside its occlusion (g, b, a:
//   24 bits of its logarithm), so the blur reads one texture, not two.
// Half-resolution pixel p stands for full-resolution pixel 2p of the pre-pass.

struct AmbientOcclusion {
    // x, y: the projection's scale (its [0][0] and [1][1]); z: 1 for an
    // orthographic camera; w: the radius in view units.
    projection: vec4<f32>,
    // x: intensity (the visibility's exponent); y: the largest radius in
    // full-resolution pixels; z: the sub-frame of an accumulated still (0 for
    // a frame of its own), which turns the noise; w: reserved.
    params: vec4<f32>,
}

@group(0) @binding(0) var<uniform> ao: AmbientOcclusion;
// The depth pre-pass (forward.wgsl fs_prepass): xy the view-space normal
// (octahedral), z + w the distance in front of the camera (a half float and
// what it rounded away); 0 where nothing was drawn. With the view target's
// samples where they are several (PREPASS_MSAA): its first sample is read, a
// surface's own (a resolve's average would put one between two surfaces).
#ifdef PREPASS_MSAA
@group(0) @binding(1) var prepass: texture_multisampled_2d<f32>;
#else
@group(0) @binding(1) var prepass: texture_2d<f32>;
#endif
// fs_blur: fs_occlusion's output (r: the occlusion; g, b, a: the distance, packed).
@group(0) @binding(2) var raw: texture_2d<f32>;

#import glint::full_screen::full_screen_clip

const PI: f32 = 3.14159265;
// Slices a pixel, and samples on each side of a slice: 24 samples a pixel
// (with 36 the passes took 10.6 % of the showcase's GPU time at 1280 × 720
// on lavapipe, with 24 under 8 %; `cargo bench -p glint --bench environment`).
const SLICES: u32 = 3u;
const STEPS: u32 = 4u;
// The sine of the angle above a surface's tangent plane below which nothing
// occludes it (about a degree): flat ground stays exactly open.
const BIAS: f32 = 0.02;

@vertex
fn vs_full(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    return full_screen_clip(i, 0.0);
}

fn decode_normal(e: vec2<f32>) -> vec3<f32> {
    var n = vec3<f32>(e, 1.0 - abs(e.x) - abs(e.y));
    let t = max(-n.z, 0.0);
    n.x += select(t, -t, n.x >= 0.0);
    n.y += select(t, -t, n.y >= 0.0);
    return normalize(n);
}

fn distance_at(q: vec2<i32>) -> f32 {
    let t = textureLoad(prepass, q, 0);
    return t.z + t.w;
}

// What turns a full-resolution pixel and its distance into a view-space
// position (the same for every pixel of a frame): view xy = (q · scale +
// offset) × the distance (× 1 for an orthographic camera).
struct Unproject {
    scale: vec2<f32>,
    offset: vec2<f32>,
    orthographic: bool,
}

fn unproject() -> Unproject {
    let inverse = 1.0 / vec2<f32>(textureDimensions(prepass));
    let flip = vec2<f32>(1.0, -1.0) / ao.projection.xy;
    // ndc = (q + 0.5) · 2 / size − 1, y pointing up.
    return Unproject(2.0 * inverse * flip, (inverse - 1.0) * flip, ao.projection.z > 0.5);
}

// The view-space position of full-resolution pixel q at `distance`.
fn view_position(u: Unproject, q: vec2<i32>, distance: f32) -> vec3<f32> {
    let scale = select(distance, 1.0, u.orthographic);
    return vec3<f32>((vec2<f32>(q) * u.scale + u.offset) * scale, -distance);
}

// A distance packed into three 8-bit channels (24 bits of its logarithm,
// from 2^-16 to 2^32 view units); 0 for "nothing drawn".
fn pack_distance(distance: f32) -> vec3<f32> {
    if distance <= 0.0 {
        return vec3<f32>(0.0);
    }
    let x = clamp((log2(distance) + 16.0) / 48.0, 0.0, 1.0);
    let v = max(round(x * 16777214.0), 0.0) + 1.0;
    let high = floor(v / 65536.0);
    let middle = floor((v - high * 65536.0) / 256.0);
    let low = v - high * 65536.0 - middle * 256.0;
    return vec3<f32>(high, middle, low) / 255.0;
}

fn unpack_distance(c: vec3<f32>) -> f32 {
    let v = dot(round(c * 255.0), vec3<f32>(65536.0, 256.0, 1.0));
    return select(exp2((v - 1.0) / 16777214.0 * 48.0 - 16.0), 0.0, v < 0.5);
}

// Interleaved gradient noise (Jimenez 2014): a different slice turn per pixel.
fn noise(p: vec2<f32>) -> f32 {
    return fract(52.9829189 * fract(dot(p, vec2<f32>(0.06711056, 0.00583715))));
}

// The cosine-weighted visible arc from the view vector to horizon angle h,
// about normal angle n in the slice (`normal`: n, its cosine and sine).
fn arc(h: f32, normal: vec3<f32>) -> f32 {
    return 0.25 * (-cos(2.0 * h - normal.x) + normal.y + 2.0 * h * normal.z);
}

@fragment
fn fs_occlusion(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    return occlusion_at(vec2<i32>(floor(position.xy)));
}

@fragment
fn fs_blur(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    return vec4<f32>(blur_at(vec2<i32>(floor(position.xy))));
}

// The occlusion of half-resolution pixel `half_pixel` (r: 1 open, 0 wholly
// occluded), and its distance, packed (g, b, a) for the blur.
fn occlusion_at(half_pixel: vec2<i32>) -> vec4<f32> {
    let q = half_pixel * 2;
    let centre = textureLoad(prepass, q, 0);
    let distance = centre.z + centre.w;
    return vec4<f32>(occlusion_of(half_pixel, centre.xy, distance), pack_distance(distance));
}

// The occlusion at half-resolution pixel `half_pixel`, whose surface has
// normal `encoded` at `distance`.
fn occlusion_of(half_pixel: vec2<i32>, encoded: vec2<f32>, distance: f32) -> f32 {
    if distance <= 0.0 {
        return 1.0;
    }
    let q = half_pixel * 2;
    let full = vec2<i32>(textureDimensions(prepass));
    let u = unproject();
    let p = view_position(u, q, distance);
    let n = decode_normal(encoded);
    let orthographic = u.orthographic;
    let v = select(normalize(-p), vec3<f32>(0.0, 0.0, 1.0), orthographic);
    let radius = ao.projection.w;
    let inverse_radius_squared = 1.0 / (radius * radius);
    // The radius in full-resolution pixels.
    let per_unit = 0.5 * f32(full.y) * ao.projection.y / select(distance, 1.0, orthographic);
    let radius_pixels = min(radius * per_unit, ao.params.y);
    if radius_pixels < 2.0 {
        return 1.0;
    }
    // Each sub-frame of a still turns every pixel's slices by a further golden ratio.
    let turn = fract(noise(vec2<f32>(half_pixel)) + ao.params.z * 0.618034);
    let jitter = fract(turn * 7.0 + 0.5);
    var visible = 0.0;
    var open = 0.0;
    for (var s = 0u; s < SLICES; s++) {
        let phi = (f32(s) + turn) * PI / f32(SLICES);
        let direction = vec2<f32>(cos(phi), sin(phi));
        // Screen y grows down, view y up.
        let d = vec3<f32>(direction.x, -direction.y, 0.0);
        let axis = normalize(cross(d, v));
        let along = cross(v, axis);
        let projected = n - axis * dot(n, axis);
        let length_n = length(projected);
        if length_n < 1e-4 {
            continue;
        }
        let cos_n = clamp(dot(projected, v) / length_n, -1.0, 1.0);
        let side_n = sign(dot(projected, along));
        let normal_angle = side_n * acos(cos_n);
        let sin_n = side_n * sqrt(max(1.0 - cos_n * cos_n, 0.0));
        let normal = vec3<f32>(normal_angle, select(cos_n, 1.0, side_n == 0.0), sin_n);
        // The highest horizon's cosine on each side: +direction, then −direction.
        var horizon = vec2<f32>(-1.0);
        for (var side = 0u; side < 2u; side++) {
            let step = select(-direction, direction, side == 0u);
            for (var k = 0u; k < STEPS; k++) {
                let t = (f32(k) + jitter) / f32(STEPS);
                let offset = step * max(t * t * radius_pixels, 1.5);
                let sq = q + vec2<i32>(round(offset));
                // Off screen, and where nothing was drawn: nothing occludes.
                if any(sq < vec2<i32>(0)) || any(sq >= full) {
                    continue;
                }
                let sample_distance = distance_at(sq);
                if sample_distance <= 0.0 {
                    continue;
                }
                let delta = view_position(u, sq, sample_distance) - p;
                let squared = dot(delta, delta);
                let falloff = saturate(1.0 - squared * inverse_radius_squared);
                let length_d = max(sqrt(squared), 1e-6);
                // Only what rises above the surface's own plane occludes it: a
                // sample rounded off the slice, on flat ground, would not lie
                // on the slice's tangent. Past the radius nothing does.
                if dot(delta, n) < BIAS * length_d || falloff <= 0.0 {
                    continue;
                }
                let cos_h = mix(-1.0, clamp(dot(delta, v) / length_d, -1.0, 1.0), falloff);
                horizon[side] = max(horizon[side], cos_h);
            }
        }
        // Horizon angles, at most a quarter turn from the normal.
        let h_plus = normal_angle + min(acos(horizon.x) - normal_angle, 0.5 * PI);
        let h_minus = normal_angle + max(-acos(horizon.y) - normal_angle, -0.5 * PI);
        // arc(n + π/2) + arc(n − π/2): the whole hemisphere's.
        let unoccluded = normal.y + normal_angle * normal.z;
        visible += length_n * (arc(h_plus, normal) + arc(h_minus, normal));
        open += length_n * unoccluded;
    }
    let visibility = select(1.0, saturate(visible / open), open > 1e-4);
    return exp2(ao.params.x * log2(max(visibility, 1e-4)));
}

// Half-resolution pixel `p` of the occlusion, blurred (the fragment pass's
// way: every tap read from `raw`; the compute pass reads a workgroup's taps
// once, into shared memory).
fn blur_at(p: vec2<i32>) -> f32 {
    let size = vec2<i32>(textureDimensions(raw));
    let centre = unpack_distance(textureLoad(raw, p, 0).gba);
    var sum = vec2<f32>(0.0);
    for (var y = -2; y <= 2; y++) {
        for (var x = -2; x <= 2; x++) {
            let tap = textureLoad(raw, clamp(p + vec2<i32>(x, y), vec2<i32>(0), size - 1), 0);
            sum += blur_tap(vec2<f32>(tap.r, unpack_distance(tap.gba)), centre);
        }
    }
    return blurred(sum, centre);
}

// A tap (its occlusion, its distance) of the blur around a pixel at
// distance `centre`: its weighted occlusion and its weight, which falls by
// e for each 2 % of the centre's distance between them (none where nothing
// was drawn).
fn blur_tap(tap: vec2<f32>, centre: f32) -> vec2<f32> {
    let w = select(0.0, exp(abs(tap.y - centre) * (-50.0 / centre)), tap.y > 0.0);
    return vec2<f32>(w * tap.x, w);
}

// The blurred occlusion from the taps' sums; open where nothing was drawn.
fn blurred(sum: vec2<f32>, centre: f32) -> f32 {
    return select(1.0, sum.x / sum.y, centre > 0.0 && sum.y > 0.0);
}
