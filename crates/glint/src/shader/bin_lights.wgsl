// A view's point and spot lights binned into its light clusters on the GPU
// (render/gpu_driven/light_binning.rs), by the rule of render/clusters.rs:
// a light is in a cluster when its view-space bounding sphere meets the
// cluster's padded box (`ClusterBoxes::meets`, the same products in the same
// order), each cluster's lights in ascending order, at most `most` of them.
//
// Two passes: `bound`, one invocation a light, finds the slices whose
// depths the light's sphere reaches and the tiles the sides of their boxes
// do (by bisection, with a little to spare, as the CPU finds them); then
// `bin`, one invocation a screen tile, takes the lights in order, skips
// those whose tiles leave it out, and tests the others' spheres against
// its clusters' boxes in their slices.
//
// `grid` (words; render/gpu_driven/light_binning.rs writes it):
//   0 tiles across, 1 tiles down, 2 slices, 3 perspective (0 or 1),
//   4 lights, 5 the word their spheres begin at, 6 the word cluster entries
//   begin at, 7 the texel the light records begin at, 8 entries a cluster
//   has room for (`most`); from 16: the tables of `ClusterBoxes` (xs, ys,
//   depths, pads); the spheres: view-space centre and radius, 4 words each.
// `clusters`: the view's cluster array (render/frame/lights.rs's layout), its
//   word 0, the (first, count) pairs from word 1, cluster c's entries from
//   word `grid[6] + c·most`.
// `counts`: 0 entries, 1 the most a cluster lists, 2 empty clusters,
//   3 entries left out, 4 lights visible, 5–7 the grid's tiles across and
//   down and its slices (so counts read back late say which grid they
//   counted); from 8, a bit per light, set once it is in a cluster. Cleared
//   before the pass.
// `bounds`: per light, its tile columns [x & 0xffff, x >> 16), rows (y) and
//   slices (z), written by `bound` for `bin`.

@group(0) @binding(0) var<storage, read> grid: array<u32>;
@group(0) @binding(1) var<storage, read_write> clusters: array<u32>;
@group(0) @binding(2) var<storage, read_write> counts: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> bounds: array<vec4<u32>>;

const TABLES: u32 = 16u;
// The most depth slices (render/gpu_driven/light_binning.rs's MOST_SLICES).
const MOST_SLICES: u32 = 64u;

struct Box {
    lo: vec3<f32>,
    hi: vec3<f32>,
}

fn grid_f32(i: u32) -> f32 {
    return bitcast<f32>(grid[i]);
}

// The padded box of column `i`, row `j` between depths `d0` and `d1`.
fn cluster_box(i: u32, j: u32, d0: f32, d1: f32, pad: f32) -> Box {
    let xs = TABLES;
    let ys = tables().y;
    let perspective = grid[3] != 0u;
    let s0 = select(1.0, d0, perspective);
    let s1 = select(1.0, d1, perspective);
    let x0 = grid_f32(xs + i);
    let x1 = grid_f32(xs + i + 1u);
    let y0 = grid_f32(ys + j);
    let y1 = grid_f32(ys + j + 1u);
    let lo = vec3<f32>(min(x0 * s0, x0 * s1), min(y1 * s0, y1 * s1), -d1);
    let hi = vec3<f32>(max(x1 * s0, x1 * s1), max(y0 * s0, y0 * s1), -d0);
    return Box(lo - vec3<f32>(pad), hi + vec3<f32>(pad));
}

fn sphere(light: u32) -> vec4<f32> {
    let at = grid[5] + 4u * light;
    return vec4<f32>(grid_f32(at), grid_f32(at + 1u), grid_f32(at + 2u), grid_f32(at + 3u));
}

fn meets(b: Box, s: vec4<f32>) -> bool {
    let d = min(max(s.xyz, b.lo), b.hi) - s.xyz;
    return d.x * d.x + d.y * d.y + d.z * d.z <= s.w * s.w;
}

// Where the tables begin: xs, ys, depths, pads.
fn tables() -> vec4<u32> {
    let ys = TABLES + grid[0] + 1u;
    let depths = ys + grid[1] + 1u;
    return vec4<u32>(TABLES, ys, depths, depths + grid[2] + 1u);
}

