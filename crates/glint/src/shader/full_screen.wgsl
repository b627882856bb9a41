// The full-screen triangle every full-screen pass draws (blits, post effects,
// the sky, the environment's prefilter, ambient occlusion): vertices 0, 1, 2
// at clip (-1, -1), (3, -1), (-1, 3), covering the target; uv (0, 0) at its
// top-left corner and (1, 1) at its bottom-right, as textures are read.

#define_import_path glint::full_screen

// Vertex `index`'s corner: (0, 0), (2, 0), (0, 2).
fn full_screen_corner(index: u32) -> vec2<f32> {
    return vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
}

// Where vertex `index` of the triangle lies, at depth `depth`.
fn full_screen_clip(index: u32, depth: f32) -> vec4<f32> {
    return vec4<f32>(full_screen_corner(index) * 2.0 - 1.0, depth, 1.0);
}

// The texture coordinate at vertex `index` of the triangle (v down).
fn full_screen_uv(index: u32) -> vec2<f32> {
    let corner = full_screen_corner(index);
    return vec2<f32>(corner.x, 1.0 - corner.y);
}
