// Caustic reconstruction on the compute path (`raster=compute`, issue 17): the caustic
// triangles of §4.2 added into the cube map's fixed-point accumulator (photon-hits'
// atlas_accumulator.wgsl) by compute kernels instead of drawn with additive blending,
// so the map is the same on every run and no raster unit is needed.
//
// Same texels, same values as triangles.wgsl: a triangle covers the texels of a face
// whose centres its projection from the centre contains, with the rasterizer's
// perspective-correct barycentrics there (caustics-gpu's triangle_raster.wgsl: edge
// functions of the projected vertices, homogeneous ones for a triangle with a vertex
// behind the centre, ties on a shared edge to one of its two triangles).
//
// Small triangles, large footprints: `rasterize` gives each triangle one invocation,
// which walks its bounding rectangle on each face it reaches, up to `small_texels`
// texels (the `raster_small_footprint` parameter); a larger rectangle is listed
// (`large`) and walked by all 64 invocations of a workgroup of `rasterize_large`, so a
// triangle near the centre or across a face does not hold one invocation for a whole
// face (llvmpipe also stops an invocation after 65,535 loop iterations in all). Where
// the list is full the invocation walks the footprint itself.

@group(1) @binding(0) var<uniform> cm: CausticMapUniform;
@group(1) @binding(1) var<uniform> tri: TriUniform;
@group(1) @binding(2) var<storage, read> hits: array<PhotonHit>;
@group(1) @binding(3) var<storage, read> tri_area: array<f32>;
@group(1) @binding(4) var<storage, read> vertex_irradiance: array<vec4<f32>>;
@group(1) @binding(5) var<storage, read_write> accum: array<atomic<u32>>;
@group(1) @binding(6) var atlas_out: texture_storage_2d<rgba32float, write>;
// (triangle, face) of the footprints larger than `small_texels`.
@group(1) @binding(7) var<storage, read_write> large: array<vec2<u32>>;
// RASTER_LARGE: footprints listed in `large` (also past its end); RASTER_WALKED_BY_LANE:
// of those, the ones the list had no room for; RASTER_TEXELS (low, high): (triangle,
// texel) pairs whose centre a triangle covers, each adding its light.
@group(1) @binding(8) var<storage, read_write> raster_counts: array<atomic<u32>, 4>;

const RASTER_LARGE: u32 = 0u;
const RASTER_WALKED_BY_LANE: u32 = 1u;
const RASTER_TEXELS: u32 = 2u;

// Bounding rectangles of at most this many texels are walked by the triangle's own
// invocation (caustic triangles cover a few texels each, the focus less than one).
override small_texels: u32 = 256u;

// Triangle `t`'s footprint on face `face` (an empty rectangle where it misses it).
fn footprint(t: u32, face: u32) -> TriangleFootprint {
    let v = triangle_vertices(t);
    let m = cm.face_view_proj[face];
    return triangle_footprint(
        m * vec4<f32>(hits[v.x].position.xyz, 1.0),
        m * vec4<f32>(hits[v.y].position.xyz, 1.0),
        m * vec4<f32>(hits[v.z].position.xyz, 1.0),
        vec2<f32>(cm.params.x),
    );
}

// Adds triangle `t`'s light at texel `texel` of `face` where the footprint covers its
// centre; true then. The value is fs_triangle's: the interpolated irradiance, and its
// luminance × the interpolated point's distance from the centre.
fn shade_texel(t: u32, face: u32, f: TriangleFootprint, texel: vec2<u32>) -> bool {
    let covered = footprint_barycentrics(f, texel, vec2<f32>(cm.params.x));
    if covered.w == 0.0 {
        return false;
    }
    let bary = covered.xyz;
    let v = triangle_vertices(t);
    let e = bary.x * vertex_irradiance[v.x].rgb + bary.y * vertex_irradiance[v.y].rgb
        + bary.z * vertex_irradiance[v.z].rgb;
    let p = bary.x * hits[v.x].position.xyz + bary.y * hits[v.y].position.xyz
        + bary.z * hits[v.z].position.xyz;
    add_atlas(face, texel, vec4<f32>(e, luminance(e) * length(p - cm.center.xyz)));
    return true;
}