// Whether the sphere `s` (radius `r`, with some to spare) lies wholly past
// one side of every box in slice `k` and column or row `m` (and all before
// it, as each test holds up to a point and no further): `side` 0, 1 its
// back and front (`m` unused); 2, 3 left of the sphere and right of its
// left side; 4, 5 above it and below its top.
fn beyond(side: u32, k: u32, m: u32, s: vec3<f32>, r: f32) -> bool {
    let t = tables();
    let d0 = grid_f32(t.z + k);
    let d1 = grid_f32(t.z + k + 1u);
    let pad = grid_f32(t.w + k);
    let perspective = grid[3] != 0u;
    let s0 = select(1.0, d0, perspective);
    let s1 = select(1.0, d1, perspective);
    switch side {
        case 0u: {
            return -d1 - pad > s.z + r;
        }
        case 1u: {
            return -d0 + pad >= s.z - r;
        }
        case 2u: {
            let x = grid_f32(t.x + m + 1u);
            return max(x * s0, x * s1) + pad < s.x - r;
        }
        case 3u: {
            let x = grid_f32(t.x + m);
            return min(x * s0, x * s1) - pad <= s.x + r;
        }
        case 4u: {
            let y = grid_f32(t.y + m + 1u);
            return min(y * s0, y * s1) - pad > s.y + r;
        }
        default: {
            let y = grid_f32(t.y + m);
            return max(y * s0, y * s1) + pad >= s.y - r;
        }
    }
}

// The first of 0..n where `beyond(side, …)` fails, by bisection: over
// slices (`side` 0, 1) or over the columns or rows of slice `k`.
fn first_failing(n: u32, side: u32, k: u32, s: vec3<f32>, r: f32) -> u32 {
    var lo = 0u;
    var hi = n;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        var holds: bool;
        if side < 2u {
            holds = beyond(side, mid, 0u, s, r);
        } else {
            holds = beyond(side, k, mid, s, r);
        }
        if holds {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

@compute @workgroup_size(64)
fn bound(@builtin(global_invocation_id) id: vec3<u32>) {
    let light = id.x;
    if light >= grid[4] {
        return;
    }
    let tiles = vec2<u32>(grid[0], grid[1]);
    let s = sphere(light);
    let r = s.w * (1.0 + 1e-4) + 1e-6;
    let k0 = first_failing(grid[2], 0u, 0u, s.xyz, r);
    let k1 = first_failing(grid[2], 1u, 0u, s.xyz, r);
    var lo = tiles;
    var hi = vec2<u32>(0u);
    for (var k = k0; k < k1; k++) {
        let start = vec2<u32>(first_failing(tiles.x, 2u, k, s.xyz, r), first_failing(tiles.y, 4u, k, s.xyz, r));
        let end = vec2<u32>(first_failing(tiles.x, 3u, k, s.xyz, r), first_failing(tiles.y, 5u, k, s.xyz, r));
        if all(start < end) {
            lo = min(lo, start);
            hi = max(hi, end);
        }
    }
    bounds[light] = vec4<u32>(lo.x | (hi.x << 16u), lo.y | (hi.y << 16u), k0 | (k1 << 16u), 0u);
}

@compute @workgroup_size(64)
fn bin(@builtin(global_invocation_id) id: vec3<u32>) {
    let tiles = vec2<u32>(grid[0], grid[1]);
    if id.x >= tiles.x * tiles.y {
        return;
    }
    let tile = vec2<u32>(id.x % tiles.x, id.x / tiles.x);
    let slices = grid[2];
    let lights = grid[4];
    let most = grid[8];
    let t = tables();
    var listed: array<u32, MOST_SLICES>;
    var left_out = 0u;
    for (var light = 0u; light < lights; light++) {
        let b = bounds[light];
        let start = b.xy & vec2<u32>(0xffffu);
        let end = b.xy >> vec2<u32>(16u);
        if any(tile < start) || any(tile >= end) {
            continue;
        }
        let s = sphere(light);
        for (var k = b.z & 0xffffu; k < (b.z >> 16u); k++) {
            let d0 = grid_f32(t.z + k);
            let d1 = grid_f32(t.z + k + 1u);
            if !meets(cluster_box(tile.x, tile.y, d0, d1, grid_f32(t.w + k)), s) {
                continue;
            }
            let cluster = tile.x + tiles.x * (tile.y + tiles.y * k);
            let n = listed[k];
            if n < most {
                clusters[grid[6] + cluster * most + n] = light;
                listed[k] = n + 1u;
            } else {
                left_out++;
            }
            let bit = 1u << (light % 32u);
            if (atomicOr(&counts[8u + light / 32u], bit) & bit) == 0u {
                atomicAdd(&counts[4], 1u);
            }
        }
    }
    var most_listed = 0u;
    var empty = 0u;
    var entries = 0u;
    for (var k = 0u; k < slices; k++) {
        let cluster = tile.x + tiles.x * (tile.y + tiles.y * k);
        let n = listed[k];
        clusters[1u + 2u * cluster] = grid[6] + cluster * most;
        clusters[2u + 2u * cluster] = n;
        most_listed = max(most_listed, n);
        empty += select(0u, 1u, n == 0u);
        entries += n;
    }
    atomicAdd(&counts[0], entries);
    atomicMax(&counts[1], most_listed);
    atomicAdd(&counts[2], empty);
    atomicAdd(&counts[3], left_out);
    if id.x == 0u {
        clusters[0] = grid[7];
        atomicStore(&counts[5], tiles.x);
        atomicStore(&counts[6], tiles.y);
        atomicStore(&counts[7], slices);
    }
}
