// GPU frustum culling of one draw list (render/gpu_cull.rs), two entry points
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
// `compact`: one invocation per run of batches drawn by one multi-draw call.
// It copies the run's non-empty commands, in order, to the start of the run's
// range of `drawn_args`, writes how many there are (the count a
// multi-draw-indirect-count call reads) and adds the run's instances to its
// frustum's total (read back late for FrameStats).

struct Bounds {
    center: vec4<f32>,
    extent: vec4<f32>,
}

// Candidates `start .. start + count` (numbered across the whole list) are
// store instances `first ..`, tested against `frustum`, drawn by `batch`, whose
// instances start at `out` in the draw-index buffer.
struct CullRange {
    first: u32,
    count: u32,
    start: u32,
    batch: u32,
    frustum: u32,
    out: u32,
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
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> bounds: array<Bounds>;
@group(0) @binding(2) var<storage, read> ranges: array<CullRange>;
@group(0) @binding(3) var<storage, read> planes: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> draw_indices: array<u32>;
// Indirect commands, five words each: index count, instance count, first index,
// base vertex, first instance.
@group(0) @binding(5) var<storage, read_write> args: array<atomic<u32>>;

@group(1) @binding(0) var<storage, read> runs: array<Run>;
@group(1) @binding(1) var<storage, read_write> drawn_args: array<u32>;
// Each run's command count, then each frustum's instances drawn.
@group(1) @binding(2) var<storage, read_write> counts: array<atomic<u32>>;

const WORKGROUP: u32 = 64u;

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

@compute @workgroup_size(64)
fn cull(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let g = invocation(id, groups);
    if g >= params.candidates {
        return;
    }
    // The last range starting at or before g.
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
    let r = ranges[lo];
    let instance = r.first + (g - r.start);
    let b = bounds[instance];
    if visible(b.center.xyz, b.extent.xyz, r.frustum * 6u) {
        let place = atomicAdd(&args[r.batch * 5u + 1u], 1u);
        draw_indices[r.out + place] = instance;
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
    for (var b = run.first; b < run.first + run.len; b++) {
        let count = atomicLoad(&args[b * 5u + 1u]);
        if count > 0u {
            let to = (run.first + kept) * 5u;
            for (var w = 0u; w < 5u; w++) {
                drawn_args[to + w] = atomicLoad(&args[b * 5u + w]);
            }
            kept += 1u;
            instances += count;
        }
    }
    atomicStore(&counts[k], kept);
    atomicAdd(&counts[params.totals + run.frustum], instances);
}
