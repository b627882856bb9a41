// Fish schooling on the GPU: the same rules as sim/school/rules.rs, stepped
// by these compute passes (gpu.rs records them in this order):
//   clear    every cell's count to 0, and the predator's nearest fish
//   count    each fish's cell, as the pair (cell, fish number), and the
//            cell's count (an atomic add); the predator's nearest distance
//            (an atomic min of the squared distance's bits)
//   (sim/scan.wgsl: the counts' exclusive running sum, each cell's first slot)
//   (sim/radix.wgsl: the pairs sorted by cell, stably: cells in order and
//    fish by number inside each, as the CPU's counting sort orders them)
//   gather   each slot's fish into the sorted copy; the nearest fish's number
//            (an atomic min: the smallest of equals)
//   steer    every fish from the sorted copy: rules, speed limits, confinement
//   hunt     the predator, one thread, after the fish read where it was
// Nothing depends on the order in which threads ran (the atomics only count
// and take minima), so a step gives the same bits on the same device every
// time.

struct Params {
    origin: vec3<f32>,
    cell: f32,
    dims: vec3<u32>,
    count: u32,
    bounds_min: vec3<f32>,
    radius: f32,
    bounds_max: vec3<f32>,
    cos_half: f32,
    // separation, alignment, cohesion, bounds
    weights: vec4<f32>,
    // avoid, flee, max_accel, dt
    more: vec4<f32>,
    // min speed, max speed, beat rate, floor
    speed: vec4<f32>,
    // hunter speed, accel, fear, 1 with a predator
    hunter: vec4<f32>,
    // 1 with a floor, obstacles, cells, most neighbour tests a fish
    flags: vec4<u32>,
    obstacles: array<vec4<f32>, 64>,
}

struct Fish {
    position: vec3<f32>,
    phase: f32,
    velocity: vec3<f32>,
    pad: f32,
}

