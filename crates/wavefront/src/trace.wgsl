// Pass 1 of wavefront (Wallace 2016): trace one light ray per wavefront vertex
// through the caustic generator (a dielectric: one refraction at an open surface,
// two through a closed sphere; a mirror: one reflection) to the first diffuse
// receiver, and record where it started in the light's parametrization ("old": the
// light plane for a directional light, the unit sphere of directions for a
// point/spot light) and where it lands ("new").

struct Source {
    // xyz: a point on the specular surface (SOURCE_SURFACE) or a ray origin (SOURCE_RAY); w: kind.
    origin: vec4<f32>,
    // xyz: surface normal (SOURCE_SURFACE, analytic) or unit ray direction (SOURCE_RAY).
    dir_or_normal: vec4<f32>,
}

const SOURCE_SURFACE: f32 = 0.0;
const SOURCE_RAY: f32 = 1.0;

const INVALID_NONE: u32 = 0u;
const INVALID_MISSED_SPECULAR: u32 = 1u;
const INVALID_SHADOWED: u32 = 2u;
const INVALID_TIR: u32 = 3u;
const INVALID_NO_RECEIVER: u32 = 4u;
// The ray meets a specular surface again (e.g. a second bounce inside a ring):
// wavefront follows one specular event.
const INVALID_SPECULAR_RECEIVER: u32 = 5u;

@group(1) @binding(0) var<uniform> tp: TraceParams;
@group(1) @binding(1) var<storage, read> sources: array<Source>;
@group(1) @binding(2) var<storage, read_write> traced: array<Traced>;

struct SceneHit {
    t: f32,
    object: u32,
}

// Closest analytic object along a ray, skipping `skip` (NONE: skip nothing).
// Heightfields and meshes are not intersected: `wavefront` declares scenes with them
// as receivers unsupported.
fn closest_analytic_hit(o: vec3<f32>, d: vec3<f32>, t_min: f32, skip: u32) -> SceneHit {
    var best = SceneHit(NO_HIT, NONE);
    for (var i = 0u; i < frame.counts.x; i++) {
        if i == skip {
            continue;
        }
        let t = intersect_analytic(o, d, objects[i], t_min);
        if t < best.t {
            best = SceneHit(t, i);
        }
    }
    return best;
}

fn invalid(why: u32) -> Traced {
    var v: Traced;
    v.info = vec4<u32>(NONE, why, 0u, 0u);
    return v;
}

// Refracts `d` at a surface with outward normal `n_out` of a dielectric with index
// `ior` (outside 1.0). Returns the new direction (xyz) and the Fresnel transmittance
// (w), or w < 0 under total internal reflection.
fn refract_through(d: vec3<f32>, n_out: vec3<f32>, ior: f32) -> vec4<f32> {
    let entering = dot(d, n_out) < 0.0;
    let n = select(-n_out, n_out, entering);
    let eta = select(ior, 1.0 / ior, entering);
    let cos_i = -dot(d, n);
    let f = fresnel_dielectric(cos_i, eta);
    let t = refract(d, n, eta);
    if f >= 1.0 || dot(t, t) < 0.5 {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    return vec4<f32>(normalize(t), 1.0 - f);
}

@compute @workgroup_size(64)
fn trace_vertices(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= tp.source_count {
        return;
    }
    let src = sources[i];
    let light = lights[tp.light_index];
    let obj = objects[tp.specular_object];
    let mat = materials[obj.material];
    let eps = 1e-4;

    // Hit point on the generator and the light direction there.
    var p: vec3<f32>;
    var n_out: vec3<f32>;
    var d: vec3<f32>;
    if src.origin.w == SOURCE_RAY {
        d = src.dir_or_normal.xyz;
        let t = intersect_analytic(src.origin.xyz, d, obj, 0.0);
        if t >= NO_HIT {
            traced[i] = invalid(INVALID_MISSED_SPECULAR);
            return;
        }
        p = src.origin.xyz + t * d;
        n_out = analytic_normal(obj, p);
    } else {
        p = src.origin.xyz;
        n_out = src.dir_or_normal.xyz;
        if light.kind == LIGHT_DIRECTIONAL {
            d = light.direction.xyz;
        } else {
            d = normalize(p - light.position.xyz);
        }
    }
    // Which face of the generator the light meets (0 outside, 1 inside): a
    // triangle whose vertices meet different faces (outer and inner wall of a ring)
    // spans no continuous wavefront.
    let face = select(0u, 1u, dot(d, n_out) > 0.0);

    // Light-space coordinate and the flux density the vertex carries.
    var old_pos: vec3<f32>;
    var flux: vec3<f32>;
    var light_dist = NO_HIT;
    if light.kind == LIGHT_DIRECTIONAL {
        let l = light.direction.xyz;
        old_pos = p - dot(p, l) * l;
        flux = light.power.xyz;
    } else {
        old_pos = d;
        flux = light_intensity(light, d);
        light_dist = length(p - light.position.xyz);
    }

    // Is the hit point lit? (walls or other objects between light and surface)
    let shadow = closest_analytic_hit(p, -d, eps, tp.specular_object);
    if shadow.t < light_dist - eps {
        traced[i] = invalid(INVALID_SHADOWED);
        return;
    }

    if mat.kind == MAT_MIRROR {
        // DESIGN: mirrors reflect with their reflectance at every angle, both sides.
        flux *= mat.color.xyz;
        d = reflect(d, n_out);
    } else {
        let r1 = refract_through(d, n_out, mat.ior);
        if r1.w < 0.0 {
            traced[i] = invalid(INVALID_TIR);
            return;
        }
        flux *= r1.w;
        d = r1.xyz;
        // Closed refractor: leave it through the second interface.
        if obj.kind == OBJ_SPHERE {
            let t = intersect_sphere(p, d, obj.p0.xyz, obj.p0.w, eps);
            if t >= NO_HIT {
                traced[i] = invalid(INVALID_MISSED_SPECULAR);
                return;
            }
            p = p + t * d;
            let r2 = refract_through(d, analytic_normal(obj, p), mat.ior);
            if r2.w < 0.0 {
                traced[i] = invalid(INVALID_TIR);
                return;
            }
            flux *= r2.w;
            d = r2.xyz;
        }
    }

    // First surface along the outgoing ray, the generator included (a second
    // specular event invalidates the vertex).
    let hit = closest_analytic_hit(p, d, eps, NONE);
    if hit.object == NONE {
        traced[i] = invalid(INVALID_NO_RECEIVER);
        return;
    }
    let receiver = objects[hit.object];
    if materials[receiver.material].kind != MAT_DIFFUSE {
        traced[i] = invalid(INVALID_SPECULAR_RECEIVER);
        return;
    }
    let q = p + hit.t * d;
    let side = select(1.0, -1.0, dot(d, analytic_normal(receiver, q)) > 0.0);
    var v: Traced;
    v.old_pos = vec4<f32>(old_pos, 0.0);
    v.new_pos = vec4<f32>(q, side);
    v.flux = vec4<f32>(flux, 0.0);
    v.info = vec4<u32>(hit.object, INVALID_NONE, face, 0u);
    traced[i] = v;
}
