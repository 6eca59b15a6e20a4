// A photon hit drawn as a box kernel into the caustic cube map (shared by splatting's
// splat pass and caustic-triangles' splat of the hits that join no triangle). The
// kernel is a box of `k` × `k` texels aligned to the texel grid of the face the hit's
// direction from the centre falls in, shifted inside the face where it would cross an
// edge (its energy stays whole, slightly displaced). Each texel carries an equal share
// Φ / k² of the hit's flux, spread over that texel's own footprint on the plane tangent
// to the receiver at the hit: E = (Φ / k²) · cos θ / (Ω · t²), where t is the distance
// from the centre along the texel's direction to that plane, θ the angle between the
// receiver's normal and that direction, and Ω the texel's solid angle (a face texel at
// face coordinates (a, b) subtends (2/s)² / (1 + a² + b²)^(3/2)). So Σ_texels E ·
// (texel area on the receiver) = Φ: energy is conserved whatever the kernel. The
// distance stored with the light (alpha = luminance(E) · t) is the plane's in each
// texel, not the hit's: on a receiver seen obliquely from the centre the hit's own
// distance would fail the camera pass's distance test a few texels away and drop the
// kernel's outer texels (ring: 16% of the caustic at the default 16-texel kernel). A
// texel whose direction misses the plane in front of the centre (past its horizon, or
// more than twice or less than half the hit's distance) takes the hit's own distance
// and angle (energy is then kept only approximately). Needs `cm: CausticMapUniform`
// bound by the including pass.

struct SplatOut {
    @builtin(position) clip: vec4<f32>,
    // rgb: the hit's flux share per texel, Φ / k² (W); a: the kernel's face.
    @location(0) @interpolate(flat) flux_face: vec4<f32>,
    // xyz: the receiver's unit normal at the hit; w: the hit's distance from the centre.
    @location(1) @interpolate(flat) normal_distance: vec4<f32>,
    // The hit's position relative to the centre (m).
    @location(2) @interpolate(flat) offset: vec3<f32>,
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
// The top-left texel (face texels) of the k × k kernel of a hit at `fuv.xy` (face uv).
fn splat_origin(fuv: vec2<f32>, k: f32) -> vec2<f32> {
    let s = cm.params.x;
    return clamp(floor(fuv * s + 0.5 - 0.5 * k), vec2<f32>(0.0), vec2<f32>(s - k));
}

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
    let origin = splat_origin(fuv.xy, k);
    let texel = origin + splat_corner(corner) * k;
    o.flux_face = vec4<f32>(h.flux.rgb / (k * k), f32(face));
    o.normal_distance = vec4<f32>(h.normal.xyz, length(l));
    o.offset = l;
    o.clip = vec4<f32>(texel.x / s * 2.0 - 1.0, 1.0 - texel.y / s * 2.0, 0.5, 1.0);
    return o;
}

// The direction from the centre through face coordinates `ab` (in [-1, 1], the
// inverse of `impostor_face_uv`) of cube face `face`.
fn splat_face_direction(face: u32, ab: vec2<f32>) -> vec3<f32> {
    switch face {
        case 0u: { return vec3<f32>(1.0, -ab.y, -ab.x); }
        case 1u: { return vec3<f32>(-1.0, -ab.y, ab.x); }
        case 2u: { return vec3<f32>(ab.x, 1.0, ab.y); }
        case 3u: { return vec3<f32>(ab.x, -1.0, -ab.y); }
        case 4u: { return vec3<f32>(ab.x, -ab.y, 1.0); }
        default: { return vec3<f32>(-ab.x, -ab.y, -1.0); }
    }
}

// What one kernel texel receives: irradiance (rgb, W/m²) and luminance × distance
// (alpha) of `flux_share` (W, Φ / k²) at the texel whose centre is `local` (texels from
// the face's top-left corner) on `face`, for a hit with receiver normal `n` at `offset`
// from the centre (distance `d_hit`). Shared by the raster splat (`fs_splat`) and the
// compute splat (splatting's splat_compute.wgsl), so both paths add the same values.
fn splat_texel(face: u32, local: vec2<f32>, flux_share: vec3<f32>, n: vec3<f32>, d_hit: f32, offset: vec3<f32>) -> vec4<f32> {
    let s = cm.params.x;
    let ab = local / s * 2.0 - 1.0;
    let ab2 = dot(ab, ab);
    let omega = (4.0 / (s * s)) / pow(1.0 + ab2, 1.5);
    let dir = splat_face_direction(face, ab) * inverseSqrt(1.0 + ab2);
    let n_dot_dir = dot(n, dir);
    var t = d_hit;
    var cos_theta = abs(dot(n, offset / d_hit));
    if abs(n_dot_dir) > 1e-4 {
        let on_plane = dot(n, offset) / n_dot_dir;
        if on_plane >= 0.5 * d_hit && on_plane <= 2.0 * d_hit {
            t = on_plane;
            cos_theta = abs(n_dot_dir);
        }
    }
    // Clamped so a texel seen edge-on from the centre stays finite.
    let e = flux_share * max(cos_theta, 0.01) / (omega * t * t);
    return vec4<f32>(e, luminance(e) * t);
}

@fragment
fn fs_splat(i: SplatOut) -> @location(0) vec4<f32> {
    let s = cm.params.x;
    let face = u32(i.flux_face.a + 0.5);
    // The fragment's texel centre in face coordinates (the face's viewport sits at
    // column face % 3, row face / 3 of the atlas).
    let local = i.clip.xy - vec2<f32>(f32(face % 3u), f32(face / 3u)) * s;
    return splat_texel(face, local, i.flux_face.rgb, i.normal_distance.xyz, i.normal_distance.w, i.offset);
}
