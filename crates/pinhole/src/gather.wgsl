// Pass 2 of pinhole (Wand & Straßer 2003, §3.1): every receiver pixel loops over the
// point samples of the generator, each a pinhole camera projecting the light's cube
// map: the vector from the receiver x to the sample p is reflected (mirror), refracted
// through the sphere, or refracted once at an open surface (the paper's "underwater
// scenes", §5), the result looks up the light map, and the value is weighted by
// cos(theta_s) cos(theta_x) A_s / (d² + eps) and by the reflectance or the Fresnel
// transmittances. One instance of a fullscreen triangle per batch of samples,
// added into the surface target (the paper's additive passes of a few samples each).
// With filtering on, the lookup averages the map (footprint assembly, as texldd) over the
// footprint of the sample's patch: the lookup vectors at p ± r t1 and p ± r t2, the
// normals there taken from the principal curvatures (differential point samples).

@group(1) @binding(0) var<uniform> params: Params;
@group(1) @binding(1) var<storage, read> samples: array<Sample>;
@group(1) @binding(2) var<storage, read> sample_light: array<vec4<f32>>;
// receiver fragments, pairs (lo, hi), texture fetches (lo, hi), visibility tests (lo,
// hi): count frames only.
@group(1) @binding(3) var<storage, read_write> counters: array<atomic<u32>>;
@group(1) @binding(4) var light_map: texture_2d<f32>;
@group(1) @binding(5) var light_sampler: sampler;

// Receiver-to-sample segments traced by this invocation (sample_irradiance).
var<private> visibility_tests: u32 = 0u;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) batch: u32,
}

@vertex
fn vs_gather(@builtin(vertex_index) vi: u32, @builtin(instance_index) batch: u32) -> VsOut {
    let uv = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u));
    var o: VsOut;
    o.clip = vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
    o.batch = batch;
    return o;
}

// Where the light that reaches the receiver through a sample comes from.
struct Path {
    // xyz: light-map lookup vector; w: 1 valid, 0 no light can come this way.
    lookup: vec4<f32>,
    // The last specular point before the light (the sample for a mirror, the entry
    // point for a refracting sphere).
    origin: vec3<f32>,
    // Product of the Fresnel transmittances (1 for a mirror); one refraction also
    // carries eta² (radiance scales with the squared index, flux does not).
    transmit: f32,
}

fn no_path() -> Path {
    return Path(vec4<f32>(0.0), vec3<f32>(0.0), 0.0);
}

// Far intersection of the ray (o, d) with the sphere (centre c, radius R): the exit.
fn sphere_exit(o: vec3<f32>, d: vec3<f32>, c: vec3<f32>, radius: f32) -> f32 {
    let oc = o - c;
    let b = dot(oc, d);
    let disc = b * b - (dot(oc, oc) - radius * radius);
    if disc < 0.0 {
        return NO_HIT;
    }
    return -b + sqrt(disc);
}

// Follows the ray from the receiver through the sample at o (direction din, unit)
// with surface normal n (mirror: the lit side's; sphere: outward; open surface: the
// receiver's side) towards the light. eta: index on the receiver's side over the
// light's (open surfaces only).
fn trace_path(mode: u32, light: GpuLight, din: vec3<f32>, o: vec3<f32>, n: vec3<f32>, eta: f32) -> Path {
    if mode == MODE_MIRROR || mode == MODE_FRESNEL_REFLECT {
        let r = reflect(din, n);
        return Path(env_lookup(light, params, o, r), o, 1.0);
    }
    if mode == MODE_SURFACE_REFRACT {
        // One refraction, receiver side to light side, with exact Fresnel. The radiance
        // on the receiver's side is (1 - F) eta² times the light's.
        let cos1 = -dot(din, n);
        let out_dir = refract(din, n, eta);
        let f = fresnel_dielectric(cos1, eta);
        if cos1 <= 0.0 || f >= 1.0 || dot(out_dir, out_dir) < 0.5 {
            return no_path();
        }
        return Path(env_lookup(light, params, o, normalize(out_dir)), o, (1.0 - f) * eta * eta);
    }
    // Refracting sphere: in at o, out at the far side, both with exact Fresnel.
    let obj = objects[params.generator];
    let ior = materials[obj.material].ior;
    let cos1 = -dot(din, n);
    if cos1 <= 0.0 {
        return no_path();
    }
    let f1 = fresnel_dielectric(cos1, 1.0 / ior);
    let inside = refract(din, n, 1.0 / ior);
    let t = sphere_exit(o, inside, obj.p0.xyz, obj.p0.w);
    if f1 >= 1.0 || t == NO_HIT {
        return no_path();
    }
    let p2 = o + t * inside;
    let n2 = normalize(p2 - obj.p0.xyz);
    let cos2 = dot(inside, n2);
    let f2 = fresnel_dielectric(cos2, ior);
    if f2 >= 1.0 || cos2 <= 0.0 {
        return no_path();
    }
    let out_dir = refract(inside, -n2, ior);
    return Path(env_lookup(light, params, p2, out_dir), p2, (1.0 - f1) * (1.0 - f2));
}

