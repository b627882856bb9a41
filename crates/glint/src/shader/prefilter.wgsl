// Prefiltering an environment for image-based lighting (render/passes/environment.rs):
// full-screen passes, so every backend (WebGL2 too) runs them the same way.
// - fs_specular: one level of the specular map (equirectangular, level k for
//   roughness k / (levels − 1)): GGX importance sampling with n = v = r, each
//   sample read from the source mip whose texels cover the sample's share of the
//   lobe (filtered importance sampling: no fireflies from a few hot texels), at
//   most the level 8 texels wide (coarser ones bias wide lobes: 12 % at
//   roughness 1, against 2 % with the cap, in the unit test's integration).
// - fs_irradiance: the nine spherical-harmonic coefficients of the diffuse light
//   (texel k of a 9 × 1 target), already convolved with the clamped cosine and
//   divided by π, so Σ c_k Y_k(n) is the radiance a white Lambert surface returns.
// - fs_brdf: the split-sum table (x: n·v, y: roughness) of the scale and bias
//   applied to F0, with the height-correlated Smith term the forward shader's
//   lights use.

#import glint::equirect::{equirect_uv, equirect_direction, sh_basis, EQUIRECT_PI}
#import glint::full_screen::full_screen_clip

struct Params {
    // x: the level's roughness (0: a copy of the source); y: the source level a
    // copy reads; z, w: the target's size in texels.
    level: vec4<f32>,
    // x, y: the source's size at level 0; z: its levels; w: samples per texel.
    source: vec4<f32>,
    // x: the source level the irradiance sums.
    irradiance: vec4<f32>,
}

@group(0) @binding(0) var source: texture_2d<f32>;
@group(0) @binding(1) var source_sampler: sampler;
@group(0) @binding(2) var<uniform> params: Params;

@vertex
fn vs_full(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    return full_screen_clip(index, 0.0);
}

// The i-th of n points of the Hammersley set (bits reversed by hand: GLSL ES
// 3.0 has no bitfieldReverse).
fn hammersley(i: u32, n: u32) -> vec2<f32> {
    var b = i;
    b = (b << 16u) | (b >> 16u);
    b = ((b & 0x55555555u) << 1u) | ((b & 0xAAAAAAAAu) >> 1u);
    b = ((b & 0x33333333u) << 2u) | ((b & 0xCCCCCCCCu) >> 2u);
    b = ((b & 0x0F0F0F0Fu) << 4u) | ((b & 0xF0F0F0F0u) >> 4u);
    b = ((b & 0x00FF00FFu) << 8u) | ((b & 0xFF00FF00u) >> 8u);
    return vec2<f32>(f32(i) / f32(n), f32(b) * 2.3283064365386963e-10);
}

// The GGX half vector (z along the normal) for Hammersley point `xi`, its
// density D(h)(n·h) for α² = `a2`.
fn ggx_half_vector(xi: vec2<f32>, a2: f32) -> vec3<f32> {
    let cos_h = sqrt((1.0 - xi.y) / (1.0 + (a2 - 1.0) * xi.y));
    let sin_h = sqrt(max(1.0 - cos_h * cos_h, 0.0));
    let phi = 2.0 * EQUIRECT_PI * xi.x;
    return vec3<f32>(sin_h * cos(phi), sin_h * sin(phi), cos_h);
}

