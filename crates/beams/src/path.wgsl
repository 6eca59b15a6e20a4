// Light paths of grid vertices (Liktor & Dachsbacher 2011, Sect. 4.1 and 6): the
// first hit comes from the light G-buffer, two-sided refraction and further specular
// bounces from distance impostors (Szirmay-Kalos et al. 2005); with `tracer` = bvh
// (u.exact_trace) every hit comes from the scene's triangle BVH and analytic shapes
// instead, with the adjoint shading-normal factor at each event. Composed into
// generate.wgsl after types.wgsl, the impostor functions and triangle_bvh.wgsl.

@group(1) @binding(0) var<uniform> u: BeamUniforms;
@group(1) @binding(1) var light_position: texture_2d<f32>;
@group(1) @binding(2) var light_normal: texture_2d<f32>;
@group(1) @binding(3) var light_ids: texture_2d<u32>;
// The impostor atlas: specular slot k in layers 6k..6k+6, the diffuse receivers
// (around the generators' centre) after the last slot.
@group(1) @binding(4) var impostor_map: texture_2d_array<f32>;
@group(1) @binding(5) var impostor_ids: texture_2d_array<u32>;

// Objects a path meets (each generator once; `bounces` adds the meetings again).
const MAX_SPECULAR_EVENTS: u32 = 4u;
// Light-path families of a leaf (one beam each): the main path, the Fresnel
// reflection at the first interface, then FAMILY_INTERNAL + j - 1 for the light that
// reflects j times inside the first object, a closed refractor, before it leaves
// (j = 1..=bounces).
const FAMILY_MAIN: u32 = 0u;
const FAMILY_REFLECTED: u32 = 1u;
const FAMILY_INTERNAL: u32 = 2u;
// Signature events: first hit, exit of a closed refractor, next object, internal or
// total internal reflection.
const EVENT_INTERNAL: u32 = 3u;

struct Ray {
    origin: vec3<f32>,
    dir: vec3<f32>,
}

// The light ray through light-view uv (origin on the near plane).
fn light_ray(uv: vec2<f32>) -> Ray {
    let ndc = vec2<f32>(2.0 * uv.x - 1.0, 1.0 - 2.0 * uv.y);
    let a = u.light_inv_view_proj * vec4<f32>(ndc, 0.0, 1.0);
    let b = u.light_inv_view_proj * vec4<f32>(ndc, 1.0, 1.0);
    var r: Ray;
    r.origin = a.xyz / a.w;
    r.dir = normalize(b.xyz / b.w - r.origin);
    return r;
}

struct LightHit {
    hit: bool,
    position: vec3<f32>,
    // Shading normal (outward for closed objects) and geometric normal on its side
    // (the same from the light G-buffer, which stores one normal).
    normal: vec3<f32>,
    ng: vec3<f32>,
    object: u32,
}

