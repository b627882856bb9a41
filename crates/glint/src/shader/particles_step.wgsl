// Particles on the GPU (sim/particles/gpu.rs): the same spawn, motion and
// looks as sim/particles/mod.rs, one thread a slot. Each frame records
//   update   (once a step) every slot: its particle number from the step's
//            counts; a new particle spawned and moved to the step's end, a
//            living one moved on by dt
// then, for an additive layer,
//   write    every slot's billboard (size 0 when dead) into the layer
// or, for an alpha-blended layer, a counting sort by distance from the eye:
//   clear    the bucket counts and the layer's records
//   count    each living particle's bucket (farthest first) and rank in it
//   (sim/scan.wgsl: each bucket's first record)
//   scatter  each living particle's billboard to its record, back to front

const BUCKETS: u32 = 4096u;
const BURST: u32 = 0x80000000u;

struct Emitter {
    origin: vec3<f32>,
    // 0 point, 1 sphere, 2 box, 3 cone
    shape: u32,
    axis: vec3<f32>,
    seed: u32,
    across: vec3<f32>,
    // stream slots
    stream_slots: u32,
    other: vec3<f32>,
    burst: u32,
    // sphere or cone radius in x; box half extents in xyz
    shape_size: vec4<f32>,
    gravity: vec3<f32>,
    drag: f32,
    color: vec4<f32>,
    color_end: vec4<f32>,
    // speed min, max, spread (radians), noise
    motion: vec4<f32>,
    // life min, max, rate, burst period
    timing: vec4<f32>,
    // size, size end, noise scale, 1 with a ground
    look: vec4<f32>,
    // ground height, bounce, bursts alive, slots
    ground: vec4<f32>,
}

struct Step {
    // t0, t1, dt, the farthest distance sorted
    times: vec4<f32>,
    // steady particles spawned by t1, bursts fired by t1
    counts: vec4<u32>,
    // the eye (for the depth sort)
    eye: vec4<f32>,
}

struct Particle {
    position: vec3<f32>,
    age: f32,
    velocity: vec3<f32>,
    id: u32,
}

struct Record {
    center_size: vec4<f32>,
    color: vec4<f32>,
}

@group(0) @binding(0) var<uniform> emitter: Emitter;
@group(0) @binding(1) var<uniform> step: Step;
@group(0) @binding(2) var<storage, read_write> slots: array<Particle>;
@group(0) @binding(3) var<storage, read_write> records: array<Record>;
// (bucket, rank) per slot; bucket BUCKETS: not drawn.
@group(0) @binding(4) var<storage, read_write> keys: array<vec2<u32>>;
@group(0) @binding(5) var<storage, read_write> counts: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> starts: array<u32>;

fn hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn random(id: u32, field: u32) -> f32 {
    return f32(hash(emitter.seed ^ hash(id * 8u + field)) >> 8u) / 16777216.0;
}

fn life(id: u32) -> f32 {
    return emitter.timing.x + (emitter.timing.y - emitter.timing.x) * random(id, 6u);
}

fn spawn_time(id: u32) -> f32 {
    if (id & BURST) != 0u {
        return f32((id & ~BURST) / max(emitter.burst, 1u)) * emitter.timing.w;
    }
    return f32(id) / emitter.timing.z;
}

// schedule.rs' occupant: the particle in `slot` after the step's counts
// (0xffffffff: none).
fn occupant(slot: u32) -> u32 {
    if slot < emitter.stream_slots {
        if step.counts.x == 0u || step.counts.x - 1u < slot {
            return 0xffffffffu;
        }
        let last = step.counts.x - 1u;
        return last - (last - slot) % emitter.stream_slots;
    }
    let within = slot - emitter.stream_slots;
    let burst = max(emitter.burst, 1u);
    let group = within / burst;
    let i = within % burst;
    if step.counts.y == 0u || step.counts.y - 1u < group {
        return 0xffffffffu;
    }
    let last = step.counts.y - 1u;
    let b = last - (last - group) % max(u32(emitter.ground.z), 1u);
    return BURST | (b * emitter.burst + i);
}