// Lookup vector of the neighbour point p + offset with normal nn: with the receiver's
// direction to that point (FILTER_FULL, the paper's finite differences) or with the
// centre's direction and origin (FILTER_CURVATURE: the normal's change alone).
fn neighbour_lookup(mode: u32, light: GpuLight, x: vec3<f32>, din: vec3<f32>, p: vec3<f32>, offset: vec3<f32>, nn: vec3<f32>, eta: f32) -> vec4<f32> {
    if PINHOLE_FILTERING == FILTER_FULL {
        let q = p + offset;
        return trace_path(mode, light, normalize(q - x), q, nn, eta).lookup;
    }
    return trace_path(mode, light, din, p, nn, eta).lookup;
}

fn central_difference(a: vec4<f32>, b: vec4<f32>) -> vec3<f32> {
    if a.w == 0.0 || b.w == 0.0 {
        return vec3<f32>(0.0);
    }
    return a.xyz - b.xyz;
}

// The irradiance (rgb) that sample i sends to the receiver point x (normal nx) along
// the generator's path `mode`, and the texture probes it took (w).
fn sample_irradiance(i: u32, mode: u32, light: GpuLight, x: vec3<f32>, nx: vec3<f32>, x_start: vec3<f32>) -> vec4<f32> {
    let generator_material = materials[objects[params.generator].material];
    let s = samples[i];
    let p = s.pos.xyz;
    let to_x = x - p;
    let d2 = dot(to_x, to_x);
    let dist = sqrt(d2);
    let wo = to_x / dist;
    let cos_x = -dot(nx, wo);
    if cos_x <= 0.0 {
        return vec4<f32>(0.0);
    }
    // One-event paths read the light seen from the sample (prepare.wgsl).
    var side = 1.0;
    var radiance = vec3<f32>(0.0);
    let one_event = mode != MODE_SPHERE_REFRACT;
    if one_event {
        let sl = sample_light[i];
        side = sl.w;
        radiance = sl.xyz;
        if PINHOLE_ENVIRONMENT {
            // The sky is on every side: through a mirror (or a Fresnel reflection) the
            // light a receiver gets comes from the receiver's side, through an open
            // surface from the other.
            side = select(1.0, -1.0, dot(s.normal.xyz, to_x) < 0.0);
            if mode == MODE_SURFACE_REFRACT {
                side = -side;
            }
        }
    }
    // The normal on the receiver's side: the lit side of a mirror (or of a reflecting
    // dielectric), the far side of a surface the light refracts through (the outward
    // side of a sphere).
    let facing = select(side, -side, mode == MODE_SURFACE_REFRACT);
    // Open surfaces: the receiver is in the medium when the light is outside.
    let eta = select(1.0 / generator_material.ior, generator_material.ior, side > 0.0);
    let n = facing * s.normal.xyz;
    let cos_s = dot(n, wo);
    if cos_s <= 0.0 || (one_event && all(radiance == vec3<f32>(0.0))) {
        return vec4<f32>(0.0);
    }
    if mode == MODE_MIRROR {
        radiance *= generator_material.color.xyz;
    } else if mode == MODE_FRESNEL_REFLECT {
        // The dielectric's Fresnel reflectance from the light's side (angle of
        // incidence = angle of reflection = theta_s).
        radiance *= fresnel_dielectric(cos_s, select(generator_material.ior, 1.0 / generator_material.ior, side > 0.0));
    }
    let din = -wo;
    let path = trace_path(mode, light, din, p, n, eta);
    if path.lookup.w == 0.0 {
        return vec4<f32>(0.0);
    }
    let environment = PINHOLE_ENVIRONMENT;
    // Off the map's one face no footprint can reach the light (filtered_coverage), so
    // neither the light's visibility nor the four neighbour paths of the filter are
    // traced for it. (An environment's map covers every direction.)
    if !environment && !on_light_face(path.lookup.xyz) {
        return vec4<f32>(0.0);
    }
    if mode == MODE_SPHERE_REFRACT && environment {
        // The sky's visibility along the exit direction is traced below.
        radiance = vec3<f32>(path.transmit);
    } else if mode == MODE_SPHERE_REFRACT {
        radiance = path.transmit * light_radiance(light, params, path.origin + 1e-4 * normalize(path.origin - objects[params.generator].p0.xyz), 0.0);
    } else {
        radiance *= path.transmit;
    }
    var gx = vec3<f32>(0.0);
    var gy = vec3<f32>(0.0);
    if PINHOLE_FILTERING != FILTER_OFF {
        let r = s.extra.x;
        let t1 = s.t1.xyz;
        let t2 = s.t2.xyz;
        // n(p + u t) = n + u k t on the surface; flipped with the side used.
        let n1p = normalize(facing * (s.normal.xyz + r * s.t1.w * t1));
        let n1m = normalize(facing * (s.normal.xyz - r * s.t1.w * t1));
        let n2p = normalize(facing * (s.normal.xyz + r * s.t2.w * t2));
        let n2m = normalize(facing * (s.normal.xyz - r * s.t2.w * t2));
        gx = central_difference(
            neighbour_lookup(mode, light, x, din, p, r * t1, n1p, eta),
            neighbour_lookup(mode, light, x, din, p, -r * t1, n1m, eta));
        gy = central_difference(
            neighbour_lookup(mode, light, x, din, p, r * t2, n2p, eta),
            neighbour_lookup(mode, light, x, din, p, -r * t2, n2m, eta));
    }
    var light_rgb: vec3<f32>;
    var probes: f32;
    if environment {
        let e = filtered_environment(path.lookup.xyz, gx, gy);
        light_rgb = e.xyz * params.env_scale.xyz;
        probes = e.w;
    } else {
        let c = filtered_coverage(path.lookup.xyz, gx, gy);
        light_rgb = vec3<f32>(c.x);
        probes = c.y;
    }
    // Visibility last: the receiver-to-sample segment is traced (the scene's BVH) only
    // for the few pairs whose lookup lands on the light; most see none of it, and an
    // occluded pair adds nothing either way, so the image is the same as testing first.
    if all(light_rgb == vec3<f32>(0.0)) {
        return vec4<f32>(0.0, 0.0, 0.0, probes);
    }
    // An environment's light comes from infinitely far along the lookup direction:
    // blocked if the ray leaving the generator there meets the scene (the paper tests
    // no light visibility, §5; the point-light paths test theirs in prepare.wgsl).
    if environment {
        let sky = normalize(path.lookup.xyz);
        if occluded(path.origin + sky * 1e-4, sky, NO_HIT, s.extra.y, 0.0) {
            return vec4<f32>(0.0, 0.0, 0.0, probes);
        }
    }
    // The segment from the (lifted) receiver point exactly to the sample; hits
    // within 1e-3 of its length from the sample are the sample's own surface.
    visibility_tests += 1u;
    let seg = p - x_start;
    let seg_len = length(seg);
    if occluded(x_start, seg / seg_len, seg_len, 0.0, max(s.extra.y, 1e-3 * seg_len)) {
        return vec4<f32>(0.0, 0.0, 0.0, probes);
    }
    return vec4<f32>(radiance * light_rgb * (cos_s * cos_x * s.pos.w / (d2 + s.normal.w)), probes);
}

