// The depth pyramid of occlusion culling (render/gpu_driven/occlusion.rs): texel t of
// level 0 is the farthest depth of the depth buffer's pixels 2t and 2t + 1 on
// each axis (all their samples), and the far plane (1) past the buffer, in a
// level padded to powers of two so that every level halves the one before
// exactly; texel t of each next level is the farthest of texels 2t and 2t + 1
// on each axis of the level before. So texel p >> (k + 1) of level k holds the
// farthest depth of pixel p's square. One dispatch per level, 8 × 8 texels a workgroup.

@group(0) @binding(0) var depth: texture_depth_2d;
@group(0) @binding(1) var level: texture_storage_2d<r32float, write>;
@group(0) @binding(2) var depth_samples: texture_depth_multisampled_2d;
@group(0) @binding(3) var finer: texture_2d<f32>;

@compute @workgroup_size(8, 8)
fn first(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= textureDimensions(level)) {
        return;
    }
    let size = textureDimensions(depth);
    var d = 1.0;
    if all(id.xy * 2u < size) {
        let a = id.xy * 2u;
        let b = min(a + 1u, size - 1u);
        d = max(
            max(textureLoad(depth, a, 0), textureLoad(depth, vec2<u32>(b.x, a.y), 0)),
            max(textureLoad(depth, vec2<u32>(a.x, b.y), 0), textureLoad(depth, b, 0)),
        );
    }
    textureStore(level, id.xy, vec4<f32>(d, 0.0, 0.0, 0.0));
}

@compute @workgroup_size(8, 8)
fn first_multisampled(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= textureDimensions(level)) {
        return;
    }
    let size = textureDimensions(depth_samples);
    var d = 1.0;
    if all(id.xy * 2u < size) {
        d = 0.0;
        let a = id.xy * 2u;
        let b = min(a + 1u, size - 1u);
        let corners = array<vec2<u32>, 4>(a, vec2<u32>(b.x, a.y), vec2<u32>(a.x, b.y), b);
        for (var c = 0; c < 4; c++) {
            for (var s = 0; s < i32(textureNumSamples(depth_samples)); s++) {
                d = max(d, textureLoad(depth_samples, corners[c], s));
            }
        }
    }
    textureStore(level, id.xy, vec4<f32>(d, 0.0, 0.0, 0.0));
}

@compute @workgroup_size(8, 8)
fn down(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= textureDimensions(level)) {
        return;
    }
    let last = textureDimensions(finer) - 1u;
    let a = min(id.xy * 2u, last);
    let b = min(id.xy * 2u + 1u, last);
    let d = max(
        max(textureLoad(finer, a, 0).r, textureLoad(finer, vec2<u32>(b.x, a.y), 0).r),
        max(textureLoad(finer, vec2<u32>(a.x, b.y), 0).r, textureLoad(finer, b, 0).r),
    );
    textureStore(level, id.xy, vec4<f32>(d, 0.0, 0.0, 0.0));
}
