// Forward pass: lit, textured, instanced meshes. Composed per feature set: each
// `#ifdef` below is one bit of ShaderFeatures (src/shader/mod.rs).

#import glint::blocks::{scene, camera, Light, environment_irradiance, environment_brdf, environment_sampler, environment_sample, ambient_occlusion}
#import glint::shadow_lookup::{cascaded_shadow, positional_shadow}
#import glint::equirect::sh_basis
#import glint::light_clusters::{cluster_at, clustered_light, cluster_word, towards_light, arriving}
#import glint::transparency_out::{Weighted, weighted_sums, append_fragment}

struct MaterialBlock {
    base_color: vec4<f32>,
    // x: ambient, y: diffuse, z: specular, w: Blinn-Phong exponent.
    coeffs: vec4<f32>,
    // x: metallic, y: roughness (metallic-roughness shading).
    pbr: vec4<f32>,
    // rgb: emissive colour.
    emissive: vec4<f32>,
    // Texture coordinates are (dot(uv_x, (u, v, 1)), dot(uv_y, (u, v, 1))).
    uv_x: vec3<f32>,
    alpha_cutoff: f32,
    uv_y: vec3<f32>,
    // MapSlots bits: maps that read the second uv set.
    uv1_maps: u32,
    // xyz: the Motion's parameters (scene/motion.rs: wind sway and base, flap
    // amplitude and rate, walk radii and speed).
    motion: vec4<f32>,
    // x, y: edge fade's inner and outer radius (world units, in x and z).
    fade: vec4<f32>,
}

// MapSlots bits (scene/material.rs).
const SLOT_DIFFUSE: u32 = 1u;
const SLOT_NORMAL: u32 = 2u;
const SLOT_SPECULAR: u32 = 4u;
const SLOT_METALLIC_ROUGHNESS: u32 = 8u;
const SLOT_OCCLUSION: u32 = 16u;
const SLOT_EMISSIVE: u32 = 32u;

// Material block: the table of every material, indexed by the instance's material
// (`material_at`), and this draw's texture set (materials with the same maps share one).
#ifdef DATA_TEXTURES
@group(2) @binding(0) var material_texels: texture_2d<u32>;
#else
@group(2) @binding(0) var<storage, read> materials: array<MaterialBlock>;
#endif
@group(2) @binding(1) var diffuse_map: texture_2d<f32>;
@group(2) @binding(2) var normal_map: texture_2d<f32>;
@group(2) @binding(3) var specular_map: texture_2d<f32>;
@group(2) @binding(4) var material_sampler: sampler;
@group(2) @binding(5) var metallic_roughness_map: texture_2d<f32>;
@group(2) @binding(6) var occlusion_map: texture_2d<f32>;
@group(2) @binding(7) var emissive_map: texture_2d<f32>;

const PI: f32 = 3.14159265;

// One stored instance: the top three rows of its object-to-world matrix (the
// bottom row is 0 0 0 1) and its material's index in `materials`. A skinned
// entity's joint matrices are records of this shape stored after its instances:
// `joints` records ahead of each instance, `joint_count` of them.
struct Instance {
    row_x: vec4<f32>,
    row_y: vec4<f32>,
    row_z: vec4<f32>,
    material: u32,
    joints: u32,
    joint_count: u32,
    // Bit 0: receives shadows.
    flags: u32,
}

// Renderer block: every stored instance (persistent, rewritten only where entities
// changed; `instance_at`), and this frame's visible instances in draw order
// (`draw_index_at`); a draw's first_instance points at its run of indices.
#ifdef DATA_TEXTURES
// Where vertex shaders have no storage buffers (WebGL2), the three arrays are
// data textures of DATA_WIDTH texels a row, a record's 16-byte pieces in
// consecutive texels (render/resources/gpu_array.rs).
@group(3) @binding(0) var instance_texels: texture_2d<u32>;
@group(3) @binding(1) var draw_index_texels: texture_2d<u32>;

