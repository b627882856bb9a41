// GPU frustum culling of one draw list (render/gpu_driven/gpu_cull.rs), two entry points
// dispatched in order within one compute pass:
//
// `cull`: one invocation per candidate instance. The list's cull ranges give
// each candidate's instance in the store, its batch, the frustum it is tested
// against and where its batch's instances go in the draw-index buffer. A
// visible instance takes the next place of its batch (an atomic add on the
// instance count of the batch's indirect command, reset to 0 before the pass)
// and writes its store index there. The test is the CPU culler's, term for
// term: a box is culled only when it is wholly outside one plane, so NaN keeps it.
//
// With occlusion culling (two phases, render/gpu_driven/occlusion.rs), `cull_early` and
// `cull_late` take `cull`'s place. `cull_early` keeps only what was visible last
// frame (its flag in `hidden` is 0); the frame draws that, builds a depth pyramid
// from it, and `cull_late` tests every candidate against frustum and pyramid,
// writes its flag for the next frame and places what is visible now but was not
// drawn early into the late commands (group 0 then binds those, and `params`
// says where their places and counts go).
//
// `compact`: one invocation per run of batches drawn by one multi-draw call.
// It copies the run's non-empty commands, in order, to the start of the run's
// range of `drawn_args`, writes how many there are (the count a
// multi-draw-indirect-count call reads) and adds the run's instances and their
// triangles to its frustum's totals (read back late for FrameStats; the cull
// passes count the instances they place at each level of detail).

struct Bounds {
    center: vec4<f32>,
    extent: vec4<f32>,
}

// Candidates `start .. start + count` (numbered across the whole list) are
// store instances `first ..`, tested against `frustum`, drawn by `batch`, whose
// instances start at `out` in the draw-index buffer. With `levels` > 1 each
// visible candidate picks its level of detail (render/lod.rs's rule): level l
// is drawn by batch `batch + l`, its places `l * params.level_stride` further
// on, its error (in units of the box's radius) `error[l - 1]`.
struct CullRange {
    first: u32,
    count: u32,
    start: u32,
    batch: u32,
    frustum: u32,
    out: u32,
    levels: u32,
    pad: u32,
    error: vec4<f32>,
}

// Batches `first .. first + len` drawn by one call, seen by `frustum`.
struct Run {
    first: u32,
    len: u32,
    frustum: u32,
    pad: u32,
}

struct Params {
    // Cull ranges and candidates in the list.
    ranges: u32,
    candidates: u32,
    // Runs, and where the per-frustum instance totals start in `counts`.
    runs: u32,
    totals: u32,
    // Where this phase's run counts start in `counts`, and how far past a
    // range's `out` its places are (the late phase's region).
    counts_first: u32,
    place_offset: u32,
    // How far apart each level of detail's places are.
    level_stride: u32,
    pad: u32,
}