// The light G-buffer at uv: bilinear where the four texels hold the same object,
// else the nearest texel; the position is then moved onto the light ray through uv
// (the tangent plane of the sampled surface), so a vertex's flux and its ray agree.
fn light_gbuffer_at(uv: vec2<f32>, ray: Ray) -> LightHit {
    var h: LightHit;
    h.hit = false;
    let res = vec2<f32>(textureDimensions(light_position));
    let st = uv * res - 0.5;
    let base = floor(st);
    let f = st - base;
    let hi = vec2<i32>(res) - 1;
    let p00 = clamp(vec2<i32>(base), vec2<i32>(0), hi);
    let p11 = clamp(vec2<i32>(base) + 1, vec2<i32>(0), hi);
    let p10 = vec2<i32>(p11.x, p00.y);
    let p01 = vec2<i32>(p00.x, p11.y);
    let i00 = textureLoad(light_ids, p00, 0).x;
    let i10 = textureLoad(light_ids, p10, 0).x;
    let i01 = textureLoad(light_ids, p01, 0).x;
    let i11 = textureLoad(light_ids, p11, 0).x;
    var q: vec4<f32>;
    var n: vec3<f32>;
    if i00 == i10 && i00 == i01 && i00 == i11 {
        if i00 == NONE {
            return h;
        }
        q = mix(mix(textureLoad(light_position, p00, 0), textureLoad(light_position, p10, 0), f.x),
                mix(textureLoad(light_position, p01, 0), textureLoad(light_position, p11, 0), f.x), f.y);
        n = mix(mix(textureLoad(light_normal, p00, 0).xyz, textureLoad(light_normal, p10, 0).xyz, f.x),
                mix(textureLoad(light_normal, p01, 0).xyz, textureLoad(light_normal, p11, 0).xyz, f.x), f.y);
        h.object = i00;
    } else {
        let pn = clamp(vec2<i32>(floor(uv * res)), vec2<i32>(0), hi);
        h.object = textureLoad(light_ids, pn, 0).x;
        if h.object == NONE {
            return h;
        }
        q = textureLoad(light_position, pn, 0);
        n = textureLoad(light_normal, pn, 0).xyz;
    }
    if q.w < 0.5 {
        return h;
    }
    n = normalize(n);
    let dn = dot(ray.dir, n);
    var t = dot(q.xyz - ray.origin, ray.dir);
    if abs(dn) > 1e-3 {
        t = dot(q.xyz - ray.origin, n) / dn;
    }
    h.hit = true;
    h.position = ray.origin + t * ray.dir;
    h.normal = n;
    h.ng = n;
    return h;
}

// Offset (m) past the surface a path leaves, for exact traces (wavefront's).
const EXACT_EPS: f32 = 1e-4;

// The first surface on the light ray, traced exactly (`tracer` = bvh). Anything
// between the light and the ray's origin (the light view's near plane) shadows it.
fn exact_first_hit(ray: Ray) -> LightHit {
    var h: LightHit;
    h.hit = false;
    let s = scene_closest_hit(ray.origin, ray.dir, 0.0, NONE);
    if s.object == NONE {
        return h;
    }
    var behind = NO_HIT;
    if u.light_dir_kind.w > 0.5 {
        behind = distance(ray.origin, u.light_pos_start.xyz);
    }
    if scene_closest_hit(ray.origin, -ray.dir, 0.0, NONE).t < behind {
        return h;
    }
    h.hit = true;
    h.position = ray.origin + s.t * ray.dir;
    h.normal = s.ns;
    h.ng = s.ng;
    h.object = s.object;
    return h;
}

// A surface a path meets after its first: from an impostor (`ng` = `normal`, the
// stored one; `object` unknown) or traced exactly.
struct PathHit {
    found: bool,
    t: f32,
    position: vec3<f32>,
    normal: vec3<f32>,
    ng: vec3<f32>,
    object: u32,
}

fn from_impostor(h: ImpostorHit) -> PathHit {
    var r: PathHit;
    r.found = h.found;
    r.t = h.t;
    r.position = h.position;
    r.normal = h.normal;
    r.ng = h.normal;
    r.object = NONE;
    return r;
}

// The closest surface of the scene past `o` along `d`, skipping object `skip`.
fn exact_hit(o: vec3<f32>, d: vec3<f32>, skip: u32) -> PathHit {
    let h = scene_closest_hit(o, d, EXACT_EPS, skip);
    var r: PathHit;
    r.found = h.object != NONE;
    r.t = h.t;
    r.position = o + h.t * d;
    r.normal = h.ns;
    r.ng = h.ng;
    r.object = h.object;
    return r;
}

// Where the light inside the closed refractor in `slot` meets its surface again.
fn exit_hit(slot: u32, p: vec3<f32>, d: vec3<f32>) -> PathHit {
    if u.exact_trace == 1u {
        var h = exact_hit(p, d, NONE);
        h.found = h.found && h.object == u.specular[slot].object;
        return h;
    }
    return from_impostor(trace_slot(slot, p, d, 1e-4, 2.0 * u.specular[slot].center_reach.w));
}