fn texel(array: texture_2d<u32>, i: u32) -> vec4<u32> {
    return textureLoad(array, vec2<u32>(i % #{DATA_WIDTH}u, i / #{DATA_WIDTH}u), 0);
}

fn material_at(i: u32) -> MaterialBlock {
    let at = 8u * i;
    let uv_x = texel(material_texels, at + 4u);
    let uv_y = texel(material_texels, at + 5u);
    var m: MaterialBlock;
    m.base_color = bitcast<vec4<f32>>(texel(material_texels, at));
    m.coeffs = bitcast<vec4<f32>>(texel(material_texels, at + 1u));
    m.pbr = bitcast<vec4<f32>>(texel(material_texels, at + 2u));
    m.emissive = bitcast<vec4<f32>>(texel(material_texels, at + 3u));
    m.uv_x = bitcast<vec3<f32>>(uv_x.xyz);
    m.alpha_cutoff = bitcast<f32>(uv_x.w);
    m.uv_y = bitcast<vec3<f32>>(uv_y.xyz);
    m.uv1_maps = uv_y.w;
    m.motion = bitcast<vec4<f32>>(texel(material_texels, at + 6u));
    m.fade = bitcast<vec4<f32>>(texel(material_texels, at + 7u));
    return m;
}

fn instance_at(i: u32) -> Instance {
    let ids = texel(instance_texels, 4u * i + 3u);
    return Instance(
        bitcast<vec4<f32>>(texel(instance_texels, 4u * i)),
        bitcast<vec4<f32>>(texel(instance_texels, 4u * i + 1u)),
        bitcast<vec4<f32>>(texel(instance_texels, 4u * i + 2u)),
        ids.x,
        ids.y,
        ids.z,
        ids.w,
    );
}

fn draw_index_at(i: u32) -> u32 {
    return texel(draw_index_texels, i).x;
}

// Compact instance `q`: a quarter of the instance records, one texel.
fn compact_at(q: u32) -> vec4<u32> {
    return texel(instance_texels, q);
}
#else
@group(3) @binding(0) var<storage, read> instances: array<Instance>;
@group(3) @binding(1) var<storage, read> draw_indices: array<u32>;

fn material_at(i: u32) -> MaterialBlock {
    return materials[i];
}

fn instance_at(i: u32) -> Instance {
    return instances[i];
}

// Compact instance `q`: quarter q % 4 of record q / 4.
fn compact_at(q: u32) -> vec4<u32> {
    let r = instances[q / 4u];
    switch q % 4u {
        case 0u: {
            return bitcast<vec4<u32>>(r.row_x);
        }
        case 1u: {
            return bitcast<vec4<u32>>(r.row_y);
        }
        case 2u: {
            return bitcast<vec4<u32>>(r.row_z);
        }
        default: {
            return vec4<u32>(r.material, r.joints, r.joint_count, r.flags);
        }
    }
}

fn draw_index_at(i: u32) -> u32 {
    return draw_indices[i];
}
#endif

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
#ifdef TEXCOORDS
    @location(2) uv: vec2<f32>,
#endif
#ifdef NORMAL_MAP
    @location(3) tangent: vec4<f32>,
#endif
#ifdef VERTEX_COLOR
    @location(4) color: vec4<f32>,
#endif
#ifdef UV1
    @location(5) uv1: vec2<f32>,
#endif
#ifdef SKINNED
    @location(6) joints: vec4<u32>,
    @location(7) weights: vec4<f32>,
#endif
}

struct VertexOut {
    // Invariant: a view's depth pre-pass and its forward pass compute the same
    // depth for the same vertex, whatever else their variants compute (the
    // forward pass tests the pre-pass's depth for equality).
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    // Texture coordinates and tangents only where a map reads them: for the
    // peers' 100,000 untextured cubes they cost a sixth of the process's CPU
    // (vertex work, and what each triangle interpolates).
#ifdef TEXCOORDS
    @location(2) uv: vec2<f32>,
#endif
#ifdef NORMAL_MAP
    @location(3) tangent: vec4<f32>,
#endif
    @location(4) @interpolate(flat) material: u32,
#ifdef VERTEX_COLOR
    @location(5) color: vec4<f32>,
#endif
#ifdef TEXCOORDS
#ifdef UV1
    @location(6) uv1: vec2<f32>,
    // The material's uv1_maps, passed down rather than read per fragment: helper
    // invocations may not read storage buffers (lavapipe gives them zeros), and
    // a uv choice that differs inside a 2×2 quad ruins its mip level.
    @location(7) @interpolate(flat) uv1_maps: u32,
#endif
#endif
#ifdef SHADOWS
    @location(8) @interpolate(flat) receive_shadows: u32,
#endif
#ifdef EDGE_FADE
    // The instance's placed position in x and z, where its fade is measured from.
    @location(9) @interpolate(flat) origin: vec2<f32>,
#endif
#ifdef LOD_FADE
    // The draw index's fade bits (render/lod.rs): bit 0 on the coarser copy,
    // bits 1..=4 the 16ths of the pixels the coarser draws (0: not fading).
    @location(10) @interpolate(flat) lod_fade: u32,
#endif
}

fn record_matrix(r: Instance) -> mat4x4<f32> {
    return transpose(mat4x4<f32>(r.row_x, r.row_y, r.row_z, vec4<f32>(0.0, 0.0, 0.0, 1.0)));
}

fn uv_transform(material: MaterialBlock, uv: vec2<f32>) -> vec2<f32> {
    let h = vec3<f32>(uv, 1.0);
    return vec2<f32>(dot(material.uv_x, h), dot(material.uv_y, h));
}

#ifdef SKINNED
// The weighted sum of the vertex's joint matrices (record `at` is the instance);
// joint indices past the end use the last joint, and no joints at all is no skinning.
fn skin_matrix(at: u32, instance: Instance, joints: vec4<u32>, weights: vec4<f32>) -> mat4x4<f32> {
    if instance.joint_count == 0u {
        return mat4x4<f32>(vec4<f32>(1.0, 0.0, 0.0, 0.0), vec4<f32>(0.0, 1.0, 0.0, 0.0), vec4<f32>(0.0, 0.0, 1.0, 0.0), vec4<f32>(0.0, 0.0, 0.0, 1.0));
    }
    let first = at + instance.joints;
    let last = instance.joint_count - 1u;
    var m = record_matrix(instance_at(first + min(joints.x, last))) * weights.x;
    m += record_matrix(instance_at(first + min(joints.y, last))) * weights.y;
    m += record_matrix(instance_at(first + min(joints.z, last))) * weights.z;
    m += record_matrix(instance_at(first + min(joints.w, last))) * weights.w;
    return m;
}
#endif

#ifdef COMPACT
// The half float whose bits are `h` (unpack2x16float needs a capability not
// every device has). Exact: a half is a power of two times its mantissa.
fn half_float(h: u32) -> f32 {
    let sign = select(1.0, -1.0, (h & 0x8000u) != 0u);
    let e = (h >> 10u) & 0x1fu;
    let m = f32(h & 0x3ffu);
    if e == 0u {
        return sign * m * exp2(-24.0);
    }
    return sign * (1.0 + m / 1024.0) * exp2(f32(e) - 15.0);
}

// Compact instance `q` (render/resources/blocks.rs CompactGpu) as a full one: x and z,
// y and scale (half floats), a turn about +Y in 1/65536 of a turn, its
// material (15 bits) and its shadow flag (the top bit); never skinned.
fn compact_instance(q: u32) -> Instance {
    let c = compact_at(q);
    let ys = vec2<f32>(half_float(c.z & 0xffffu), half_float(c.z >> 16u));
    let turn = f32(c.w & 0xffffu) * (TAU / 65536.0);
    let s = ys.y * sin(turn);
    let k = ys.y * cos(turn);
    let x = bitcast<f32>(c.x);
    let z = bitcast<f32>(c.y);
    return Instance(
        vec4<f32>(k, 0.0, s, x),
        vec4<f32>(0.0, ys.y, 0.0, ys.x),
        vec4<f32>(-s, 0.0, k, z),
        (c.w >> 16u) & 0x7fffu,
        0u,
        0u,
        c.w >> 31u,
    );
}
#endif

// A number in 0..1 fixed per instance, from its placed position: the phase
// of its motion (no instance data needed).
fn instance_hash(p: vec3<f32>) -> f32 {
    var q = fract(p * vec3<f32>(0.1127, 0.1361, 0.0959));
    q += dot(q, q.zyx + 31.71);
    return fract((q.x + q.y) * q.z);
}

const TAU: f32 = 6.2831853;

// A draw index's fade bits start here (render/lod.rs FADE_SHIFT).
const FADE_SHIFT: u32 = 27u;

#ifdef LOD_FADE
// Whether the pixel at `pixel` belongs to the other level of an instance
// fading by `fade` (render/lod.rs coarser_pixel): the coarser copy draws the
// pixels whose place in the 4 × 4 ordered-dither matrix is under its 16ths,
// the finer the rest, so every pixel shows one level.
fn lod_dithered_out(pixel: vec2<f32>, fade: u32) -> bool {
    let q = fade >> 1u;
    if q == 0u {
        return false;
    }
    let p = vec2<u32>(pixel);
    let low = (((p.x ^ p.y) & 1u) << 1u) | (p.y & 1u);
    let high = ((((p.x >> 1u) ^ (p.y >> 1u)) & 1u) << 1u) | ((p.y >> 1u) & 1u);
    let coarser_pixel = ((low << 2u) | high) < q;
    return coarser_pixel != ((fade & 1u) == 1u);
}
#endif

#ifdef WIND
// How far a vertex `h` object units above the model's base moves in the world
// (x, z) in the wind: sway · h² along the wind, times its strength and a gust
// varying with time, the instance's phase and a noise term (the bounds allow
// for 0.6 + 0.4 + 0.15 at most: scene/motion.rs).
fn wind_offset(h: f32, material: MaterialBlock, origin: vec3<f32>, scale: f32) -> vec2<f32> {
    let t = camera.motion.x;
    let phase = instance_hash(origin) * TAU;
    let gust = 0.6 + 0.4 * sin(1.7 * t + phase) + 0.15 * sin(4.3 * t + 3.0 * phase + 0.37 * (origin.x + origin.z));
    let lean = material.motion.x * h * h * gust * camera.motion.y * scale;
    return camera.motion.zw * lean;
}
#endif

#ifdef FLAP
// A wing beat: vertices |x| object units off the model's YZ plane rise and
// fall by amplitude · |x|, at the material's rate varied ±20 % per instance.
fn flap_lift(x: f32, material: MaterialBlock, origin: vec3<f32>) -> f32 {
    let k = instance_hash(origin);
    let beat = sin(TAU * (camera.motion.x * material.motion.y * (0.8 + 0.4 * k) + k));
    return material.motion.x * abs(x) * beat;
}
#endif

#ifdef CIRCLE
// Where an instance placed at `origin` walks: around a circle of a radius
// between the material's two, at its speed, clockwise or not per instance,
// turned to face along the path. Returns the turn and the new origin.
struct Walk {
    turn: mat3x3<f32>,
    origin: vec3<f32>,
}

fn walk(material: MaterialBlock, origin: vec3<f32>) -> Walk {
    let k = instance_hash(origin);
    let radius = max(mix(material.motion.x, material.motion.y, k), 1e-3);
    let turning = select(-1.0, 1.0, fract(k * 7.31) < 0.5);
    let a = turning * camera.motion.x * material.motion.z / radius + k * TAU;
    let along = turning * vec2<f32>(-sin(a), cos(a));
    // A turn about +Y taking +Z (the model's front) to `along`.
    let c = along.y;
    let s = along.x;
    let turn = mat3x3<f32>(vec3<f32>(c, 0.0, -s), vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(s, 0.0, c));
    return Walk(turn, origin + radius * vec3<f32>(cos(a), 0.0, sin(a)));
}
#endif

#ifdef FAR_FIELD
// The far field (scene/far_field.rs, which these follow step by step and whose
// constants these are): an instance's rank, a hash of its position's x and z bits.
const FAR_MIN_SHARE: f32 = 0.0625;
const FAR_BAND: f32 = 0.25;
const FAR_RING: f32 = 0.2;

fn far_rank(origin: vec3<f32>) -> f32 {
    var h = (bitcast<u32>(origin.x) * 0x9e3779b1u) ^ bitcast<u32>(origin.z);
    h ^= h >> 16u;
    h *= 0x7feb352du;
    h ^= h >> 15u;
    h *= 0x846ca68bu;
    h ^= h >> 16u;
    return f32(h >> 8u) / 16777216.0;
}

// The width (times its own, in x and z) of the instance placed at `origin`:
// FarField::width at its distance from the far-field eye, 1 with far fields
// off. The material's fade.zw are the field's start and end.
fn far_field_width(material: MaterialBlock, origin: vec3<f32>) -> f32 {
    if camera.far_eye.w == 0.0 {
        return 1.0;
    }
    let start = material.fade.z;
    let end = material.fade.w;
    let d = distance(camera.far_eye.xyz, origin);
    let r = start / max(d, 1e-6);
    let falloff = clamp(r * r, FAR_MIN_SHARE, 1.0);
    let share = falloff * saturate((end - d) / (FAR_RING * end));
    let band = FAR_BAND * falloff * (1.0 - falloff);
    let rank = far_rank(origin);
    let narrowing = select(select(0.0, 1.0, rank < share), saturate((share - rank) / band), band > 0.0);
    return narrowing / (falloff - 0.5 * band);
}
#endif

#ifdef SWIM
// A tail's sideways swing: vertices d = pivot - z behind the pivot move by
// amplitude · d² along x, a wave running down the body at the instance's
// phase (flags bits 16-31).
fn swim_offset(z: f32, material: MaterialBlock, flags: u32) -> f32 {
    let d = max(material.motion.y - z, 0.0);
    let phase = f32(flags >> 16u) / 65536.0;
    return material.motion.x * d * d * sin(TAU * phase - 2.0 * d);
}
#endif

@vertex
fn vs_main(v: VertexIn, @builtin(instance_index) draw_instance: u32) -> VertexOut {
#ifdef COMPACT
    // Drawn by their number: whole tiles, no draw indices (and never skinned).
    let at = draw_instance;
    // Never faded: compact instances are drawn at full detail.
    let drawn = 0u;
    let instance = compact_instance(at);
#else
    // A draw index is a store index with a level-of-detail fade above it.
    let drawn = draw_index_at(draw_instance);
    let at = drawn & ((1u << FADE_SHIFT) - 1u);
    let instance = instance_at(at);
#endif
    let model = record_matrix(instance);
    var position = vec4<f32>(v.position, 1.0);
    var normal = v.normal;
#ifdef NORMAL_MAP
    var tangent = v.tangent.xyz;
#endif
#ifdef SKINNED
    // Joint matrices are rigid or uniformly scaled: their 3×3 part moves normals.
    let skin = skin_matrix(at, instance, v.joints, v.weights);
    let skin3 = mat3x3<f32>(skin[0].xyz, skin[1].xyz, skin[2].xyz);
    position = skin * position;
    normal = skin3 * normal;
#ifdef NORMAL_MAP
    tangent = skin3 * tangent;
#endif
#endif
#ifdef SWIM
    position.x += swim_offset(position.z, material_at(instance.material), instance.flags);
#endif
#ifdef FLAP
    position.y += flap_lift(position.x, material_at(instance.material), model[3].xyz);
#endif
#ifdef FAR_FIELD
    // Wider (or narrowed away) about the model's axis; normals are kept.
    let far_width = far_field_width(material_at(instance.material), model[3].xyz);
    position = vec4<f32>(position.x * far_width, position.y, position.z * far_width, position.w);
#endif
    var world = model * position;
#ifdef WIND
    let scale = length(model[1].xyz);
    let height = max(position.y - material_at(instance.material).motion.y, 0.0);
    let lean = wind_offset(height, material_at(instance.material), model[3].xyz, scale);
    world += vec4<f32>(lean.x, 0.0, lean.y, 0.0);
#endif
    // Normals transform by the inverse transpose, which is the cofactor matrix over
    // the determinant: only the determinant's sign matters once normalised. This is
    // right for non-uniform scale and mirroring without a matrix inverse.
    let m = mat3x3<f32>(model[0].xyz, model[1].xyz, model[2].xyz);
    let cofactor = mat3x3<f32>(cross(m[1], m[2]), cross(m[2], m[0]), cross(m[0], m[1]));
    let det_sign = select(-1.0, 1.0, dot(m[0], cofactor[0]) >= 0.0);
    var out: VertexOut;
    out.normal = cofactor * normal * det_sign;
#ifdef CIRCLE
    let walked = walk(material_at(instance.material), model[3].xyz);
    world = vec4<f32>(walked.origin + walked.turn * (world.xyz - model[3].xyz), 1.0);
    out.normal = walked.turn * out.normal;
#endif
    out.clip = camera.view_proj * world;
    out.world_position = world.xyz;
#ifdef TEXCOORDS
    out.uv = uv_transform(material_at(instance.material), v.uv);
#endif
#ifdef NORMAL_MAP
    out.tangent = vec4<f32>(m * tangent, v.tangent.w * det_sign);
#ifdef CIRCLE
    out.tangent = vec4<f32>(walked.turn * out.tangent.xyz, out.tangent.w);
#endif
#endif
    out.material = instance.material;
#ifdef SHADOWS
    out.receive_shadows = instance.flags & 1u;
#endif
#ifdef EDGE_FADE
    out.origin = model[3].xz;
#endif
#ifdef LOD_FADE
    out.lod_fade = drawn >> FADE_SHIFT;
#endif
#ifdef VERTEX_COLOR
    out.color = v.color;
#endif
#ifdef TEXCOORDS
#ifdef UV1
    out.uv1 = uv_transform(material_at(instance.material), v.uv1);
    out.uv1_maps = material_at(instance.material).uv1_maps;
#endif
#endif
    return out;
}

#ifdef CLUSTERED
// The heat map of lights per cluster (Renderer::set_cluster_heat_map): the
// count of the fragment's cluster on the jet scale, t = log2(1 + count) / 8:
// dark blue for none, then a step for each doubling (1, 3, 7, 15, 31, 63,
// 127) to dark red for 255 or more,
// shaded by the normal `n` facing the eye, its tile's edges darkened.
fn cluster_heat(surface: Surface, n: vec3<f32>) -> vec3<f32> {
    let t = min(log2(1.0 + f32(cluster_at(surface.pixel, surface.position).y)) / 8.0, 1.0);
    let jet = clamp(1.5 - abs(4.0 * t - vec3<f32>(3.0, 2.0, 1.0)), vec3<f32>(0.0), vec3<f32>(1.0));
    let facing = abs(dot(n, normalize(camera.position.xyz - surface.position)));
    let within = surface.pixel % f32(scene.counts.z);
    let edge = select(1.0, 0.6, any(within < vec2<f32>(1.0)));
    return jet * (0.4 + 0.6 * facing) * edge;
}
#endif

// The lights this variant loops over (LightCounts, src/shader/mod.rs): the Scene
// block holds the directional lights first, then the point and spot lights.
// Counts fixed at compile time unroll the loops, so each light is read at a
// constant index: a loop to a count read from the block cost llvmpipe about a
// quarter of a simple frame (its lights were gathered lane by lane).
const DIRECTIONAL_LIGHTS: u32 = #{DIRECTIONAL_LIGHTS}u;
const LIGHTS: u32 = #{DIRECTIONAL_LIGHTS}u + #{POSITIONAL_LIGHTS}u;

// Direction to a light from `p`, and the light arriving there; `ng` is the
// geometric normal (facing the viewer), for the shadow lookup's normal offset.
struct Incoming {
    l: vec3<f32>,
    radiance: vec3<f32>,
}

// Directional light `i` (i < DIRECTIONAL_LIGHTS).
fn directional(i: u32, p: vec3<f32>, ng: vec3<f32>, receive: bool) -> Incoming {
    let light = scene.lights[i];
    var lit = 1.0;
#ifdef SHADOWS
    if receive && light.params.y >= 0.0 {
        lit = cascaded_shadow(u32(light.params.y), light, p, ng);
    }
#endif
    return Incoming(-normalize(light.position.xyz), light.color.rgb * lit);
}

// A point or spot light: the Scene block's (DIRECTIONAL_LIGHTS <= i < LIGHTS)
// or a cluster's.
fn positional(light: Light, p: vec3<f32>, ng: vec3<f32>, receive: bool) -> Incoming {
    let towards = towards_light(light, p);
    let l = towards.xyz;
    var lit = 1.0;
#ifdef SHADOWS
    if receive && light.params.y >= 0.0 {
        lit = positional_shadow(u32(light.params.y), light, p, ng, l, towards.w);
    }
#endif
    return Incoming(l, arriving(light, towards, lit));
}

// Where a fragment is, its geometric normal (facing the viewer), and whether
// shadows darken it.
struct Surface {
    position: vec3<f32>,
    normal: vec3<f32>,
    receive_shadows: bool,
    // The fragment's pixel in the view (its light cluster's tile).
    pixel: vec2<f32>,
}

fn shade(
    material: MaterialBlock,
    n: vec3<f32>,
    surface: Surface,
    base: vec3<f32>,
    specular: f32,
    occlusion: f32,
) -> vec3<f32> {
    let p = surface.position;
    let v = normalize(camera.position.xyz - p);
    let ng = surface.normal;
    let receive = surface.receive_shadows;
#ifdef ENVIRONMENT
    var color = environment_irradiance_at(n) * material.coeffs.x * occlusion * base;
#else
    var color = scene.ambient.rgb * material.coeffs.x * occlusion * base;
#endif
    for (var i = 0u; i < DIRECTIONAL_LIGHTS; i++) {
        color += blinn_phong(directional(i, p, ng, receive), material, n, v, base, specular);
    }
#ifdef CLUSTERED
    let cluster = cluster_at(surface.pixel, surface.position);
    for (var k = 0u; k < cluster.y; k++) {
        let light = clustered_light(cluster.z, cluster_word(cluster.x + k));
        color += blinn_phong(positional(light, p, ng, receive), material, n, v, base, specular);
    }
#else
    for (var i = DIRECTIONAL_LIGHTS; i < LIGHTS; i++) {
        color += blinn_phong(positional(scene.lights[i], p, ng, receive), material, n, v, base, specular);
    }
#endif
    return color;
}

// One light's Blinn-Phong diffuse and highlight, towards the viewer `v`.
fn blinn_phong(light: Incoming, material: MaterialBlock, n: vec3<f32>, v: vec3<f32>, base: vec3<f32>, specular: f32) -> vec3<f32> {
    let n_dot_l = max(dot(n, light.l), 0.0);
    let h = normalize(light.l + v);
    let highlight = pow(max(dot(n, h), 0.0), material.coeffs.w) * n_dot_l;
    return light.radiance * (material.coeffs.y * n_dot_l * base + material.coeffs.z * specular * highlight);
}

// What glTF's BRDF needs of the surface besides the light, computed once per fragment.
struct Brdf {
    n: vec3<f32>,
    v: vec3<f32>,
    n_v: f32,
    a2: f32,
    f0: vec3<f32>,
    c_diff: vec3<f32>,
}

// glTF 2.0 metallic-roughness (spec appendix B): GGX normal distribution,
// height-correlated Smith visibility, Schlick Fresnel, Lambert diffuse for the
// dielectric part. Light radiance is scaled by π so that a white Lambert surface
// facing a light of intensity 1 is as bright as under Blinn-Phong.
fn shade_metallic_roughness(
    n: vec3<f32>,
    surface: Surface,
    base: vec3<f32>,
    metallic: f32,
    roughness: f32,
    occlusion: f32,
) -> vec3<f32> {
    let p = surface.position;
    let v = normalize(camera.position.xyz - p);
    let alpha = max(roughness * roughness, 1e-3);
    let f0 = mix(vec3<f32>(0.04), base, metallic);
    let b = Brdf(n, v, max(dot(n, v), 1e-4), alpha * alpha, f0, base * (1.0 - metallic));
    let ng = surface.normal;
    let receive = surface.receive_shadows;
#ifdef ENVIRONMENT
    var color = environment_light(b, roughness, occlusion);
#else
    var color = scene.ambient.rgb * occlusion * (b.c_diff + f0);
#endif
    for (var i = 0u; i < DIRECTIONAL_LIGHTS; i++) {
        color += ggx(directional(i, p, ng, receive), b);
    }
#ifdef CLUSTERED
    let cluster = cluster_at(surface.pixel, surface.position);
    for (var k = 0u; k < cluster.y; k++) {
        color += ggx(positional(clustered_light(cluster.z, cluster_word(cluster.x + k)), p, ng, receive), b);
    }
#else
    for (var i = DIRECTIONAL_LIGHTS; i < LIGHTS; i++) {
        color += ggx(positional(scene.lights[i], p, ng, receive), b);
    }
#endif
    return color;
}

#ifdef ENVIRONMENT
// The radiance a white Lambert surface facing `n` returns under the
// environment: its nine spherical-harmonic coefficients against the basis.
fn environment_irradiance_at(n: vec3<f32>) -> vec3<f32> {
    let c = scene.environment.y;
    let s = scene.environment.z;
    var basis = sh_basis(vec3<f32>(c * n.x - s * n.z, n.y, s * n.x + c * n.z));
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < 9u; k++) {
        sum += textureLoad(environment_irradiance, vec2<u32>(k, 0u), 0).rgb * basis[k];
    }
    return max(sum, vec3<f32>(0.0)) * scene.environment.x;
}