@fragment
fn fs_specular(@builtin(position) at: vec4<f32>) -> @location(0) vec4<f32> {
    let uv = at.xy / params.level.zw;
    let n = equirect_direction(uv);
    let roughness = params.level.x;
    if roughness <= 0.0 {
        return vec4<f32>(textureSampleLevel(source, source_sampler, uv, params.level.y).rgb, 1.0);
    }
    let a = max(roughness * roughness, 1e-3);
    let a2 = a * a;
    let up = select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(1.0, 0.0, 0.0), abs(n.y) > 0.999);
    let t = normalize(cross(up, n));
    let b = cross(n, t);
    let count = u32(params.source.w);
    // A level-0 source texel's solid angle, per unit of sin θ.
    let texel = 2.0 * EQUIRECT_PI * EQUIRECT_PI / (params.source.x * params.source.y);
    var sum = vec3<f32>(0.0);
    var weight = 0.0;
    for (var i = 0u; i < count; i++) {
        let local = ggx_half_vector(hammersley(i, count), a2);
        let cos_h = local.z;
        let h = t * local.x + b * local.y + n * cos_h;
        let l = 2.0 * cos_h * h - n;
        let n_l = dot(n, l);
        if n_l > 0.0 {
            let k = cos_h * cos_h * (a2 - 1.0) + 1.0;
            // pdf(l) = D (n·h) / (4 v·h), and v·h = n·h here.
            let pdf = a2 / (EQUIRECT_PI * k * k) * 0.25;
            let sample_angle = 1.0 / (f32(count) * pdf);
            let texel_angle = texel * max(sqrt(max(1.0 - l.y * l.y, 0.0)), 1e-3);
            let lod = clamp(0.5 * log2(sample_angle / texel_angle), 0.0, max(params.source.z - 4.0, 0.0));
            sum += textureSampleLevel(source, source_sampler, equirect_uv(l), lod).rgb * n_l;
            weight += n_l;
        }
    }
    return vec4<f32>(sum / max(weight, 1e-6), 1.0);
}

@fragment
fn fs_irradiance(@builtin(position) at: vec4<f32>) -> @location(0) vec4<f32> {
    let k = u32(at.x);
    // Signed: naga's GLSL writes an unsigned level as is, which textureSize refuses.
    let level = i32(params.irradiance.x);
    let size = textureDimensions(source, level);
    let texel = 2.0 * EQUIRECT_PI * EQUIRECT_PI / f32(size.x * size.y);
    var sum = vec3<f32>(0.0);
    var total = 0.0;
    for (var y = 0u; y < size.y; y++) {
        for (var x = 0u; x < size.x; x++) {
            let uv = (vec2<f32>(f32(x), f32(y)) + 0.5) / vec2<f32>(size);
            let d = equirect_direction(uv);
            var basis = sh_basis(d);
            let solid_angle = texel * sqrt(max(1.0 - d.y * d.y, 0.0));
            sum += textureLoad(source, vec2<u32>(x, y), level).rgb * (basis[k] * solid_angle);
            total += solid_angle;
        }
    }
    // The texels' solid angles are sampled at their centres: scaled so they
    // cover the sphere exactly (2.6 % too much for a 4-row image otherwise).
    sum *= 4.0 * EQUIRECT_PI / total;
    // The clamped cosine's band factors (π, 2π/3, π/4), over π.
    var band = 1.0;
    if k >= 4u {
        band = 0.25;
    } else if k >= 1u {
        band = 2.0 / 3.0;
    }
    return vec4<f32>(sum * band, 1.0);
}

@fragment
fn fs_brdf(@builtin(position) at: vec4<f32>) -> @location(0) vec4<f32> {
    let coords = at.xy / params.level.zw;
    let n_v = max(coords.x, 1e-4);
    let a = max(coords.y * coords.y, 1e-3);
    let a2 = a * a;
    let v = vec3<f32>(sqrt(1.0 - n_v * n_v), 0.0, n_v);
    let count = u32(params.source.w);
    var scale = 0.0;
    var bias = 0.0;
    for (var i = 0u; i < count; i++) {
        let h = ggx_half_vector(hammersley(i, count), a2);
        let cos_h = h.z;
        let v_h = dot(v, h);
        let l = 2.0 * v_h * h - v;
        let n_l = l.z;
        if n_l > 0.0 && v_h > 0.0 {
            let vis = 0.5 / (n_l * sqrt(n_v * n_v * (1.0 - a2) + a2) + n_v * sqrt(n_l * n_l * (1.0 - a2) + a2));
            // The sample's weight D·Vis·n_l / pdf(l), pdf(l) = D (n·h) / (4 v·h).
            let g = vis * n_l * 4.0 * v_h / cos_h;
            let fc = pow(1.0 - v_h, 5.0);
            scale += (1.0 - fc) * g;
            bias += fc * g;
        }
    }
    return vec4<f32>(scale / f32(count), bias / f32(count), 0.0, 1.0);
}
