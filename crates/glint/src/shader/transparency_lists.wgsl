// Exact transparency's composite (render/passes/transparency.rs): each
// pixel's list of transparent fragments (glint::transparency_out's
// append_fragment) sorted near to far and blended, over what the opaque stages drew. Blended One +
// OneMinusSrcAlpha: the fragments' colour, each behind the ones before it,
// and the coverage 1 - Π(1 - alpha).
//
// Bindings: the list heads (0: the nodes taken; 1 + pixel: its first node,
// 0 for none), the nodes (colour as half floats rg and ba, the depth's
// bits, the next node), the lists' width (x).

#import glint::full_screen::full_screen_clip

@group(0) @binding(0) var<storage, read> heads: array<u32>;
@group(0) @binding(1) var<storage, read> nodes: array<vec4<u32>>;
@group(0) @binding(2) var<uniform> lists: vec4<u32>;

// The nearest fragments of a pixel that are blended; farther ones are dropped.
const KEPT: u32 = 32u;

@vertex
fn vs_composite(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    return full_screen_clip(index, 0.0);
}

// Whether node `a` is blended in front of node `b`: nearer (depths in 0..1
// order as their bits do), then by colour, so equal depths blend the same
// way whatever order the fragments were appended in.
fn in_front(a: vec4<u32>, b: vec4<u32>) -> bool {
    if a.z != b.z {
        return a.z < b.z;
    }
    if a.x != b.x {
        return a.x < b.x;
    }
    return a.y < b.y;
}

@fragment
fn fs_composite(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<u32>(position.xy);
    var node = heads[1u + pixel.y * lists.x + pixel.x];
    if node == 0u {
        discard;
    }
    // Insertion sort of the nearest KEPT, near to far (each node goes after
    // those in front of it, the rest move back one, the last falling off);
    // the walk ends after as many steps as there are nodes.
    var kept: array<vec4<u32>, KEPT>;
    var count = 0u;
    let taken = min(heads[0], arrayLength(&nodes));
    for (var step = 0u; step < taken && node != 0u && node < arrayLength(&nodes); step++) {
        let n = nodes[node];
        node = n.w;
        var at = 0u;
        for (var k = 0u; k < count; k++) {
            at = select(at, k + 1u, in_front(kept[k], n));
        }
        for (var k = min(count, KEPT - 1u); k > at; k--) {
            kept[k] = kept[k - 1u];
        }
        if at < KEPT {
            kept[at] = n;
        }
        count = min(count + 1u, KEPT);
    }
    var color = vec3<f32>(0.0);
    var through = 1.0;
    for (var k = 0u; k < count; k++) {
        let c = vec4<f32>(unpack2x16float(kept[k].x), unpack2x16float(kept[k].y));
        color += through * c.rgb * c.a;
        through *= 1.0 - c.a;
    }
    return vec4<f32>(color, 1.0 - through);
}