// The environment's light on a metallic-roughness surface: the split-sum
// specular (prefiltered radiance times F0 scaled and biased by the BRDF table)
// with multiple-scattering energy compensation (Fdez-Agüera 2019: rough
// metals keep the energy single scattering loses), Lambert diffuse from the
// harmonics, specular occlusion from `occlusion` (Lagarde 2014), and the
// diffuse darkened by `occlusion`.
fn environment_light(b: Brdf, roughness: f32, occlusion: f32) -> vec3<f32> {
    let half_texel = 0.5 / vec2<f32>(textureDimensions(environment_brdf));
    let at = clamp(vec2<f32>(b.n_v, roughness), half_texel, 1.0 - half_texel);
    let fab = textureSampleLevel(environment_brdf, environment_sampler, at, 0.0).rg;
    let fr = max(vec3<f32>(1.0 - roughness), b.f0) - b.f0;
    let k_s = b.f0 + fr * pow(1.0 - b.n_v, 5.0);
    let fss_ess = k_s * fab.x + fab.y;
    let ems = 1.0 - (fab.x + fab.y);
    let f_avg = b.f0 + (1.0 - b.f0) / 21.0;
    let fms_ems = ems * fss_ess * f_avg / (1.0 - f_avg * ems);
    let k_d = b.c_diff * (1.0 - fss_ess - fms_ems);
    let specular_occlusion = saturate(pow(b.n_v + occlusion, exp2(-16.0 * roughness - 1.0)) - 1.0 + occlusion);
    let radiance = environment_sample(reflect(-b.v, b.n), roughness * scene.environment.w);
    return fss_ess * radiance * specular_occlusion + (fms_ems + k_d) * environment_irradiance_at(b.n) * occlusion;
}
#endif

