// Beam rasterization on the compute path (`raster=compute`, issue 17): workgroups of a
// beam clip its hull at the camera plane, find the convex polygon it projects to, and
// shade the pixels of the polygon's rectangle that lie inside it with the same
// function as the hardware path's fragments (`shade_beam`, beam_shading.wgsl), adding
// what it gives into a fixed-point accumulator with integer atomics (fixed_point.wgsl),
// which `resolve.wgsl` then writes into the raw surface caustic and the volume target.
//
// Same pixels lit: a pixel gets light from a beam only where its camera ray meets the
// beam (volume) or its G-buffer point lies in it (surface), and the hull (the convex
// hull of the base and top triangles, or the bounding prism, Sect. 4.3) contains the
// beam, so both such pixels are inside the hull's projection, the polygon, each edge
// moved out past every point and by a hundredth of a pixel for rounding. The compute
// path thus shades as many pixels as the rasterizer covers, or a few more, in vain
// (counted, `raster_pairs_*`), none fewer. Same values: each pixel's ray comes from
// its centre (`camera_ray`) where the fragment interpolates the hull point on the same
// ray, so the two differ by f32 rounding and the fixed point's 2^-24.
//
// Beam-binned, not tile-binned: a beam's rectangle is walked by its own workgroups
// (as many as the image needs to keep each invocation under llvmpipe's loop limit, see
// below), 64 pixels at a time, so no binning pass or per-tile list is needed; the cost
// is an edge test for each of the rectangle's pixels outside the polygon and the
// polygon found once per workgroup.

@group(1) @binding(2) var<storage, read> control: array<u32>;
@group(1) @binding(3) var<storage, read_write> accum: array<atomic<u32>>;
// 64-bit counts as (low, high) words: [0, 1] (beam, pixel) pairs shaded (inside the
// polygon), [2, 3] those that added light.
@group(1) @binding(4) var<storage, read_write> raster_counts: array<atomic<u32>, 4>;

// u32 words per pixel of the accumulator: surface r, g, b, then volume r, g, b, each a
// (low, high) pair.
const ACCUM_WORDS: u32 = 12u;

// Pixels' slack at the footprint's edges, beside a relative 1e-6 of the edge's offset:
// the hull's projection rounded in f32 (points clipped near the eye project far out).
const EDGE_SLACK_PX: f32 = 0.01;
// Clip w of the plane the hull is clipped at: in front of every near plane.
const NEAR_W: f32 = 1e-4;

