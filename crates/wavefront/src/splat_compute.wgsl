// Pass 3 of wavefront on the compute path (`raster=compute`, issue 17): the kept
// triangles' light added into a camera-sized fixed-point accumulator (caustics-gpu's
// fixed_point.wgsl) by compute kernels instead of drawn with additive blending, so the
// image is the same on every run and no raster unit is needed; `resolve.wgsl` then adds
// it into the surface caustic.
//
// Same pixels, same values as splat.wgsl: a triangle covers the pixels whose centres
// its projection contains, with the rasterizer's perspective-correct barycentrics
// there (caustics-gpu's triangle_raster.wgsl), and each covered pixel passes the
// fragment shader's receiver, tolerance and side tests. The area ratio is the
// triangle's: splat.wgsl takes it from screen-space derivatives of the old and new
// positions, which are affine in the same barycentrics over a triangle, so the ratio
// of their derivatives' cross products is the ratio of the two triangles' areas.
//
// Small triangles, large footprints: `splat` gives each kept triangle one invocation,
// which walks its bounding rectangle of pixels up to `small_pixels`; a larger one is
// listed (`large`) and walked by the 64 invocations of a workgroup of `splat_large`;
// `next_sheet` empties the list before the next sheet's triangles. Where the list is
// full the invocation walks the footprint itself.

@group(2) @binding(0) var<storage, read_write> accum: array<atomic<u32>>;
// Kept triangles of the current sheet whose footprint exceeds `small_pixels`.
@group(2) @binding(1) var<storage, read_write> large: array<u32>;
// RASTER_LISTED: entries of `large` for the current sheet (also past its end);
// RASTER_LARGE: large footprints in all; RASTER_WALKED_BY_LANE: of those, the ones the
// list had no room for; RASTER_PIXELS (low, high): (triangle, pixel) pairs whose centre
// a kept triangle covers (the hardware path's fragments).
@group(2) @binding(2) var<storage, read_write> raster_counts: array<atomic<u32>, 6>;

const RASTER_LISTED: u32 = 0u;
const RASTER_LARGE: u32 = 1u;
const RASTER_WALKED_BY_LANE: u32 = 2u;
const RASTER_PIXELS: u32 = 4u;

// u32 words per pixel of the accumulator: r, g, b, each a (low, high) pair.
const ACCUM_WORDS: u32 = 6u;

// Bounding rectangles of at most this many pixels are walked by the triangle's own
// invocation (a default wavefront triangle covers a pixel or less).
override small_pixels: u32 = 256u;

fn triangle_count() -> u32 {
    return arrayLength(&triangles) / 3u;
}

fn footprint(tri: u32) -> TriangleFootprint {
    let a = traced[triangles[3u * tri]].new_pos.xyz;
    let b = traced[triangles[3u * tri + 1u]].new_pos.xyz;
    let c = traced[triangles[3u * tri + 2u]].new_pos.xyz;
    return triangle_footprint(
        frame.view_proj * vec4<f32>(a, 1.0),
        frame.view_proj * vec4<f32>(b, 1.0),
        frame.view_proj * vec4<f32>(c, 1.0),
        frame.resolution.xy,
    );
}

// Wallace's old area / new area of triangle `tri` (0 where the new area is 0, which
// the fragment shader discards).
fn area_ratio(tri: u32) -> f32 {
    let v0 = traced[triangles[3u * tri]];
    let v1 = traced[triangles[3u * tri + 1u]];
    let v2 = traced[triangles[3u * tri + 2u]];
    let area_old = length(cross(v1.old_pos.xyz - v0.old_pos.xyz, v2.old_pos.xyz - v0.old_pos.xyz));
    let area_new = length(cross(v1.new_pos.xyz - v0.new_pos.xyz, v2.new_pos.xyz - v0.new_pos.xyz));
    return select(0.0, area_old / area_new, area_new > 0.0);
}

