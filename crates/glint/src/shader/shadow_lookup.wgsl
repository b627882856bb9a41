// Shadow lookups: how much of a light reaches a point past the shadow
// casters, filtered, from the frame's shadow maps (render/passes/shadow_maps.rs
// draws them; blocks.wgsl binds them): directional lights' cascades, spot
// lights' maps and point lights' cubes (SHADOW_CUBES); soft shadows of lights
// with a size (SOFT_SHADOWS).
#define_import_path glint::shadow_lookup

#import glint::blocks::{camera, scene, shadows, shadow_maps, shadow_cubes, shadow_sampler, Light, CASCADES}

// How much of a point or spot light reaches `p` (towards it `l`, `dist` away) past
// the shadow casters (0..1, filtered). The lookup point moves `params.w` texels
// along the normal and `params.z` texels towards the light first, so lit surfaces
// do not shadow themselves.
fn positional_shadow(first: u32, light: Light, p: vec3<f32>, ng: vec3<f32>, l: vec3<f32>, dist: f32) -> f32 {
    if light.spot.w > 0.0 {
        let texel = shadows.info[first].x * dist;
        return map_shadow(first, p + ng * (light.params.w * texel) + l * (light.params.z * texel), ng);
    }
#ifdef SHADOW_CUBES
    let texel = 2.0 * shadows.params.y * dist;
    return cube_shadow(first, light, p + ng * (light.params.w * texel) + l * (light.params.z * texel));
#else
    // Only frames that drew point lights' cubes look them up (SHADOW_CUBES).
    return 1.0;
#endif
}

// The cascade whose slice holds `p`, blended into the next over the last part of
// its slice; past the last cascade, light. The offsets are those of
// positional_shadow, in the cascade's texels.
fn cascaded_shadow(first: u32, light: Light, p: vec3<f32>, ng: vec3<f32>) -> f32 {
    let depth = -(camera.view * vec4<f32>(p, 1.0)).z;
    var c = 0u;
    while c < CASCADES && depth >= shadows.info[first + c].y {
        c++;
    }
    if c == CASCADES {
        return 1.0;
    }
    let end = shadows.info[first + c].y;
    var start = 0.0;
    if c > 0u {
        start = shadows.info[first + c - 1u].y;
    }
    let band = (end - start) * shadows.params.z;
    let lit = cascade_sample(first + c, light, p, ng);
    let t = saturate((depth - (end - band)) / max(band, 1e-6));
    if t <= 0.0 {
        return lit;
    }
    var next = 1.0;
    if c + 1u < CASCADES {
        next = cascade_sample(first + c + 1u, light, p, ng);
    }
    return mix(lit, next, t);
}

fn cascade_sample(view: u32, light: Light, p: vec3<f32>, ng: vec3<f32>) -> f32 {
    let texel = shadows.info[view].x;
    let q = p + ng * (light.params.w * texel) - normalize(light.position.xyz) * (light.params.z * texel);
    return map_shadow(view, q, ng);
}

// 3×3 comparison taps a texel apart (each one bilinear): a 4×4-texel filter;
// for a view whose light has a size, percentage-closer soft shadows of the
// receiver at `q` whose surface faces `n`.
fn map_shadow(layer: u32, q: vec3<f32>, n: vec3<f32>) -> f32 {
    let clip = shadows.view_proj[layer] * vec4<f32>(q, 1.0);
    let ndc = clip.xyz / clip.w;
    if clip.w <= 0.0 || any(abs(ndc.xy) > vec2<f32>(1.0)) || ndc.z > 1.0 {
        return 1.0;
    }
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
#ifdef SOFT_SHADOWS
    if shadows.info[layer].z > 0.0 {
        let receiver = Receiver(uv, ndc.z, receiver_slope(layer, q, n, vec3<f32>(uv, ndc.z), clip.w));
        return soft_shadow(layer, receiver, shadows.info[layer].z);
    }
#endif
    let step = shadows.params.x;
    var lit = 0.0;
    for (var y = -1; y <= 1; y++) {
        for (var x = -1; x <= 1; x++) {
            let at = uv + vec2<f32>(f32(x), f32(y)) * step;
            lit += textureSampleCompareLevel(shadow_maps, shadow_sampler, at, layer, ndc.z);
        }
    }
    return lit / 9.0;
}

