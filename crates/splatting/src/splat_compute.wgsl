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
// into the accumulator (photon-hits' atlas_accumulator.wgsl, which also holds the
// `resolve` kernel). Kernels are at most 64 × 64 texels, the small-footprint regime
// in which Schütz, Kerbl & Wimmer (2021, "Rendering point clouds with compute shaders
// and vertex order optimization") find direct global atomics fastest for points.

struct SplatUniform {
    // Kernel side in cube-map texels.
    kernel_px: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

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
    let share = h.flux.rgb / (kf * kf);
    let y = u32(origin.y) + row;
    for (var c = 0u; c < k; c++) {
        let x = u32(origin.x) + c;
        // The texel's centre, as the fragment shader sees it.
        let local = vec2<f32>(f32(x), f32(y)) + 0.5;
        let value = splat_texel(face, local, share, h.normal.xyz, length(l), l);
        add_atlas(face, vec2<u32>(x, y), value);
    }
}
