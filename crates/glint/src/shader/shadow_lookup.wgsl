// Shadow lookups: how much of a light reaches a point past the shadow
// casters, filtered, from the frame's shadow maps (render/passes/shadow_maps.rs
// draws them; blocks.wgsl binds them): directional lights' cascades, spot
// lights' maps and point lights' cubes (SHADOW_CUBES).
#define_import_path glint::shadow_lookup

#import glint::blocks::{camera, shadows, shadow_maps, shadow_cubes, shadow_sampler, Light, CASCADES}

// How much of a point or spot light reaches `p` (towards it `l`, `dist` away) past
// the shadow casters (0..1, filtered). The lookup point moves `params.w` texels
// along the normal and `params.z` texels towards the light first, so lit surfaces
// do not shadow themselves.
fn positional_shadow(first: u32, light: Light, p: vec3<f32>, ng: vec3<f32>, l: vec3<f32>, dist: f32) -> f32 {
    if light.spot.w > 0.0 {
        let texel = shadows.info[first].x * dist;
        return map_shadow(first, p + ng * (light.params.w * texel) + l * (light.params.z * texel));
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
    return map_shadow(view, p + ng * (light.params.w * texel) - normalize(light.position.xyz) * (light.params.z * texel));
}

// 3×3 comparison taps a texel apart (each one bilinear): a 4×4-texel filter.
fn map_shadow(layer: u32, q: vec3<f32>) -> f32 {
    let clip = shadows.view_proj[layer] * vec4<f32>(q, 1.0);
    let ndc = clip.xyz / clip.w;
    if clip.w <= 0.0 || any(abs(ndc.xy) > vec2<f32>(1.0)) || ndc.z > 1.0 {
        return 1.0;
    }
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
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
