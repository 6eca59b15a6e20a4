// With `splat_orphans`: the light of the light-path families a leaf emits no beam for
// (its corners part ways: a silhouette of the generator, a fold, different receivers),
// which the paper loses. Each corner that landed is drawn as a one-pixel point of its
// third of the triangle's flux (write_orphan in generate.wgsl) into the raw surface
// caustic, so the surface filter (Sect. 7) smooths the points with the beams' light.
// Surface caustic only: a dropped beam's in-scattered light in a medium stays lost.

@group(1) @binding(0) var<uniform> u: BeamUniforms;
@group(1) @binding(1) var<storage, read> orphans: array<Orphan>;

// Accept a point within this fraction of the distance to the eye off the pixel's
// tangent plane (wavefront's default tolerance): a corner lands on the receiver
// exactly, so this only absorbs the receiver's curvature within a pixel.
const ORPHAN_TOLERANCE: f32 = 2e-3;

struct OrphanOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) point: vec3<f32>,
    @location(1) flux_w: vec3<f32>,
    @location(2) dir: vec3<f32>,
    @location(3) path_m: f32,
    @location(4) @interpolate(flat) receiver: u32,
}

// One point per (record, corner): vertex_index = 3 × record + corner.
@vertex
fn vs_orphan(@builtin(vertex_index) vi: u32) -> OrphanOut {
    let o = orphans[vi / 3u];
    let i = vi % 3u;
    var out: OrphanOut;
    out.clip = vec4<f32>(2.0, 2.0, 2.0, 1.0);
    if o.receiver[i] == NONE {
        return out;
    }
    out.clip = frame.view_proj * vec4<f32>(o.point[i].xyz, 1.0);
    out.point = o.point[i].xyz;
    out.flux_w = o.flux[i].xyz;
    out.dir = o.dir[i].xyz;
    out.path_m = o.point[i].w;
    out.receiver = o.receiver[i];
    return out;
}

@fragment
fn fs_orphan(in: OrphanOut) -> @location(0) vec4<f32> {
    count_fragment(in.clip);
    let g = gbuffer_sample(vec2<u32>(in.clip.xy));
    // The side of the receiver's stored normal the light arrives on.
    let side = select(1.0, -1.0, dot(in.dir, g.normal) > 0.0);
    let radiance = point_splat_radiance(g, in.point, in.flux_w, in.receiver, side, ORPHAN_TOLERANCE);
    if all(radiance == vec3<f32>(0.0)) {
        discard;
    }
    // Extinction along the rest of the beam's edge and on to the camera.
    let ext = extinction(in.path_m + distance(g.position, frame.eye.xyz));
    return vec4<f32>(radiance * ext, 0.0);
}