@fragment
fn fs_gather(in: VsOut) -> @location(0) vec4<f32> {
    count_fragment(in.clip);
    let g = gbuffer_sample(vec2<u32>(in.clip.xy));
    if !g.hit || materials[g.material].kind != MAT_DIFFUSE {
        discard;
    }
    let light = lights[params.light_index];
    let x = g.position;
    let nx = g.facing_normal;
    let x_start = x + nx * 1e-4;
    let first = in.batch * params.batch_size;
    let last = min(first + params.batch_size, params.sample_count);
    // A dielectric's Fresnel reflection (`reflections`) is a second pinhole image per
    // sample: the sample as a mirror of reflectance F.
    let reflect_too = PINHOLE_REFLECTIONS && PINHOLE_MODE != MODE_MIRROR;
    var irradiance = vec3<f32>(0.0);
    var fetches = 0u;
    for (var i = first; i < last; i++) {
        let c = sample_irradiance(i, PINHOLE_MODE, light, x, nx, x_start);
        irradiance += c.xyz;
        fetches += u32(c.w);
        if reflect_too {
            let r = sample_irradiance(i, MODE_FRESNEL_REFLECT, light, x, nx, x_start);
            irradiance += r.xyz;
            fetches += u32(r.w);
        }
    }
    if FILL_COUNT {
        atomicAdd(&counters[0], 1u);
        add_wide(1u, last - first);
        add_wide(3u, fetches);
        add_wide(5u, visibility_tests);
    }
    let albedo = materials[g.material].color.xyz;
    return vec4<f32>(albedo * INV_PI * irradiance, 1.0);
}

// Texture coordinates of the lookup vector v on the map (the +Z face of the light's
// cube map in the frame (map_u, map_v, map_axis), light_map.rs); z < 0: behind.
fn map_uv(v: vec3<f32>) -> vec3<f32> {
    let l = vec3<f32>(dot(v, params.map_u.xyz), dot(v, params.map_v.xyz), dot(v, params.map_axis.xyz));
    return vec3<f32>(0.5 * l.xy / max(l.z, 1e-20) + 0.5, l.z);
}

