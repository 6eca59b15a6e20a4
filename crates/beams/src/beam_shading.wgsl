// The beam's light seen through one camera pixel (Sect. 5), shared by the hardware
// path (rasterize.wgsl: the hull's fragments) and the compute path
// (rasterize_compute.wgsl: the pixels of the hull's screen rectangle). The camera ray
// through the pixel is intersected with the beam itself (scan plane, Sect. 5.1) for the
// single-scattered radiance along the covered segment (volume caustic, Sect. 5.2), and
// the camera G-buffer position is tested against the beam's cross-section at its height
// for the irradiance on the visible receiver (surface caustic, Sect. 5.3). Outside the
// beam both are zero, so which covering of the hull calls it changes nothing.

// Whether the scene has a medium (u.sigma_t.w): the volume caustic's code exists only
// then (set per pass by lib.rs; no default, so a pass built without it fails).
override BEAM_MEDIUM: bool;

@group(1) @binding(0) var<uniform> u: BeamUniforms;
@group(1) @binding(1) var<storage, read> beams: array<Beam>;

struct BeamOut {
    @location(0) surface: vec4<f32>,
    @location(1) volume: vec4<f32>,
}

fn henyey_greenstein(cos_theta: f32, g: f32) -> f32 {
    let d = 1.0 + g * g - 2.0 * g * cos_theta;
    return (1.0 - g * g) / (4.0 * PI * d * sqrt(d));
}

// vertex_irradiance (generate.wgsl `vertex_irradiance`): the corners' irradiance
// factors are interpolated; set per pass by lib.rs (no default, so a pass built
// without it fails).
override VERTEX_IRRADIANCE: bool;

// Irradiance on the plane parallel to the base at height y, for barycentrics bc:
// Φ(bc) / A(y), with A clamped at A(0)/max_focus (Sect. 5.2; a point sample of a
// focus is singular). With vertex_irradiance each corner's flux is scaled by its
// vertex's irradiance over the beam's own where the light lands (hull[i].w): the
// paper's value where the corners agree with the beam, smooth across beam edges where
// they do not.
fn parallel_irradiance(b: Beam, bc: vec3<f32>, y: f32) -> vec3<f32> {
    let a = vec3<f32>(b.v[0].w, b.v[1].w, b.v[2].w);
    var w = bc;
    if VERTEX_IRRADIANCE {
        w *= vec3<f32>(b.hull[0].w, b.hull[1].w, b.hull[2].w);
    }
    let area = max(abs(area_at(a, y)), a.x / u.max_focus);
    let flux = w.x * b.flux[0].xyz + w.y * b.flux[1].xyz + w.z * b.flux[2].xyz;
    return flux / area;
}