// One light through glTF's BRDF.
fn ggx(light: Incoming, b: Brdf) -> vec3<f32> {
    let n_l = max(dot(b.n, light.l), 0.0);
    let h = normalize(light.l + b.v);
    let n_h = max(dot(b.n, h), 0.0);
    let v_h = max(dot(b.v, h), 0.0);
    let f = b.f0 + (1.0 - b.f0) * pow(1.0 - v_h, 5.0);
    let k = n_h * n_h * (b.a2 - 1.0) + 1.0;
    let d = b.a2 / (PI * k * k);
    let vis = 0.5 / max(n_l * sqrt(b.n_v * b.n_v * (1.0 - b.a2) + b.a2) + b.n_v * sqrt(n_l * n_l * (1.0 - b.a2) + b.a2), 1e-6);
    let brdf = (1.0 - f) * b.c_diff / PI + f * d * vis;
    return PI * light.radiance * brdf * n_l;
}

// The texture coordinates of the map in `slot`: the second set where the
// material asks for it and the mesh has one.
#ifdef TEXCOORDS
fn map_uv(in: VertexOut, slot: u32) -> vec2<f32> {
#ifdef UV1
    return select(in.uv, in.uv1, (in.uv1_maps & slot) != 0u);
#else
    return in.uv;
#endif
}
#endif

