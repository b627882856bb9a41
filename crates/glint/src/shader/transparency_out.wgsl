// What transparent fragments write for order-independent transparency
// (render/passes/transparency.rs), shared by forward.wgsl's blended
// materials and particles.wgsl's alpha-blended layers.
//
// Weighted (McGuire and Bavoil 2013): both targets take one blend state,
// colour One + One and alpha Zero + OneMinusSrcAlpha (WebGL2 has no blend
// state per target): target 0 sums colour × alpha × weight in rgb and
// multiplies the revealage (what shows through) in alpha; target 1 sums
// alpha × weight.
//
// Exact (TRANSPARENCY_LISTS): each fragment appended to its pixel's list, in
// group 1 beside the Camera block: heads[0] counts the nodes taken,
// heads[1 + pixel] is the pixel's first node (0: none); a node is the colour
// as half floats (rg, ba), the depth's bits and the next node; node 0 is
// never used. transparency_lists.wgsl sorts and blends them.

#define_import_path glint::transparency_out

#import glint::blocks::camera

struct Weighted {
    @location(0) sums: vec4<f32>,
    @location(1) weights: vec4<f32>,
}

// The weight of a fragment `d` world units from the eye: the paper's
// equation 9, larger near the camera, within half floats' range.
fn transparency_weight(d: f32) -> f32 {
    let a = d / 5.0;
    let b = d / 200.0;
    return clamp(10.0 / (1e-5 + a * a + b * b * b * b * b * b), 1e-2, 3e3);
}

// The weighted targets' values for a fragment of colour `c` (not
// premultiplied) at world position `p`.
fn weighted_sums(c: vec4<f32>, p: vec3<f32>) -> Weighted {
    let w = c.a * transparency_weight(length(camera.position.xyz - p));
    return Weighted(vec4<f32>(c.rgb * w, c.a), vec4<f32>(w, 0.0, 0.0, c.a));
}

#ifdef TRANSPARENCY_LISTS
@group(1) @binding(1) var<storage, read_write> heads: array<atomic<u32>>;
@group(1) @binding(2) var<storage, read_write> nodes: array<vec4<u32>>;
// x: the lists' width in pixels.
@group(1) @binding(3) var<uniform> lists: vec4<u32>;

// Append a fragment of colour `c` (not premultiplied) at framebuffer
// position `clip` to its pixel's list; dropped when the nodes are all taken.
fn append_fragment(c: vec4<f32>, clip: vec4<f32>) {
    let node = atomicAdd(&heads[0], 1u) + 1u;
    if node >= arrayLength(&nodes) {
        return;
    }
    let pixel = vec2<u32>(clip.xy);
    let head = &heads[1u + pixel.y * lists.x + pixel.x];
    nodes[node] = vec4<u32>(pack2x16float(c.rg), pack2x16float(c.ba), bitcast<u32>(clip.z), atomicExchange(head, node));
}
#endif