var<workgroup> pairs_shaded: atomic<u32>;
var<workgroup> pairs_lit: atomic<u32>;
// The hull's six points in clip space.
var<workgroup> clip: array<vec4<f32>, 6>;
// The points of the hull's part in front of the eye, projected (pixels): the points in
// front and, for each pair with one point on either side, where their segment crosses
// the plane w = NEAR_W (the clipped hull is the convex hull of these). At most 3 + 9.
var<workgroup> projected: array<vec2<f32>, 12>;
var<workgroup> projected_count: atomic<u32>;
// The projection's edges: edge e keeps the pixel centres p with
// dot(edges[e].xy, p) + edges[e].z >= 0 (unit normal pointing inwards, z loosened by
// EDGE_SLACK_PX). At most one per ordered pair of points; more than the polygon's
// sides only where points coincide or are collinear, redundant then but still
// supporting lines.
var<workgroup> edges: array<vec3<f32>, 132>;
var<workgroup> edge_count: atomic<u32>;
// The rectangle of pixels the footprint can hold, (x0, y0, x1, y1) inclusive.
var<workgroup> rect: vec4<i32>;
@compute @workgroup_size(64)
fn rasterize(
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let beam = wid.y * groups.x + wid.x;
    // Workgroup z of groups.z shades every groups.z-th run of 64 pixels of the beam's
    // rectangle: on lavapipe one workgroup walking a whole 1024x768 rectangle stopped
    // after about 65,535 loop iterations per invocation in all (llvmpipe's loop limit,
    // as the counts fit), silently skipping the rest of its pixels.
    let chunk = wid.z;
    let chunks = groups.z;
    // Uniform across the workgroup (a read-only load at the workgroup's index), so the
    // barriers below are reached by every invocation or by none.
    if beam >= control[C_BEAM_TOTAL] {
        return;
    }
    let b = beams[beam];
    let size = frame.resolution.xy;
    if lane == 0u {
        atomicStore(&pairs_shaded, 0u);
        atomicStore(&pairs_lit, 0u);
        atomicStore(&projected_count, 0u);
        atomicStore(&edge_count, 0u);
    }
    if lane < 6u {
        // Through the buffer: `b` indexed by a variable would be written into a
        // temporary first (generate.wgsl `size_px`).
        clip[lane] = frame.view_proj * vec4<f32>(beams[beam].hull[lane].xyz, 1.0);
    }
    workgroupBarrier();
    // Clipped at the camera plane as the rasterizer clips the hull's triangles (at the
    // near plane; NEAR_W is closer, so this keeps a little more): 36 invocations take
    // a pair (i, j) each, the diagonal ones a point.
    if lane < 36u {
        let i = lane / 6u;
        let j = lane % 6u;
        let ci = clip[i];
        let cj = clip[j];
        var keep = false;
        var c = ci;
        if i == j {
            keep = ci.w >= NEAR_W;
        } else if i < j && (ci.w >= NEAR_W) != (cj.w >= NEAR_W) {
            keep = true;
            c = mix(ci, cj, (ci.w - NEAR_W) / (ci.w - cj.w));
        }
        if keep {
            let ndc = c.xy / max(c.w, NEAR_W);
            projected[atomicAdd(&projected_count, 1u)] =
                vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * size;
        }
    }
    workgroupBarrier();
    // The projection's edges: i → j is one when no point lies to its right (gift
    // wrapping without the sort: a dozen points at most, all ordered pairs at once).
    let n = atomicLoad(&projected_count);
    for (var pair = lane; pair < n * n; pair += 64u) {
        let i = pair / n;
        let j = pair % n;
        let pi = projected[i];
        let d = projected[j] - pi;
        let len = length(d);
        if i != j && len > 1e-6 {
            let normal = vec2<f32>(-d.y, d.x) / len;
            // The farthest point to the line's right (≤ 0 when none is).
            var right = 0.0;
            for (var k = 0u; k < n; k++) {
                right = min(right, dot(normal, projected[k] - pi));
            }
            // An edge where no point is farther right than rounding explains; moved
            // out past every point, so the polygon of kept edges holds them all.
            if right >= -1e-4 * len {
                let offset = -dot(normal, pi);
                let slack = EDGE_SLACK_PX + 1e-6 * abs(offset) - right;
                edges[atomicAdd(&edge_count, 1u)] = vec3<f32>(normal, offset + slack);
            }
        }
    }
    workgroupBarrier();
    // The rectangle of the pixel centres (x + 0.5) the footprint can hold, clamped
    // before the conversion to integers (empty when the hull is behind the eye); found
    // once, read by all as uniform (the batch loop below has barriers).
    if lane == 0u {
        var lo = vec2<f32>(3.0e38);
        var hi = vec2<f32>(-3.0e38);
        for (var k = 0u; k < n; k++) {
            lo = min(lo, projected[k]);
            hi = max(hi, projected[k]);
        }
        let first = clamp(floor(lo - 0.5), vec2<f32>(0.0), size);
        let last = clamp(ceil(hi - 0.5), vec2<f32>(-1.0), size - 1.0);
        rect = vec4<i32>(vec2<i32>(first), vec2<i32>(last));
    }
    let r = workgroupUniformLoad(&rect);
    let width = u32(max(r.z - r.x + 1, 0));
    let inv_width = 1.0 / f32(max(width, 1u));
    let pixels = width * u32(max(r.w - r.y + 1, 0));
    let n_edges = atomicLoad(&edge_count);
    let image_width = u32(size.x);
    var shaded = 0u;
    var lit = 0u;
    // This workgroup's pixels of the rectangle, 64 at a time: tested against the
    // polygon, shaded if inside.
    for (var i = lane + 64u * chunk; i < pixels; i += 64u * chunks) {
        let pixel = vec2<u32>(r.xy) + rect_offset(i, width, inv_width);
        let center = vec2<f32>(pixel) + 0.5;
        var inside = true;
        for (var e = 0u; e < n_edges; e++) {
            let edge = edges[e];
            if dot(edge.xy, center) + edge.z < 0.0 {
                inside = false;
            }
        }
        if !inside {
            continue;
        }
        let o = shade_beam(b, pixel, camera_ray(center));
        shaded += 1u;
        if any(o.surface.xyz > vec3<f32>(0.0)) || any(o.volume.xyz > vec3<f32>(0.0)) {
            lit += 1u;
            let w = (pixel.y * image_width + pixel.x) * ACCUM_WORDS;
            add_fixed(w, o.surface.x);
            add_fixed(w + 2u, o.surface.y);
            add_fixed(w + 4u, o.surface.z);
            add_fixed(w + 6u, o.volume.x);
            add_fixed(w + 8u, o.volume.y);
            add_fixed(w + 10u, o.volume.z);
        }
    }
    atomicAdd(&pairs_shaded, shaded);
    atomicAdd(&pairs_lit, lit);
    workgroupBarrier();
    if lane == 0u {
        add_count(0u, atomicLoad(&pairs_shaded));
        add_count(2u, atomicLoad(&pairs_lit));
    }
}

// The (column, row) of index `i` in a rectangle `width` pixels wide, without an integer
// division (slow where SIMD lanes divide one at a time, as on CPU adapters): the f32
// quotient (exact operands below 2^24) is off by at most one, then corrected.
fn rect_offset(i: u32, width: u32, inv_width: f32) -> vec2<u32> {
    var row = u32(f32(i) * inv_width);
    if row * width > i {
        row -= 1u;
    } else if (row + 1u) * width <= i {
        row += 1u;
    }
    return vec2<u32>(i - row * width, row);
}
