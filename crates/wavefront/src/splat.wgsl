// Pass 3 of wavefront: draw the kept triangles at their receiver positions from the
// camera. The irradiance a triangle delivers is its flux density times the ratio of
// its area in the light's parametrization to its area on the receiver (Wallace's
// "old area / new area"), both areas taken from screen-space derivatives of the
// interpolated positions: |∂old/∂x × ∂old/∂y| / |∂new/∂x × ∂new/∂y|. The ratio is
// exact for the affine map over a triangle and needs no geometry shader. Overlapping
// sheets (folds of the wavefront) add up through additive blending.

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) old_pos: vec3<f32>,
    @location(1) new_pos: vec3<f32>,
    @location(2) flux: vec3<f32>,
    @location(3) @interpolate(flat) receiver: u32,
    @location(4) @interpolate(flat) side: f32,
}

// Three vertices per kept triangle, in triangle order (draw_list).
@vertex
fn vs_splat(@builtin(vertex_index) vi: u32) -> VsOut {
    let tri = draw_list[vi / 3u];
    var o: VsOut;
    let v = traced[triangles[3u * tri + vi % 3u]];
    o.clip = frame.view_proj * vec4<f32>(v.new_pos.xyz, 1.0);
    o.old_pos = v.old_pos.xyz;
    o.new_pos = v.new_pos.xyz;
    o.flux = v.flux.xyz;
    o.receiver = v.info.x;
    o.side = v.new_pos.w;
    return o;
}

@fragment
fn fs_splat(i: VsOut) -> @location(0) vec4<f32> {
    count_fragment(i.clip);
    // Derivatives first, in uniform control flow.
    let area_old = length(cross(dpdx(i.old_pos), dpdy(i.old_pos)));
    let area_new = length(cross(dpdx(i.new_pos), dpdy(i.new_pos)));
    let g = gbuffer_sample(vec2<u32>(i.clip.xy));
    if !g.hit || g.object != i.receiver || area_new <= 0.0 {
        discard;
    }
    let to_eye = frame.eye.xyz - g.position;
    if length(g.position - i.new_pos) > sp.tolerance * length(to_eye) {
        discard;
    }
    // The camera must see the side of the receiver the light arrives on.
    let camera_side = select(-1.0, 1.0, dot(to_eye, g.normal) >= 0.0);
    if camera_side != i.side {
        discard;
    }
    let irradiance = i.flux * (area_old / area_new);
    let albedo = materials[g.material].color.xyz;
    return vec4<f32>(albedo * INV_PI * irradiance, 1.0);
}
