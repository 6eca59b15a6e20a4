// With `splat_orphans`: the light of the light-path families a leaf emits no beam for
// (its corners part ways: a silhouette of the generator, a fold, different receivers),
// which the paper loses. Each corner that landed is drawn as a one-pixel point of its
// third of the triangle's flux (write_orphan in generate.wgsl) into the raw surface
// caustic, so the surface filter (Sect. 7) smooths the points with the beams' light.
// Surface caustic only: a dropped beam's in-scattered light in a medium stays lost.
// With `orphan_kernel_px` = sigma > 0 each corner is spread over a Gaussian of sigma
// camera pixels instead (frame.wgsl's point kernel: a quad of six vertices over the
// pixels within 2 sigma, normalised over them, so a flat receiver keeps the corner's
// flux exactly): on a bumpy refractor, whose internal reflections tear most leaves,
// lone points are bright dots at every exposure.

// Sigma (camera pixels) of the kernel; 0: one-pixel points (the pass draws points).
override ORPHAN_SIGMA_PX: f32;

@group(1) @binding(0) var<uniform> u: BeamUniforms;
@group(1) @binding(1) var<storage, read> orphans: array<Orphan>;

// Accept a point within this fraction of the distance to the eye off the pixel's
// tangent plane (wavefront's default tolerance): a corner lands on the receiver
// exactly, so this only absorbs the receiver's curvature within a pixel.
const ORPHAN_TOLERANCE: f32 = 2e-3;

struct OrphanOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) point: vec3<f32>,
    // (With a kernel: already divided by the kernel's sum over its square.)
    @location(1) @interpolate(flat) flux_w: vec3<f32>,
    @location(2) @interpolate(flat) dir: vec3<f32>,
    @location(3) @interpolate(flat) path_m: f32,
    @location(4) @interpolate(flat) receiver: u32,
    // With a kernel: where the corner lands, in pixels (framebuffer coordinates).
    @location(5) @interpolate(flat) center_px: vec2<f32>,
}

// One point per (record, corner): vertex_index = 3 × record + corner; with a kernel
// the six vertices of its quad, (3 × record + corner) × 6 + quad corner.
@vertex
fn vs_orphan(@builtin(vertex_index) index: u32) -> OrphanOut {
    let kernel = ORPHAN_SIGMA_PX > 0.0;
    let vi = select(index, index / 6u, kernel);
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
    if kernel {
        let k = point_kernel_vertex(out.clip, ORPHAN_SIGMA_PX, index % 6u);
        out.clip = k.clip;
        out.center_px = k.center_px;
        out.flux_w *= k.flux_scale;
    }
    return out;
}

@fragment
fn fs_orphan(in: OrphanOut) -> @location(0) vec4<f32> {
    count_fragment(in.clip);
    let g = gbuffer_sample(vec2<u32>(in.clip.xy));
    // The side of the receiver's stored normal the light arrives on.
    let side = select(1.0, -1.0, dot(in.dir, g.normal) > 0.0);
    var flux_w = in.flux_w;
    if ORPHAN_SIGMA_PX > 0.0 {
        flux_w *= point_kernel_gaussian(in.clip.xy, in.center_px, ORPHAN_SIGMA_PX);
    }
    let radiance = point_splat_radiance(g, in.point, flux_w, in.receiver, side, ORPHAN_TOLERANCE);
    if all(radiance == vec3<f32>(0.0)) {
        discard;
    }
    // Extinction along the rest of the beam's edge and on to the camera.
    let ext = extinction(in.path_m + distance(g.position, frame.eye.xyz));
    return vec4<f32>(radiance * ext, 0.0);
}
