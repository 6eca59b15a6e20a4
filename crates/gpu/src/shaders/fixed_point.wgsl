// Fixed-point accumulation with integer atomics, shared by the compute-raster paths
// (`raster=compute`, issue 17). The including shader declares
//     var<storage, read_write> accum: array<atomic<u32>>;
// Each channel is a 64-bit number of 2^-FIXED_FRAC_BITS units in two u32 words (low,
// high). Integer addition is associative, so a channel's sum, and the image, are the
// same on every run whatever order the invocations run in, which float atomics or
// blending do not promise. A channel holds sums up to 2^(64 - FIXED_FRAC_BITS)
// ≈ 1.1e12 at a resolution of 2^-FIXED_FRAC_BITS ≈ 6e-8; each contribution is rounded
// to the nearest unit (so the rounding errors of many contributions cancel on average
// instead of adding up as a bias), on top of its own f32 rounding.

const FIXED_FRAC_BITS: f32 = 24.0;

// Adds `v` (negative values count as 0) to the 64-bit number at words `w`, `w + 1`.
fn add_fixed(w: u32, v: f32) {
    let q = floor(max(v, 0.0) * exp2(FIXED_FRAC_BITS) + 0.5);
    let high = min(floor(q * exp2(-32.0)), 4294967295.0);
    // Exact: below 2^32, q is its own low part; above, q's last bit is worth ≥ 2^9, so
    // q − high·2^32 is a multiple of it below 2^32.
    let low = u32(min(q - high * 4294967296.0, 4294967295.0));
    if low != 0u {
        let before = atomicAdd(&accum[w], low);
        // The low word wrapped: carry one into the high word, once per contribution.
        if before > 0xffffffffu - low {
            atomicAdd(&accum[w + 1u], 1u);
        }
    }
    if high >= 1.0 {
        atomicAdd(&accum[w + 1u], u32(high));
    }
}

// The number at words `w`, `w + 1` as f32, leaving zero behind for the next frame.
// Called by a resolve dispatched after every addition (no invocation adds meanwhile),
// so loads and stores suffice, and an untouched channel (most of a sparse caustic's) is
// only read.
fn take_fixed(w: u32) -> f32 {
    let low = atomicLoad(&accum[w]);
    let high = atomicLoad(&accum[w + 1u]);
    if low == 0u && high == 0u {
        return 0.0;
    }
    atomicStore(&accum[w], 0u);
    atomicStore(&accum[w + 1u], 0u);
    return (f32(high) * 4294967296.0 + f32(low)) * exp2(-FIXED_FRAC_BITS);
}