// The light map averaged over the parallelogram footprint (centre v, edges gx, gy in
// lookup space): footprint assembly (Schilling et al., the paper's ref. 18), what
// texldd / textureSampleGrad do in hardware. The mip level comes from the minor
// axis, and up to MAX_ANISOTROPY probes are spread along the major axis. Done in the
// shader because lavapipe ignores explicit gradients on cube maps (gradients scaled by
// 1000 left the image unchanged), and the footprint must mean the same on every
// adapter. Returns (coverage, probes taken).
const MAX_ANISOTROPY: f32 = 16.0;

// The light covers less than 45° around the axis: nothing outside the face.
fn on_light_face(v: vec3<f32>) -> bool {
    return on_face(map_uv(v));
}

// Whether map coordinates c (map_uv) lie on the map's face, in front.
fn on_face(c: vec3<f32>) -> bool {
    return c.z > 0.0 && all(c.xy >= vec2<f32>(0.0)) && all(c.xy <= vec2<f32>(1.0));
}

fn filtered_coverage(v: vec3<f32>, gx: vec3<f32>, gy: vec3<f32>) -> vec2<f32> {
    let c = map_uv(v);
    if !on_face(c) {
        return vec2<f32>(0.0, 0.0);
    }
    let size = f32(textureDimensions(light_map).x);
    let du = map_uv(v + 0.5 * gx).xy - map_uv(v - 0.5 * gx).xy;
    let dv = map_uv(v + 0.5 * gy).xy - map_uv(v - 0.5 * gy).xy;
    let lx = length(du) * size;
    let ly = length(dv) * size;
    let major = select(dv, du, lx >= ly);
    let p_max = max(lx, ly);
    let p_min = min(lx, ly);
    if p_max <= 1.0 {
        return vec2<f32>(textureSampleLevel(light_map, light_sampler, c.xy, 0.0).r, 1.0);
    }
    let n = clamp(ceil(p_max / max(p_min, 1e-6)), 1.0, MAX_ANISOTROPY);
    let lod = log2(max(p_max / n, 1.0));
    var sum = 0.0;
    let count = u32(n);
    for (var i = 0u; i < count; i++) {
        let f = (f32(i) + 0.5) / n - 0.5;
        sum += textureSampleLevel(light_map, light_sampler, c.xy + f * major, lod).r;
    }
    return vec2<f32>(sum / n, n);
}

// Lat-long coordinates of direction d (Mitsuba 3's convention, EnvironmentMap::uv).
fn env_uv(d: vec3<f32>) -> vec2<f32> {
    let n = normalize(d);
    return vec2<f32>(atan2(n.x, -n.z) * (0.5 * INV_PI) + 0.5, acos(clamp(n.y, -1.0, 1.0)) * INV_PI);
}

// The environment map averaged over the footprint (centre direction v, edges gx, gy):
// the same footprint assembly as filtered_coverage, in the map's (u, v), a footprint
// across the seam at u = 0|1 taken the short way round (the sampler repeats in u).
// Returns (rgb in units of the map's peak, probes taken).
fn filtered_environment(v: vec3<f32>, gx: vec3<f32>, gy: vec3<f32>) -> vec4<f32> {
    let c = env_uv(v);
    let size = vec2<f32>(textureDimensions(light_map));
    var du = env_uv(v + 0.5 * gx) - env_uv(v - 0.5 * gx);
    var dv = env_uv(v + 0.5 * gy) - env_uv(v - 0.5 * gy);
    du.x -= round(du.x);
    dv.x -= round(dv.x);
    let lx = length(du * size);
    let ly = length(dv * size);
    let major = select(dv, du, lx >= ly);
    let p_max = max(lx, ly);
    let p_min = min(lx, ly);
    if p_max <= 1.0 {
        return vec4<f32>(textureSampleLevel(light_map, light_sampler, c, 0.0).rgb, 1.0);
    }
    let n = clamp(ceil(p_max / max(p_min, 1e-6)), 1.0, MAX_ANISOTROPY);
    let lod = log2(max(p_max / n, 1.0));
    var sum = vec3<f32>(0.0);
    let count = u32(n);
    for (var i = 0u; i < count; i++) {
        let f = (f32(i) + 0.5) / n - 0.5;
        sum += textureSampleLevel(light_map, light_sampler, c + f * major, lod).rgb;
    }
    return vec4<f32>(sum / n, n);
}

// Adds to the 64-bit counter in counters[at] (low word) and counters[at + 1] (high).
fn add_wide(at: u32, v: u32) {
    let old = atomicAdd(&counters[at], v);
    if old + v < old {
        atomicAdd(&counters[at + 1u], 1u);
    }
}
