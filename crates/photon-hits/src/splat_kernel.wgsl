// A photon hit drawn as a box kernel into the caustic cube map (shared by splatting's
// splat pass and caustic-triangles' splat of the hits that join no triangle). The
// kernel is a box of `k` × `k` texels aligned to the texel grid of the face the hit's
// direction from the centre falls in, shifted inside the face where it would cross an
// edge (its energy stays whole, slightly displaced). Its value is the hit's flux over
// the receiver area the kernel covers, A = k² · Ω · d² / cos θ, where Ω is the solid
// angle of a texel at the kernel's centre (a face texel at face coordinates (a, b)
// subtends (2/s)² / (1 + a² + b²)^(3/2)), d the hit's distance from the centre and θ
// the angle between the receiver's normal and the direction from the centre: so
// Σ_texels E · (texel area on the receiver) = the hit's flux, energy is conserved.
// Needs `cm: CausticMapUniform` bound by the including pass.

struct SplatOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) value: vec4<f32>,
}

// Quad corners (two triangles) in kernel units.
fn splat_corner(i: u32) -> vec2<f32> {
    switch i {
        case 0u: { return vec2<f32>(0.0, 0.0); }
        case 1u: { return vec2<f32>(1.0, 0.0); }
        case 2u, 4u: { return vec2<f32>(1.0, 1.0); }
        case 3u: { return vec2<f32>(0.0, 0.0); }
        default: { return vec2<f32>(0.0, 1.0); }
    }
}

// Corner `corner` (0..6) of hit `h`'s kernel of side `k` texels on cube face `face`;
// outside the clip volume where the hit is invalid or lies on another face.
fn splat_vertex(h: PhotonHit, corner: u32, face: u32, k: f32) -> SplatOut {
    var o: SplatOut;
    o.clip = vec4<f32>(2.0, 2.0, 2.0, 1.0);
    if h.ids.x == NONE {
        return o;
    }
    let l = h.position.xyz - cm.center.xyz;
    let fuv = impostor_face_uv(l);
    if u32(fuv.z) != face {
        return o;
    }
    let s = cm.params.x;
    let origin = clamp(floor(fuv.xy * s + 0.5 - 0.5 * k), vec2<f32>(0.0), vec2<f32>(s - k));
    let texel = origin + splat_corner(corner) * k;
    let ab = (origin + 0.5 * k) / s * 2.0 - 1.0;
    let omega = (4.0 / (s * s)) / pow(1.0 + dot(ab, ab), 1.5);
    let d = length(l);
    // Clamped so a hit seen edge-on from the centre stays finite.
    let cos_theta = max(abs(dot(h.normal.xyz, l / d)), 0.01);
    let e = h.flux.rgb * cos_theta / (k * k * omega * d * d);
    o.value = vec4<f32>(e, luminance(e) * d);
    o.clip = vec4<f32>(texel.x / s * 2.0 - 1.0, 1.0 - texel.y / s * 2.0, 0.5, 1.0);
    return o;
}

@fragment
fn fs_splat(i: SplatOut) -> @location(0) vec4<f32> {
    return i.value;
}
