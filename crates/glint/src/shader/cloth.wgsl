// Cloth on compute shaders (sim/cloth/dynamics/gpu.rs): one implicit time
// step of Discrete Elastic Plates solved by Vertex Block Descent (Chen et al.,
// SIGGRAPH 2024). The step minimises the same incremental potential as the
// CPU's Newton solve (sim/cloth/dynamics.rs),
//   ½ s' Σ m |q − x̂|² − Σ m g·q + stretching + bending + contact,
// but one node at a time: `predict` sets each node's target x̂ and first
// guess, then each iteration runs `solve_colour` once per colour, every node
// of the colour taking one 3×3 Newton step on the terms that hold it, with
// the other nodes fixed (nodes of a colour share no element, so they move
// at once without touching each other's terms); `finish` turns the result
// into velocities and accelerations. Every node's step is shortened until its
// own terms' sum falls (or it stays put), so the sweeps never raise the
// potential; `accelerate`, between sweeps where it is on, may.
//
// Hessians are the positive semi-definite ones of Hessian::Definite: a
// squeezed edge's sideways term dropped, the hinge's k ∇θ ∇θᵀ, the contact's
// k n nᵀ; the mass term s' m I makes each node's block positive definite.

struct Params {
    nodes: u32,
    // 0: implicit Euler; 1: Newmark (β = ¼, γ = ½).
    integrator: u32,
    colliders: u32,
    pad: u32,
    dt: f32,
    // s: 1/dt² (Euler) or 1/(β dt²) (Newmark); drag: the damping c κ folded
    // into the inertia term (κ = 1/dt or γ/(β dt)); kappa: κ.
    inertia: f32,
    drag: f32,
    kappa: f32,
    gravity: vec3<f32>,
    bend_k: f32,
    pin_velocity: vec3<f32>,
    // The contact distance δ.
    contact_distance: f32,
    pin_spin: vec3<f32>,
    // A node's contact stiffness over its mass.
    contact_per_kg: f32,
    pin_centre: vec3<f32>,
    // Simulated time when the state was uploaded; steps since are in State.
    start_time: f32,
    // Per collider: a.w is its kind (0 plane: a point, b normal; 1 sphere:
    // a centre, b.x radius; 2 box: a min, b max).
    collider_a: array<vec4<f32>, 64>,
    collider_b: array<vec4<f32>, 64>,
}

struct State {
    steps: u32,
}

// One colour's nodes: order[first .. first + count].
struct Colour {
    first: u32,
    count: u32,
    pad: vec2<u32>,
}

// Edge (a, b) with rest length and stiffness (stretch_energy's k).
struct Edge {
    nodes: vec2<u32>,
    rest: f32,
    k: f32,
}

// Hinge [x₀, x₁, x₂, x₃] (Topology::hinges) with its rest angle.
struct Hinge {
    nodes: vec4<u32>,
    rest: f32,
    pad: array<f32, 3>,
}

const BETA: f32 = 0.25;
const GAMMA: f32 = 0.5;
const WORKGROUP: u32 = 64u;
// Halvings of a node's Newton step before it stays put.
const LINE_SEARCH_HALVINGS: u32 = 3u;

// Every pass: the parameters, the step's positions q (the solve's unknowns),
// each node's target x̂, and rest positions; rest.w is the node's mass,
// negative for a pinned node. Positions are xyz of vec4s.
@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> q: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> goal: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> rest: array<vec4<f32>>;

// `predict` and `finish`: the state between steps.
@group(1) @binding(0) var<storage, read_write> position: array<vec4<f32>>;
@group(1) @binding(1) var<storage, read_write> velocity: array<vec4<f32>>;
@group(1) @binding(2) var<storage, read_write> acceleration: array<vec4<f32>>;
@group(1) @binding(3) var<storage, read_write> state: State;

// `accelerate`: Chebyshev's semi-iterative acceleration between sweeps
// (Wang 2015, as Vertex Block Descent uses it): the sweep's result is carried
// on past the position two sweeps back, by ω, which grows from 1 to its limit
// over the first sweeps. Block 0 (before the first sweep) only records the
// start; the positions one and two sweeps back are `last` and `before`.
struct Chebyshev {
    omega: f32,
    // 1: only record the start.
    record: u32,
    pad: vec2<u32>,
}

@group(3) @binding(0) var<uniform> chebyshev: Chebyshev;
@group(3) @binding(1) var<storage, read_write> last: array<vec4<f32>>;
@group(3) @binding(2) var<storage, read_write> before: array<vec4<f32>>;

