// Forward pass: lit, textured, instanced meshes. Composed per feature set: each
// `#ifdef` below is one bit of ShaderFeatures (src/shader/mod.rs).

#import glint::blocks::{scene, camera}

struct MaterialBlock {
    base_color: vec4<f32>,
    // x: ambient, y: diffuse, z: specular, w: Blinn-Phong exponent.
    coeffs: vec4<f32>,
    // x: metallic, y: roughness (metallic-roughness shading).
    pbr: vec4<f32>,
    // rgb: emissive colour.
    emissive: vec4<f32>,
    alpha_cutoff: f32,
    reserved: u32,
    uv_scale: vec2<f32>,
}

// Material block: the table of every material, indexed by the instance's material,
// and this draw's texture set (materials with the same maps share one).
@group(2) @binding(0) var<storage, read> materials: array<MaterialBlock>;
@group(2) @binding(1) var diffuse_map: texture_2d<f32>;
@group(2) @binding(2) var normal_map: texture_2d<f32>;
@group(2) @binding(3) var specular_map: texture_2d<f32>;
@group(2) @binding(4) var material_sampler: sampler;
@group(2) @binding(5) var metallic_roughness_map: texture_2d<f32>;
@group(2) @binding(6) var occlusion_map: texture_2d<f32>;
@group(2) @binding(7) var emissive_map: texture_2d<f32>;

const PI: f32 = 3.14159265;

// One stored instance: the top three rows of its object-to-world matrix (the
// bottom row is 0 0 0 1) and its material's index in `materials`.
struct Instance {
    row_x: vec4<f32>,
    row_y: vec4<f32>,
    row_z: vec4<f32>,
    material: u32,
    reserved_x: u32,
    reserved_y: u32,
    reserved_z: u32,
}

// Renderer block: every stored instance (persistent, rewritten only where entities
// changed), and this frame's visible instances in draw order; a draw's
// first_instance points at its run of indices.
@group(3) @binding(0) var<storage, read> instances: array<Instance>;
@group(3) @binding(1) var<storage, read> draw_indices: array<u32>;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) tangent: vec4<f32>,
#ifdef VERTEX_COLOR
    @location(4) color: vec4<f32>,
#endif
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) tangent: vec4<f32>,
    @location(4) @interpolate(flat) material: u32,
#ifdef VERTEX_COLOR
    @location(5) color: vec4<f32>,
#endif
}

@vertex
fn vs_main(v: VertexIn, @builtin(instance_index) draw_instance: u32) -> VertexOut {
    let instance = instances[draw_indices[draw_instance]];
    let model = transpose(mat4x4<f32>(instance.row_x, instance.row_y, instance.row_z, vec4<f32>(0.0, 0.0, 0.0, 1.0)));
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
    out.uv = v.uv * materials[instance.material].uv_scale;
    out.tangent = vec4<f32>(m * v.tangent.xyz, v.tangent.w * det_sign);
    out.material = instance.material;
#ifdef VERTEX_COLOR
    out.color = v.color;
#endif
    return out;
}

// Direction to light `i` from `p`, and the light arriving there.
struct Incoming {
    l: vec3<f32>,
    radiance: vec3<f32>,
}

fn incoming(i: u32, p: vec3<f32>) -> Incoming {
    let light = scene.lights[i];
    if light.position.w == 0.0 {
        return Incoming(-normalize(light.position.xyz), light.color.rgb);
    }
    let to_light = light.position.xyz - p;
    let dist = length(to_light);
    // Inverse square, windowed to reach exactly zero at the range.
    let x = dist / light.color.w;
    let window = saturate(1.0 - x * x * x * x);
    return Incoming(to_light / max(dist, 1e-4), light.color.rgb * window * window / max(dist * dist, 1e-4));
}

fn shade(
    material: MaterialBlock,
    n: vec3<f32>,
    world_position: vec3<f32>,
    base: vec3<f32>,
    specular: f32,
    occlusion: f32,
) -> vec3<f32> {
    let view_dir = normalize(camera.position.xyz - world_position);
    var color = scene.ambient.rgb * material.coeffs.x * occlusion * base;
    for (var i = 0u; i < scene.counts.x; i++) {
        let light = incoming(i, world_position);
        let n_dot_l = max(dot(n, light.l), 0.0);
        let h = normalize(light.l + view_dir);
        let highlight = pow(max(dot(n, h), 0.0), material.coeffs.w) * n_dot_l;
        color += light.radiance * (material.coeffs.y * n_dot_l * base + material.coeffs.z * specular * highlight);
    }
    return color;
}

// glTF 2.0 metallic-roughness (spec appendix B): GGX normal distribution,
// height-correlated Smith visibility, Schlick Fresnel, Lambert diffuse for the
// dielectric part. Light radiance is scaled by π so that a white Lambert surface
// facing a light of intensity 1 is as bright as under Blinn-Phong.
fn shade_metallic_roughness(
    n: vec3<f32>,
    world_position: vec3<f32>,
    base: vec3<f32>,
    metallic: f32,
    roughness: f32,
    occlusion: f32,
) -> vec3<f32> {
    let v = normalize(camera.position.xyz - world_position);
    let alpha = max(roughness * roughness, 1e-3);
    let a2 = alpha * alpha;
    let f0 = mix(vec3<f32>(0.04), base, metallic);
    let c_diff = base * (1.0 - metallic);
    let n_v = max(dot(n, v), 1e-4);
    var color = scene.ambient.rgb * occlusion * (c_diff + f0);
    for (var i = 0u; i < scene.counts.x; i++) {
        let light = incoming(i, world_position);
        let n_l = max(dot(n, light.l), 0.0);
        let h = normalize(light.l + v);
        let n_h = max(dot(n, h), 0.0);
        let v_h = max(dot(v, h), 0.0);
        let f = f0 + (1.0 - f0) * pow(1.0 - v_h, 5.0);
        let k = n_h * n_h * (a2 - 1.0) + 1.0;
        let d = a2 / (PI * k * k);
        let vis = 0.5 / max(n_l * sqrt(n_v * n_v * (1.0 - a2) + a2) + n_v * sqrt(n_l * n_l * (1.0 - a2) + a2), 1e-6);
        let brdf = (1.0 - f) * c_diff / PI + f * d * vis;
        color += PI * light.radiance * brdf * n_l;
    }
    return color;
}

@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let material = materials[in.material];
    var base = material.base_color;
#ifdef VERTEX_COLOR
    base *= in.color;
#endif
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
    var occlusion = 1.0;
#ifdef OCCLUSION_MAP
    occlusion = textureSample(occlusion_map, material_sampler, in.uv).r;
#endif
#ifdef UNLIT
    var color = base.rgb;
#else
#ifdef METALLIC_ROUGHNESS
    var metallic = material.pbr.x;
    var roughness = material.pbr.y;
#ifdef METALLIC_ROUGHNESS_MAP
    let mr = textureSample(metallic_roughness_map, material_sampler, in.uv);
    roughness *= mr.g;
    metallic *= mr.b;
#endif
    var color = shade_metallic_roughness(n, in.world_position, base.rgb, metallic, roughness, occlusion);
#else
    var color = shade(material, n, in.world_position, base.rgb, specular, occlusion);
#endif
#endif
    var emissive = material.emissive.rgb;
#ifdef EMISSIVE_MAP
    emissive *= textureSample(emissive_map, material_sampler, in.uv).rgb;
#endif
    color += emissive;
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