// The surface's base colour: the material's, times the vertex colour and the
// diffuse map, its alpha faded at the tile's edge. Alpha-tested materials drop
// the fragment here, in the forward pass and the depth pre-pass alike (the
// forward pass tests the pre-pass's depth for equality: both keep the same
// fragments).
fn base_color(in: VertexOut) -> vec4<f32> {
    let material = material_at(in.material);
    var base = material.base_color;
#ifdef VERTEX_COLOR
    base *= in.color;
#endif
#ifdef DIFFUSE_MAP
    base *= textureSample(diffuse_map, material_sampler, map_uv(in, SLOT_DIFFUSE));
#endif
#ifdef EDGE_FADE
    base.a *= 1.0 - smoothstep(material.fade.x, material.fade.y, distance(in.world_position.xz, in.origin));
#endif
#ifdef ALPHA_MASK
    if base.a < material.alpha_cutoff {
        discard;
    }
#endif
#ifdef LOD_FADE
    if lod_dithered_out(in.clip.xy, in.lod_fade) {
        discard;
    }
#endif
    return base;
}

@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    return forward_color(in, front);
}

// The fragment's lit colour, and its alpha where the material blends (else 1).
fn forward_color(in: VertexOut, front: bool) -> vec4<f32> {
    let material = material_at(in.material);
    let base = base_color(in);
    // Double-sided materials light back faces with the flipped normal.
    let side = select(-1.0, 1.0, front);
    var n = normalize(in.normal) * side;
#ifdef SHADOWS
    let surface = Surface(in.world_position, n, in.receive_shadows != 0u, in.clip.xy);
#else
    let surface = Surface(in.world_position, n, false, in.clip.xy);
#endif
#ifdef NORMAL_MAP
    let t = normalize(in.tangent.xyz - n * dot(n, in.tangent.xyz));
    let b = cross(n, t) * in.tangent.w * side;
    let s = textureSample(normal_map, material_sampler, map_uv(in, SLOT_NORMAL)).xyz * 2.0 - 1.0;
    n = normalize(t * s.x + b * s.y + n * s.z);
#endif
    var specular = 1.0;
#ifdef SPECULAR_MAP
    specular = textureSample(specular_map, material_sampler, map_uv(in, SLOT_SPECULAR)).r;
#endif
    var occlusion = 1.0;
#ifdef OCCLUSION_MAP
    occlusion = textureSample(occlusion_map, material_sampler, map_uv(in, SLOT_OCCLUSION)).r;
#endif
#ifdef AMBIENT_OCCLUSION
    occlusion *= screen_occlusion(in.clip.xy);
#endif
#ifdef UNLIT
    var color = base.rgb;
#else
#ifdef METALLIC_ROUGHNESS
    var metallic = material.pbr.x;
    var roughness = material.pbr.y;
#ifdef METALLIC_ROUGHNESS_MAP
    let mr = textureSample(metallic_roughness_map, material_sampler, map_uv(in, SLOT_METALLIC_ROUGHNESS));
    roughness *= mr.g;
    metallic *= mr.b;
#endif
    var color = shade_metallic_roughness(n, surface, base.rgb, metallic, roughness, occlusion);
#else
    var color = shade(material, n, surface, base.rgb, specular, occlusion);
#endif
#endif
    var emissive = material.emissive.rgb;
#ifdef EMISSIVE_MAP
    emissive *= textureSample(emissive_map, material_sampler, map_uv(in, SLOT_EMISSIVE)).rgb;
#endif
    color += emissive;
#ifdef FOG
    let distance = length(camera.position.xyz - in.world_position) * scene.fog.w;
    color = mix(scene.fog.rgb, color, exp(-distance * distance));
#endif
#ifdef CLUSTERED
    if scene.environment_sky.y > 0.0 {
        color = cluster_heat(surface, n);
    }
#endif
#ifdef ALPHA_BLEND
    return vec4<f32>(color, base.a);
#else
    return vec4<f32>(color, 1.0);
#endif
}

