// Splatting (the caustic-mapping baseline the paper compares against, §2 and Fig. 1):
// each valid photon hit is drawn as a fixed kernel of kernel_px × kernel_px texels
// into the face of the caustic cube map its direction from the centre falls in, with
// additive blending. The kernel is a box aligned to the texel grid (so it covers
// exactly kernel_px² texels) and shifted inside the face where it would cross an edge
// (its energy stays whole, slightly displaced). Its value is the hit's flux over the
// receiver area the kernel covers, A = k² · Ω · d² / cos θ, where Ω is the solid angle
// of a texel at the kernel's centre (a face texel at face coordinates (a, b) subtends
// (2/s)² / (1 + a² + b²)^(3/2)), d the hit's distance from the centre and θ the angle
// between the receiver's normal and the direction from the centre: so
// Σ_texels E · (texel area on the receiver) = the hit's flux, energy is conserved.

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

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) value: vec4<f32>,
}

// Quad corners (two triangles) in kernel units.
fn corner(i: u32) -> vec2<f32> {
    switch i {
        case 0u: { return vec2<f32>(0.0, 0.0); }
        case 1u: { return vec2<f32>(1.0, 0.0); }
        case 2u, 4u: { return vec2<f32>(1.0, 1.0); }
        case 3u: { return vec2<f32>(0.0, 0.0); }
        default: { return vec2<f32>(0.0, 1.0); }
    }
}

// The instance index is the cube face being drawn (one instance per face draw).
@vertex
fn vs_splat(@builtin(vertex_index) vi: u32, @builtin(instance_index) face: u32) -> VsOut {
    var o: VsOut;
    o.clip = vec4<f32>(2.0, 2.0, 2.0, 1.0);
    let h = hits[vi / 6u];
    if h.ids.x == NONE {
        return o;
    }
    let l = h.position.xyz - cm.center.xyz;
    let fuv = impostor_face_uv(l);
    if u32(fuv.z) != face {
        return o;
    }
    let s = cm.params.x;
    let k = f32(su.kernel_px);
    let origin = clamp(floor(fuv.xy * s + 0.5 - 0.5 * k), vec2<f32>(0.0), vec2<f32>(s - k));
    let texel = origin + corner(vi % 6u) * k;
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
fn fs_splat(i: VsOut) -> @location(0) vec4<f32> {
    return i.value;
}