// `solve_colour`: one colour's nodes and the elements. An adjacency entry is
// element << 3 | hinge << 2 | slot: the node is `slot` of edge or hinge
// `element`.
@group(2) @binding(0) var<uniform> colour: Colour;
@group(2) @binding(1) var<storage, read_write> adjacency_start: array<u32>;
@group(2) @binding(2) var<storage, read_write> adjacency: array<u32>;
@group(2) @binding(3) var<storage, read_write> edges: array<Edge>;
@group(2) @binding(4) var<storage, read_write> hinges: array<Hinge>;
@group(2) @binding(5) var<storage, read_write> order: array<u32>;

// Signed distance to collider k and the outward normal (xyz), as
// Collider::distance computes it.
fn collider_distance(k: u32, x: vec3<f32>) -> vec4<f32> {
    let a = params.collider_a[k];
    let b = params.collider_b[k];
    let kind = u32(a.w);
    if kind == 0u {
        return vec4<f32>(b.xyz, dot(x - a.xyz, b.xyz));
    }
    if kind == 1u {
        let d = x - a.xyz;
        let length = length(d);
        var n = vec3<f32>(0.0, 0.0, 1.0);
        if length > 0.0 {
            n = d / length;
        }
        return vec4<f32>(n, length - b.x);
    }
    let centre = 0.5 * (a.xyz + b.xyz);
    let half = 0.5 * (b.xyz - a.xyz);
    let local = x - centre;
    let qd = abs(local) - half;
    let outside = max(qd, vec3<f32>(0.0));
    if dot(outside, outside) > 0.0 {
        let length = length(outside);
        return vec4<f32>(outside * sign(local) / length, length);
    }
    var axis = 2u;
    if qd.x >= qd.y && qd.x >= qd.z {
        axis = 0u;
    } else if qd.y >= qd.z {
        axis = 1u;
    }
    var n = vec3<f32>(0.0);
    n[axis] = select(-1.0, 1.0, local[axis] >= 0.0);
    return vec4<f32>(n, qd[axis]);
}

fn inside_any(x: vec3<f32>) -> bool {
    for (var k = 0u; k < params.colliders; k += 1u) {
        if collider_distance(k, x).w < 0.0 {
            return true;
        }
    }
    return false;
}

// `step` cut short where it would carry a node from outside every collider
// into one, sampled at quarters (Contact::clamp_motion).
fn clamp_motion(start: vec3<f32>, step: vec3<f32>) -> vec3<f32> {
    if params.colliders == 0u || inside_any(start) {
        return step;
    }
    var safe = 0.0;
    for (var k = 1u; k <= 4u; k += 1u) {
        let t = 0.25 * f32(k);
        if inside_any(start + t * step) {
            break;
        }
        safe = t;
    }
    return safe * step;
}

// Where a pin that started at `start` is at time t (PinMotion::at).
fn pin_at(start: vec3<f32>, t: f32) -> vec3<f32> {
    let turn = params.pin_spin * t;
    let angle = length(turn);
    var r = start - params.pin_centre;
    if angle > 0.0 {
        let axis = turn / angle;
        r = r * cos(angle) + cross(axis, r) * sin(angle) + axis * dot(axis, r) * (1.0 - cos(angle));
    }
    return params.pin_centre + r + params.pin_velocity * t;
}

// Newmark's or implicit Euler's predicted position x̃ from the step's start.
fn predicted(i: u32) -> vec3<f32> {
    let dt = params.dt;
    let x = position[i].xyz + dt * velocity[i].xyz;
    if params.integrator == 1u {
        return x + dt * dt * (0.5 - BETA) * acceleration[i].xyz;
    }
    return x;
}

@compute @workgroup_size(WORKGROUP)
fn predict(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= params.nodes {
        return;
    }
    let x0 = position[i].xyz;
    if rest[i].w < 0.0 {
        let t = params.start_time + f32(state.steps + 1u) * params.dt;
        q[i] = vec4<f32>(pin_at(rest[i].xyz, t), 0.0);
        return;
    }
    let dt = params.dt;
    let tilde = predicted(i);
    // Damping folded into the inertia term (Cloth::damped): the end velocity
    // is κ (q − q_d), so the drag's and the inertia's terms add up.
    var q_d = x0;
    if params.integrator == 1u {
        q_d = tilde - (velocity[i].xyz + dt * (1.0 - GAMMA) * acceleration[i].xyz) / params.kappa;
    }
    let goal_x = (params.inertia * tilde + params.drag * q_d) / (params.inertia + params.drag);
    goal[i] = vec4<f32>(goal_x, 0.0);
    // The first guess (Vertex Block Descent's adaptive start): inertia plus
    // the part of the last acceleration along gravity, at most gravity, so a
    // falling node keeps falling and one held up (by the table, or the cloth)
    // stays held, while sideways jolts of an inexact last step are not
    // carried on; stopped short of a collider it would enter.
    let g = length(params.gravity);
    var along = 0.0;
    if g > 0.0 {
        along = clamp(dot(acceleration[i].xyz, params.gravity) / (g * g), 0.0, 1.0);
    }
    let guess = dt * velocity[i].xyz + dt * dt * along * params.gravity;
    q[i] = vec4<f32>(x0 + clamp_motion(x0, guess), 0.0);
}

