// Splatting on the compute path (`raster=compute`, issue 17): the same kernels as
// splat.wgsl, with the same values per texel (`splat_texel` of photon-hits'
// splat_kernel.wgsl), added by a compute pass into a fixed-point accumulator with
// integer atomics instead of blended by the rasterizer; `resolve` then writes the
// accumulator into the caustic cube map's atlas and zeroes it for the next frame.
//
// Why fixed point, and its range and resolution: caustics-gpu's fixed_point.wgsl
// (`add_fixed`, `take_fixed`), whose 64-bit channels hold W/m² here, and luminance × m
// for alpha.
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

// Words per atlas texel: (low, high) for r, g, b and alpha.
const WORDS: u32 = 8u;

@group(1) @binding(0) var<uniform> cm: CausticMapUniform;
@group(1) @binding(1) var<uniform> su: SplatUniform;
@group(1) @binding(2) var<storage, read> hits: array<PhotonHit>;
@group(1) @binding(3) var<storage, read_write> accum: array<atomic<u32>>;
@group(1) @binding(4) var atlas_out: texture_storage_2d<rgba32float, write>;

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

// One invocation per atlas texel: the accumulated sums into the atlas (every texel
// written, so no clear is needed), and the accumulator zeroed for the next frame.
@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(atlas_out);
    if gid.x >= size.x || gid.y >= size.y {
        return;
    }
    let w = (gid.y * size.x + gid.x) * WORDS;
    let value = vec4<f32>(take_fixed(w), take_fixed(w + 2u), take_fixed(w + 4u), take_fixed(w + 6u));
    textureStore(atlas_out, vec2<i32>(gid.xy), value);
}