#ifdef ALPHA_BLEND
// Weighted blended transparency's sums (glint::transparency_out).
@fragment
fn fs_weighted(in: VertexOut, @builtin(front_facing) front: bool) -> Weighted {
    return weighted_sums(forward_color(in, front), in.world_position);
}
#endif

#ifdef TRANSPARENCY_LISTS
// Exact transparency: the fragment into its pixel's list. The depth test
// runs before the shader, so hidden fragments append nothing. Under MSAA the
// shader runs per sample and only sample 0 appends: a pixel gets what one
// sample a pixel would (one fragment of a surface, whole at its silhouette),
// not a fragment from each triangle that covers part of it.
@fragment
@early_depth_test(force)
fn fs_exact(in: VertexOut, @builtin(front_facing) front: bool, @builtin(sample_index) sample: u32) {
    if sample == 0u {
        append_fragment(forward_color(in, front), in.clip);
    }
}
#endif

// The view's ambient occlusion at framebuffer position `pixel`, bilinear
// between the half-resolution texels around it.
fn screen_occlusion(pixel: vec2<f32>) -> f32 {
    let size = vec2<i32>(textureDimensions(ambient_occlusion));
    let at = pixel * 0.5 - 0.5;
    let base = vec2<i32>(floor(at));
    let f = at - floor(at);
    var v = vec4<f32>();
    for (var k = 0; k < 4; k++) {
        let q = clamp(base + vec2<i32>(k & 1, k >> 1u), vec2<i32>(0), size - 1);
        v[k] = textureLoad(ambient_occlusion, q, 0).r;
    }
    return mix(mix(v.x, v.y, f.x), mix(v.z, v.w, f.x), f.y);
}