// Adds triangle `tri`'s light at `pixel` where its footprint covers the pixel's centre
// and the fragment shader's tests pass there; whether the centre was covered.
fn shade_pixel(tri: u32, f: TriangleFootprint, ratio: f32, pixel: vec2<u32>) -> bool {
    let covered = footprint_barycentrics(f, pixel, frame.resolution.xy);
    if covered.w == 0.0 {
        return false;
    }
    let b = covered.xyz;
    let v0 = traced[triangles[3u * tri]];
    let v1 = traced[triangles[3u * tri + 1u]];
    let v2 = traced[triangles[3u * tri + 2u]];
    let g = gbuffer_sample(pixel);
    // The receiver and side are the first vertex's (flat, as the raster path's); a
    // kept triangle's three agree.
    if !g.hit || g.object != v0.info.x || ratio <= 0.0 {
        return true;
    }
    let new_pos = b.x * v0.new_pos.xyz + b.y * v1.new_pos.xyz + b.z * v2.new_pos.xyz;
    let to_eye = frame.eye.xyz - g.position;
    if length(g.position - new_pos) > sp.tolerance * length(to_eye) {
        return true;
    }
    let camera_side = select(-1.0, 1.0, dot(to_eye, g.normal) >= 0.0);
    if camera_side != v0.new_pos.w {
        return true;
    }
    let flux = b.x * v0.flux.xyz + b.y * v1.flux.xyz + b.z * v2.flux.xyz;
    let albedo = materials[g.material].color.xyz;
    let radiance = albedo * INV_PI * flux * ratio;
    let w = (pixel.y * u32(frame.resolution.x) + pixel.x) * ACCUM_WORDS;
    add_fixed(w, radiance.r);
    add_fixed(w + 2u, radiance.g);
    add_fixed(w + 4u, radiance.b);
    return true;
}

// Every pixel of the footprint's rectangle, by one invocation; how many it covered.
fn walk(tri: u32, f: TriangleFootprint) -> u32 {
    let ratio = area_ratio(tri);
    var covered = 0u;
    for (var y = f.rect.y; y <= f.rect.w; y++) {
        for (var x = f.rect.x; x <= f.rect.z; x++) {
            if shade_pixel(tri, f, ratio, vec2<u32>(u32(x), u32(y))) {
                covered += 1u;
            }
        }
    }
    return covered;
}

// One invocation per triangle of the sheet: a kept one's small footprint walked, its
// large one listed.
@compute @workgroup_size(64)
fn splat(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    group_count_begin(lane);
    let tri = gid.y * groups.x * 64u + gid.x;
    var covered = 0u;
    if tri < triangle_count() && keep[tri] == KEEP_TRIANGLE {
        let f = footprint(tri);
        let pixels = footprint_pixels(f);
        var here = pixels > 0u;
        if pixels > small_pixels {
            atomicAdd(&raster_counts[RASTER_LARGE], 1u);
            let slot = atomicAdd(&raster_counts[RASTER_LISTED], 1u);
            if slot < arrayLength(&large) {
                large[slot] = tri;
                here = false;
            } else {
                atomicAdd(&raster_counts[RASTER_WALKED_BY_LANE], 1u);
            }
        }
        if here {
            covered = walk(tri, f);
        }
    }
    group_count_end(lane, covered, RASTER_PIXELS);
}

// The listed footprints, each walked by a whole workgroup (64 pixels at a time); the
// workgroups take every num_workgroups-th entry.
@compute @workgroup_size(64)
fn splat_large(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    group_count_begin(lane);
    let listed = min(atomicLoad(&raster_counts[RASTER_LISTED]), arrayLength(&large));
    var covered = 0u;
    for (var entry = wid.x; entry < listed; entry += groups.x) {
        let tri = large[entry];
        let f = footprint(tri);
        let ratio = area_ratio(tri);
        let width = u32(f.rect.z - f.rect.x + 1);
        let pixels = footprint_pixels(f);
        for (var i = lane; i < pixels; i += 64u) {
            let pixel = vec2<u32>(u32(f.rect.x) + i % width, u32(f.rect.y) + i / width);
            if shade_pixel(tri, f, ratio, pixel) {
                covered += 1u;
            }
        }
    }
    group_count_end(lane, covered, RASTER_PIXELS);
}

// After a sheet's `splat_large`: its list emptied for the next sheet.
@compute @workgroup_size(1)
fn next_sheet() {
    atomicStore(&raster_counts[RASTER_LISTED], 0u);
}
