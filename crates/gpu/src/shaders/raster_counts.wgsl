// 64-bit work counts of the compute-raster paths (pixels covered, pairs shaded), each a
// (low, high) pair of words, summed per workgroup first so that one invocation per
// workgroup touches the global words. The including shader declares
//     var<storage, read_write> raster_counts: array<atomic<u32>, N>;

var<workgroup> group_count: atomic<u32>;

// Adds `n` to the 64-bit count at words `w`, `w + 1`.
fn add_count(w: u32, n: u32) {
    let before = atomicAdd(&raster_counts[w], n);
    if before > 0xffffffffu - n {
        atomicAdd(&raster_counts[w + 1u], 1u);
    }
}

// Starts the workgroup's sum; every invocation calls it first, in uniform control flow.
fn group_count_begin(lane: u32) {
    if lane == 0u {
        atomicStore(&group_count, 0u);
    }
    workgroupBarrier();
}

// Adds the invocation's `n` to the workgroup's sum and, once every invocation has, the
// sum to the 64-bit count at words `w`, `w + 1`; every invocation calls it last, in
// uniform control flow.
fn group_count_end(lane: u32, n: u32, w: u32) {
    atomicAdd(&group_count, n);
    workgroupBarrier();
    if lane == 0u {
        add_count(w, atomicLoad(&group_count));
    }
}
