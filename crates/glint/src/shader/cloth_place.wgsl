// The GPU cloth drawn in place (sim/cloth/dynamics/surface.rs): after the
// frame's steps, each node's vertex of the cloth's surface shape in the mesh
// pool gets the node's position and its area-weighted normal (the sum of its
// triangles' unnormalised face normals, in triangle order, as
// sim/cloth/view.rs's node_normals sums them on the CPU; +Y where they cancel),
// so the surface is drawn from the simulation's buffers and never read back.
// The vertex's texture coordinate and tangent stay as uploaded at rest.

struct Place {
    // The surface's first vertex, in words from the start of the bound window.
    first_word: u32,
    nodes: u32,
    pad: vec2<u32>,
}

@group(0) @binding(0) var<uniform> place: Place;
// Each node's position in xyz (the cloth's state). Every buffer is bound
// read-write, as the compute helpers lay them out; only `vertices` is written.
@group(0) @binding(1) var<storage, read_write> position: array<vec4<f32>>;
// Node i's triangles: around[around_start[i] .. around_start[i + 1]], ascending.
@group(0) @binding(2) var<storage, read_write> around_start: array<u32>;
@group(0) @binding(3) var<storage, read_write> around: array<u32>;
// Three nodes a triangle.
@group(0) @binding(4) var<storage, read_write> triangles: array<u32>;
// The mesh pool page's base vertex stream (scene::Vertex, 12 words each:
// position, normal, uv, tangent), bound from a window before the surface.
@group(0) @binding(5) var<storage, read_write> vertices: array<f32>;

const VERTEX_WORDS: u32 = 12u;

@compute @workgroup_size(64)
fn place_surface(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= place.nodes {
        return;
    }
    var sum = vec3<f32>(0.0);
    for (var k = around_start[i]; k < around_start[i + 1u]; k++) {
        let t = 3u * around[k];
        let a = position[triangles[t]].xyz;
        let b = position[triangles[t + 1u]].xyz;
        let c = position[triangles[t + 2u]].xyz;
        sum += cross(b - a, c - a);
    }
    let squared = dot(sum, sum);
    var normal = vec3<f32>(0.0, 1.0, 0.0);
    if squared > 0.0 {
        normal = sum * inverseSqrt(squared);
    }
    let p = position[i].xyz;
    let w = place.first_word + i * VERTEX_WORDS;
    vertices[w] = p.x;
    vertices[w + 1u] = p.y;
    vertices[w + 2u] = p.z;
    vertices[w + 3u] = normal.x;
    vertices[w + 4u] = normal.y;
    vertices[w + 5u] = normal.z;
}