// The view seen by the occlusion test: its view-projection matrix, the depth
// buffer's size in pixels and the pyramid's levels (shader/pyramid.wgsl: level
// k texel p >> (k + 1) holds the farthest depth of depth pixel p's square).
struct Occlusion {
    view_proj: mat4x4<f32>,
    size: vec2<f32>,
    levels: u32,
    pad: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> bounds: array<Bounds>;
@group(0) @binding(2) var<storage, read> ranges: array<CullRange>;
// Per view, eight rows: its six frustum planes, then its level-of-detail rule
// (render/lod.rs): row 3 of its view-projection, then its pixel scale over the
// error allowed (0: full detail) and padding.
@group(0) @binding(3) var<storage, read> planes: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> draw_indices: array<u32>;
// Indirect commands, five words each: index count, instance count, first index,
// base vertex, first instance.
@group(0) @binding(5) var<storage, read_write> args: array<atomic<u32>>;
// Each run's command count (the early phase's, then the late's), then each
// frustum's totals (TOTAL_WORDS words: instances drawn, triangles drawn,
// instances culled here drawn at each level of detail, then the coarser copies
// of fading ones, counted among the instances drawn), then the late phase's
// hidden count.
@group(0) @binding(6) var<storage, read_write> counts: array<atomic<u32>>;

@group(1) @binding(0) var<storage, read> runs: array<Run>;
@group(1) @binding(1) var<storage, read_write> drawn_args: array<u32>;


// Per candidate: 1 when it was not visible last frame; then one more word,
// where the late phase counts the instances it found hidden.
@group(2) @binding(0) var<storage, read_write> hidden: array<atomic<u32>>;
@group(2) @binding(1) var pyramid: texture_2d<f32>;
@group(2) @binding(2) var<uniform> occlusion: Occlusion;

const WORKGROUP: u32 = 64u;
// Words of a frustum's totals in `counts` (render/gpu_driven/gpu_cull.rs).
const TOTAL_WORDS: u32 = 8u;
// How much farther than the pyramid's depth a box must be to count hidden:
// more than a 24-bit depth buffer's rounding, so a surface never hides itself.
const DEPTH_MARGIN: f32 = 1e-6;

// The invocation's number across a dispatch of several rows of workgroups.
fn invocation(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.x + id.y * groups.x * WORKGROUP;
}

// Whether the box `c ± e` may be inside the six planes starting at `first`.
fn visible(c: vec3<f32>, e: vec3<f32>, first: u32) -> bool {
    for (var k = 0u; k < 6u; k++) {
        let p = planes[first + k];
        let reach = c.x * p.x + c.y * p.y + c.z * p.z + p.w + e.x * abs(p.x) + e.y * abs(p.y) + e.z * abs(p.z);
        if reach < 0.0 {
            return false;
        }
    }
    return true;
}

// Candidate `g`'s store instance and range, by binary search for the last range
// starting at or before it.
fn candidate(g: u32) -> CullRange {
    var lo = 0u;
    var hi = params.ranges - 1u;
    while lo < hi {
        let mid = (lo + hi + 1u) / 2u;
        if ranges[mid].start <= g {
            lo = mid;
        } else {
            hi = mid - 1u;
        }
    }
    return ranges[lo];
}

// A draw index's fade bits start here (render/lod.rs FADE_SHIFT).
const FADE_SHIFT: u32 = 27u;

// The level of detail a box `c ± e` of range `r` draws at: the coarsest whose
// error projects to at most the view's allowed pixels at the box's nearest
// depth; and (y) how far it has faded into the next, in 16ths (render/lod.rs
// LodView::pick, term for term).
fn pick_of(r: CullRange, c: vec3<f32>, e: vec3<f32>) -> vec2<u32> {
    let w_row = planes[r.frustum * 8u + 6u];
    let scale = planes[r.frustum * 8u + 7u].x;
    let band = planes[r.frustum * 8u + 7u].y;
    if r.levels <= 1u || scale <= 0.0 {
        return vec2<u32>(0u);
    }
    let radius = length(e);
    let w = dot(w_row, vec4<f32>(c, 1.0)) - radius * length(w_row.xyz);
    let allowed = w / (radius * scale);
    if !(allowed > 0.0) {
        return vec2<u32>(0u);
    }
    var level = 0u;
    for (var l = r.levels - 1u; l > 0u; l--) {
        if r.error[l - 1u] <= allowed {
            level = l;
            break;
        }
    }
    if band <= 0.0 || level + 1u >= r.levels {
        return vec2<u32>(level, 0u);
    }
    let coarser = (allowed / r.error[level] * (1.0 + band) - 1.0) / band;
    return vec2<u32>(level, min(u32(clamp(coarser, 0.0, 1.0) * 16.0), 15u));
}

// Put draw index `value` among the instances of range `r`'s batch at `level`.
fn put(r: CullRange, level: u32, value: u32) {
    let at = atomicAdd(&args[(r.batch + level) * 5u + 1u], 1u);
    draw_indices[r.out + level * params.level_stride + params.place_offset + at] = value;
}

// Place store instance `instance` of range `r`, whose box is `c ± e`, among
// the instances of its batch at its level of detail; one fading into the next
// level goes there too, its coarser copy, both with their fade bits.
fn place(r: CullRange, instance: u32, c: vec3<f32>, e: vec3<f32>) {
    let pick = pick_of(r, c, e);
    let totals = params.totals + r.frustum * TOTAL_WORDS;
    atomicAdd(&counts[totals + 2u + pick.x], 1u);
    if pick.y == 0u {
        put(r, pick.x, instance);
        return;
    }
    let fade = instance | (pick.y << (FADE_SHIFT + 1u));
    put(r, pick.x, fade);
    put(r, pick.x + 1u, fade | (1u << FADE_SHIFT));
    atomicAdd(&counts[totals + TOTAL_WORDS - 1u], 1u);
}

// Whether the box `c ± e` is wholly behind what the depth pyramid holds.
// Conservative: a box crossing the eye plane, or with NaN in it, is not.
fn occluded(c: vec3<f32>, e: vec3<f32>) -> bool {
    var lo = vec3<f32>(1e30);
    var hi = vec3<f32>(-1e30);
    for (var k = 0u; k < 8u; k++) {
        let s = vec3<f32>(select(-1.0, 1.0, (k & 1u) != 0u), select(-1.0, 1.0, (k & 2u) != 0u), select(-1.0, 1.0, (k & 4u) != 0u));
        let p = occlusion.view_proj * vec4<f32>(c + e * s, 1.0);
        if !(p.w > 1e-6) {
            return false;
        }
        lo = min(lo, p.xyz / p.w);
        hi = max(hi, p.xyz / p.w);
    }
    let size = occlusion.size;
    let x = clamp(vec2<f32>(lo.x, hi.x) * 0.5 + 0.5, vec2<f32>(0.0), vec2<f32>(1.0)) * size.x;
    let y = clamp(0.5 - vec2<f32>(hi.y, lo.y) * 0.5, vec2<f32>(0.0), vec2<f32>(1.0)) * size.y;
    let last = vec2<u32>(size) - 1u;
    let p0 = min(vec2<u32>(u32(x.x), u32(y.x)), last);
    let p1 = min(vec2<u32>(u32(x.y), u32(y.y)), last);
    // The finest level where the box's pixels span at most two texels each way.
    var level = 0u;
    while level + 1u < occlusion.levels && any((p1 >> vec2<u32>(level + 1u)) - (p0 >> vec2<u32>(level + 1u)) > vec2<u32>(1u)) {
        level += 1u;
    }
    let a = p0 >> vec2<u32>(level + 1u);
    let b = p1 >> vec2<u32>(level + 1u);
    let l = i32(level);
    let far = max(
        max(textureLoad(pyramid, a, l).r, textureLoad(pyramid, vec2<u32>(b.x, a.y), l).r),
        max(textureLoad(pyramid, vec2<u32>(a.x, b.y), l).r, textureLoad(pyramid, b, l).r),
    );
    return lo.z > far + DEPTH_MARGIN;
}

// One invocation's candidate: its number, range and store instance, and the
// instance's world box; `valid` is false past the list's candidates.
struct Candidate {
    valid: bool,
    g: u32,
    range: CullRange,
    instance: u32,
    center: vec3<f32>,
    extent: vec3<f32>,
}

fn candidate_of(id: vec3<u32>, groups: vec3<u32>) -> Candidate {
    let g = invocation(id, groups);
    if g >= params.candidates {
        return Candidate(false, g, CullRange(0u, 0u, 0u, 0u, 0u, 0u, 0u, 0u, vec4<f32>(0.0)), 0u, vec3<f32>(0.0), vec3<f32>(0.0));
    }
    let r = candidate(g);
    let instance = r.first + (g - r.start);
    let b = bounds[instance];
    return Candidate(true, g, r, instance, b.center.xyz, b.extent.xyz);
}

@compute @workgroup_size(64)
fn cull(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let c = candidate_of(id, groups);
    if c.valid && visible(c.center, c.extent, c.range.frustum * 8u) {
        place(c.range, c.instance, c.center, c.extent);
    }
}

@compute @workgroup_size(64)
fn cull_early(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let c = candidate_of(id, groups);
    if c.valid && atomicLoad(&hidden[c.g]) == 0u && visible(c.center, c.extent, c.range.frustum * 8u) {
        place(c.range, c.instance, c.center, c.extent);
    }
}

@compute @workgroup_size(64)
fn cull_late(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let c = candidate_of(id, groups);
    if !c.valid {
        return;
    }
    let in_frustum = visible(c.center, c.extent, c.range.frustum * 8u);
    let seen = in_frustum && !occluded(c.center, c.extent);
    if in_frustum && !seen {
        atomicAdd(&hidden[params.candidates], 1u);
    }
    let drawn_early = atomicLoad(&hidden[c.g]) == 0u;
    atomicStore(&hidden[c.g], select(1u, 0u, seen));
    if seen && !drawn_early {
        place(c.range, c.instance, c.center, c.extent);
    }
}

@compute @workgroup_size(64)
fn compact(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = invocation(id, groups);
    if k >= params.runs {
        return;
    }
    let run = runs[k];
    var kept = 0u;
    var instances = 0u;
    var triangles = 0u;
    let totals = params.totals + run.frustum * TOTAL_WORDS;
    for (var b = run.first; b < run.first + run.len; b++) {
        let count = atomicLoad(&args[b * 5u + 1u]);
        if count > 0u {
            let to = (run.first + kept) * 5u;
            for (var w = 0u; w < 5u; w++) {
                drawn_args[to + w] = atomicLoad(&args[b * 5u + w]);
            }
            kept += 1u;
            instances += count;
            triangles += count * (atomicLoad(&args[b * 5u]) / 3u);
        }
    }
    atomicStore(&counts[params.counts_first + k], kept);
    atomicAdd(&counts[totals], instances);
    atomicAdd(&counts[totals + 1u], triangles);
}