struct Hunt {
    position: vec3<f32>,
    phase: f32,
    velocity: vec3<f32>,
    nearest_bits: atomic<u32>,
    nearest: atomic<u32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> fish_in: array<Fish>;
@group(0) @binding(2) var<storage, read_write> fish_out: array<Fish>;
@group(0) @binding(3) var<storage, read_write> sorted: array<Fish>;
// (cell, fish number): by fish from `count`, by slot once sorted.
@group(0) @binding(4) var<storage, read_write> keys: array<vec2<u32>>;
@group(0) @binding(5) var<storage, read_write> counts: array<atomic<u32>>;
// cells + 1 entries: each cell's first slot, then the fish count.
@group(0) @binding(6) var<storage, read_write> starts: array<u32>;
@group(0) @binding(7) var<storage, read_write> hunt_state: Hunt;

fn coords(p: vec3<f32>) -> vec3<i32> {
    let c = floor((p - params.origin) / params.cell);
    return vec3<i32>(clamp(c, vec3<f32>(0.0), vec3<f32>(params.dims - 1u)));
}

fn cell_index(c: vec3<i32>) -> u32 {
    return u32(c.x) + params.dims.x * (u32(c.y) + params.dims.y * u32(c.z));
}

// The sorted fish in row `row` (0..9: dy fastest, then dz, each -1..1) of
// the 27 cells around cell `c`: the cells x-1..x+1 of that row are
// consecutive in cell order. Empty where the row is outside the grid.
fn row_slots(c: vec3<i32>, row: i32) -> vec2<u32> {
    let hi = vec3<i32>(params.dims) - 1;
    let y = c.y + row % 3 - 1;
    let z = c.z + row / 3 - 1;
    if y < 0 || z < 0 || y > hi.y || z > hi.z {
        return vec2<u32>(0u, 0u);
    }
    let x0 = max(c.x - 1, 0);
    let x1 = min(c.x + 1, hi.x);
    return vec2<u32>(starts[cell_index(vec3<i32>(x0, y, z))], starts[cell_index(vec3<i32>(x1, y, z)) + 1u]);
}

@compute @workgroup_size(256)
fn clear(@builtin(global_invocation_id) id: vec3<u32>) {
    let cells = params.flags.z;
    if id.x <= cells {
        atomicStore(&counts[id.x], 0u);
    }
    if id.x == 0u {
        atomicStore(&hunt_state.nearest_bits, 0xffffffffu);
        atomicStore(&hunt_state.nearest, 0xffffffffu);
    }
}

@compute @workgroup_size(256)
fn count(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= params.count {
        return;
    }
    let p = fish_in[i].position;
    let c = cell_index(coords(p));
    keys[i] = vec2<u32>(c, i);
    atomicAdd(&counts[c], 1u);
    if params.hunter.w > 0.0 {
        let d = p - hunt_state.position;
        atomicMin(&hunt_state.nearest_bits, bitcast<u32>(dot(d, d)));
    }
}

@compute @workgroup_size(256)
fn gather(@builtin(global_invocation_id) id: vec3<u32>) {
    let slot = id.x;
    if slot >= params.count {
        return;
    }
    let i = keys[slot].y;
    sorted[slot] = fish_in[i];
    if params.hunter.w > 0.0 {
        let d = fish_in[i].position - hunt_state.position;
        if bitcast<u32>(dot(d, d)) == atomicLoad(&hunt_state.nearest_bits) {
            atomicMin(&hunt_state.nearest, i);
        }
    }
}

fn limit_speed(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let s = length(v);
    var dir = vec3<f32>(0.0, 0.0, 1.0);
    if s > 1e-6 {
        dir = v / s;
    } else if length(fallback) > 0.0 {
        dir = normalize(fallback);
    }
    return dir * clamp(s, params.speed.x, params.speed.y);
}

struct Moved {
    position: vec3<f32>,
    velocity: vec3<f32>,
}

// rules.rs' confine: out of obstacles, then into the bounds and above the floor.
fn confine(p_in: vec3<f32>, v_in: vec3<f32>) -> Moved {
    var p = p_in;
    var v = v_in;
    for (var k = 0u; k < params.flags.y; k = k + 1u) {
        let o = params.obstacles[k];
        let e = p - o.xyz;
        let d = length(e);
        if d < o.w {
            var n = vec3<f32>(0.0, 1.0, 0.0);
            if d > 1e-6 {
                n = e / d;
            }
            p = o.xyz + n * o.w;
            v = v - n * min(dot(v, n), 0.0);
        }
    }
    for (var k = 0; k < 3; k = k + 1) {
        if p[k] < params.bounds_min[k] {
            p[k] = params.bounds_min[k];
            v[k] = abs(v[k]);
        } else if p[k] > params.bounds_max[k] {
            p[k] = params.bounds_max[k];
            v[k] = -abs(v[k]);
        }
    }
    if params.flags.x == 1u && p.y < params.speed.w {
        p.y = params.speed.w;
        v.y = abs(v.y);
    }
    return Moved(p, v);
}

fn beat(phase: f32, speed: f32, rate: f32, top: f32) -> f32 {
    let pace = 0.4 + 0.6 * min(speed / max(top, 1e-6), 1.5);
    return fract(phase + params.more.w * rate * pace);
}

@compute @workgroup_size(256)
fn steer(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= params.count {
        return;
    }
    let me = fish_in[i];
    let p = me.position;
    let v = me.velocity;
    let r2 = params.radius * params.radius;
    let cos_half = params.cos_half;
    var ahead = vec3<f32>(0.0);
    if length(v) > 0.0 {
        ahead = normalize(v);
    }
    var separation = vec3<f32>(0.0);
    var velocity_sum = vec3<f32>(0.0);
    var position_sum = vec3<f32>(0.0);
    var seen = 0u;
    let c = coords(p);
    // More candidates in the 27 cells than a fish tests: every stride-th
    // (rules.rs and School::forces_of do the same).
    var candidates = 0u;
    for (var row = 0; row < 9; row = row + 1) {
        let slots = row_slots(c, row);
        candidates = candidates + slots.y - slots.x;
    }
    let stride = max((candidates + params.flags.w - 1u) / params.flags.w, 1u);
    var before = 0u;
    for (var row = 0; row < 9; row = row + 1) {
        let slots = row_slots(c, row);
        let first = slots.x;
        let last = slots.y;
        let skip = (stride - before % stride) % stride;
        before = before + last - first;
        for (var s = first + skip; s < last; s = s + stride) {
            let q = sorted[s].position;
            let d = q - p;
            let d2 = dot(d, d);
            if d2 >= r2 || d2 == 0.0 {
                continue;
            }
            if cos_half > -1.0 && dot(d, ahead) < cos_half * sqrt(d2) {
                continue;
            }
            separation = separation - d / max(d2, 1e-4);
            velocity_sum = velocity_sum + sorted[s].velocity;
            position_sum = position_sum + q;
            seen = seen + 1u;
        }
    }
    separation = separation * f32(stride);
    var alignment = vec3<f32>(0.0);
    var cohesion = vec3<f32>(0.0);
    if seen > 0u {
        alignment = velocity_sum / f32(seen) - v;
        cohesion = position_sum / f32(seen) - p;
    }
    let m = params.radius;
    let bounds = (max(params.bounds_min + m - p, vec3<f32>(0.0)) - max(p - (params.bounds_max - m), vec3<f32>(0.0))) / m;
    var avoid = vec3<f32>(0.0);
    for (var k = 0u; k < params.flags.y; k = k + 1u) {
        let o = params.obstacles[k];
        let e = p - o.xyz;
        let d = length(e);
        let gap = d - o.w;
        if gap < m && d > 0.0 {
            avoid = avoid + e / d * min((m - gap) / m, 2.0);
        }
    }
    if params.flags.x == 1u {
        avoid.y = avoid.y + max((params.speed.w + m - p.y) / m, 0.0);
    }
    var flee = vec3<f32>(0.0);
    if params.hunter.w > 0.0 {
        let e = p - hunt_state.position;
        let d = length(e);
        if d < params.hunter.z && d > 0.0 {
            flee = e / d * (1.0 - d / params.hunter.z);
        }
    }
    let w = params.weights;
    var a = w.x * separation + w.y * alignment + w.z * cohesion + w.w * bounds + params.more.x * avoid + params.more.y * flee;
    let a_len = length(a);
    if a_len > params.more.z {
        a = a * (params.more.z / a_len);
    }
    let dt = params.more.w;
    let nv = limit_speed(v + a * dt, v);
    let moved = confine(p + nv * dt, nv);
    let vel = limit_speed(moved.velocity, nv);
    fish_out[i] = Fish(moved.position, beat(me.phase, length(vel), params.speed.z, params.speed.y), vel, 0.0);
}

@compute @workgroup_size(1)
fn hunt() {
    if params.hunter.w == 0.0 {
        return;
    }
    let dt = params.more.w;
    var v = hunt_state.velocity;
    let nearest = atomicLoad(&hunt_state.nearest);
    if nearest < params.count {
        let to = fish_in[nearest].position - hunt_state.position;
        var want = vec3<f32>(0.0);
        if length(to) > 0.0 {
            want = normalize(to) * params.hunter.x;
        }
        var turn = want - v;
        let most = params.hunter.y * dt;
        if length(turn) > most {
            turn = turn * (most / length(turn));
        }
        v = v + turn;
    }
    let s = length(v);
    var dir = vec3<f32>(0.0, 0.0, 1.0);
    if s > 1e-6 {
        dir = v / s;
    }
    v = dir * clamp(s, params.hunter.x * 0.5, params.hunter.x * 1.2);
    let moved = confine(hunt_state.position + v * dt, v);
    hunt_state.position = moved.position;
    hunt_state.velocity = moved.velocity;
    hunt_state.phase = beat(hunt_state.phase, length(moved.velocity), params.speed.z * 0.5, params.hunter.x);
}
