// SMAA 1x (Jimenez, Echevarria, Sousa and Gutierrez, "SMAA: Enhanced
// Subpixel Morphological Antialiasing", 2012), the three passes of a post
// chain's `smaa` effect (render/passes/post.rs), after the reference shader
// at https://github.com/iryoku/smaa (MIT licence, © 2013 Jorge Jimenez, Jose
// I. Echevarria, Belen Masia, Fernando Navarro and Diego Gutierrez; its text in
// crates/glint/licenses/SMAA-LICENSE.txt):
//   1. fs_smaa_edges: luma edges between each pixel and its left and top
//      neighbours (red: left, green: top), kept where they stand out locally;
//      a pixel without one is discarded, the rest are marked in a stencil;
//   2. fs_smaa_weights, on the marked pixels only: for each edge, the distances to the ends of its line
//      and the crossing edges there name a pattern, whose area (from the area
//      texture, render/passes/smaa_area.rs) says how much of the neighbour
//      across the edge this pixel takes: red/green for its top edge, blue/alpha
//      for its left (diagonal lines first, where found);
//   3. fs_smaa_blend: each pixel mixes with the neighbour its largest weight
//      names, by one bilinear fetch.
// The edge and weight images are the chain's float intermediates; the search
// texture of the reference (how far the last step of a line search reaches)
// is computed here from the fetched edges instead of looked up.
//
// Bindings: post_inputs.wgsl's, and the area texture.

#import glint::full_screen::{full_screen_clip, full_screen_uv}
#import glint::post_inputs::{Params, Varyings, source, extra, linear_clamp, params}

@group(0) @binding(4) var area_texture: texture_2d<f32>;

@vertex
fn vs_post(@builtin(vertex_index) index: u32) -> Varyings {
    return Varyings(full_screen_clip(index, 0.0), full_screen_uv(index));
}

// Texels per orthogonal pattern square, per diagonal one, and the area
// texture's size (SMAA 1x's part of the reference texture).
const AREA_MAX_DISTANCE: f32 = 16.0;
const AREA_MAX_DISTANCE_DIAG: f32 = 20.0;
const AREA_SIZE: vec2<f32> = vec2<f32>(160.0, 80.0);
// An edge is kept only where no edge around it is this many times stronger.
const LOCAL_CONTRAST: f32 = 2.0;

// ---- 1. Edges ----

// Perceived luma (as FXAA's: the square root of clamped luminance) of the
// texel `offset` texels from `pixel`, clamped to the image.
fn luma(pixel: vec2<i32>, offset: vec2<i32>) -> f32 {
    let size = vec2<i32>(textureDimensions(source));
    let at = clamp(pixel + offset, vec2<i32>(0), size - vec2<i32>(1));
    let c = clamp(textureLoad(source, at, 0).rgb, vec3<f32>(0.0), vec3<f32>(1.0));
    return sqrt(dot(c, vec3<f32>(0.2126, 0.7152, 0.0722)));
}

@fragment
fn fs_smaa_edges(in: Varyings) -> @location(0) vec4<f32> {
    let p = vec2<i32>(floor(in.uv * params.texel.zw));
    let l = luma(p, vec2<i32>(0, 0));
    let left = luma(p, vec2<i32>(-1, 0));
    let top = luma(p, vec2<i32>(0, -1));
    let delta = abs(l - vec2<f32>(left, top));
    var edges = step(vec2<f32>(params.a.x), delta);
    if edges.x + edges.y == 0.0 {
        // Left unmarked: the weights pass skips the pixel.
        discard;
    }
    let right = luma(p, vec2<i32>(1, 0));
    let bottom = luma(p, vec2<i32>(0, 1));
    let left_left = luma(p, vec2<i32>(-2, 0));
    let top_top = luma(p, vec2<i32>(0, -2));
    var most = max(delta, abs(l - vec2<f32>(right, bottom)));
    most = max(most, abs(vec2<f32>(left, top) - vec2<f32>(left_left, top_top)));
    edges *= step(vec2<f32>(max(most.x, most.y)), LOCAL_CONTRAST * delta);
    return vec4<f32>(edges, 0.0, 0.0);
}

// ---- 2. Blending weights ----

fn edges_at(uv: vec2<f32>) -> vec2<f32> {
    return textureSampleLevel(source, linear_clamp, uv, 0.0).rg;
}

// The edges `offset` texels from `uv`.
fn edges_by(uv: vec2<f32>, offset: vec2<f32>) -> vec2<f32> {
    return edges_at(uv + offset * params.texel.xy);
}

