// The school drawn in place (sim/school/gpu.rs, `GpuSchool::place`): after a
// frame's steps, one invocation per instance record writes a swimmer's
// instance into the renderer's store, where its entity's range is this frame,
// and its world box beside it for GPU culling and level selection. Record k
// of the range is swimmer k / each drawn by part transform k % each (a
// model's part may repeat its mesh), as World::show places them on the CPU.
// The swimmer's frame is Swimmer::transform's: front (+Z) along its velocity,
// +Y as near up as it can be, scaled; its tail beat goes in the record's
// motion phase.

struct Place {
    // The range's first record, the swimmers drawn, part transforms each.
    first: u32,
    count: u32,
    each: u32,
    material: u32,
    // Bit 0: receives shadows; bit 1: the predator (one swimmer, from
    // `hunter`); bit 2: each fish's size varied by its number.
    flags: u32,
    size: f32,
    // How far the material's motion walks an instance from its placed
    // position (InstanceRange::walk; 0: none).
    walk: f32,
    pad: u32,
    // The shape's box grown by its motion (Reach::local): centre, half extent.
    local_center: vec4<f32>,
    local_extent: vec4<f32>,
    parts: array<mat4x4<f32>, 4>,
}

struct Fish {
    position: vec3<f32>,
    phase: f32,
    velocity: vec3<f32>,
    pad: f32,
}

// forward.wgsl's `Instance`, as render/resources/blocks.rs writes it.
struct Instance {
    row_x: vec4<f32>,
    row_y: vec4<f32>,
    row_z: vec4<f32>,
    material: u32,
    joints: u32,
    joint_count: u32,
    // Bit 0: receives shadows; bits 16–31: the motion phase in 1/65536 cycles.
    flags: u32,
}

// cull.wgsl's `Bounds`.
struct Bounds {
    center: vec4<f32>,
    extent: vec4<f32>,
}

@group(0) @binding(0) var<uniform> place: Place;
@group(0) @binding(1) var<storage, read_write> fish: array<Fish>;
// The predator's state: its first 32 bytes are a Fish.
@group(0) @binding(2) var<storage, read_write> hunter: Fish;
@group(0) @binding(3) var<storage, read_write> records: array<Instance>;
@group(0) @binding(4) var<storage, read_write> bounds: array<Bounds>;

// SchoolDesc::fish_scale: `size` varied ±15 % by the fish's number.
fn fish_scale(i: u32) -> f32 {
    let h = (i * 0x9e3779b9u) ^ 0x85ebca6bu;
    let unit = f32((h * 0xc2b2ae35u) >> 8u) / 16777216.0;
    return place.size * (0.85 + 0.3 * unit);
}

fn swimmer_frame(s: Fish, scale: f32) -> mat4x4<f32> {
    var z = vec3<f32>(0.0, 0.0, 1.0);
    if length(s.velocity) > 0.0 {
        z = normalize(s.velocity);
    }
    var x = cross(vec3<f32>(0.0, 1.0, 0.0), z);
    if length(x) > 0.0 {
        x = normalize(x);
    } else {
        x = vec3<f32>(1.0, 0.0, 0.0);
    }
    let y = cross(z, x);
    return mat4x4<f32>(vec4<f32>(x * scale, 0.0), vec4<f32>(y * scale, 0.0), vec4<f32>(z * scale, 0.0), vec4<f32>(s.position, 1.0));
}

@compute @workgroup_size(256)
fn place_swimmers(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if k >= place.count * place.each {
        return;
    }
    let i = k / place.each;
    var s: Fish;
    var scale = place.size;
    if (place.flags & 2u) != 0u {
        s = hunter;
    } else {
        s = fish[i];
        if (place.flags & 4u) != 0u {
            scale = fish_scale(i);
        }
    }
    let m = swimmer_frame(s, scale) * place.parts[k % place.each];
    let t = transpose(m);
    let phase = u32(fract(s.phase) * 65536.0) & 0xffffu;
    records[place.first + k] = Instance(t[0], t[1], t[2], place.material, 0u, 0u, (place.flags & 1u) | (phase << 16u));
    let e = place.local_extent.xyz;
    var extent = abs(m[0].xyz) * e.x + abs(m[1].xyz) * e.y + abs(m[2].xyz) * e.z;
    var center = (m * vec4<f32>(place.local_center.xyz, 1.0)).xyz;
    if place.walk > 0.0 {
        // Reach::walked: around the placed position, the walk's radius plus
        // the box's own reach from there, at any heading.
        let o = m[3].xyz;
        let side = place.walk + sqrt(extent.x * extent.x + extent.z * extent.z) + length((center - o).xy);
        center = vec3<f32>(o.x, center.y, o.z);
        extent = vec3<f32>(side, extent.y, side);
    }
    bounds[place.first + k] = Bounds(vec4<f32>(center, 0.0), vec4<f32>(extent, 0.0));
}
