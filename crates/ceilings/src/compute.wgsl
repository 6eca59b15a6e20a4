// Compute probes: FP32 throughput (independent FMA chains), memory bandwidth (a
// sequential copy and a strided gather), storage-buffer atomics, and an empty kernel
// for the per-pass overhead.

struct ComputeParams {
    // Elements (vec4<f32>) of the bandwidth buffers: a power of two.
    elements: u32,
    // FMA loop trips of the fp32 kernel.
    iterations: u32,
    // Gather stride in elements (odd, so index * stride mod elements is a permutation).
    stride: u32,
    // Counters of the atomics kernel minus one (a power of two minus one).
    counter_mask: u32,
    // To 32 bytes, as the Rust side lays it out.
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
    _pad3: u32,
}

@group(0) @binding(0) var<uniform> params: ComputeParams;
@group(0) @binding(1) var<storage, read> source: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> destination: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> counters: array<atomic<u32>>;

const WORKGROUP: u32 = 256u;
// Atomic adds per invocation of the atomics kernel.
const ATOMICS_PER_INVOCATION: u32 = 8u;

fn invocation(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.x + id.y * groups.x * WORKGROUP;
}

// Four independent vec4 FMA chains: 16 FMAs (32 FLOPs) per loop trip, enough
// independent work to hide the FMA latency on any adapter.
@compute @workgroup_size(256)
fn fp32(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = f32(invocation(id, groups));
    var a = vec4<f32>(i, i + 1.0, i + 2.0, i + 3.0) * 1e-7;
    var b = a + 0.25;
    var c = a + 0.5;
    var d = a + 0.75;
    let m = vec4<f32>(0.999999);
    let k = vec4<f32>(1e-7);
    for (var t = 0u; t < params.iterations; t++) {
        a = fma(a, m, k);
        b = fma(b, m, k);
        c = fma(c, m, k);
        d = fma(d, m, k);
    }
    // Written, so the chains are live (a write under a guard the compiler cannot
    // decide would let it sink the whole loop into the guard); 16 bytes per invocation
    // are nothing against the calibrated loop.
    destination[invocation(id, groups) & (params.elements - 1u)] = a + b + c + d;
}

// Sequential copy: 16 bytes read and 16 written per invocation.
@compute @workgroup_size(256)
fn copy(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation(id, groups);
    if i < params.elements {
        destination[i] = source[i];
    }
}

// Strided gather: neighbouring invocations read elements `stride` apart (528 bytes
// for stride 33), so every read touches its own cache line; the writes stay
// sequential. Bytes counted: the 32 useful bytes per invocation.
@compute @workgroup_size(256)
fn strided(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation(id, groups);
    if i < params.elements {
        destination[i] = source[(i * params.stride) & (params.elements - 1u)];
    }
}

// A 32-bit integer hash (Jarzynski & Olano 2020, PCG) spreads the adds over the
// counters, as photon and fill counters are hit.
fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

@compute @workgroup_size(256)
fn atomics(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation(id, groups);
    for (var k = 0u; k < ATOMICS_PER_INVOCATION; k++) {
        atomicAdd(&counters[pcg(i * ATOMICS_PER_INVOCATION + k) & params.counter_mask], 1u);
    }
}

// Nothing: one workgroup of it per pass measures what a pass costs by itself.
@compute @workgroup_size(1)
fn empty() {
}
