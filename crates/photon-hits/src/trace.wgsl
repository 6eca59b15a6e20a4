// Photon tracing pass (Umenhoffer, Patow, Szirmay-Kalos §4.1): one invocation per
// texel of the light's view of the caustic generator. The light G-buffer gives the
// first surface the light meets; where that is the generator, the light ray is
// reflected (mirror) or refracted (dielectric, exact Fresnel), leaves a closed
// refractor through the exit point found in the generator's own distance map (§3:
// linear then secant search), and lands on the diffuse receiver found in the distance
// map of the receivers around the generator's centre (the paper's layered distance
// map of the environment). The texel's flux is the light's power through the texel
// times the Fresnel transmittances or the mirror's reflectance (§4.1).
//
// That is the default path (one event per interface, §4.1's Fresnel factors), sheet 0
// of the hit image. Beyond it (off by default, the `bounces` and `reflections`
// parameters) each texel also follows:
// * inside a closed refractor, the light reflected at the exit (Fresnel, or all of it
//   under total internal reflection), up to `bounces` internal reflections; the light
//   leaving after j of them is sheet j, so each sheet is one smooth specular path and
//   triangles never join two;
// * off a mirror, further reflections on the generator itself (the ring's opposite
//   wall), up to `bounces`, in sheet 0 with their own path id;
// * off a dielectric, the Fresnel reflection at the first interface, in the last sheet;
// * light meeting another specular object after the generator (a chain: the ball's
//   light on the water), traced on exactly through the scene's BVH (`chain_on`), up to
//   `bounces` events, in the sheet of its path with a path id of its own.
// Hit slot of (sheet, face, texel): (sheet × faces + face) × texels per face + texel.
//
// Silhouette hits (FLAG_SILHOUETTE, the photon-hit methods' `silhouette_hits`, off by
// default as in the paper): a texel whose centre's light misses the generator but one
// of whose eight neighbours meets it stands for the generator's edge between them. Its
// ray is bisected between the two texel centres against the exact scene (the triangle
// BVH and the analytic shapes) to the last direction that still meets the generator,
// and that light is traced on as any texel's, landing as HIT_EDGE. It carries the
// light of the part of its texel on the generator's side of the edge (the texel spans
// the second half of the way from the neighbour's centre on; the paper drops that
// light with the texel). Triangles then reach the silhouette's landing instead of
// stopping one texel short of it: a one-texel strip that a fast-turning reflection
// (the ring's rim) spreads over tens of centimetres of floor.

struct TraceUniform {
    // Faces of the light view (1 or 6).
    faces: u32,
    // Texels per side of a face.
    resolution: u32,
    // The caustic generator (object index).
    generator: u32,
    // Bit 0: closed refractor (two interfaces); bit 1: orthographic light view.
    flags: u32,
    // xyz: the receivers' distance map centre (= the caustic map centre); w: its reach (m).
    center: vec4<f32>,
    // xyz: the generator's distance map centre; w: its reach (m).
    generator_center: vec4<f32>,
    // x: texel size (m for orthographic, tan units per texel for perspective);
    // y: tan of the half field of view (perspective); z unused;
    // w: search tolerance relative to a map's reach.
    view: vec4<f32>,
    // x: further specular events followed on the generator (`bounces`); y: sheets of
    // the hit image; z: the Fresnel-reflection sheet, or NONE; w: the light (index into `lights`).
    paths: vec4<u32>,
    // Clip → world of each face of the light view (silhouette hits: texel rays).
    clip_to_world: array<mat4x4<f32>, 6>,
}

const FLAG_CLOSED: u32 = 1u;
const FLAG_ORTHOGRAPHIC: u32 = 2u;
const FLAG_SILHOUETTE: u32 = 4u;