#ifdef SOFT_SHADOWS
// The widest penumbra and blocker search, in texels.
const MAX_PENUMBRA: f32 = 24.0;
// The narrowest filter, in texels: about the 3×3 filter's.
const MIN_PENUMBRA: f32 = 3.0;
// Taps across the blocker search's square, and its halvings of the blockers' gap.
const SEARCH_TAPS: i32 = 4;
const SEARCH_STEPS: i32 = 4;
// The filter's taps (each bilinear) are at most this many texels apart, so
// that they cover its square without gaps: 3 to 12 across.
const FILTER_SPACING: f32 = 2.0;

// Where a soft shadow is looked up: the receiver's uv in the view, its NDC
// depth, and how that depth changes across its surface per unit of uv.
struct Receiver {
    uv: vec2<f32>,
    z: f32,
    slope: vec2<f32>,
}

// The NDC depth gradient per unit of uv, in layer `layer`'s view, of the plane
// through `q` facing `n` (`o`: q's uv and NDC depth there, `w`: its clip w),
// from two points of the plane beside `q` projected as `q` was: so a wide filter compares each texel with the
// receiver's own depth there, not its depth at the centre, and a surface
// sloped to the light neither shadows itself nor counts as its own blocker
// (receiver plane depth bias, Isidoro 2006). 0 for a plane seen edge on.
fn receiver_slope(layer: u32, q: vec3<f32>, n: vec3<f32>, o: vec3<f32>, w: f32) -> vec2<f32> {
    // A few texels: absolute for a cascade, per unit of distance for a spot view.
    let e = 4.0 * shadows.info[layer].x * select(w, 1.0, shadows.info[layer].y > 0.0);
    let helper = select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(1.0, 0.0, 0.0), abs(n.y) > 0.9);
    let t = normalize(cross(n, helper));
    let a = light_uv_depth(layer, q + t * e) - o;
    let b = light_uv_depth(layer, q + cross(n, t) * e) - o;
    // Seen (nearly) edge on, the plane's tangents project (nearly) parallel:
    // no slope rather than an unbounded one.
    let det = a.x * b.y - a.y * b.x;
    if abs(det) <= 1e-3 * length(a.xy) * length(b.xy) {
        return vec2<f32>(0.0);
    }
    return vec2<f32>(a.z * b.y - b.z * a.y, a.x * b.z - b.x * a.z) / det;
}

// `p` in layer `layer`'s view: its uv and NDC depth.
fn light_uv_depth(layer: u32, p: vec3<f32>) -> vec3<f32> {
    let clip = shadows.view_proj[layer] * vec4<f32>(p, 1.0);
    let ndc = clip.xyz / clip.w;
    return vec3<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5, ndc.z);
}

// Percentage-closer soft shadows (Fernando 2005) of `receiver` in layer
// `layer`. `scale` is the penumbra's width in uv per unit of NDC depth between
// blocker and receiver, the similar triangles' ratio (render/passes/
// shadow_views.rs penumbra_scale): the same linear rule for a directional
// light's orthographic cascades and, in NDC depth, a spot light's perspective
// view. 1. Blocker search, over the square a blocker at the near plane could
// shade the receiver from: the median gap between the receiver's plane and
// the texels nearer the light, found by halving with comparisons only (no
// texel is read as a number: GLSL cannot load from a depth texture, nor bind
// it to a second sampler, and WebGL2's 16 texture units are all taken).
// 2. The penumbra that gap gives. 3. A box filter that wide: a square grid of
// bilinear comparisons, the grid moved by the sub-frame's offset (Scene block
// environment_sky.zw) so that an accumulated still smooths what ripple is left.
fn soft_shadow(layer: u32, receiver: Receiver, scale: f32) -> f32 {
    let texel = shadows.params.x;
    let widest = MAX_PENUMBRA * texel;
    let search = min(receiver.z * scale, widest);
    let all = blocked(layer, receiver, search, 0.0);
    // Nothing nearer the light: lit; everything: in the umbra.
    if all <= 0.0 || all >= 1.0 {
        return 1.0 - all;
    }
    // More than half the blockers are further than `low` from the receiver, at most half further than `high`.
    var low = 0.0;
    var high = widest / scale;
    for (var k = 0; k < SEARCH_STEPS; k++) {
        let middle = 0.5 * (low + high);
        if blocked(layer, receiver, search, middle) > 0.5 * all {
            low = middle;
        } else {
            high = middle;
        }
    }
    let width = clamp(0.5 * (low + high) * scale, MIN_PENUMBRA * texel, widest);
    let taps = i32(ceil(width / (FILTER_SPACING * texel)));
    let step = width / f32(taps);
    let start = (scene.environment_sky.zw + 0.5 - 0.5 * f32(taps)) * step;
    var lit = 0.0;
    for (var y = 0; y < taps; y++) {
        for (var x = 0; x < taps; x++) {
            let offset = start + vec2<f32>(f32(x), f32(y)) * step;
            lit += lit_at(layer, receiver, offset, 0.0);
        }
    }
    return lit / f32(taps * taps);
}

