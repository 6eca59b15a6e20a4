// Pass 1 of wavefront (Wallace 2016): trace one light ray per wavefront vertex from
// its caustic generator through every specular surface it meets (refracted at each
// dielectric interface, reflected off mirrors) to the first diffuse receiver, and
// record where it started in the light's parametrization ("old": the light plane for
// a directional light, the unit sphere of directions for a point/spot light), where it
// lands ("new") and which specular path it took (a triangle whose vertices took
// different paths spans no continuous wavefront and is dropped by classify.wgsl).
//
// Wallace refracts once, at the water. The same construction carries a wavefront
// through a chain of generators (a glass sphere over water, two lenses): each
// interface maps the wavefront's rays on, and the area ratio at the receiver is then
// that of the whole chain. Surfaces are found by `scene_closest_hit`: analytic objects
// exactly, meshes and heightfields through the scene's triangle BVH with interpolated
// (shading) normals. Light transport with shading normals is not symmetric: each
// event multiplies the flux by |ωi·ns|·|ωo·ng| / (|ωo·ns|·|ωi·ng|) (Veach 1997,
// §5.3), as the reference's photons do, and a ray for which ns and ng disagree about
// a side is dropped.
//
// By default a path passes each specular object once (in, through, out, on to the
// next), transmitted at every dielectric interface with weight 1 − F, as Wallace's
// one refraction is: total internal reflection and a second hit on an object already
// left end it. The other paths are further sheets, each one fixed choice per
// interface so that every sheet is one smooth wavefront: `reflect_mask` bit k takes
// the Fresnel reflection (weight F, 1 under total internal reflection) at the path's
// k-th dielectric interface instead (bit 0: the reflection off the generator; bits
// 1..j: j internal reflections before the light leaves). A vertex that lands before
// using all its sheet's reflections belongs to another sheet and is dropped here, so
// the sheets partition the light. `bounces` allows that many hits on objects a path
// has already left (the ring's opposite wall).
//
// Every sheet of a (light, generator) starts alike: the light's ray to the generator
// and whether it is lit there (on a mesh, one or two BVH traversals per ray).
// `find_first_hits` finds that once per wavefront, and every sheet's `trace_vertices`
// starts from its record (the ten sheets of bumpy_glass with bounces=8: 10 % less
// tracing; sphere_over_water's twelve: 22 %).

struct Source {
    // xyz: a point on the specular surface (SOURCE_SURFACE) or a ray origin (SOURCE_RAY); w: kind.
    origin: vec4<f32>,
    // xyz: surface normal (SOURCE_SURFACE, analytic) or unit ray direction (SOURCE_RAY).
    dir_or_normal: vec4<f32>,
}

const SOURCE_SURFACE: f32 = 0.0;
const SOURCE_RAY: f32 = 1.0;

// Why a vertex is invalid (Traced.info.y), and the index of its counter.
const INVALID_NONE: u32 = 0u;
// The ray's first surface is not this wavefront's generator (another generator's
// wavefront, or direct light).
const INVALID_MISSED_GENERATOR: u32 = 1u;
const INVALID_SHADOWED: u32 = 2u;
const INVALID_TIR: u32 = 3u;
const INVALID_NO_RECEIVER: u32 = 4u;
// The ray meets an object it has already left (the ring's opposite wall) with no
// bounce left.
const INVALID_REHIT: u32 = 5u;
// Shading and geometric normal disagree about the side of ωi or ωo.
const INVALID_WRONG_SIDE: u32 = 6u;
// More than MAX_EVENTS specular events.
const INVALID_TOO_MANY_EVENTS: u32 = 7u;
// Landed without taking every reflection its sheet asks for (another sheet's path).
const INVALID_OTHER_SHEET: u32 = 8u;

// Specular events one path may have (interfaces and reflections).
const MAX_EVENTS: u32 = 16u;
// Objects one path may leave before it must land (its re-hit memory).
const MAX_LEFT: u32 = 8u;

@group(1) @binding(0) var<uniform> tp: TraceParams;
@group(1) @binding(1) var<storage, read> sources: array<Source>;
@group(1) @binding(2) var<storage, read_write> traced: array<Traced>;
@group(1) @binding(3) var<storage, read_write> vertex_counts: VertexCounts;
// One per source, shared by the wavefront's sheets (find_first_hits writes it).
@group(1) @binding(4) var<storage, read_write> first_hits: array<FirstHit>;

// Where a source's light meets the generator.
struct FirstHit {
    // xyz: the source's light-space coordinate (light_coordinate); w: INVALID_NONE, or
    // why no sheet traces it on (a small whole number, exact as f32).
    old_pos: vec4<f32>,
    // The hit point, its shading and geometric normals, the light's direction there.
    p: vec4<f32>,
    ns: vec4<f32>,
    ng: vec4<f32>,
    d: vec4<f32>,
}

// Vertices per outcome (INVALID_* index; INVALID_NONE = landed), and landed vertices
// whose path used a further bounce. Read back as `VERTEX_COUNTERS` in lib.rs.
struct VertexCounts {
    reasons: array<atomic<u32>, 9>,
    bounced: atomic<u32>,
}