@compute @workgroup_size(WORKGROUP)
fn finish(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= params.nodes {
        return;
    }
    let dt = params.dt;
    let x0 = position[i].xyz;
    let q1 = q[i].xyz;
    if rest[i].w < 0.0 {
        velocity[i] = vec4<f32>((q1 - x0) / dt, 0.0);
    } else if params.integrator == 1u {
        let a0 = acceleration[i].xyz;
        let a1 = params.inertia * (q1 - predicted(i));
        velocity[i] = vec4<f32>(velocity[i].xyz + dt * ((1.0 - GAMMA) * a0 + GAMMA * a1), 0.0);
        acceleration[i] = vec4<f32>(a1, 0.0);
    } else {
        let v1 = (q1 - x0) / dt;
        acceleration[i] = vec4<f32>((v1 - velocity[i].xyz) / dt, 0.0);
        velocity[i] = vec4<f32>(v1, 0.0);
    }
    position[i] = vec4<f32>(q1, 0.0);
    if i == 0u {
        state.steps += 1u;
    }
}

// The gradient and definite Hessian of the terms holding one node.
struct Derivatives {
    gradient: vec3<f32>,
    hessian: mat3x3<f32>,
}

// The quantities of one hinge with node `slot` at x: the angle's gradient
// for that node and the angle.
struct HingeAt {
    gradient: vec3<f32>,
    angle: f32,
}

fn hinge_at(h: Hinge, slot: u32, x: vec3<f32>) -> HingeAt {
    var p = array<vec3<f32>, 4>(q[h.nodes.x].xyz, q[h.nodes.y].xyz, q[h.nodes.z].xyz, q[h.nodes.w].xyz);
    p[slot] = x;
    let e = p[1] - p[0];
    let a = p[2] - p[0];
    let b = p[3] - p[0];
    let n1 = cross(e, a);
    let n2 = cross(b, e);
    let length = length(e);
    let a1 = dot(n1, n1);
    let a2 = dot(n2, n2);
    let g2 = -(length / a1) * n1;
    let g3 = -(length / a2) * n2;
    let l2 = length * length;
    let t2 = dot(a, e) / l2;
    let t3 = dot(b, e) / l2;
    var g = array<vec3<f32>, 4>(-((1.0 - t2) * g2 + (1.0 - t3) * g3), -(t2 * g2 + t3 * g3), g2, g3);
    let angle = atan2(dot(e / length, cross(n1, n2)), dot(n1, n2));
    return HingeAt(g[slot], angle);
}

fn outer(u: vec3<f32>, v: vec3<f32>) -> mat3x3<f32> {
    return mat3x3<f32>(u * v.x, u * v.y, u * v.z);
}

// The node's mass (rest.w).
fn mass_of(i: u32) -> f32 {
    return rest[i].w;
}

// Inertia, gravity and contact of node i at x.
fn own_derivatives(i: u32, x: vec3<f32>) -> Derivatives {
    let m = mass_of(i);
    let s = params.inertia + params.drag;
    var g = s * m * (x - goal[i].xyz) - m * params.gravity;
    var h = mat3x3<f32>(vec3<f32>(s * m, 0.0, 0.0), vec3<f32>(0.0, s * m, 0.0), vec3<f32>(0.0, 0.0, s * m));
    let kc = params.contact_per_kg * m;
    for (var k = 0u; k < params.colliders; k += 1u) {
        let d = collider_distance(k, x);
        if d.w < params.contact_distance {
            let gap = params.contact_distance - d.w;
            g -= kc * gap * d.xyz;
            h += kc * outer(d.xyz, d.xyz);
        }
    }
    return Derivatives(g, h);
}

