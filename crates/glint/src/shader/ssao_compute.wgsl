// The compute passes of screen-space ambient occlusion, appended to ssao.wgsl
// where the frame's path has compute (render/passes/ambient_occlusion.rs): one
// invocation per half-resolution pixel, into a storage texture; the blur
// reads its workgroup's taps into shared memory once.

@group(0) @binding(3) var output: texture_storage_2d<rgba8unorm, write>;

@compute @workgroup_size(8, 8)
fn cs_occlusion(@builtin(global_invocation_id) id: vec3<u32>) {
    if all(id.xy < textureDimensions(output)) {
        textureStore(output, vec2<i32>(id.xy), occlusion_at(vec2<i32>(id.xy)));
    }
}

// The blur's tile: a workgroup's 8 × 8 pixels and the two-pixel border its
// 5 × 5 taps reach, each texel's occlusion and distance read once.
const TILE: u32 = 12u;
var<workgroup> tile: array<vec2<f32>, 144>;

@compute @workgroup_size(8, 8)
fn cs_blur(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(workgroup_id) group: vec3<u32>,
) {
    let size = vec2<i32>(textureDimensions(raw));
    let origin = vec2<i32>(group.xy * 8u) - 2;
    for (var k = local.y * 8u + local.x; k < TILE * TILE; k += 64u) {
        let at = clamp(origin + vec2<i32>(i32(k % TILE), i32(k / TILE)), vec2<i32>(0), size - 1);
        let texel = textureLoad(raw, at, 0);
        tile[k] = vec2<f32>(texel.r, unpack_distance(texel.gba));
    }
    workgroupBarrier();
    if any(id.xy >= textureDimensions(output)) {
        return;
    }
    let centre = tile[(local.y + 2u) * TILE + local.x + 2u].y;
    var sum = vec2<f32>(0.0);
    for (var y = 0u; y < 5u; y++) {
        for (var x = 0u; x < 5u; x++) {
            sum += blur_tap(tile[(local.y + y) * TILE + local.x + x], centre);
        }
    }
    textureStore(output, vec2<i32>(id.xy), vec4<f32>(blurred(sum, centre)));
}