// A diagonal search's fetch reads two edges at once, at a quarter texel's
// offset: red 0.25 or 1 where the right pixel's left edge is set, green 0.75
// or 1 where this one's top edge is. This unpacks both to 0 or 1.
fn unpack_diagonal(e: vec4<f32>) -> vec4<f32> {
    var d = e;
    d.x = e.x * abs(5.0 * e.x - 3.75);
    d.z = e.z * abs(5.0 * e.z - 3.75);
    return round(d);
}

// How far a diagonal search went (steps, and whether the line still went
// on: 1, or ended: 0), and the last edges it fetched.
struct DiagonalEnd {
    steps: f32,
    going: f32,
    edges: vec2<f32>,
}

// Follow the diagonal from `uv` along `dir`, fetching the two edges a
// diagonal step needs; `packed` reads them in one fetch at a quarter texel's
// offset (the second diagonal's case).
fn search_diagonal(uv: vec2<f32>, dir: vec2<f32>, packed: bool) -> DiagonalEnd {
    var at = uv;
    if packed {
        at.x += 0.25 * params.texel.x;
    }
    var end = DiagonalEnd(-1.0, 1.0, vec2<f32>(0.0));
    while end.steps < params.a.z - 1.0 && end.going > 0.9 {
        at += dir * params.texel.xy;
        end.steps += 1.0;
        end.edges = edges_at(at);
        if packed {
            end.edges = unpack_diagonal(vec4<f32>(end.edges, 0.0, 0.0)).xy;
        }
        end.going = dot(end.edges, vec2<f32>(0.5));
    }
    return end;
}

// The area of a diagonal line `dist` pixels from its ends with crossing
// edges `e` (0..2 at each end).
fn area_diagonal(dist: vec2<f32>, e: vec2<f32>) -> vec2<f32> {
    var uv = (AREA_MAX_DISTANCE_DIAG * e + dist + 0.5) / AREA_SIZE;
    uv.x += 0.5;
    return textureSampleLevel(area_texture, linear_clamp, uv, 0.0).rg;
}

// The weights of the diagonal lines through a pixel with edges `e`: first
// the one rising to the right, then the one falling.
fn diagonal_weights(uv: vec2<f32>, e: vec2<f32>) -> vec2<f32> {
    let t = params.texel.xy;
    var weights = vec2<f32>(0.0);
    // d: distances to the ends; going: whether each search ran out of steps.
    var d = vec2<f32>(0.0);
    var going = vec2<f32>(0.0);
    if e.x > 0.0 {
        let end = search_diagonal(uv, vec2<f32>(-1.0, 1.0), false);
        d.x = end.steps + f32(end.edges.y > 0.9);
        going.x = end.going;
    }
    let up = search_diagonal(uv, vec2<f32>(1.0, -1.0), false);
    d.y = up.steps;
    going.y = up.going;
    if d.x + d.y > 2.0 {
        let coords = vec4<f32>(-d.x + 0.25, d.x, d.y, -d.y - 0.25) * vec4<f32>(t, t) + vec4<f32>(uv, uv);
        let fetched = vec4<f32>(edges_by(coords.xy, vec2<f32>(-1.0, 0.0)), edges_by(coords.zw, vec2<f32>(1.0, 0.0)));
        let c = unpack_diagonal(fetched).yxwz;
        let crossing = select(2.0 * c.xz + c.yw, vec2<f32>(0.0), going >= vec2<f32>(0.9));
        weights += area_diagonal(d, crossing);
    }
    let down = search_diagonal(uv, vec2<f32>(-1.0, -1.0), true);
    d.x = down.steps;
    going.x = down.going;
    if edges_by(uv, vec2<f32>(1.0, 0.0)).x > 0.0 {
        let end = search_diagonal(uv, vec2<f32>(1.0, 1.0), true);
        d.y = end.steps + f32(end.edges.y > 0.9);
        going.y = end.going;
    } else {
        d.y = 0.0;
        going.y = 0.0;
    }
    if d.x + d.y > 2.0 {
        let coords = vec4<f32>(-d.x, -d.x, d.y, d.y) * vec4<f32>(t, t) + vec4<f32>(uv, uv);
        let far = edges_by(coords.zw, vec2<f32>(1.0, 0.0));
        let c = vec4<f32>(
            edges_by(coords.xy, vec2<f32>(-1.0, 0.0)).y,
            edges_by(coords.xy, vec2<f32>(0.0, -1.0)).x,
            far.y,
            far.x,
        );
        let crossing = select(2.0 * c.xz + c.yw, vec2<f32>(0.0), going >= vec2<f32>(0.9));
        weights += area_diagonal(d, crossing).yx;
    }
    return weights;
}