fn spawn(id: u32) -> Particle {
    let tau = 6.2831853;
    var offset = vec3<f32>(0.0);
    let radius = emitter.shape_size.x;
    if emitter.shape == 1u {
        let z = random(id, 0u) * 2.0 - 1.0;
        let a = random(id, 1u) * tau;
        let s = sqrt(max(1.0 - z * z, 0.0));
        offset = vec3<f32>(s * cos(a), s * sin(a), z) * pow(random(id, 2u), 1.0 / 3.0) * radius;
    } else if emitter.shape == 2u {
        offset = (vec3<f32>(random(id, 0u), random(id, 1u), random(id, 2u)) * 2.0 - 1.0) * emitter.shape_size.xyz;
    } else if emitter.shape == 3u {
        let a = random(id, 0u) * tau;
        let d = sqrt(random(id, 1u));
        offset = (emitter.across * cos(a) + emitter.other * sin(a)) * d * radius;
    }
    let spread = emitter.motion.z;
    var dir: vec3<f32>;
    if emitter.shape == 3u && radius > 0.0 {
        let tilted = emitter.axis * cos(spread) + offset / radius * sin(spread);
        dir = select(emitter.axis, normalize(tilted), length(tilted) > 0.0);
    } else {
        let c = 1.0 - random(id, 3u) * (1.0 - cos(spread));
        let s = sqrt(max(1.0 - c * c, 0.0));
        let a = random(id, 4u) * tau;
        dir = emitter.axis * c + (emitter.across * cos(a) + emitter.other * sin(a)) * s;
    }
    let speed = emitter.motion.x + (emitter.motion.y - emitter.motion.x) * random(id, 5u);
    return Particle(emitter.origin + offset, 0.0, dir * speed, id + 1u);
}

fn noise(p: vec3<f32>, t: f32) -> vec3<f32> {
    return vec3<f32>(
        sin(p.y * 1.7 + t * 1.3) + sin(p.z * 2.3 - t * 0.7),
        sin(p.z * 1.9 + t * 1.1) + sin(p.x * 2.1 + t * 0.9),
        sin(p.x * 1.5 - t * 1.2) + sin(p.y * 2.7 + t * 0.5),
    ) * 0.5;
}

fn advance(p_in: Particle, dt: f32, time: f32) -> Particle {
    var p = p_in;
    let a = emitter.gravity + emitter.motion.w * noise(p.position / max(emitter.look.z, 1e-3), time);
    p.velocity = (p.velocity + a * dt) * exp(-emitter.drag * dt);
    p.position = p.position + p.velocity * dt;
    if emitter.look.w > 0.0 && p.position.y < emitter.ground.x {
        p.position.y = emitter.ground.x;
        p.velocity = vec3<f32>(p.velocity.x * 0.8, -p.velocity.y * emitter.ground.y, p.velocity.z * 0.8);
    }
    return p;
}

@compute @workgroup_size(256)
fn update(@builtin(global_invocation_id) gid: vec3<u32>) {
    let slot = gid.x;
    if slot >= u32(emitter.ground.w) {
        return;
    }
    let id = occupant(slot);
    if id == 0xffffffffu {
        return;
    }
    let t1 = step.times.y;
    var p = slots[slot];
    if id + 1u != p.id {
        let born = spawn_time(id);
        p = advance(spawn(id), t1 - born, born);
        p.age = t1 - born;
    } else if p.age < life(id) {
        p = advance(p, step.times.z, step.times.x);
        p.age = t1 - spawn_time(id);
    } else {
        return;
    }
    slots[slot] = p;
}

fn record(p: Particle) -> Record {
    if p.id == 0u {
        return Record(vec4<f32>(0.0), vec4<f32>(0.0));
    }
    let l = life(p.id - 1u);
    if p.age >= l {
        return Record(vec4<f32>(0.0), vec4<f32>(0.0));
    }
    let t = clamp(p.age / l, 0.0, 1.0);
    let size = emitter.look.x + (emitter.look.y - emitter.look.x) * t;
    return Record(vec4<f32>(p.position, size), mix(emitter.color, emitter.color_end, t));
}

@compute @workgroup_size(256)
fn write(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x < u32(emitter.ground.w) {
        records[gid.x] = record(slots[gid.x]);
    }
}

@compute @workgroup_size(256)
fn clear(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x <= BUCKETS {
        atomicStore(&counts[gid.x], 0u);
    }
    if gid.x < u32(emitter.ground.w) {
        records[gid.x] = Record(vec4<f32>(0.0), vec4<f32>(0.0));
    }
}

@compute @workgroup_size(256)
fn count(@builtin(global_invocation_id) gid: vec3<u32>) {
    let slot = gid.x;
    if slot >= u32(emitter.ground.w) {
        return;
    }
    let r = record(slots[slot]);
    if r.center_size.w <= 0.0 {
        keys[slot] = vec2<u32>(BUCKETS, 0u);
        return;
    }
    let d = distance(r.center_size.xyz, step.eye.xyz) / max(step.times.w, 1e-6);
    let bucket = BUCKETS - 1u - min(u32(max(d, 0.0) * f32(BUCKETS)), BUCKETS - 1u);
    keys[slot] = vec2<u32>(bucket, atomicAdd(&counts[bucket], 1u));
}

@compute @workgroup_size(256)
fn scatter(@builtin(global_invocation_id) gid: vec3<u32>) {
    let slot = gid.x;
    if slot >= u32(emitter.ground.w) {
        return;
    }
    let key = keys[slot];
    if key.x < BUCKETS {
        records[starts[key.x] + key.y] = record(slots[slot]);
    }
}
