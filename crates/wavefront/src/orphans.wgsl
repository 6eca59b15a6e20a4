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

struct OrphanOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) new_pos: vec3<f32>,
    // W: the vertex's share of the triangle's flux.
    @location(1) flux_w: vec3<f32>,
    @location(2) @interpolate(flat) receiver: u32,
    @location(3) @interpolate(flat) side: f32,
}

// One point per landed corner of a dropped triangle: draw_list's orphan entries are
// 3 × triangle + corner, in that order (the draw starts at the first of them).
@vertex
fn vs_orphan(@builtin(vertex_index) entry: u32) -> OrphanOut {
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
    return o;
}

@fragment
fn fs_orphan(i: OrphanOut) -> @location(0) vec4<f32> {
    count_fragment(i.clip);
    let g = gbuffer_sample(vec2<u32>(i.clip.xy));
    let radiance = point_splat_radiance(g, i.new_pos, i.flux_w, i.receiver, i.side, sp.tolerance);
    if all(radiance == vec3<f32>(0.0)) {
        discard;
    }
    return vec4<f32>(radiance, 1.0);
}
