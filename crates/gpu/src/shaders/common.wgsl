// Shared WGSL of caustics-bench: constants, the scene tables (mirroring
// crates/gpu/src/scene_upload.rs) and radiometry/intersection helpers. Every pass
// composes this file first (see `caustics_gpu::shader::compose`).

const PI: f32 = 3.14159265358979;
const INV_PI: f32 = 0.31830988618379;
const NO_HIT: f32 = 3.0e38;
const NONE: u32 = 0xffffffffu;

// One vertex of the scene's vertex buffer (`SceneVertex::LAYOUT` in scene_upload.rs),
// as the passes that rasterize the scene's triangles read it.
struct SceneVertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) ids: vec2<u32>,
}

// The vertex stage of every full-screen pass (`caustics_gpu::pass::RasterPass::fullscreen`):
// one triangle covering the viewport, drawn with 3 vertices.
@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

const OBJ_SPHERE: u32 = 0u;
const OBJ_QUAD: u32 = 1u;
const OBJ_HEIGHTFIELD: u32 = 2u;
const OBJ_CYLINDER: u32 = 3u;
const OBJ_MESH: u32 = 4u;

const MAT_DIFFUSE: u32 = 0u;
const MAT_DIELECTRIC: u32 = 1u;
const MAT_MIRROR: u32 = 2u;

const LIGHT_DIRECTIONAL: u32 = 0u;
const LIGHT_POINT: u32 = 1u;
const LIGHT_SPOT: u32 = 2u;

struct GpuObject {
    kind: u32,
    material: u32,
    first_triangle: u32,
    triangle_count: u32,
    p0: vec4<f32>,
    p1: vec4<f32>,
    p2: vec4<f32>,
    p3: vec4<f32>,
}

struct GpuMaterial {
    kind: u32,
    ior: f32,
    pad0: u32,
    pad1: u32,
    color: vec4<f32>,
}

struct GpuLight {
    kind: u32,
    cone_rad: f32,
    falloff_rad: f32,
    pad: u32,
    position: vec4<f32>,
    direction: vec4<f32>,
    power: vec4<f32>,
}

struct GpuWave {
    k_amp_phase: vec4<f32>,
}

// Exact unpolarized Fresnel reflectance of a smooth dielectric interface (mean of
// s and p), DESIGN "Conventions". cos_i >= 0 on the incident side, eta = n_i / n_t.
// Returns 1 under total internal reflection.
fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let c = clamp(cos_i, 0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - c * c);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = sqrt(1.0 - sin2_t);
    let rs = (eta * c - cos_t) / (eta * c + cos_t);
    let rp = (c - eta * cos_t) / (c + eta * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

// Spot cone factor (DESIGN "Spot light"): 1 inside, 0 outside, and a smoothstep
// over `falloff` radians inside the edge: 1 - smoothstep(cone - falloff, cone, angle).
fn spot_factor(light: GpuLight, dir_from_light: vec3<f32>) -> f32 {
    let angle = acos(clamp(dot(dir_from_light, light.direction.xyz), -1.0, 1.0));
    if light.falloff_rad <= 0.0 {
        return select(0.0, 1.0, angle <= light.cone_rad);
    }
    return 1.0 - smoothstep(light.cone_rad - light.falloff_rad, light.cone_rad, angle);
}

// Radiant intensity (W/sr) of a point/spot light towards `dir_from_light` (unit).
fn light_intensity(light: GpuLight, dir_from_light: vec3<f32>) -> vec3<f32> {
    if light.kind == LIGHT_SPOT {
        return light.power.xyz * spot_factor(light, dir_from_light);
    }
    return light.power.xyz;
}

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// Ray/sphere: smallest t > t_min, or NO_HIT.
fn intersect_sphere(o: vec3<f32>, d: vec3<f32>, center: vec3<f32>, radius: f32, t_min: f32) -> f32 {
    let oc = o - center;
    let b = dot(oc, d);
    let c = dot(oc, oc) - radius * radius;
    let disc = b * b - c;
    if disc < 0.0 {
        return NO_HIT;
    }
    let s = sqrt(disc);
    let t0 = -b - s;
    if t0 > t_min {
        return t0;
    }
    let t1 = -b + s;
    if t1 > t_min {
        return t1;
    }
    return NO_HIT;
}

// Ray/rectangle (both sides).
fn intersect_quad(o: vec3<f32>, d: vec3<f32>, obj: GpuObject, t_min: f32) -> f32 {
    let n = obj.p1.xyz;
    let denom = dot(d, n);
    if abs(denom) < 1e-8 {
        return NO_HIT;
    }
    let t = dot(obj.p0.xyz - o, n) / denom;
    if t <= t_min {
        return NO_HIT;
    }
    let q = o + t * d - obj.p0.xyz;
    if abs(dot(q, obj.p2.xyz)) > obj.p0.w || abs(dot(q, obj.p3.xyz)) > obj.p1.w {
        return NO_HIT;
    }
    return t;
}

// Ray/open cylinder (no caps).
fn intersect_cylinder(o: vec3<f32>, d: vec3<f32>, obj: GpuObject, t_min: f32) -> f32 {
    let axis = obj.p1.xyz;
    let oc = o - obj.p0.xyz;
    let d_perp = d - dot(d, axis) * axis;
    let o_perp = oc - dot(oc, axis) * axis;
    let a = dot(d_perp, d_perp);
    if a < 1e-12 {
        return NO_HIT;
    }
    let b = dot(o_perp, d_perp);
    let c = dot(o_perp, o_perp) - obj.p0.w * obj.p0.w;
    let disc = b * b - a * c;
    if disc < 0.0 {
        return NO_HIT;
    }
    let s = sqrt(disc);
    for (var i = 0; i < 2; i++) {
        let t = select((-b + s) / a, (-b - s) / a, i == 0);
        if t > t_min && abs(dot(oc + t * d, axis)) <= obj.p1.w {
            return t;
        }
    }
    return NO_HIT;
}

// Ray against any analytic object (sphere, quad, open cylinder); NO_HIT for the
// others (heightfields and meshes have no closed form).
fn intersect_analytic(o: vec3<f32>, d: vec3<f32>, obj: GpuObject, t_min: f32) -> f32 {
    if obj.kind == OBJ_SPHERE {
        return intersect_sphere(o, d, obj.p0.xyz, obj.p0.w, t_min);
    }
    if obj.kind == OBJ_QUAD {
        return intersect_quad(o, d, obj, t_min);
    }
    if obj.kind == OBJ_CYLINDER {
        return intersect_cylinder(o, d, obj, t_min);
    }
    return NO_HIT;
}

// Geometric unit normal of an analytic object at a point on it (outward).
fn analytic_normal(obj: GpuObject, p: vec3<f32>) -> vec3<f32> {
    if obj.kind == OBJ_SPHERE {
        return normalize(p - obj.p0.xyz);
    }
    if obj.kind == OBJ_CYLINDER {
        let q = p - obj.p0.xyz;
        return normalize(q - dot(q, obj.p1.xyz) * obj.p1.xyz);
    }
    return obj.p1.xyz;
}