// The fraction of the square `search` wide about the receiver whose texels
// are nearer the light than the receiver's plane by more than `gap` (NDC
// depth): SEARCH_TAPS² bilinear comparisons.
fn blocked(layer: u32, receiver: Receiver, search: f32, gap: f32) -> f32 {
    var lit = 0.0;
    for (var y = 0; y < SEARCH_TAPS; y++) {
        for (var x = 0; x < SEARCH_TAPS; x++) {
            let offset = ((vec2<f32>(f32(x), f32(y)) + 0.5) / f32(SEARCH_TAPS) - 0.5) * search;
            lit += lit_at(layer, receiver, offset, gap);
        }
    }
    return 1.0 - lit / f32(SEARCH_TAPS * SEARCH_TAPS);
}

// One bilinear comparison `offset` (uv) from the receiver, against its plane
// there moved `gap` towards the light.
fn lit_at(layer: u32, receiver: Receiver, offset: vec2<f32>, gap: f32) -> f32 {
    let reference = receiver.z + dot(receiver.slope, offset) - gap;
    return textureSampleCompareLevel(shadow_maps, shadow_sampler, receiver.uv + offset, layer, reference);
}
#endif

#ifdef SHADOW_CUBES
// 3×3 taps across the cube face around the direction, a texel apart, each in
// the face its direction falls on.
fn cube_shadow(cube: u32, light: Light, q: vec3<f32>) -> f32 {
    let d = q - light.position.xyz;
    let depth = length(d) / light.color.w;
    let n = d / max(length(d), 1e-6);
    let helper = select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(1.0, 0.0, 0.0), abs(n.y) > 0.9);
    let t = normalize(cross(n, helper));
    let b = cross(n, t);
    let step = 2.0 * shadows.params.y;
    var lit = 0.0;
    for (var y = -1; y <= 1; y++) {
        for (var x = -1; x <= 1; x++) {
            let at = cube_face(n + (t * f32(x) + b * f32(y)) * step);
            lit += textureSampleCompareLevel(shadow_cubes, shadow_sampler, at.uv, 6u * cube + at.face, depth);
        }
    }
    return lit / 9.0;
}
#endif

#ifdef SHADOW_CUBES
// Where direction `d` meets a cube map: the face (+X −X +Y −Y +Z −Z) and the
// texture coordinates on it, origin at the face's top-left, by the major axis as
// the Vulkan specification's cube-map table has them.
struct CubeTexel {
    face: u32,
    uv: vec2<f32>,
}

fn cube_face(d: vec3<f32>) -> CubeTexel {
    let a = abs(d);
    var face: u32;
    var st: vec2<f32>;
    var major: f32;
    if a.x >= a.y && a.x >= a.z {
        major = a.x;
        face = select(1u, 0u, d.x > 0.0);
        st = vec2<f32>(select(d.z, -d.z, d.x > 0.0), -d.y);
    } else if a.y >= a.z {
        major = a.y;
        face = select(3u, 2u, d.y > 0.0);
        st = vec2<f32>(d.x, select(-d.z, d.z, d.y > 0.0));
    } else {
        major = a.z;
        face = select(5u, 4u, d.z > 0.0);
        st = vec2<f32>(select(-d.x, d.x, d.z > 0.0), -d.y);
    }
    return CubeTexel(face, (st / max(major, 1e-6) + 1.0) * 0.5);
}
#endif
