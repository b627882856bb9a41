// A stable radix sort of (key, value) pairs by key (sim/radix.rs): four bits
// of the key a pass, least significant first. Each pass:
//   radix_count    each workgroup's 256 pairs counted by digit, into
//                  counts[digit * workgroups + workgroup]
//   (scan.wgsl: the counts' exclusive running sum; digit-major, so digit d
//    of workgroup g starts after every smaller digit and after digit d of
//    every earlier workgroup)
//   radix_scatter  each pair to that start plus the pairs of its digit before
//                  it in its workgroup (counted by chunks of 16 lanes, then
//                  inside its own chunk)
// Pairs of equal keys keep their order, and nothing depends on the order in
// which threads ran (there are no atomics): the same pairs sort to the same
// bits every time.

const WORKGROUP: u32 = 256u;
const DIGITS: u32 = 16u;

// x: pairs, y: this pass's shift, z: workgroups.
@group(0) @binding(0) var<uniform> sort: vec4<u32>;
@group(0) @binding(1) var<storage, read_write> pairs_in: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read_write> pairs_out: array<vec2<u32>>;
@group(0) @binding(3) var<storage, read_write> counts: array<u32>;
@group(0) @binding(4) var<storage, read_write> starts: array<u32>;

var<workgroup> digits: array<u32, 256>;
// [chunk * DIGITS + digit]: how many of the chunk's 16 pairs have the digit
// (from `tally`), or, after `running`, how many of the earlier chunks' do.
var<workgroup> chunk_counts: array<u32, 256>;

// Pair i's digit this pass; DIGITS past the last pair.
fn digit_of(i: u32) -> u32 {
    if i >= sort.x {
        return DIGITS;
    }
    return (pairs_in[i].x >> sort.y) & (DIGITS - 1u);
}

// The workgroup's digits, and each chunk of 16 lanes' count of each digit:
// lane `lane` counts digit lane % 16 in chunk lane / 16.
fn tally(lane: u32, group: u32) -> u32 {
    let d = digit_of(group * WORKGROUP + lane);
    digits[lane] = d;
    workgroupBarrier();
    let first = lane / DIGITS * DIGITS;
    var n = 0u;
    for (var t = first; t < first + DIGITS; t = t + 1u) {
        n = n + u32(digits[t] == lane % DIGITS);
    }
    chunk_counts[lane] = n;
    workgroupBarrier();
    return d;
}

@compute @workgroup_size(256)
fn radix_count(@builtin(local_invocation_index) lane: u32, @builtin(workgroup_id) group: vec3<u32>) {
    tally(lane, group.x);
    if lane < DIGITS {
        var n = 0u;
        for (var chunk = 0u; chunk < WORKGROUP / DIGITS; chunk = chunk + 1u) {
            n = n + chunk_counts[chunk * DIGITS + lane];
        }
        counts[lane * sort.z + group.x] = n;
    }
}

@compute @workgroup_size(256)
fn radix_scatter(@builtin(local_invocation_index) lane: u32, @builtin(workgroup_id) group: vec3<u32>) {
    let d = tally(lane, group.x);
    // Each digit's count over the chunks before each chunk.
    if lane < DIGITS {
        var before = 0u;
        for (var chunk = 0u; chunk < WORKGROUP / DIGITS; chunk = chunk + 1u) {
            let n = chunk_counts[chunk * DIGITS + lane];
            chunk_counts[chunk * DIGITS + lane] = before;
            before = before + n;
        }
    }
    workgroupBarrier();
    if d == DIGITS {
        return;
    }
    let first = lane / DIGITS * DIGITS;
    var rank = chunk_counts[first + d];
    for (var t = first; t < lane; t = t + 1u) {
        rank = rank + u32(digits[t] == d);
    }
    pairs_out[starts[d * sort.z + group.x] + rank] = pairs_in[group.x * WORKGROUP + lane];
}