// The four edges a line search's fetch (at an offset of (-0.25, -0.125)
// texels) mixed: 32 times it is e0 + 3 e1 + 7 e2 + 21 e3, each 0 or 1 (e0,
// e1 the upper pair left to right, e2, e3 the lower); `valid` is false
// where no four edges give it.
struct Fetched {
    e: vec4<bool>,
    valid: bool,
}

fn fetched_edges(value: f32) -> Fetched {
    var k = i32(round(32.0 * value));
    let e3 = k >= 21;
    k -= select(0, 21, e3);
    let e2 = k >= 7;
    k -= select(0, 7, e2);
    let e1 = k >= 3;
    k -= select(0, 3, e1);
    return Fetched(vec4<bool>(k == 1, e1, e2, e3), k <= 1);
}

// How many pixels past a line search's last fetch its line goes on (0..2):
// what the reference's search texture holds. `e` is the fetch (x: the
// crossing edges, y: the line's own), for the search to the left (or up),
// or `forward`, to the right (or down).
fn last_step(e: vec2<f32>, forward: bool) -> f32 {
    let side = fetched_edges(e.x);
    let along = fetched_edges(e.y);
    if !side.valid || !along.valid {
        return 0.0;
    }
    let s = side.e;
    let a = along.e;
    // One pixel on where the nearer edge is set (going forward, also with no
    // crossing edge at it), two where the further one is too and no
    // crossing edge stops it.
    var d = 0.0;
    if a.w && (!forward || (!s.y && !s.w)) {
        d = 1.0;
    }
    let open = select(!s.y && !s.w, !s.x && !s.z, forward);
    if d == 1.0 && a.z && open {
        d = 2.0;
    }
    return d;
}

// The texture coordinate where the horizontal line through `start` ends,
// searching left (`dir` -1) or right (1) by two pixels a step until `end`.
fn search_x(start: vec2<f32>, end: f32, dir: f32) -> f32 {
    var at = start;
    var e = vec2<f32>(0.0, 1.0);
    while (at.x - end) * dir < 0.0 && e.y > 0.8281 && e.x == 0.0 {
        e = edges_at(at);
        at.x += dir * 2.0 * params.texel.x;
    }
    return at.x - dir * params.texel.x * (3.25 - last_step(e, dir > 0.0));
}

// As search_x, for the vertical line through `start` (`dir` -1 up, 1 down).
fn search_y(start: vec2<f32>, end: f32, dir: f32) -> f32 {
    var at = start;
    var e = vec2<f32>(1.0, 0.0);
    while (at.y - end) * dir < 0.0 && e.x > 0.8281 && e.y == 0.0 {
        e = edges_at(at);
        at.y += dir * 2.0 * params.texel.y;
    }
    return at.y - dir * params.texel.y * (3.25 - last_step(e.yx, dir > 0.0));
}

// The area of an orthogonal line, `sqrt_dist` the square roots of the
// distances to its ends (the texture is compressed quadratically), `e1` and
// `e2` the crossing edges' fetches at them.
fn area(sqrt_dist: vec2<f32>, e1: f32, e2: f32) -> vec2<f32> {
    let uv = (AREA_MAX_DISTANCE * round(4.0 * vec2<f32>(e1, e2)) + sqrt_dist + 0.5) / AREA_SIZE;
    return textureSampleLevel(area_texture, linear_clamp, uv, 0.0).rg;
}

// Less blending at a line's end where it meets a corner (SMAA's corner
// rounding): `coords` holds the line's ends, `d` the distances to them, and
// `offsets` where the crossing edges' fetches lie about each end (the end's
// two, then the far end's two). `vertical` reads the top edges.
fn round_corners(weights: vec2<f32>, coords: vec4<f32>, d: vec2<f32>, vertical: bool) -> vec2<f32> {
    let left_right = step(d.xy, d.yx);
    let rounding = (1.0 - params.a.w) * left_right / (left_right.x + left_right.y);
    var factor = vec2<f32>(1.0);
    if vertical {
        factor.x -= rounding.x * edges_by(coords.xy, vec2<f32>(1.0, 0.0)).y;
        factor.x -= rounding.y * edges_by(coords.zw, vec2<f32>(1.0, 1.0)).y;
        factor.y -= rounding.x * edges_by(coords.xy, vec2<f32>(-2.0, 0.0)).y;
        factor.y -= rounding.y * edges_by(coords.zw, vec2<f32>(-2.0, 1.0)).y;
    } else {
        factor.x -= rounding.x * edges_by(coords.xy, vec2<f32>(0.0, 1.0)).x;
        factor.x -= rounding.y * edges_by(coords.zw, vec2<f32>(1.0, 1.0)).x;
        factor.y -= rounding.x * edges_by(coords.xy, vec2<f32>(0.0, -2.0)).x;
        factor.y -= rounding.y * edges_by(coords.zw, vec2<f32>(1.0, -2.0)).x;
    }
    return weights * clamp(factor, vec2<f32>(0.0), vec2<f32>(1.0));
}

