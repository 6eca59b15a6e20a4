// Caustic reconstruction, raster half (§4.2, Fig. 6): every triangle of the photon
// hit image is drawn into each face of the caustic cube map with additive blending.
// The vertex shader places a vertex at its hit (so the triangle is the receiver
// triangle seen from the centre, and perspective-correct interpolation is Gouraud
// shading over the receiver); a discarded triangle is moved outside the clip volume,
// as the paper does with invalid texels. Each fragment adds the interpolated
// irradiance (rgb) and luminance × its distance from the centre (alpha), which the
// camera pass turns back into a flux-weighted mean distance for the distance test.

@group(1) @binding(0) var<uniform> cm: CausticMapUniform;
@group(1) @binding(1) var<uniform> tri: TriUniform;
@group(1) @binding(2) var<storage, read> hits: array<PhotonHit>;
@group(1) @binding(3) var<storage, read> tri_area: array<f32>;
@group(1) @binding(4) var<storage, read> vertex_irradiance: array<vec4<f32>>;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) irradiance: vec3<f32>,
}

// The instance index is the cube face being drawn (one instance per face draw).
@vertex
fn vs_triangle(@builtin(vertex_index) vi: u32, @builtin(instance_index) face: u32) -> VsOut {
    var o: VsOut;
    let t = vi / 3u;
    if tri_area[t] <= 0.0 {
        o.clip = vec4<f32>(2.0, 2.0, 2.0, 1.0);
        return o;
    }
    let v = triangle_vertices(t)[vi % 3u];
    let p = hits[v].position.xyz;
    o.clip = cm.face_view_proj[face] * vec4<f32>(p, 1.0);
    o.world = p;
    o.irradiance = vertex_irradiance[v].rgb;
    return o;
}

@fragment
fn fs_triangle(i: VsOut) -> @location(0) vec4<f32> {
    let e = i.irradiance;
    return vec4<f32>(e, luminance(e) * length(i.world - cm.center.xyz));
}