@group(1) @binding(0) var<uniform> tu: TraceUniform;
@group(1) @binding(1) var light_position: texture_2d_array<f32>;
@group(1) @binding(2) var light_normal: texture_2d_array<f32>;
@group(1) @binding(3) var light_ids: texture_2d_array<u32>;
@group(1) @binding(4) var generator_map: texture_2d_array<f32>;
@group(1) @binding(5) var generator_ids: texture_2d_array<u32>;
@group(1) @binding(6) var receiver_map: texture_2d_array<f32>;
@group(1) @binding(7) var receiver_ids: texture_2d_array<u32>;
@group(1) @binding(8) var<storage, read_write> hits: array<PhotonHit>;
// One counter per HIT_* reason (per hit slot), then the valid hits of the Fresnel
// reflection (COUNTER_REFLECTED) and of each further bounce k (COUNTER_BOUNCE + k - 1).
@group(1) @binding(9) var<storage, read_write> trace_counters: array<atomic<u32>>;

// HIT_EDGE's counter is the slot after the HIT_* reasons (index 7).
const COUNTER_REFLECTED: u32 = 8u;
const COUNTER_BOUNCE: u32 = 9u;
// The valid hits whose light took a chain through another specular object (after the
// bounce orders: COUNTER_BOUNCE + MAX_BOUNCES).
const COUNTER_CHAINED: u32 = 17u;
// Path ids: (generator × 2 + side) × PATH_ORDERS + order, where order is the number of
// specular events beyond the default path, or PATH_REFLECTED for the Fresnel reflection.
const PATH_ORDERS: u32 = 16u;
const PATH_REFLECTED: u32 = 15u;

