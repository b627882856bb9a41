// An exclusive running sum of counts (sim/scan.rs): `starts[i]` becomes the
// sum of `counts[0..i]`, for up to 256 × 4096 entries, in three passes:
//   scan_blocks  each block of 256 summed in a workgroup; block totals kept
//   scan_sums    the block totals summed by one workgroup, 16 a thread
//   scan_add     each block's offset added to its entries
// The counting sorts of the school's grid and of particles by depth use it.

const WORKGROUP: u32 = 256u;
const SUMS_PER_THREAD: u32 = 16u;

// x: entries.
@group(0) @binding(0) var<uniform> size: vec4<u32>;
@group(0) @binding(1) var<storage, read_write> counts: array<u32>;
@group(0) @binding(2) var<storage, read_write> starts: array<u32>;
@group(0) @binding(3) var<storage, read_write> block_sums: array<u32>;

var<workgroup> scratch: array<u32, 256>;

// An inclusive scan of `scratch` by the workgroup (Hillis–Steele); returns the total.
fn scan_scratch(lane: u32) -> u32 {
    for (var step = 1u; step < WORKGROUP; step = step * 2u) {
        workgroupBarrier();
        var add = 0u;
        if lane >= step {
            add = scratch[lane - step];
        }
        workgroupBarrier();
        scratch[lane] = scratch[lane] + add;
    }
    workgroupBarrier();
    return scratch[WORKGROUP - 1u];
}

@compute @workgroup_size(256)
fn scan_blocks(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) lane: u32, @builtin(workgroup_id) block: vec3<u32>) {
    var own = 0u;
    if id.x < size.x {
        own = counts[id.x];
    }
    scratch[lane] = own;
    let total = scan_scratch(lane);
    if id.x < size.x {
        starts[id.x] = scratch[lane] - own;
    }
    if lane == 0u {
        block_sums[block.x] = total;
    }
}

@compute @workgroup_size(256)
fn scan_sums(@builtin(local_invocation_index) lane: u32) {
    let blocks = (size.x + WORKGROUP - 1u) / WORKGROUP;
    let first = lane * SUMS_PER_THREAD;
    var run = 0u;
    for (var k = 0u; k < SUMS_PER_THREAD; k = k + 1u) {
        if first + k < blocks {
            run = run + block_sums[first + k];
        }
    }
    scratch[lane] = run;
    _ = scan_scratch(lane);
    var before = scratch[lane] - run;
    for (var k = 0u; k < SUMS_PER_THREAD; k = k + 1u) {
        if first + k < blocks {
            let own = block_sums[first + k];
            block_sums[first + k] = before;
            before = before + own;
        }
    }
}

@compute @workgroup_size(256)
fn scan_add(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) block: vec3<u32>) {
    if id.x < size.x {
        starts[id.x] = starts[id.x] + block_sums[block.x];
    }
}
