// The light of orphan hits (valid hits none of whose triangles was kept, marked by
// the vertex_irradiance pass with w = 1), which the paper loses: with `splat_orphans`
// each is drawn as a splat of `orphan_kernel_px` cube-map texels a side (photon-hits'
// splat_kernel.wgsl, the energy-conserving box kernel of splatting; 1 by default), so
// every photon's flux reaches the map.
// Where the hit image resolves the caustic few hits are orphans; where it does not
// (a bumpy refractor's total internal reflection speckle) they are its dots.

@group(1) @binding(0) var<uniform> cm: CausticMapUniform;
@group(1) @binding(1) var<storage, read> hits: array<PhotonHit>;
@group(1) @binding(2) var<storage, read> vertex_irradiance: array<vec4<f32>>;

// Side of an orphan's kernel (cube-map texels).
override ORPHAN_KERNEL_PX: f32;

// The instance index is the cube face being drawn (one instance per face draw).
@vertex
fn vs_orphan(@builtin(vertex_index) vi: u32, @builtin(instance_index) face: u32) -> SplatOut {
    let v = vi / 6u;
    if vertex_irradiance[v].w == 0.0 {
        var o: SplatOut;
        o.clip = vec4<f32>(2.0, 2.0, 2.0, 1.0);
        return o;
    }
    return splat_vertex(hits[v], vi % 6u, face, ORPHAN_KERNEL_PX);
}
