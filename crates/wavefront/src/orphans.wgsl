// Pass 4 of wavefront, only with `splat_orphans`: the light of the triangles classify
// drops, which Wallace loses. A dropped triangle whose vertices did not all take one
// path to one receiver has no area ratio, but each vertex that landed still carries a
// third of the triangle's flux (its flux density × the triangle's area in the light's
// parametrization / 3: the vertex rule of quadrature over the triangle). Each such
// share is drawn as a one-pixel point at the vertex's landing point, an irradiance of
// share / (the pixel's footprint on the receiver). A vertex that left the sheet (total
// internal reflection where the sheet transmits) is drawn by the sheet it belongs to, so
// with `bounces` and `reflections` the sheets still partition the light. On a smooth
// refractor few triangles are dropped; on a bumpy one, whose total internal
// reflections speckle the wavefront, these points are a third of the caustic.
// With `orphan_kernel_px` = sigma > 0 each share is spread instead over a Gaussian of
// sigma camera pixels (frame.wgsl's point kernel: normalised over the pixels it covers,
// so a flat receiver keeps the share's flux exactly).

// Sigma (camera pixels) of the kernel; 0: one-pixel points (the pass draws points).
override ORPHAN_SIGMA_PX: f32;

struct OrphanOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) new_pos: vec3<f32>,
    // W: the vertex's share of the triangle's flux.
    // (With a kernel: already divided by the kernel's sum over its square.)
    @location(1) @interpolate(flat) flux_w: vec3<f32>,
    @location(2) @interpolate(flat) receiver: u32,
    @location(3) @interpolate(flat) side: f32,
    // With a kernel: where the vertex lands, in pixels (framebuffer coordinates).
    @location(4) @interpolate(flat) center_px: vec2<f32>,
}

// One point per landed corner of a dropped triangle, or with a kernel the six vertices
// of its quad: draw_list's orphan entries are 3 × triangle + corner, in that order (the
// draw starts at the first of them, classify.wgsl's ORPHAN_VERTICES per entry).
@vertex
fn vs_orphan(@builtin(vertex_index) index: u32) -> OrphanOut {
    let kernel = ORPHAN_SIGMA_PX > 0.0;
    let entry = select(index, index / 6u, kernel);
    let vi = draw_list[entry];
    let tri = vi / 3u;
    var o: OrphanOut;
    let v = traced[triangles[vi]];
    let a = traced[triangles[3u * tri]].old_pos.xyz;
    let b = traced[triangles[3u * tri + 1u]].old_pos.xyz;
    let c = traced[triangles[3u * tri + 2u]].old_pos.xyz;
    let area_old = 0.5 * length(cross(b - a, c - a));
    o.clip = frame.view_proj * vec4<f32>(v.new_pos.xyz, 1.0);
    o.new_pos = v.new_pos.xyz;
    o.flux_w = v.flux.xyz * (area_old / 3.0);
    o.receiver = v.info.x;
    o.side = v.new_pos.w;
    if kernel {
        let k = point_kernel_vertex(o.clip, ORPHAN_SIGMA_PX, index % 6u);
        o.clip = k.clip;
        o.center_px = k.center_px;
        o.flux_w *= k.flux_scale;
    }
    return o;
}

@fragment
fn fs_orphan(i: OrphanOut) -> @location(0) vec4<f32> {
    count_fragment(i.clip);
    let g = gbuffer_sample(vec2<u32>(i.clip.xy));
    var flux_w = i.flux_w;
    if ORPHAN_SIGMA_PX > 0.0 {
        flux_w *= point_kernel_gaussian(i.clip.xy, i.center_px, ORPHAN_SIGMA_PX);
    }
    let radiance = point_splat_radiance(g, i.new_pos, flux_w, i.receiver, i.side, sp.tolerance);
    if all(radiance == vec3<f32>(0.0)) {
        discard;
    }
    return vec4<f32>(radiance, 1.0);
}