// Depth pre-pass of a view with ambient occlusion (render/passes/ambient_occlusion.rs):
// the view-space normal (octahedral) and the distance in front of the camera
// as a half float plus what it rounded away, for ssao.wgsl.
@fragment
fn fs_prepass(in: VertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    base_color(in);
    let n = normalize((camera.view * vec4<f32>(normalize(in.normal) * select(-1.0, 1.0, front), 0.0)).xyz);
    let e = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    let folded = (1.0 - abs(e.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), e >= vec2<f32>(0.0));
    let distance = min(-(camera.view * vec4<f32>(in.world_position, 1.0)).z, 65504.0);
    // Cut to a half float's 10 mantissa bits: exact in the target.
    let high = bitcast<f32>(bitcast<u32>(distance) & 0xffffe000u);
    return vec4<f32>(select(e, folded, n.z < 0.0), high, distance - high);
}

// Shadow maps: alpha-tested casters drop their cut-away fragments.
fn shadow_alpha_test(in: VertexOut) {
#ifdef ALPHA_MASK
    var alpha = material_at(in.material).base_color.a;
#ifdef VERTEX_COLOR
    alpha *= in.color.a;
#endif
#ifdef DIFFUSE_MAP
    alpha *= textureSampleLevel(diffuse_map, material_sampler, map_uv(in, SLOT_DIFFUSE), 0.0).a;
#endif
    if alpha < material_at(in.material).alpha_cutoff {
        discard;
    }
#endif
}

@fragment
fn fs_shadow_mask(in: VertexOut) {
    shadow_alpha_test(in);
}

// Point-light cube faces: depth is the distance to the light over its range
// (the view's position.w is 1 / range).
@fragment
fn fs_shadow_distance(in: VertexOut) -> @builtin(frag_depth) f32 {
    shadow_alpha_test(in);
    return length(in.world_position - camera.position.xyz) * camera.position.w;
}
