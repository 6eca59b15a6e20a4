// Group 0 of every method pass: the frame's camera, the camera G-buffer, the scene
// tables and the fill-rate counter (crates/gpu/src/frame.rs builds the layout).

struct FrameUniforms {
    view_proj: mat4x4<f32>,
    // xyz: camera position (m); w: vertical field of view (rad).
    eye: vec4<f32>,
    // xyz: unit forward axis of the camera.
    forward: vec4<f32>,
    // width, height, 1/width, 1/height (pixels).
    resolution: vec4<f32>,
    // object count, material count, light count, wave count.
    counts: vec4<u32>,
}

@group(0) @binding(0) var<uniform> frame: FrameUniforms;
// xyz: world position of the first surface seen through the pixel; w: 1 hit, 0 none.
@group(0) @binding(1) var gbuf_position: texture_2d<f32>;
// xyz: smooth world normal (as stored, not flipped); w: +1 front face seen, -1 back face.
@group(0) @binding(2) var gbuf_normal: texture_2d<f32>;
// x: object index, y: material index (NONE where nothing is hit).
@group(0) @binding(3) var gbuf_ids: texture_2d<u32>;
@group(0) @binding(4) var<storage, read> objects: array<GpuObject>;
@group(0) @binding(5) var<storage, read> materials: array<GpuMaterial>;
@group(0) @binding(6) var<storage, read> lights: array<GpuLight>;
@group(0) @binding(7) var<storage, read> waves: array<GpuWave>;
@group(0) @binding(8) var<storage, read_write> fill_counts: array<atomic<u32>>;

// Fill-rate mode: the harness builds every camera-resolution fragment pipeline twice,
// with FILL_COUNT false (timed frames) and true (count frames, DESIGN "Measuring
// honestly"). Call first thing in the fragment shader, before any discard, so the
// count matches the fragment-shader invocations that pipeline statistics report.
override FILL_COUNT: bool = false;

fn count_fragment(frag_coord: vec4<f32>) {
    if FILL_COUNT {
        let p = vec2<u32>(frag_coord.xy);
        atomicAdd(&fill_counts[p.y * u32(frame.resolution.x) + p.x], 1u);
    }
}

// Unit direction of the camera ray through `pixel_center` (pixels, y down, centres at
// +0.5), for passes that shade pixels without a rasterized primitive (compute-raster
// paths). The eye projects to x = y = w = 0, so a direction d is on the ray exactly when
// (row0 − x·row3)·d = 0 and (row1 − y·row3)·d = 0 (rows of view_proj, xyz parts): d is
// their cross product, on the side in front of the eye (row3·d > 0).
fn camera_ray(pixel_center: vec2<f32>) -> vec3<f32> {
    let ndc = vec2<f32>(
        pixel_center.x * frame.resolution.z * 2.0 - 1.0,
        1.0 - pixel_center.y * frame.resolution.w * 2.0,
    );
    let m = frame.view_proj;
    let row0 = vec3<f32>(m[0].x, m[1].x, m[2].x);
    let row1 = vec3<f32>(m[0].y, m[1].y, m[2].y);
    let row3 = vec3<f32>(m[0].w, m[1].w, m[2].w);
    let d = normalize(cross(row0 - ndc.x * row3, row1 - ndc.y * row3));
    return select(-d, d, dot(row3, d) > 0.0);
}

// Camera G-buffer at a pixel.
struct GSample {
    hit: bool,
    position: vec3<f32>,
    normal: vec3<f32>,
    // Unit normal flipped to the side the camera sees.
    facing_normal: vec3<f32>,
    object: u32,
    material: u32,
}

fn gbuffer_sample(pixel: vec2<u32>) -> GSample {
    var s: GSample;
    let p = textureLoad(gbuf_position, pixel, 0);
    let n = textureLoad(gbuf_normal, pixel, 0);
    let ids = textureLoad(gbuf_ids, pixel, 0);
    s.hit = p.w > 0.5;
    s.position = p.xyz;
    s.normal = normalize(n.xyz);
    s.facing_normal = s.normal * select(-1.0, 1.0, n.w >= 0.0);
    s.object = ids.x;
    s.material = ids.y;
    return s;
}

// World area (m²) of one pixel's footprint on a surface at `position` with unit normal
// `normal`: the pixel's solid angle, s² cos³α for square pixels of side
// s = 2 tan(fov/2) / height at unit distance along the forward axis (α: the ray's angle
// off that axis), times distance² over the cosine at the surface. A point of flux Φ
// drawn into the pixel is an irradiance Φ / area there, so its energy is kept.
fn pixel_footprint_m2(position: vec3<f32>, normal: vec3<f32>) -> f32 {
    let to_eye = frame.eye.xyz - position;
    let dist = length(to_eye);
    let w = to_eye / dist;
    let side = 2.0 * tan(0.5 * frame.eye.w) * frame.resolution.w;
    let cos_axis = max(dot(-w, frame.forward.xyz), 1e-4);
    let cos_surface = max(abs(dot(w, normal)), 1e-4);
    return side * side * cos_axis * cos_axis * cos_axis * dist * dist / cos_surface;
}