fn specular_slot_of(object: u32) -> u32 {
    for (var k = 0u; k < u.specular_count; k++) {
        if u.specular[k].object == object {
            return k;
        }
    }
    return NONE;
}

// One call site per query: WGSL inlines every call, and the search loop is large.
fn trace_slot(k: u32, o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32) -> ImpostorHit {
    let s = u.specular[k];
    return impostor_trace_at(impostor_map, i32(6u * k), s.center_reach.xyz, o, d, t_min, t_max,
                             u.impostor_tolerance * s.center_reach.w);
}

fn receiver_layer() -> i32 {
    return i32(6u * u.specular_count);
}

// Where a vertex's light leaves its last specular surface.
struct PathEnd {
    valid: bool,
    // Start of the beam edge (on the last specular surface) and its unit direction.
    origin: vec3<f32>,
    dir: vec3<f32>,
    // Flux weight: irradiance (directional) or intensity (positional) times every
    // Fresnel factor, reflectance and extinction along the way.
    weight: vec3<f32>,
    // Hash of the objects met (a silhouette of any of them changes it).
    signature: u32,
    first_object: u32,
    first_normal: vec3<f32>,
    // Distance from the light ray's origin to the first hit (m).
    first_depth: f32,
    first_point: vec3<f32>,
    light_dir: vec3<f32>,
    // Distance along `dir` to the receiver it lands on (m), and that receiver.
    t_end: f32,
    end_object: u32,
    // Slot of the first object (NONE where the light G-buffer shows no generator).
    first_slot: u32,
    // Further specular events taken (`bounces`): generators met again, and total
    // internal reflections (inside the first object or elsewhere).
    rehits: u32,
    tir: u32,
}

fn mix_signature(s: u32, object: u32, event: u32) -> u32 {
    return (s ^ (object * 4u + event + 1u)) * 0x9E3779B1u;
}