// Beam `b`'s surface and volume radiance at camera pixel `pixel`, whose ray from the eye
// has the unit direction `r`.
fn shade_beam(b: Beam, pixel: vec2<u32>, r: vec3<f32>) -> BeamOut {
    var out: BeamOut;
    out.surface = vec4<f32>(0.0);
    out.volume = vec4<f32>(0.0);
    let n = b.n.xyz;
    let y_max = b.n.w;
    let eye = frame.eye.xyz;
    let g = gbuffer_sample(pixel);
    var t_surface = 3.0e38;
    if g.hit {
        t_surface = distance(g.position, eye);
    }

    // Surface caustic: is the visible point inside the beam?
    if g.hit && materials[g.material].kind == MAT_DIFFUSE {
        let y = dot(g.position - b.v[0].xyz, n);
        if y >= 0.0 && y <= y_max {
            let bc = beam_barycentrics(b, g.position, y);
            let y_end = dot(bc, vec3<f32>(b.d[0].w, b.d[1].w, b.d[2].w));
            if min(bc.x, min(bc.y, bc.z)) >= 0.0 && y <= 1.02 * y_end + 1e-3 {
                let dp = bc.x * b.d[0].xyz + bc.y * b.d[1].xyz + bc.z * b.d[2].xyz;
                let d = normalize(dp);
                let cos_r = -dot(d, g.facing_normal);
                if cos_r > 0.0 {
                    // E on the receiver = (Φ/A) · |d·n_r| / |d·n| (d·n = 1/|dp|).
                    let e = parallel_irradiance(b, bc, y) * cos_r * length(dp);
                    let albedo = materials[g.material].color.xyz;
                    let ext = extinction(y * length(dp) + t_surface);
                    out.surface = vec4<f32>(albedo * INV_PI * e * ext, 0.0);
                }
            }
        }
    }

    // Volume caustic: the camera ray's segment inside the beam (scan plane, Sect. 5.1).
    if BEAM_MEDIUM {
        var np = cross(r, cross(r, n));
        if dot(np, np) < 1e-12 {
            np = cross(r, select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), abs(r.x) > 0.9));
        }
        np = normalize(np);
        let q = cross(np, r);
        var a_edge: array<f32, 3>;
        var c_edge: array<f32, 3>;
        var ok = true;
        // The edges picked by select() rather than b.d[i]: a Beam value indexed by a
        // variable is written into a temporary to be indexed (generate.wgsl `size_px`).
        let v0 = b.v[0].xyz;
        let v1 = b.v[1].xyz;
        let v2 = b.v[2].xyz;
        let d0 = b.d[0].xyz;
        let d1 = b.d[1].xyz;
        let d2 = b.d[2].xyz;
        for (var i = 0u; i < 3u; i++) {
            let di = select(select(d2, d1, i == 1u), d0, i == 0u);
            let vi = select(select(v2, v1, i == 1u), v0, i == 0u);
            let den = dot(di, np);
            if abs(den) < 1e-12 {
                ok = false;
            }
            let s = dot(eye - vi, np) / select(den, 1.0, abs(den) < 1e-12);
            let p = vi + s * di;
            a_edge[i] = dot(p - eye, r);
            c_edge[i] = dot(p - eye, q);
        }
        var t_in = 3.0e38;
        var t_out = -3.0e38;
        var crossings = 0u;
        for (var i = 0u; i < 3u; i++) {
            let j = (i + 1u) % 3u;
            if (c_edge[i] < 0.0) != (c_edge[j] < 0.0) {
                let t = a_edge[i] + (a_edge[j] - a_edge[i]) * c_edge[i] / (c_edge[i] - c_edge[j]);
                t_in = min(t_in, t);
                t_out = max(t_out, t);
                crossings += 1u;
            }
        }
        // Clip to the beam's height range [0, y_max] and to the visible surface.
        let y0 = dot(eye - b.v[0].xyz, n);
        let dy = dot(r, n);
        if abs(dy) > 1e-9 {
            let ta = (0.0 - y0) / dy;
            let tb = (y_max - y0) / dy;
            t_in = max(t_in, min(ta, tb));
            t_out = min(t_out, max(ta, tb));
        } else if y0 < 0.0 || y0 > y_max {
            ok = false;
        }
        t_in = max(t_in, 0.0);
        t_out = min(t_out, t_surface);
        if ok && crossings >= 2u && t_out > t_in {
            let tm = 0.5 * (t_in + t_out);
            let x = eye + tm * r;
            let y = dot(x - b.v[0].xyz, n);
            var bc = max(beam_barycentrics(b, x, y), vec3<f32>(0.0));
            let bc_sum = bc.x + bc.y + bc.z;
            // Near a focus the cross-section degenerates and the barycentrics of a
            // point on the segment can all come out negative: the centroid stands in
            // (a zero bc would make dp zero and normalize(dp) NaN, seen with prism
            // hulls on fog_sphere at 1024x768).
            bc = select(vec3<f32>(1.0 / 3.0), bc / bc_sum, bc_sum > 0.0);
            let dp = bc.x * b.d[0].xyz + bc.y * b.d[1].xyz + bc.z * b.d[2].xyz;
            let d = normalize(dp);
            // Irradiance perpendicular to the rays: (Φ/A) / (d·n) = (Φ/A)·|dp|.
            let e_perp = parallel_irradiance(b, bc, y) * length(dp);
            let phase = henyey_greenstein(dot(d, -r), u.sigma_s_g.w);
            var l = (t_out - t_in) * u.sigma_s_g.xyz * phase * e_perp
                * extinction(y * length(dp) + tm);
            if u.soft_depth > 0.0 {
                // Soft-particle fade (Sect. 5.2) towards the surface behind the segment.
                l *= clamp((t_surface - tm) / u.soft_depth, 0.0, 1.0);
            }
            out.volume = vec4<f32>(l, 0.0);
        }
    }
    return out;
}