// The light-space coordinate of this invocation's vertex (see light_coordinate), set
// before any outcome: an invalid vertex keeps it too, so that a dropped triangle's
// area in the light's parametrization is known (the orphans pass divides it).
var<private> vertex_old_pos: vec3<f32>;

fn invalid(why: u32) -> Traced {
    var v: Traced;
    v.old_pos = vec4<f32>(vertex_old_pos, 0.0);
    v.info = vec4<u32>(NONE, why, 0u, 0u);
    return v;
}

// Where a light ray through `p` along `d` sits in the light's parametrization: on the
// plane perpendicular to a directional light (m), or its unit direction from a point or
// spot light (the triangle of three is the solid angle, sr).
fn light_coordinate(light: GpuLight, p: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    if light.kind == LIGHT_DIRECTIONAL {
        let l = light.direction.xyz;
        return p - dot(p, l) * l;
    }
    return d;
}

fn count_vertex(why: u32) {
    atomicAdd(&vertex_counts.reasons[why], 1u);
}

// Refracts `d` at a surface with shading normal `n` facing the incoming light
// (dot(d, n) < 0), eta = index on the light's side / index beyond. Returns the new
// direction (xyz) and the Fresnel transmittance (w), or w < 0 under total internal
// reflection.
fn refract_facing(d: vec3<f32>, n: vec3<f32>, eta: f32) -> vec4<f32> {
    let cos_i = -dot(d, n);
    let f = fresnel_dielectric(cos_i, eta);
    let t = refract(d, n, eta);
    if f >= 1.0 || dot(t, t) < 0.5 {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    return vec4<f32>(normalize(t), 1.0 - f);
}

// Order-dependent hash of the specular events so far: object, and which side of it the
// light arrived on (outside 0, inside 1).
fn mix_path(h: u32, object: u32, inside: u32) -> u32 {
    var x = h ^ (object * 2u + inside + 1u) * 0x9e3779b9u;
    x = (x ^ (x >> 16u)) * 0x85ebca6bu;
    return x ^ (x >> 13u);
}

fn first_hit_invalid(old_pos: vec3<f32>, why: u32) -> FirstHit {
    var h: FirstHit;
    h.old_pos = vec4<f32>(old_pos, f32(why));
    return h;
}

// The start every sheet shares: the first hit on the generator and the light's
// visibility there (one invocation per source).
@compute @workgroup_size(64)
fn find_first_hits(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= tp.source_count {
        return;
    }
    let src = sources[i];
    let light = lights[tp.light_index];
    let generator = tp.specular_object;
    let eps = 1e-4;

    var p: vec3<f32>;
    var ns: vec3<f32>;
    var ng: vec3<f32>;
    var d: vec3<f32>;
    var old_pos: vec3<f32>;
    var light_dist = NO_HIT;
    if src.origin.w == SOURCE_RAY {
        d = src.dir_or_normal.xyz;
        old_pos = light_coordinate(light, src.origin.xyz, d);
        let first = scene_closest_hit(src.origin.xyz, d, 0.0, NONE);
        if first.object != generator {
            first_hits[i] = first_hit_invalid(old_pos, INVALID_MISSED_GENERATOR);
            return;
        }
        p = src.origin.xyz + first.t * d;
        ns = first.ns;
        ng = first.ng;
        // A directional light's lattice starts on a plane past the generator's bounds:
        // anything behind that plane shadows the ray.
        if light.kind == LIGHT_DIRECTIONAL && scene_closest_hit(src.origin.xyz, -d, 0.0, NONE).object != NONE {
            first_hits[i] = first_hit_invalid(old_pos, INVALID_SHADOWED);
            return;
        }
    } else {
        p = src.origin.xyz;
        ns = src.dir_or_normal.xyz;
        ng = ns;
        if light.kind == LIGHT_DIRECTIONAL {
            d = light.direction.xyz;
        } else {
            d = normalize(p - light.position.xyz);
            light_dist = length(p - light.position.xyz);
        }
        old_pos = light_coordinate(light, p, d);
        // Is the vertex lit? (walls or other objects between the light and the surface)
        if scene_closest_hit(p, -d, eps, generator).t < light_dist - eps {
            first_hits[i] = first_hit_invalid(old_pos, INVALID_SHADOWED);
            return;
        }
    }
    var h: FirstHit;
    h.old_pos = vec4<f32>(old_pos, f32(INVALID_NONE));
    h.p = vec4<f32>(p, 0.0);
    h.ns = vec4<f32>(ns, 0.0);
    h.ng = vec4<f32>(ng, 0.0);
    h.d = vec4<f32>(d, 0.0);
    first_hits[i] = h;
}

@compute @workgroup_size(64)
fn trace_vertices(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= tp.source_count {
        return;
    }
    let light = lights[tp.light_index];
    let generator = tp.specular_object;
    let eps = 1e-4;

    // The first hit, on the generator, and the light's direction there (find_first_hits).
    let start = first_hits[i];
    vertex_old_pos = start.old_pos.xyz;
    let start_outcome = u32(start.old_pos.w);
    if start_outcome != INVALID_NONE {
        traced[i] = invalid(start_outcome);
        count_vertex(start_outcome);
        return;
    }
    var p = start.p.xyz;
    var ns = start.ns.xyz;
    var ng = start.ng.xyz;
    var d = start.d.xyz;

    // The flux density the vertex carries.
    let old_pos = vertex_old_pos;
    var flux: vec3<f32>;
    if light.kind == LIGHT_DIRECTIONAL {
        flux = light.power.xyz;
    } else {
        flux = light_intensity(light, d);
    }

    var object = generator;
    var path = 0u;
    var rehits_left = tp.bounces;
    // The dielectric the ray is in (NONE: outside every object), and the objects it
    // has left, for the re-hit rule.
    var inside = NONE;
    var left: array<u32, MAX_LEFT>;
    var left_count = 0u;
    var bounced = false;
    // Dielectric interfaces met so far (the bit of `reflect_mask` the next one reads).
    var interfaces_met = 0u;
    for (var event = 0u; event < MAX_EVENTS; event++) {
        let mat = materials[objects[object].material];
        let wi = -d;
        if dot(wi, ns) * dot(wi, ng) <= 0.0 {
            traced[i] = invalid(INVALID_WRONG_SIDE);
            count_vertex(INVALID_WRONG_SIDE);
            return;
        }
        let arrives_inside = dot(d, ng) > 0.0;
        path = mix_path(path, object, select(0u, 1u, arrives_inside));
        var wo: vec3<f32>;
        if mat.kind == MAT_MIRROR {
            // DESIGN: mirrors reflect with their reflectance at every angle, both sides.
            flux *= mat.color.xyz;
            wo = reflect(d, ns);
            if left_count < MAX_LEFT {
                left[left_count] = object;
                left_count++;
            }
        } else {
            // The shading normal on the side the light comes from.
            let n = select(ns, -ns, arrives_inside);
            let eta = select(1.0 / mat.ior, mat.ior, arrives_inside);
            let r = refract_facing(d, n, eta);
            let take_reflection = ((tp.reflect_mask >> interfaces_met) & 1u) == 1u;
            interfaces_met++;
            if take_reflection {
                // Fresnel reflection: F, or all of it under total internal reflection.
                flux *= select(1.0 - r.w, 1.0, r.w < 0.0);
                wo = reflect(d, n);
                if !arrives_inside && left_count < MAX_LEFT {
                    left[left_count] = object;
                    left_count++;
                }
            } else if r.w < 0.0 {
                traced[i] = invalid(INVALID_TIR);
                count_vertex(INVALID_TIR);
                return;
            } else {
                flux *= r.w;
                wo = r.xyz;
                if arrives_inside {
                    inside = NONE;
                    if left_count < MAX_LEFT {
                        left[left_count] = object;
                        left_count++;
                    }
                } else {
                    inside = object;
                }
            }
        }
        let k = adjoint_shading_factor(wi, wo, ns, ng);
        if k < 0.0 {
            traced[i] = invalid(INVALID_WRONG_SIDE);
            count_vertex(INVALID_WRONG_SIDE);
            return;
        }
        flux *= k;
        d = wo;

        // The next surface along the ray.
        let hit = scene_closest_hit(p, d, eps, NONE);
        if hit.object == NONE {
            traced[i] = invalid(INVALID_NO_RECEIVER);
            count_vertex(INVALID_NO_RECEIVER);
            return;
        }
        let q = p + hit.t * d;
        if materials[objects[hit.object].material].kind == MAT_DIFFUSE {
            if (tp.reflect_mask >> interfaces_met) != 0u {
                traced[i] = invalid(INVALID_OTHER_SHEET);
                count_vertex(INVALID_OTHER_SHEET);
                return;
            }
            var v: Traced;
            let side = select(1.0, -1.0, dot(d, hit.ns) > 0.0);
            v.old_pos = vec4<f32>(old_pos, 0.0);
            v.new_pos = vec4<f32>(q, side);
            v.flux = vec4<f32>(flux, 0.0);
            v.info = vec4<u32>(hit.object, INVALID_NONE, path, 0u);
            traced[i] = v;
            count_vertex(INVALID_NONE);
            if bounced {
                atomicAdd(&vertex_counts.bounced, 1u);
            }
            return;
        }
        // A specular surface: the exit of the object the ray is in, the next object of
        // a chain, or one already left (a further bounce).
        if hit.object != inside {
            var seen = false;
            for (var j = 0u; j < left_count; j++) {
                seen = seen || left[j] == hit.object;
            }
            if seen {
                if rehits_left == 0u {
                    traced[i] = invalid(INVALID_REHIT);
                    count_vertex(INVALID_REHIT);
                    return;
                }
                rehits_left--;
                bounced = true;
            }
        }
        p = q;
        ns = hit.ns;
        ng = hit.ng;
        object = hit.object;
    }
    traced[i] = invalid(INVALID_TOO_MANY_EVENTS);
    count_vertex(INVALID_TOO_MANY_EVENTS);
}
