// The compute passes of screen-space ambient occlusion, appended to ssao.wgsl
// where the frame's path has compute (render/passes/ambient_occlusion.rs): one
// invocation per half-resolution pixel, into a storage texture.

@group(0) @binding(3) var output: texture_storage_2d<rgba8unorm, write>;

@compute @workgroup_size(8, 8)
fn cs_occlusion(@builtin(global_invocation_id) id: vec3<u32>) {
    if all(id.xy < textureDimensions(output)) {
        textureStore(output, vec2<i32>(id.xy), vec4<f32>(occlusion_at(vec2<i32>(id.xy))));
    }
}

@compute @workgroup_size(8, 8)
fn cs_blur(@builtin(global_invocation_id) id: vec3<u32>) {
    if all(id.xy < textureDimensions(output)) {
        textureStore(output, vec2<i32>(id.xy), vec4<f32>(blur_at(vec2<i32>(id.xy))));
    }
}