// Traces the light path of light-view uv in `family`. FAMILY_MAIN refracts at
// dielectrics (through closed ones: exit via the impostor) and reflects at mirrors;
// FAMILY_REFLECTED takes the Fresnel reflection at the first (dielectric) surface;
// FAMILY_INTERNAL + j - 1 reflects j times inside the first object (a closed
// refractor: each time with the Fresnel reflectance, or all of it under total internal
// reflection) and leaves at the next exit. The paper's path (`bounces` = 0, Fig. 4 and
// Sect. 6) ends at a total internal reflection and passes through a generator it meets
// again; with `bounces` > 0 the events beyond it share that budget: the family's
// internal reflections, then total internal reflections elsewhere (followed: no light
// is lost, no family needed) and generators met again (a ring's opposite wall, a
// concave mesh). Fresnel reflections inside a refractor other than the first object
// are not followed (they would need families of their own). With exact tracing every
// event also takes the adjoint shading-normal factor (1 on analytic shapes), and a
// path on which a mesh's shading and geometric normals disagree is dropped.
fn trace_path(uv: vec2<f32>, family: u32) -> PathEnd {
    var e: PathEnd;
    e.valid = false;
    e.first_slot = NONE;
    let ray = light_ray(uv);
    var g: LightHit;
    if u.exact_trace == 1u {
        g = exact_first_hit(ray);
    } else {
        g = light_gbuffer_at(uv, ray);
    }
    if !g.hit {
        return e;
    }
    var slot = specular_slot_of(g.object);
    if slot == NONE {
        return e;
    }
    e.first_slot = slot;
    e.first_object = g.object;
    e.first_normal = g.normal;
    e.first_depth = dot(g.position - ray.origin, ray.dir);
    e.first_point = g.position;
    e.light_dir = ray.dir;
    // Internal reflections the family takes in the first object, and the rest of the
    // `bounces` budget for the other further events.
    // The Fresnel reflection is a dielectric's (a mirror's reflection is the main path).
    if family == FAMILY_REFLECTED && u.specular[slot].kind != MAT_DIELECTRIC {
        return e;
    }
    var internal = 0u;
    if family >= FAMILY_INTERNAL {
        let first = u.specular[slot];
        internal = family - FAMILY_INTERNAL + 1u;
        if first.kind != MAT_DIELECTRIC || first.closed != 1u || internal > u.bounces {
            return e;
        }
    }
    var budget = u.bounces - internal;
    var w: vec3<f32>;
    if u.light_dir_kind.w < 0.5 {
        w = u.light_power.xyz * extinction(dot(g.position, ray.dir) - u.light_pos_start.w);
    } else {
        let light = lights[u.light_index];
        w = light_intensity(light, ray.dir) * extinction(distance(g.position, u.light_pos_start.xyz));
    }
    var p = g.position;
    var d = ray.dir;
    var n = g.normal;
    var ng = g.ng;
    var sig = mix_signature(0u, g.object, 0u);
    for (var event = 0u; event < MAX_SPECULAR_EVENTS + u.bounces; event++) {
        let s = u.specular[slot];
        // Normal of the surface the path leaves at this event (the exit's, through a
        // closed refractor), to tell meeting it again from grazing it.
        var n_leave = n;
        let nf = select(n, -n, dot(d, n) > 0.0);
        let cos_i = -dot(d, nf);
        let d_in = d;
        if s.kind == MAT_MIRROR {
            d = reflect(d, nf);
            w *= s.color.xyz;
        } else {
            let entering = dot(d, n) < 0.0;
            let eta = select(s.ior, 1.0 / s.ior, entering);
            let fresnel = fresnel_dielectric(cos_i, eta);
            if family == FAMILY_REFLECTED && event == 0u {
                d = reflect(d, nf);
                w *= fresnel;
            } else {
                let t = refract(d, nf, eta);
                if dot(t, t) < 0.5 {
                    // Total internal reflection at a surface met from inside (an open
                    // refractor from below): the paper's path ends here.
                    if budget == 0u {
                        return e;
                    }
                    budget -= 1u;
                    e.tir += 1u;
                    d = reflect(d, nf);
                    sig = mix_signature(sig, s.object, EVENT_INTERNAL);
                } else {
                    w *= 1.0 - fresnel;
                    d = normalize(t);
                }
            }
        }
        let k_event = adjoint_shading_factor(-d_in, d, n, ng);
        if k_event < 0.0 {
            return e;
        }
        w *= k_event;
        if s.kind != MAT_MIRROR && s.closed == 1u && dot(d_in, n) < 0.0 && dot(d, n) < 0.0 {
            // Two-sided refraction (Sect. 6): the exit point (from the impostor, or
            // traced), after the internal reflections the path takes. Each pass of the
            // loop reflects (spending `wanted` or `budget`) or leaves.
            var wanted = select(0u, internal, event == 0u);
            // In the first object the count of internal reflections is the
            // family's: a total internal reflection beyond it is another
            // family's light, not this one's.
            let counted = event == 0u && family != FAMILY_REFLECTED;
            var left = false;
            for (var k = 0u; k <= u.bounces; k++) {
                let h = exit_hit(slot, p, d);
                if !h.found {
                    return e;
                }
                w *= extinction(h.t);
                p = h.position;
                let n_out = h.normal;
                let cos_o = dot(d, n_out);
                let f_out = fresnel_dielectric(abs(cos_o), s.ior);
                let t2 = refract(d, select(n_out, -n_out, cos_o > 0.0), s.ior);
                let tir = dot(t2, t2) < 0.5;
                var reflects = wanted > 0u;
                if tir && !reflects {
                    if counted || budget == 0u {
                        return e;
                    }
                    budget -= 1u;
                    reflects = true;
                } else if reflects {
                    wanted -= 1u;
                }
                let d_inside = d;
                if reflects {
                    // f_out is 1 under total internal reflection.
                    w *= f_out;
                    e.tir += u32(tir);
                    d = reflect(d, n_out);
                    sig = mix_signature(sig, s.object, EVENT_INTERNAL);
                } else {
                    w *= 1.0 - f_out;
                    d = normalize(t2);
                    n_leave = n_out;
                    sig = mix_signature(sig, s.object, 1u);
                    left = true;
                }
                let k_exit = adjoint_shading_factor(-d_inside, d, n_out, h.ng);
                if k_exit < 0.0 {
                    return e;
                }
                w *= k_exit;
                if left {
                    break;
                }
            }
            if !left {
                return e;
            }
        }
        // The receiver this edge would land on, and any specular object before it.
        var t_receiver = u.scene_reach;
        var end_object = NONE;
        var next = NONE;
        var best: PathHit;
        if u.exact_trace == 1u {
            // The paper's path passes through the surface it left (`bounces` = 0).
            let h = exact_hit(p, d, select(NONE, s.object, budget == 0u));
            if h.found {
                let k = specular_slot_of(h.object);
                if k == NONE {
                    t_receiver = h.t;
                    end_object = h.object;
                } else {
                    // A closed generator met again is met from outside; from inside it
                    // is the surface just left, found again by rounding.
                    if k == slot && s.closed == 1u && dot(d, h.ng) > 0.0 {
                        return e;
                    }
                    next = k;
                    best = h;
                }
            }
        } else {
            let r = impostor_trace_at(impostor_map, receiver_layer(), u.receivers.xyz, p, d, 1e-4,
                                      2.0 * u.scene_reach, u.impostor_tolerance * u.receivers.w);
            if r.found {
                t_receiver = r.t;
                end_object = impostor_object_at(impostor_ids, receiver_layer(), r.position - u.receivers.xyz);
            }
            var nearest: ImpostorHit;
            nearest.t = t_receiver;
            for (var k = 0u; k < u.specular_count; k++) {
                // The paper's path does not meet the surface it just left again (convex
                // or open generators; the stated limit of impostor tracing). With
                // `bounces` left it may (the ring's opposite wall): that search starts 5 %
                // of the reach away, so the point just left is not found again (as
                // photon-hits), and not at all where the receiver is nearer (a search
                // with t_max below t_min runs backwards, into the object just left).
                var t_min = 1e-4;
                if k == slot {
                    t_min = 0.05 * u.specular[k].center_reach.w;
                    if budget == 0u || t_min >= t_receiver {
                        continue;
                    }
                }
                let h = trace_slot(k, p, d, t_min, t_receiver);
                // The same surface met again is approached from the side the path left
                // it on. A closed one (normals stored outward) is met from outside: the
                // path left it outwards and meets it inwards; one left inwards is an exit
                // the impostor search misplaced onto the entry (where the paper's path
                // passes through, and so does this one).
                var again = k != slot;
                if k == slot {
                    let leave = dot(d, n_leave);
                    let meet = dot(d, h.normal);
                    let outside = (leave > 0.0) && (meet < 0.0);
                    again = select((leave * meet) < 0.0, outside, u.specular[k].closed == 1u);
                }
                if h.found && h.t < nearest.t && again {
                    nearest = h;
                    next = k;
                }
            }
            best = from_impostor(nearest);
        }
        if next == NONE {
            e.valid = true;
            e.origin = p;
            e.dir = d;
            e.weight = w;
            e.signature = sig;
            e.t_end = t_receiver;
            e.end_object = end_object;
            return e;
        }
        if next == slot {
            budget -= 1u;
            e.rehits += 1u;
        }
        w *= extinction(best.t);
        p = best.position;
        n = best.normal;
        ng = best.ng;
        slot = next;
        sig = mix_signature(sig, u.specular[next].object, 2u);
    }
    return e;
}