@fragment
fn fs_smaa_weights(in: Varyings) -> @location(0) vec4<f32> {
    let uv = in.uv;
    let t = params.texel;
    let pixel = uv * t.zw;
    // Where the searches start (see last_step's fetches) and the furthest
    // they may reach.
    let horizontal = vec4<f32>(t.xy, t.xy) * vec4<f32>(-0.25, -0.125, 1.25, -0.125) + vec4<f32>(uv, uv);
    let vertical = vec4<f32>(t.xy, t.xy) * vec4<f32>(-0.125, -0.25, -0.125, 1.25) + vec4<f32>(uv, uv);
    let reach = vec4<f32>(t.xx, t.yy) * vec4<f32>(-2.0, 2.0, -2.0, 2.0) * params.a.y
        + vec4<f32>(horizontal.xz, vertical.yw);
    var weights = vec4<f32>(0.0);
    var e = edges_at(uv);
    if e.y > 0.0 {
        var diagonal = vec2<f32>(0.0);
        if params.a.z > 0.0 {
            diagonal = diagonal_weights(uv, e);
        }
        if diagonal.x + diagonal.y == 0.0 {
            let left = search_x(horizontal.xy, reach.x, -1.0);
            let right = search_x(horizontal.zw, reach.y, 1.0);
            let e1 = edges_at(vec2<f32>(left, vertical.y)).x;
            let e2 = edges_by(vec2<f32>(right, vertical.y), vec2<f32>(1.0, 0.0)).x;
            let d = abs(round(t.zz * vec2<f32>(left, right) - pixel.xx));
            let w = area(sqrt(d), e1, e2);
            let ends = vec4<f32>(left, uv.y, right, uv.y);
            let rounded = round_corners(w, ends, d, false);
            weights = vec4<f32>(rounded, 0.0, 0.0);
        } else {
            // A diagonal takes the pixel: no vertical line through it.
            weights = vec4<f32>(diagonal, 0.0, 0.0);
            e.x = 0.0;
        }
    }
    if e.x > 0.0 {
        let up = search_y(vertical.xy, reach.z, -1.0);
        let down = search_y(vertical.zw, reach.w, 1.0);
        let e1 = edges_at(vec2<f32>(horizontal.x, up)).y;
        let e2 = edges_by(vec2<f32>(horizontal.x, down), vec2<f32>(0.0, 1.0)).y;
        let d = abs(round(t.ww * vec2<f32>(up, down) - pixel.yy));
        let w = area(sqrt(d), e1, e2);
        let ends = vec4<f32>(uv.x, up, uv.x, down);
        let rounded = round_corners(w, ends, d, true);
        weights.z = rounded.x;
        weights.w = rounded.y;
    }
    return weights;
}

// ---- 3. Neighbourhood blending ----

fn color_at(uv: vec2<f32>) -> vec3<f32> {
    return textureSampleLevel(source, linear_clamp, uv, 0.0).rgb;
}

fn weights_at(uv: vec2<f32>) -> vec4<f32> {
    return textureSampleLevel(extra, linear_clamp, uv, 0.0);
}

@fragment
fn fs_smaa_blend(in: Varyings) -> @location(0) vec4<f32> {
    let uv = in.uv;
    let t = params.texel.xy;
    let here = weights_at(uv);
    // The weights towards each neighbour: right, bottom, left, top.
    let a = vec4<f32>(
        weights_at(uv + vec2<f32>(t.x, 0.0)).w,
        weights_at(uv + vec2<f32>(0.0, t.y)).y,
        here.z,
        here.x,
    );
    if dot(a, vec4<f32>(1.0)) < 1e-5 {
        return vec4<f32>(color_at(uv), 1.0);
    }
    let horizontal = max(a.x, a.z) > max(a.y, a.w);
    var offset = vec4<f32>(0.0, a.y, 0.0, a.w);
    var weight = a.yw;
    if horizontal {
        offset = vec4<f32>(a.x, 0.0, a.z, 0.0);
        weight = a.xz;
    }
    weight /= weight.x + weight.y;
    let coords = offset * vec4<f32>(t, -t) + vec4<f32>(uv, uv);
    let color = weight.x * color_at(coords.xy) + weight.y * color_at(coords.zw);
    return vec4<f32>(color, 1.0);
}