// The radiance (W m⁻² sr⁻¹) a point of light adds to the pixel it is drawn into: flux_w
// (W) landed at `p` on object `receiver`, arriving on the `side` of the object's
// stored normal (+1 the side it points to), seen in the pixel's G-buffer sample `g`.
// A one-pixel point is an irradiance Φ / (the pixel's footprint), so its energy is
// kept wherever in the pixel it lands (the light of a corner a method could not join
// into a triangle or beam). Zero where the pixel shows another object or the other side,
// or where `p` is off the pixel's tangent plane by more than tolerance × the distance
// to the eye (the point is anywhere in the pixel, not at its centre).
fn point_splat_radiance(g: GSample, p: vec3<f32>, flux_w: vec3<f32>, receiver: u32, side: f32, tolerance: f32) -> vec3<f32> {
    if !g.hit || g.object != receiver {
        return vec3<f32>(0.0);
    }
    let to_eye = frame.eye.xyz - g.position;
    if abs(dot(g.position - p, g.normal)) > tolerance * length(to_eye) {
        return vec3<f32>(0.0);
    }
    let camera_side = select(-1.0, 1.0, dot(to_eye, g.normal) >= 0.0);
    if camera_side != side {
        return vec3<f32>(0.0);
    }
    let albedo = materials[g.material].color.xyz;
    return albedo * INV_PI * flux_w / pixel_footprint_m2(g.position, g.normal);
}

// A point of light spread over a Gaussian of `sigma_px` camera pixels instead of one
// pixel (the orphan kernels of wavefront and the beam methods): truncated to the
// square of pixels within 2 sigma (rounded up) of the pixel it lands in, and
// normalised over those pixels' centres, so that on a flat receiver the point's flux is
// kept exactly. The kernel spreads in the image: where its square reaches onto another
// object (an occluder's silhouette, the receiver's edge) that part is not shaded, as
// the light of a point hidden there is not (normalising over the pixels that show the
// receiver instead would bring hidden light into view: measured on bumpy_glass at
// 128x96, static-grid, sigma 2, relMSE 8.1e-4 -> 1.1e-3). A vertex shader draws the
// square as a quad of six vertices and folds one over the kernel's sum into the
// point's flux, which depends only on where the point lands (`point_kernel_vertex`
// gives both); the fragment shader multiplies by `point_kernel_gaussian` at its pixel
// centre. A point's light is a sample of light that spreads (its triangle's corners
// parted ways), and as a lone pixel it is noise that the eye and HDR-FLIP see at every
// exposure.

// Half-width (pixels) of the kernel's square around the landing pixel.
fn point_kernel_radius_px(sigma_px: f32) -> f32 {
    return ceil(2.0 * sigma_px);
}

// Where a clip-space point lands, in framebuffer pixels (clip.w > 0).
fn clip_to_framebuffer_px(clip: vec4<f32>) -> vec2<f32> {
    let ndc = clip.xy / clip.w;
    return vec2<f32>(0.5 + 0.5 * ndc.x, 0.5 - 0.5 * ndc.y) * frame.resolution.xy;
}

// Corner `corner` (0..6: two triangles) of the quad over the kernel's square for a
// point landing at `center_px`, in clip space at NDC depth `ndc_z`: its edges lie on
// pixel boundaries, so it covers exactly the square's pixels.
fn point_kernel_corner_clip(center_px: vec2<f32>, sigma_px: f32, corner: u32, ndc_z: f32) -> vec4<f32> {
    let r = point_kernel_radius_px(sigma_px);
    let lo = floor(center_px) - r;
    let hi = floor(center_px) + r + 1.0;
    let x = select(lo.x, hi.x, corner == 1u || corner == 3u || corner == 4u);
    let y = select(lo.y, hi.y, corner == 2u || corner == 4u || corner == 5u);
    let size = frame.resolution.xy;
    return vec4<f32>(2.0 * x / size.x - 1.0, 1.0 - 2.0 * y / size.y, ndc_z, 1.0);
}

// Vertex `corner` (0..6) of the kernel's quad for a point at clip-space position
// `clip`: its clip position, where the point lands (framebuffer pixels, for
// `point_kernel_gaussian`) and the factor its flux takes (`point_kernel_inv_sum`).
// A point behind the eye is clipped, and so is its quad.
struct PointKernelVertex {
    clip: vec4<f32>,
    center_px: vec2<f32>,
    flux_scale: f32,
}

fn point_kernel_vertex(clip: vec4<f32>, sigma_px: f32, corner: u32) -> PointKernelVertex {
    var v: PointKernelVertex;
    if clip.w <= 0.0 {
        v.clip = vec4<f32>(2.0, 2.0, 2.0, 1.0);
        return v;
    }
    v.center_px = clip_to_framebuffer_px(clip);
    v.flux_scale = point_kernel_inv_sum(v.center_px, sigma_px);
    v.clip = point_kernel_corner_clip(v.center_px, sigma_px, corner, clip.z / clip.w);
    return v;
}

// -1 / (2 sigma^2). (max: a pipeline's constants are folded where sigma is 0 too, and
// the kernel is then never called.)
fn point_kernel_exponent_scale(sigma_px: f32) -> f32 {
    let sigma = max(sigma_px, 1e-3);
    return -0.5 / (sigma * sigma);
}

// One over the separable Gaussian's sum over the square of pixel centres around the
// pixel `center_px` lands in: the weights of the square then add up to 1.
fn point_kernel_inv_sum(center_px: vec2<f32>, sigma_px: f32) -> f32 {
    let r = i32(point_kernel_radius_px(sigma_px));
    let inv = point_kernel_exponent_scale(sigma_px);
    let first = floor(center_px) + 0.5 - center_px;
    var sum = vec2<f32>(0.0);
    for (var k = -r; k <= r; k++) {
        let d = first + f32(k);
        sum += exp(d * d * inv);
    }
    return 1.0 / (sum.x * sum.y);
}

// The kernel's unnormalised weight at the pixel centre `pixel` for a point landing at
// `center_px`.
fn point_kernel_gaussian(pixel: vec2<f32>, center_px: vec2<f32>, sigma_px: f32) -> f32 {
    let d = pixel - center_px;
    let w = exp(d * d * point_kernel_exponent_scale(sigma_px));
    return w.x * w.y;
}
