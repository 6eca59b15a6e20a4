// Types and light helpers shared by pinhole's passes (prepare, gather).

// One pinhole: a point sample of the caustic generator (sampling.rs).
struct Sample {
    // xyz: position (m); w: area it stands for, A_s (m²).
    pos: vec4<f32>,
    // xyz: unit outward normal; w: epsilon added to d² (m²), the paper's singularity guard.
    normal: vec4<f32>,
    // xyz: first principal direction; w: its curvature k1 (1/m).
    t1: vec4<f32>,
    // xyz: second principal direction; w: its curvature k2 (1/m).
    t2: vec4<f32>,
    // x: finite-difference step r = half the sample spacing (m); y: occluders closer
    // than this to the sample are ignored (m, covers the quantized displacement).
    extra: vec4<f32>,
}

struct Params {
    generator: u32,
    light_index: u32,
    sample_count: u32,
    batch_size: u32,
    // xyz: centre c of the cube map (point/spot: the generator's centre); w: unused.
    map_center: vec4<f32>,
    // xyz: axis of the light's disc in the map; w: disc radius rho (m, point/spot) or
    // cone half angle (rad, directional).
    map_axis: vec4<f32>,
    // xyz: unit axes u, v completing the map's frame (u, v, axis).
    map_u: vec4<f32>,
    map_v: vec4<f32>,
    // x: radiance of the disc per unit power: 1/(pi rho²) (point/spot, per W/sr) or
    // 1/Omega (directional, per W/m²); y: cos(alpha) of the map's cone.
    light_scale: vec4<f32>,
    // xyz: what an environment map's texels are multiplied by (its scale × peak).
    env_scale: vec4<f32>,
}

// What both passes are specialized on (pipeline-overridable constants, set per kind of
// light when the passes are built: `specialization` in lib.rs). As uniforms they left
// the choice to every (pixel, sample) pair of the gather's loop, and lavapipe runs both
// sides of a branch on a uniform under a mask: the gather took 2.4-6x as long. No
// defaults, so a pass built without them fails to build.
// 0: mirror (one reflection), 1: dielectric sphere (refracted in and out),
// 2: open dielectric surface (one refraction: water, a glass quad).
override PINHOLE_MODE: u32;
// 0: off, 1: curvature only, 2: full footprint (curvature and parallax, the paper).
override PINHOLE_FILTERING: u32;
// Also the Fresnel reflection off a dielectric generator (`reflections`).
override PINHOLE_REFLECTIONS: bool;
// The light is an environment: light_map holds its lat-long radiance (divided by its
// peak), env_scale its scale times that peak; the lookup is a direction.
override PINHOLE_ENVIRONMENT: bool;

const MODE_MIRROR: u32 = 0u;
const MODE_SPHERE_REFRACT: u32 = 1u;
const MODE_SURFACE_REFRACT: u32 = 2u;
// The Fresnel reflection off a dielectric generator (a path of its own, `reflections`).
const MODE_FRESNEL_REFLECT: u32 = 3u;
const FILTER_OFF: u32 = 0u;
const FILTER_CURVATURE: u32 = 1u;
const FILTER_FULL: u32 = 2u;

// Cube-map lookup vector for the ray (o, r) leaving the generator towards the light.
// Directional light: the map is at infinity, the lookup is r. Point/spot light: the
// light is a disc of radius rho centred on the light, facing the map centre c; the ray
// meets the disc's plane at q and the lookup is q - c, which lies inside the map's
// cone exactly when |q - light| < rho (a parallax-corrected environment map, so one
// map serves every sample even with the light near the reflector). w = 0: the ray
// never reaches the plane.
fn env_lookup(light: GpuLight, p: Params, o: vec3<f32>, r: vec3<f32>) -> vec4<f32> {
    if light.kind == LIGHT_DIRECTIONAL {
        return vec4<f32>(r, 1.0);
    }
    let w = p.map_axis.xyz;
    let denom = dot(r, w);
    let t = dot(light.position.xyz - o, w);
    if denom <= 1e-6 || t <= 0.0 {
        return vec4<f32>(0.0, 0.0, 0.0, 0.0);
    }
    let q = o + (t / denom) * r;
    return vec4<f32>(q - p.map_center.xyz, 1.0);
}

// Radiance of the light's disc as seen from o (W m⁻² sr⁻¹), times the light's
// visibility from o; rgb. For a point/spot light the disc's radiance is
// I(towards o) / (pi rho² cos beta), beta the angle between the disc's normal and the
// direction to o, so that the disc sends exactly the light's intensity to o.
fn light_radiance(light: GpuLight, p: Params, o: vec3<f32>, skip_tol: f32) -> vec3<f32> {
    if light.kind == LIGHT_DIRECTIONAL {
        let to_light = -light.direction.xyz;
        if occluded(o, to_light, NO_HIT, skip_tol, 0.0) {
            return vec3<f32>(0.0);
        }
        return light.power.xyz * p.light_scale.x;
    }
    let v = o - light.position.xyz;
    let dist = length(v);
    let u = v / dist;
    let cos_beta = -dot(u, p.map_axis.xyz);
    if cos_beta <= 0.05 || occluded(o, -u, dist, skip_tol, 0.0) {
        return vec3<f32>(0.0);
    }
    return light_intensity(light, u) * p.light_scale.x / cos_beta;
}

// Whether any surface of the scene (analytic objects exactly, meshes and heightfields
// through the BVH) blocks the segment from o along unit d over
// (start_tol, t_max - end_tol); the tolerances are at least 0.1 mm.
fn occluded(o: vec3<f32>, d: vec3<f32>, t_max: f32, start_tol: f32, end_tol: f32) -> bool {
    let t_min = max(start_tol, 1e-4);
    let t_end = t_max - max(end_tol, 1e-4);
    for (var i = 0u; i < frame.counts.x; i++) {
        let t = intersect_analytic(o, d, objects[i], t_min);
        if t < t_end {
            return true;
        }
    }
    return bvh_closest_hit(o, d, t_min, t_end, NONE).object != NONE;
}
