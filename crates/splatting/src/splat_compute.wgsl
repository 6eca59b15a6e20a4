// Splatting on the compute path (`raster=compute`, issue 17): the same kernels as
// splat.wgsl, with the same values per texel (`splat_texel` of photon-hits'
// splat_kernel.wgsl), added by a compute pass into a fixed-point accumulator with
// integer atomics instead of blended by the rasterizer; `resolve` then writes the
// accumulator into the caustic cube map's atlas and zeroes it for the next frame.
//
// Why fixed point: integer addition is associative, so the sum in every texel, and the
// image, are the same on every run whatever order the invocations run in, which float
// atomics or blending do not promise. Each channel is a 64-bit number of 2^-FRAC_BITS
// units kept in two u32 words (low word added first; a wrap of the low word carries one
// into the high word, counted exactly once per contribution), so a texel holds sums up
// to 2^(64 - FRAC_BITS) ≈ 1.1e12 at a resolution of 2^-FRAC_BITS ≈ 6e-8 (W/m², and
// luminance × m for alpha): each contribution is rounded down to that, on top of its
// f32 value.
//
// No tile binning: one invocation per (hit, kernel row) adds its row's texels straight
// into the accumulator. Kernels are at most 64 × 64 texels, the small-footprint regime
// in which Schütz, Kerbl & Wimmer (2021, "Rendering point clouds with compute shaders
// and vertex order optimization") find direct global atomics fastest for points.

struct SplatUniform {
    // Kernel side in cube-map texels.
    kernel_px: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

const FRAC_BITS: f32 = 24.0;
// Words per atlas texel: (low, high) for r, g, b and alpha.
const WORDS: u32 = 8u;

@group(1) @binding(0) var<uniform> cm: CausticMapUniform;
@group(1) @binding(1) var<uniform> su: SplatUniform;
@group(1) @binding(2) var<storage, read> hits: array<PhotonHit>;
@group(1) @binding(3) var<storage, read_write> accum: array<atomic<u32>>;
@group(1) @binding(4) var atlas_out: texture_storage_2d<rgba32float, write>;

// Adds `v` (≥ 0) in fixed point to the 64-bit number at words `w`, `w + 1`.
fn add_fixed(w: u32, v: f32) {
    let q = max(v, 0.0) * exp2(FRAC_BITS);
    let high = min(floor(q * exp2(-32.0)), 4294967295.0);
    let low = u32(min(q - high * 4294967296.0, 4294967295.0));
    if low != 0u {
        let before = atomicAdd(&accum[w], low);
        // The low word wrapped: carry one into the high word.
        if before > 0xffffffffu - low {
            atomicAdd(&accum[w + 1u], 1u);
        }
    }
    if high >= 1.0 {
        atomicAdd(&accum[w + 1u], u32(high));
    }
}

// One invocation per (hit, kernel row): the row's k texels of the hit's kernel on the
// face its direction falls in, as the raster path's quad covers them.
@compute @workgroup_size(64)
fn splat(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = su.kernel_px;
    let index = gid.y * groups.x * 64u + gid.x;
    let hit = index / k;
    let row = index % k;
    if hit >= arrayLength(&hits) {
        return;
    }
    let h = hits[hit];
    if h.ids.x == NONE {
        return;
    }
    let l = h.position.xyz - cm.center.xyz;
    let fuv = impostor_face_uv(l);
    let face = u32(fuv.z);
    let kf = f32(k);
    let origin = splat_origin(fuv.xy, kf);
    let s = u32(cm.params.x);
    let face_origin = vec2<u32>((face % 3u) * s, (face / 3u) * s);
    let atlas_width = 3u * s;
    let share = h.flux.rgb / (kf * kf);
    let y = u32(origin.y) + row;
    for (var c = 0u; c < k; c++) {
        let x = u32(origin.x) + c;
        // The texel's centre, as the fragment shader sees it.
        let local = vec2<f32>(f32(x), f32(y)) + 0.5;
        let value = splat_texel(face, local, share, h.normal.xyz, length(l), l);
        let texel = (face_origin.y + y) * atlas_width + face_origin.x + x;
        let w = texel * WORDS;
        add_fixed(w, value.r);
        add_fixed(w + 2u, value.g);
        add_fixed(w + 4u, value.b);
        add_fixed(w + 6u, value.a);
    }
}

fn fixed_value(w: u32) -> f32 {
    let low = atomicExchange(&accum[w], 0u);
    let high = atomicExchange(&accum[w + 1u], 0u);
    return (f32(high) * 4294967296.0 + f32(low)) * exp2(-FRAC_BITS);
}

// One invocation per atlas texel: the accumulated sums into the atlas (every texel
// written, so no clear is needed), and the accumulator zeroed for the next frame.
@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(atlas_out);
    if gid.x >= size.x || gid.y >= size.y {
        return;
    }
    let w = (gid.y * size.x + gid.x) * WORDS;
    let value = vec4<f32>(fixed_value(w), fixed_value(w + 2u), fixed_value(w + 4u), fixed_value(w + 6u));
    textureStore(atlas_out, vec2<i32>(gid.xy), value);
}