// Refracts unit `d` at a surface with outward normal `n_out` of a dielectric of index
// `ior` (outside 1.0). xyz: new direction; w: Fresnel transmittance, or -1 under total
// internal reflection.
fn refract_through(d: vec3<f32>, n_out: vec3<f32>, ior: f32) -> vec4<f32> {
    let entering = dot(d, n_out) < 0.0;
    let n = select(-n_out, n_out, entering);
    let eta = select(ior, 1.0 / ior, entering);
    let f = fresnel_dielectric(-dot(d, n), eta);
    let t = refract(d, n, eta);
    if f >= 1.0 || dot(t, t) < 0.5 {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    return vec4<f32>(normalize(t), 1.0 - f);
}

// The receiver along o + t·d: the distance-map search over ranges that grow fourfold
// (reach/64, /16, /4, 1, 2 × the reach). `impostor_trace` marches even steps over its
// range; over the whole reach at once, a receiver a few centimetres from the start
// falls inside the first step, and is missed when that step begins where the map
// stores no surface (a ray leaving the ring's wall above the map's centre, whose
// direction from the centre sees no receiver yet). Ranges that grow with the distance
// travelled keep the steps proportional to it.
fn trace_receiver(o: vec3<f32>, d: vec3<f32>) -> ImpostorHit {
    let c = tu.center.xyz;
    let reach = tu.center.w;
    let tolerance = tu.view.w * reach;
    var t0 = 1e-4 * reach;
    var t1 = reach / 64.0;
    var hit: ImpostorHit;
    hit.found = false;
    for (var k = 0u; k < 5u; k++) {
        hit = impostor_trace(receiver_map, c, o, d, t0, t1, tolerance);
        if hit.found {
            return hit;
        }
        t0 = t1;
        t1 = min(4.0 * t1, 2.0 * reach);
    }
    return hit;
}

fn store_invalid(slot: u32, why: u32) {
    var h: PhotonHit;
    h.ids = vec4<u32>(NONE, 0u, why, 0u);
    hits[slot] = h;
    atomicAdd(&trace_counters[why], 1u);
}

// Hit slot of `sheet` for the texel at `texel_slot` of sheet 0.
fn sheet_slot(texel_slot: u32, sheet: u32) -> u32 {
    return texel_slot + sheet * tu.faces * tu.resolution * tu.resolution;
}

// Whether the texel being traced is a silhouette texel (a private, since `land`
// stores it with every sheet).
var<private> on_edge: bool = false;

// Stores a landing on diffuse `receiver` at `x` (normal `n`, on the side the light
// arrives on) in `slot`. A silhouette texel's landing is stored as HIT_EDGE (counted
// apart; a valid hit otherwise): false then, true for a valid hit.
fn store_landing(slot: u32, x: vec3<f32>, n: vec3<f32>, flux: vec3<f32>, receiver: u32, path: u32, footprint: f32) -> bool {
    var h: PhotonHit;
    h.position = vec4<f32>(x, length(x - tu.center.xyz));
    h.normal = vec4<f32>(n, footprint);
    h.flux = vec4<f32>(flux, 0.0);
    if on_edge {
        h.ids = vec4<u32>(receiver, path, HIT_EDGE, 0u);
        hits[slot] = h;
        atomicAdd(&trace_counters[HIT_EDGE], 1u);
        return false;
    }
    h.ids = vec4<u32>(receiver, path, HIT_VALID, 0u);
    hits[slot] = h;
    atomicAdd(&trace_counters[HIT_VALID], 1u);
    return true;
}

// Light leaving the generator at `p` along `d` with `flux`: the receiver it lands on,
// stored in `slot`; false (and the slot invalid) where it lands on none. Light that
// meets another specular object first is a chain (`chain_on`) with `bounces` > 0, and
// dropped without (the paper's one hit image per generator).
fn land(slot: u32, p: vec3<f32>, d: vec3<f32>, flux: vec3<f32>, path: u32, footprint: f32) -> bool {
    // The receiver: the distance map of the diffuse objects around the centre.
    let c = tu.center.xyz;
    let hit = trace_receiver(p, d);
    if !hit.found {
        store_invalid(slot, HIT_NO_RECEIVER);
        return false;
    }
    let receiver = impostor_object(receiver_ids, hit.position - c);
    if receiver == NONE || materials[objects[receiver].material].kind != MAT_DIFFUSE {
        // The generator itself met again (a concave mesh) is not a chain: light
        // leaving a closed refractor is not refracted into it again (crate doc).
        if receiver != NONE && receiver != tu.generator && tu.paths.x > 0u {
            return chain_on(slot, p, d, flux, path, footprint);
        }
        store_invalid(slot, HIT_SPECULAR_RECEIVER);
        return false;
    }
    let n = select(hit.normal, -hit.normal, dot(hit.normal, d) > 0.0);
    return store_landing(slot, hit.position, n, flux, receiver, path, footprint);
}

// A chain (`bounces` > 0): light that left the generator and meets another specular
// object (the ball's light on the water) is traced on exactly, through the scene's
// BVH and analytic shapes, until a diffuse surface takes it, as §4.1's ray "is traced,
// possibly multiple times, until a diffuse or glossy surface is found". Up to
// `bounces` specular events on the way: a mirror reflects (its reflectance), a
// dielectric refracts (its Fresnel transmittance; all of the light is reflected under
// total internal reflection; the Fresnel-reflected part is not followed), each with
// the adjoint shading-normal factor of a mesh (Veach 1997, §5.3). The landing is in
// the generator's caustic map like any other (its distance from the map's centre is
// what the camera pass tests), under a path id of its own (`chain_path`), so
// triangles join only texels whose light took the same chain. Counted apart
// (COUNTER_CHAINED) and among the valid hits.
fn chain_on(slot: u32, p: vec3<f32>, d: vec3<f32>, flux: vec3<f32>, path: u32, footprint: f32) -> bool {
    let eps = 1e-4 * tu.center.w;
    var o = p;
    var dir = d;
    var f = flux;
    // The first segment leaves the generator: skip it (its distance map said so).
    var skip = tu.generator;
    var first = NONE;
    for (var events = 0u; events <= tu.paths.x; events++) {
        let h = scene_closest_hit(o, dir, eps, skip);
        if h.object == NONE {
            store_invalid(slot, HIT_NO_RECEIVER);
            return false;
        }
        let x = o + h.t * dir;
        let m = materials[objects[h.object].material];
        if m.kind == MAT_DIFFUSE {
            let n = select(h.ns, -h.ns, dot(h.ns, dir) > 0.0);
            let chained = events > 0u;
            let landed = store_landing(slot, x, n, f, h.object, select(path, chain_path(path, first, events), chained), footprint);
            if landed && chained {
                atomicAdd(&trace_counters[COUNTER_CHAINED], 1u);
            }
            return landed;
        }
        if events == tu.paths.x {
            break;
        }
        if first == NONE {
            first = h.object;
        }
        var next: vec3<f32>;
        if m.kind == MAT_MIRROR {
            next = reflect(dir, h.ns);
            f *= m.color.xyz;
        } else {
            let r = refract_through(dir, h.ns, m.ior);
            if r.w < 0.0 {
                next = reflect(dir, h.ns);
            } else {
                next = r.xyz;
                f *= r.w;
            }
        }
        let k = adjoint_shading_factor(-dir, next, h.ns, h.ng);
        if k < 0.0 {
            store_invalid(slot, HIT_SPECULAR_RECEIVER);
            return false;
        }
        f *= k;
        o = x;
        dir = next;
        skip = NONE;
    }
    store_invalid(slot, HIT_SPECULAR_RECEIVER);
    return false;
}

// The path id of light that took a chain from `path` through specular object `first`
// with `events` specular events: bit 31 set, then the object (9 bits) and the events
// (3 bits) above the generator's own path ids (< 2^19: generators < 16,384).
fn chain_path(path: u32, first: u32, events: u32) -> u32 {
    return 0x80000000u | ((first & 0x1FFu) << 22u) | ((events & 7u) << 19u) | (path & 0x7FFFFu);
}

// The world ray of the light view through texel coordinates `uv` (texels, centres at
// +0.5) of face `layer`.
struct TexelRay {
    o: vec3<f32>,
    d: vec3<f32>,
}

fn texel_ray(layer: i32, uv: vec2<f32>) -> TexelRay {
    let n = f32(tu.resolution);
    // Row 0 at the top: NDC y up.
    let ndc = vec2<f32>(uv.x / n * 2.0 - 1.0, 1.0 - uv.y / n * 2.0);
    let m = tu.clip_to_world[layer];
    let near = m * vec4<f32>(ndc, 0.0, 1.0);
    let far = m * vec4<f32>(ndc, 1.0, 1.0);
    let a = near.xyz / near.w;
    let b = far.xyz / far.w;
    return TexelRay(a, normalize(b - a));
}

// The first surface along `r` if it is the generator (object NONE otherwise).
fn generator_hit(r: TexelRay) -> SceneHit {
    let hit = scene_closest_hit(r.o, r.d, 0.0, NONE);
    if hit.object != tu.generator {
        return SceneHit(NO_HIT, NONE, vec3<f32>(0.0), vec3<f32>(0.0));
    }
    return hit;
}

// The generator's edge next to `texel` (which misses it): the first of its eight
// neighbours that meets the generator in the light G-buffer, and the last direction
// between the two texel centres that still meets it exactly (8 bisections: 1/256 of a
// texel). found = false where there is none; `fraction` is the share of this texel's
// light on the generator's side (the texel spans [0.5, 1.5] of the way from the
// neighbour's centre, the edge lies at `lo` ∈ [0, 1]: max(lo − 0.5, 0)).
struct Edge {
    found: bool,
    point: vec3<f32>,
    n: vec3<f32>,
    fraction: f32,
}

fn silhouette_edge(texel: vec2<i32>, layer: i32) -> Edge {
    var none: Edge;
    none.found = false;
    let res = i32(tu.resolution);
    let offsets = array<vec2<i32>, 8>(
        vec2<i32>(1, 0), vec2<i32>(-1, 0), vec2<i32>(0, 1), vec2<i32>(0, -1),
        vec2<i32>(1, 1), vec2<i32>(-1, 1), vec2<i32>(1, -1), vec2<i32>(-1, -1),
    );
    for (var k = 0u; k < 8u; k++) {
        let q = texel + offsets[k];
        if any(q < vec2<i32>(0)) || any(q >= vec2<i32>(res)) {
            continue;
        }
        let q_pos = textureLoad(light_position, q, layer, 0);
        if q_pos.w < 0.5 || textureLoad(light_ids, q, layer, 0).x != tu.generator {
            continue;
        }
        let inside = vec2<f32>(q) + 0.5;
        let outside = vec2<f32>(texel) + 0.5;
        var best_ray = texel_ray(layer, inside);
        var best = generator_hit(best_ray);
        if best.object == NONE {
            // The exact scene and the rasterized G-buffer disagree at this texel.
            continue;
        }
        var lo = 0.0;
        var hi = 1.0;
        for (var step = 0u; step < 8u; step++) {
            let mid = 0.5 * (lo + hi);
            let ray = texel_ray(layer, mix(inside, outside, vec2<f32>(mid)));
            let hit = generator_hit(ray);
            if hit.object != NONE {
                lo = mid;
                best = hit;
                best_ray = ray;
            } else {
                hi = mid;
            }
        }
        var e: Edge;
        e.found = true;
        e.point = best_ray.o + best.t * best_ray.d;
        e.n = best.ns;
        e.fraction = max(lo - 0.5, 0.0);
        return e;
    }
    return none;
}

// A valid hit of a further bounce `order` (≥ 1) or of the reflection is also counted
// on its own.
fn count_order(order: u32) {
    if order == PATH_REFLECTED {
        atomicAdd(&trace_counters[COUNTER_REFLECTED], 1u);
    } else if order > 0u {
        atomicAdd(&trace_counters[COUNTER_BOUNCE + order - 1u], 1u);
    }
}

@compute @workgroup_size(64)
fn trace_photons(@builtin(global_invocation_id) gid: vec3<u32>) {
    let per_face = tu.resolution * tu.resolution;
    let i = gid.x;
    if i >= per_face * tu.faces {
        return;
    }
    let sheets = tu.paths.y;
    let layer = i32(i / per_face);
    let k = i % per_face;
    let texel = vec2<i32>(i32(k % tu.resolution), i32(k / tu.resolution));
    let pos = textureLoad(light_position, texel, layer, 0);
    let obj_id = textureLoad(light_ids, texel, layer, 0).x;
    var p0 = pos.xyz;
    var n_g = normalize(textureLoad(light_normal, texel, layer, 0).xyz);
    var edge: Edge;
    edge.found = false;
    if pos.w < 0.5 || obj_id != tu.generator {
        if (tu.flags & FLAG_SILHOUETTE) != 0u {
            edge = silhouette_edge(texel, layer);
        }
        if !edge.found {
            // The light meets nothing, or a diffuse object first: no caustic path here.
            for (var s = 0u; s < sheets; s++) {
                store_invalid(sheet_slot(i, s), HIT_NOT_GENERATOR);
            }
            return;
        }
        // Traced from the generator's edge beside this texel.
        p0 = edge.point;
        n_g = edge.n;
        on_edge = true;
    }
    let light = lights[tu.paths.w];
    // Direction of the texel's light and the power through the texel (§4.1: "the power
    // going through a pixel of the light's camera"): irradiance × texel area for a
    // directional light, intensity × texel solid angle for a point/spot light, where a
    // texel at tan-plane coordinates (x, y) subtends s² / (1 + x² + y²)^(3/2).
    var d: vec3<f32>;
    var flux: vec3<f32>;
    var footprint: f32;
    let ts = tu.view.x;
    if (tu.flags & FLAG_ORTHOGRAPHIC) != 0u {
        d = light.direction.xyz;
        footprint = ts * ts;
        flux = light.power.xyz * footprint;
    } else {
        let to = p0 - light.position.xyz;
        let dist = length(to);
        d = to / dist;
        let xy = ((vec2<f32>(texel) + 0.5) * 2.0 / f32(tu.resolution) - 1.0) * tu.view.y;
        let omega = ts * ts / pow(1.0 + dot(xy, xy), 1.5);
        flux = light_intensity(light, d) * omega;
        footprint = omega * dist * dist;
    }
    if on_edge {
        // The share of the texel's light on the generator's side of the edge; the
        // footprint stays the texel's, for the stretch rule of its triangles.
        flux *= edge.fraction;
    }
    let mat = materials[objects[tu.generator].material];
    // Path id: the generator and the side of its surface the light met (the ring's
    // inner and outer walls make two sheets that must not be joined by triangles),
    // then the order of the path.
    let path = (tu.generator * 2u + select(0u, 1u, dot(d, n_g) > 0.0)) * PATH_ORDERS;
    let bounces = tu.paths.x;
    let gen_center = tu.generator_center.xyz;
    let reach = tu.generator_center.w;
    let tolerance = tu.view.w * reach;
    if mat.kind == MAT_MIRROR {
        // DESIGN: mirrors reflect with their reflectance at every angle, on both sides.
        var p = p0;
        var n = n_g;
        for (var order = 0u; ; order++) {
            flux *= mat.color.xyz;
            d = reflect(d, n);
            // A further meeting with the generator (a ray crossing the ring to its
            // other wall) is a further specular event, followed up to `bounces`. The
            // search starts 5 % of the map's reach away so the reflection point itself
            // (tessellated vs stored surface) is not taken for a crossing.
            let again = impostor_trace(generator_map, gen_center, p, d, 0.05 * reach, 2.0 * reach, tolerance);
            if !again.found {
                if land(i, p, d, flux, path + order, footprint) {
                    count_order(order);
                }
                return;
            }
            if order >= bounces {
                store_invalid(i, HIT_SECOND_BOUNCE);
                return;
            }
            p = again.position;
            n = again.normal;
        }
    }
    let r1 = refract_through(d, n_g, mat.ior);
    if tu.paths.z != NONE {
        // The light the first interface reflects (from outside no TIR: r1.w ≥ 0).
        let reflected = sheet_slot(i, tu.paths.z);
        if land(reflected, p0, reflect(d, n_g), flux * (1.0 - max(r1.w, 0.0)), path + PATH_REFLECTED, footprint) {
            count_order(PATH_REFLECTED);
        }
    }
    if r1.w < 0.0 {
        for (var s = 0u; s <= bounces && s < sheets; s++) {
            if s != tu.paths.z {
                store_invalid(sheet_slot(i, s), HIT_TIR);
            }
        }
        return;
    }
    flux *= r1.w;
    d = r1.xyz;
    if (tu.flags & FLAG_CLOSED) == 0u {
        // An open refractor (water): the light stays in the medium below the surface.
        if land(i, p0, d, flux, path, footprint) {
            count_order(0u);
        }
        return;
    }
    // Exit points from the refractor's own distance map (§3). Each search starts 5 %
    // of the reach inside: chords through a sphere of index 1.5 are at least 1.49 R
    // long, and the point just left must not count as the next one.
    var p = p0;
    for (var order = 0u; order <= bounces; order++) {
        let slot = sheet_slot(i, order);
        let exit = impostor_trace(generator_map, gen_center, p, d, 0.05 * reach, 2.0 * reach, tolerance);
        if !exit.found {
            for (var s = order; s <= bounces; s++) {
                store_invalid(sheet_slot(i, s), HIT_NO_EXIT);
            }
            return;
        }
        p = exit.position;
        let r2 = refract_through(d, exit.normal, mat.ior);
        var kept = 1.0;
        if r2.w < 0.0 {
            // Total internal reflection: all of the light goes on inside.
            store_invalid(slot, HIT_TIR);
        } else {
            if land(slot, p, r2.xyz, flux * r2.w, path + order, footprint) {
                count_order(order);
            }
            kept = 1.0 - r2.w;
        }
        flux *= kept;
        d = reflect(d, exit.normal);
    }
}
