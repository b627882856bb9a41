// Forward pass: lit, textured, instanced meshes. Composed per feature set: each
// `#ifdef` below is one bit of ShaderFeatures (src/shader/mod.rs).

#import glint::blocks::{scene, camera}

struct MaterialBlock {
    base_color: vec4<f32>,
    // x: ambient, y: diffuse, z: specular, w: Blinn-Phong exponent.
    coeffs: vec4<f32>,
    alpha_cutoff: f32,
    reserved: u32,
    uv_scale: vec2<f32>,
}

@group(2) @binding(0) var<uniform> material: MaterialBlock;
@group(2) @binding(1) var diffuse_map: texture_2d<f32>;
@group(2) @binding(2) var normal_map: texture_2d<f32>;
@group(2) @binding(3) var specular_map: texture_2d<f32>;
@group(2) @binding(4) var material_sampler: sampler;

// Renderer block: every stored instance's object-to-world matrix (persistent, rewritten
// only where entities changed), and this frame's visible instances in draw order;
// a draw's first_instance points at its run of indices.
@group(3) @binding(0) var<storage, read> transforms: array<mat4x4<f32>>;
@group(3) @binding(1) var<storage, read> draw_indices: array<u32>;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) tangent: vec4<f32>,
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) tangent: vec4<f32>,
}

@vertex
fn vs_main(v: VertexIn, @builtin(instance_index) instance: u32) -> VertexOut {
    let model = transforms[draw_indices[instance]];
    let world = model * vec4<f32>(v.position, 1.0);
    // Normals transform by the inverse transpose, which is the cofactor matrix over
    // the determinant: only the determinant's sign matters once normalised. This is
    // right for non-uniform scale and mirroring without a matrix inverse.
    let m = mat3x3<f32>(model[0].xyz, model[1].xyz, model[2].xyz);
    let cofactor = mat3x3<f32>(cross(m[1], m[2]), cross(m[2], m[0]), cross(m[0], m[1]));
    let det_sign = select(-1.0, 1.0, dot(m[0], cofactor[0]) >= 0.0);
    var out: VertexOut;
    out.clip = camera.view_proj * world;
    out.world_position = world.xyz;
    out.normal = cofactor * v.normal * det_sign;
    out.uv = v.uv * material.uv_scale;
    out.tangent = vec4<f32>(m * v.tangent.xyz, v.tangent.w * det_sign);
    return out;
}

fn shade(n: vec3<f32>, world_position: vec3<f32>, base: vec3<f32>, specular: f32) -> vec3<f32> {
    let view_dir = normalize(camera.position.xyz - world_position);
    var color = scene.ambient.rgb * material.coeffs.x * base;
    for (var i = 0u; i < scene.counts.x; i++) {
        let light = scene.lights[i];
        var l: vec3<f32>;
        var radiance = light.color.rgb;
        if light.position.w == 0.0 {
            l = -normalize(light.position.xyz);
        } else {
            let to_light = light.position.xyz - world_position;
            let dist = length(to_light);
            l = to_light / max(dist, 1e-4);
            // Inverse square, windowed to reach exactly zero at the range.
            let x = dist / light.color.w;
            let window = saturate(1.0 - x * x * x * x);
            radiance *= window * window / max(dist * dist, 1e-4);
        }
        let n_dot_l = max(dot(n, l), 0.0);
        let h = normalize(l + view_dir);
        let highlight = pow(max(dot(n, h), 0.0), material.coeffs.w) * n_dot_l;
        color += radiance * (material.coeffs.y * n_dot_l * base + material.coeffs.z * specular * highlight);
    }
    return color;
}

@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    var base = material.base_color;
#ifdef DIFFUSE_MAP
    base *= textureSample(diffuse_map, material_sampler, in.uv);
#endif
#ifdef ALPHA_MASK
    if base.a < material.alpha_cutoff {
        discard;
    }
#endif
    // Double-sided materials light back faces with the flipped normal.
    let side = select(-1.0, 1.0, front);
    var n = normalize(in.normal) * side;
#ifdef NORMAL_MAP
    let t = normalize(in.tangent.xyz - n * dot(n, in.tangent.xyz));
    let b = cross(n, t) * in.tangent.w * side;
    let s = textureSample(normal_map, material_sampler, in.uv).xyz * 2.0 - 1.0;
    n = normalize(t * s.x + b * s.y + n * s.z);
#endif
    var specular = 1.0;
#ifdef SPECULAR_MAP
    specular = textureSample(specular_map, material_sampler, in.uv).r;
#endif
#ifdef UNLIT
    var color = base.rgb;
#else
    var color = shade(n, in.world_position, base.rgb, specular);
#endif
#ifdef FOG
    let distance = length(camera.position.xyz - in.world_position) * scene.fog.w;
    color = mix(scene.fog.rgb, color, exp(-distance * distance));
#endif
#ifdef ALPHA_BLEND
    return vec4<f32>(color, base.a);
#else
    return vec4<f32>(color, 1.0);
#endif
}