// Every texel of the footprint's rectangle, by one invocation; how many it covered.
fn walk(t: u32, face: u32, f: TriangleFootprint) -> u32 {
    var covered = 0u;
    for (var y = f.rect.y; y <= f.rect.w; y++) {
        for (var x = f.rect.x; x <= f.rect.z; x++) {
            if shade_texel(t, face, f, vec2<u32>(u32(x), u32(y))) {
                covered += 1u;
            }
        }
    }
    return covered;
}

// One invocation per triangle: its small footprints walked, its large ones listed.
@compute @workgroup_size(64)
fn rasterize(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    group_count_begin(lane);
    let t = gid.y * groups.x * 64u + gid.x;
    var covered = 0u;
    // A discarded triangle (area 0) is drawn nowhere, as the vertex shader moves it out.
    if t < triangle_count() && tri_area[t] > 0.0 {
        for (var face = 0u; face < 6u; face++) {
            let f = footprint(t, face);
            let texels = footprint_pixels(f);
            if texels == 0u {
                continue;
            }
            if texels > small_texels {
                let slot = atomicAdd(&raster_counts[RASTER_LARGE], 1u);
                if slot < arrayLength(&large) {
                    large[slot] = vec2<u32>(t, face);
                    continue;
                }
                atomicAdd(&raster_counts[RASTER_WALKED_BY_LANE], 1u);
            }
            covered += walk(t, face, f);
        }
    }
    group_count_end(lane, covered, RASTER_TEXELS);
}

// The listed footprints, each walked by a whole workgroup (64 texels at a time); the
// workgroups take every num_workgroups-th entry.
@compute @workgroup_size(64)
fn rasterize_large(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    group_count_begin(lane);
    let listed = min(atomicLoad(&raster_counts[RASTER_LARGE]), arrayLength(&large));
    var covered = 0u;
    for (var entry = wid.x; entry < listed; entry += groups.x) {
        let t = large[entry].x;
        let face = large[entry].y;
        let f = footprint(t, face);
        let width = u32(f.rect.z - f.rect.x + 1);
        let texels = footprint_pixels(f);
        for (var i = lane; i < texels; i += 64u) {
            let texel = vec2<u32>(u32(f.rect.x) + i % width, u32(f.rect.y) + i / width);
            if shade_texel(t, face, f, texel) {
                covered += 1u;
            }
        }
    }
    group_count_end(lane, covered, RASTER_TEXELS);
}

// Side of an orphan's kernel (cube-map texels, `orphan_kernel_px`).
override ORPHAN_KERNEL_PX: f32;

// With `splat_orphans`: one invocation per photon-image texel; an orphan hit (marked
// by vertex_irradiance_pass with w = 1) adds its kernel's texels, the raster path's
// orphans.wgsl values (`splat_texel` with the hit's flux over the kernel's texels).
@compute @workgroup_size(64)
fn orphan_splats(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let v = gid.y * groups.x * 64u + gid.x;
    if v >= tri.layers * tri.resolution * tri.resolution || vertex_irradiance[v].w == 0.0 {
        return;
    }
    let h = hits[v];
    if h.ids.x == NONE {
        return;
    }
    let l = h.position.xyz - cm.center.xyz;
    let fuv = impostor_face_uv(l);
    let face = u32(fuv.z);
    let k = u32(ORPHAN_KERNEL_PX);
    let origin = splat_origin(fuv.xy, ORPHAN_KERNEL_PX);
    let share = h.flux.rgb / (ORPHAN_KERNEL_PX * ORPHAN_KERNEL_PX);
    for (var r = 0u; r < k; r++) {
        for (var c = 0u; c < k; c++) {
            let texel = vec2<u32>(origin) + vec2<u32>(c, r);
            let value = splat_texel(face, vec2<f32>(texel) + 0.5, share, h.normal.xyz, length(l), l);
            add_atlas(face, texel, value);
        }
    }
}