fn derivatives(i: u32, x: vec3<f32>) -> Derivatives {
    var out = own_derivatives(i, x);
    for (var k = adjacency_start[i]; k < adjacency_start[i + 1u]; k += 1u) {
        let entry = adjacency[k];
        let slot = entry & 3u;
        let element = entry >> 3u;
        if (entry & 4u) == 0u {
            let edge = edges[element];
            let other = q[edge.nodes[1u - slot]].xyz;
            // d runs from this node to the other; the energy's gradient for
            // this node is −f(d) with f stretch_gradient's.
            let d = other - x;
            let length = length(d);
            let u = d / length;
            out.gradient -= edge.k * (length / edge.rest - 1.0) / (edge.rest * length) * d;
            let along = edge.k / (edge.rest * edge.rest);
            let across = max(edge.k * (length / edge.rest - 1.0) / (edge.rest * length), 0.0);
            let uu = outer(u, u);
            let identity = mat3x3<f32>(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0, 0.0, 1.0));
            out.hessian += along * uu + across * (identity - uu);
        } else {
            let hinge = hinges[element];
            let at = hinge_at(hinge, slot, x);
            let k = params.bend_k;
            out.gradient += k * (at.angle - hinge.rest) * at.gradient;
            out.hessian += k * outer(at.gradient, at.gradient);
        }
    }
    return out;
}

// How much the terms holding node i change when it moves from x by dx.
// The inertia and gravity terms' change is written out, and each elastic
// term's is the difference of its two values: smaller numbers than the sums.
fn energy_change(i: u32, x: vec3<f32>, dx: vec3<f32>) -> f32 {
    let m = mass_of(i);
    let s = params.inertia + params.drag;
    let y = x + dx;
    var change = s * m * (dot(dx, x - goal[i].xyz) + 0.5 * dot(dx, dx)) - m * dot(params.gravity, dx);
    let kc = params.contact_per_kg * m;
    for (var k = 0u; k < params.colliders; k += 1u) {
        let before = max(params.contact_distance - collider_distance(k, x).w, 0.0);
        let after = max(params.contact_distance - collider_distance(k, y).w, 0.0);
        change += 0.5 * kc * (after - before) * (after + before);
    }
    for (var k = adjacency_start[i]; k < adjacency_start[i + 1u]; k += 1u) {
        let entry = adjacency[k];
        let slot = entry & 3u;
        let element = entry >> 3u;
        if (entry & 4u) == 0u {
            let edge = edges[element];
            let other = q[edge.nodes[1u - slot]].xyz;
            let before = length(other - x) / edge.rest - 1.0;
            let after = length(other - y) / edge.rest - 1.0;
            change += 0.5 * edge.k * (after - before) * (after + before);
        } else {
            let hinge = hinges[element];
            let before = hinge_at(hinge, slot, x).angle - hinge.rest;
            let after = hinge_at(hinge, slot, y).angle - hinge.rest;
            change += 0.5 * params.bend_k * (after - before) * (after + before);
        }
    }
    return change;
}

// The Newton step −H⁻¹g (xyz) of a symmetric H by its adjugate; w is 1 when
// H is positive definite enough to solve (its determinant above 0; a NaN
// fails the test too), else 0.
fn newton_step(h: mat3x3<f32>, g: vec3<f32>) -> vec4<f32> {
    let c0 = cross(h[1], h[2]);
    let c1 = cross(h[2], h[0]);
    let c2 = cross(h[0], h[1]);
    let det = dot(h[0], c0);
    if !(det > 0.0) {
        return vec4<f32>(0.0);
    }
    // H symmetric: its adjugate's columns are c0, c1, c2.
    return vec4<f32>(-(mat3x3<f32>(c0, c1, c2) * g) / det, 1.0);
}

@compute @workgroup_size(WORKGROUP)
fn solve_colour(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= colour.count {
        return;
    }
    let i = order[colour.first + id.x];
    let x = q[i].xyz;
    let d = derivatives(i, x);
    let newton = newton_step(d.hessian, d.gradient);
    if newton.w == 0.0 {
        return;
    }
    let step = clamp_motion(x, newton.xyz);
    var alpha = 1.0;
    for (var k = 0u; k <= LINE_SEARCH_HALVINGS; k += 1u) {
        if energy_change(i, x, alpha * step) <= 0.0 {
            q[i] = vec4<f32>(x + alpha * step, 0.0);
            return;
        }
        alpha *= 0.5;
    }
}

@compute @workgroup_size(WORKGROUP)
fn accelerate(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= params.nodes || rest[i].w < 0.0 {
        return;
    }
    let swept = q[i].xyz;
    if chebyshev.record == 1u {
        last[i] = vec4<f32>(swept, 0.0);
        return;
    }
    var x = swept;
    if chebyshev.omega != 1.0 {
        let back = before[i].xyz;
        x = swept + clamp_motion(swept, chebyshev.omega * (swept - back) + back - swept);
    }
    before[i] = last[i];
    last[i] = vec4<f32>(x, 0.0);
    q[i] = vec4<f32>(x, 0.0);
}
