// Approximate ray tracing against a distance impostor (Szirmay-Kalos, Aszódi, Lazányi,
// Premecz 2005, "Approximate ray-tracing on the GPU with distance impostors"): the
// surface is the set of points p with |p - c| = d(p - c), where d is the distance
// stored in direction p - c of a cube map around the centre c. A ray is marched in
// growing steps until f(t) = |p(t) - c| - d(p(t) - c) changes sign, then refined by
// secant steps. Exact for surfaces that are star-shaped around c (a sphere from its
// centre, a heightfield from a point below it); approximate otherwise, which is the
// method's (and the papers') stated limitation.
//
// Methods bind the impostor's `normal_distance` (texture_2d_array<f32>, 6 layers in
// the order +X, -X, +Y, -Y, +Z, -Z) and `object` (texture_2d_array<u32>) textures and
// pass them to these functions. An atlas holds several impostors, one per 6 layers;
// the `_at` variants take the first layer of one. (One call site per query keeps
// shaders small: WGSL functions are inlined at every call.)

// Face and texel coordinates of a direction: the usual cube-map convention
// (Vulkan spec, "Cube Map Face Selection"). Returns (u, v in [0, 1], face).
fn impostor_face_uv(d: vec3<f32>) -> vec3<f32> {
    let a = abs(d);
    var face: f32;
    var sc: f32;
    var tc: f32;
    var ma: f32;
    if a.x >= a.y && a.x >= a.z {
        ma = a.x;
        if d.x > 0.0 { face = 0.0; sc = -d.z; tc = -d.y; } else { face = 1.0; sc = d.z; tc = -d.y; }
    } else if a.y >= a.z {
        ma = a.y;
        if d.y > 0.0 { face = 2.0; sc = d.x; tc = d.z; } else { face = 3.0; sc = d.x; tc = -d.z; }
    } else {
        ma = a.z;
        if d.z > 0.0 { face = 4.0; sc = d.x; tc = -d.y; } else { face = 5.0; sc = -d.x; tc = -d.y; }
    }
    let m = max(ma, 1e-30);
    return vec3<f32>(0.5 * (sc / m + 1.0), 0.5 * (tc / m + 1.0), face);
}

// Normal (xyz) and distance (w, 0 where no surface) in direction `d`, bilinear within
// the face. Texels with no surface are not blended into ones with a surface (a
// silhouette stays a silhouette): if any of the four is empty, the nearest is taken.
fn impostor_fetch(map: texture_2d_array<f32>, d: vec3<f32>) -> vec4<f32> {
    return impostor_fetch_at(map, 0, d);
}

fn impostor_fetch_at(map: texture_2d_array<f32>, base_layer: i32, d: vec3<f32>) -> vec4<f32> {
    let res = vec2<f32>(textureDimensions(map));
    let fuv = impostor_face_uv(d);
    let layer = base_layer + i32(fuv.z);
    let st = fuv.xy * res - 0.5;
    let base = floor(st);
    let f = st - base;
    let hi = vec2<i32>(res) - 1;
    let p00 = clamp(vec2<i32>(base), vec2<i32>(0), hi);
    let p11 = clamp(vec2<i32>(base) + 1, vec2<i32>(0), hi);
    let t00 = textureLoad(map, p00, layer, 0);
    let t10 = textureLoad(map, vec2<i32>(p11.x, p00.y), layer, 0);
    let t01 = textureLoad(map, vec2<i32>(p00.x, p11.y), layer, 0);
    let t11 = textureLoad(map, p11, layer, 0);
    if min(min(t00.w, t10.w), min(t01.w, t11.w)) <= 0.0 {
        let nearest = clamp(vec2<i32>(floor(fuv.xy * res)), vec2<i32>(0), hi);
        return textureLoad(map, nearest, layer, 0);
    }
    return mix(mix(t00, t10, f.x), mix(t01, t11, f.x), f.y);
}

// Object index stored in direction `d` (nearest texel).
fn impostor_object(ids: texture_2d_array<u32>, d: vec3<f32>) -> u32 {
    return impostor_object_at(ids, 0, d);
}

fn impostor_object_at(ids: texture_2d_array<u32>, base_layer: i32, d: vec3<f32>) -> u32 {
    let res = vec2<f32>(textureDimensions(ids));
    let fuv = impostor_face_uv(d);
    let p = clamp(vec2<i32>(floor(fuv.xy * res)), vec2<i32>(0), vec2<i32>(res) - 1);
    return textureLoad(ids, p, base_layer + i32(fuv.z), 0).x;
}

struct ImpostorHit {
    found: bool,
    // Ray parameter of the hit (m along a unit direction).
    t: f32,
    position: vec3<f32>,
    // Unit normal as stored (outward for closed meshes).
    normal: vec3<f32>,
}

// f(t) of the search; +1e30 where the cube map stores no surface (never a crossing).
fn impostor_f(map: texture_2d_array<f32>, base_layer: i32, center: vec3<f32>, p: vec3<f32>) -> f32 {
    let l = p - center;
    let s = impostor_fetch_at(map, base_layer, l);
    if s.w <= 0.0 {
        return 1e30;
    }
    return length(l) - s.w;
}

const IMPOSTOR_LINEAR_STEPS: u32 = 32u;
const IMPOSTOR_SECANT_STEPS: u32 = 12u;
const IMPOSTOR_EDGE_STEPS: u32 = 10u;

// First crossing of the ray o + t·d (|d| = 1) with the impostor's surface for t in
// (t_min, t_max]. `tolerance` (m) bounds |f| at the accepted hit: a sign change that
// secant steps cannot close is a jump across a depth discontinuity, not a surface.
fn impostor_trace(
    map: texture_2d_array<f32>,
    center: vec3<f32>,
    o: vec3<f32>,
    d: vec3<f32>,
    t_min: f32,
    t_max: f32,
    tolerance: f32,
) -> ImpostorHit {
    return impostor_trace_at(map, 0, center, o, d, t_min, t_max, tolerance);
}

// `impostor_trace` against the impostor whose six faces start at `base_layer`.
fn impostor_trace_at(
    map: texture_2d_array<f32>,
    base_layer: i32,
    center: vec3<f32>,
    o: vec3<f32>,
    d: vec3<f32>,
    t_min: f32,
    t_max: f32,
    tolerance: f32,
) -> ImpostorHit {
    var hit: ImpostorHit;
    hit.found = false;
    var t_prev = t_min;
    var f_prev = impostor_f(map, base_layer, center, o + d * t_min);
    // Steps grow quadratically: the first is (t_max - t_min)/32², so a surface near
    // the ray's origin is not stepped over (a step that starts where the map stores
    // nothing and ends behind the surface shows no sign change), the last are coarse.
    let span = t_max - t_min;
    let n = f32(IMPOSTOR_LINEAR_STEPS);
    for (var i = 1u; i <= IMPOSTOR_LINEAR_STEPS; i++) {
        let x = f32(i) / n;
        let t_step = t_min + span * x * x;
        let f_step = impostor_f(map, base_layer, center, o + d * t_step);
        var ta = t_prev;
        var fa = f_prev;
        var tb = t_step;
        var fb = f_step;
        let a_empty = abs(fa) > 1e29;
        if a_empty != (abs(fb) > 1e29) {
            // One end looks where the map stores nothing: bisect to the edge of the
            // surface's region and search only the part that sees the surface, so a
            // step from "nothing" to "behind the surface" is not taken as no hit.
            var lo = ta;
            var hi = tb;
            for (var k = 0u; k < IMPOSTOR_EDGE_STEPS; k++) {
                let mid = 0.5 * (lo + hi);
                if (abs(impostor_f(map, base_layer, center, o + d * mid)) > 1e29) == a_empty {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            if a_empty {
                ta = hi;
            } else {
                tb = lo;
            }
            fa = impostor_f(map, base_layer, center, o + d * ta);
            fb = impostor_f(map, base_layer, center, o + d * tb);
        }
        let crossing = (fa < 0.0) != (fb < 0.0);
        if crossing && abs(fa) < 1e29 && abs(fb) < 1e29 {
            // Secant refinement inside [ta, tb], Illinois variant: an end kept twice
            // has its f halved, so a strongly curved f (a floor seen at grazing
            // angles) still converges instead of creeping in from one side.
            var tm = tb;
            var fm = fb;
            var kept = 0;
            for (var k = 0u; k < IMPOSTOR_SECANT_STEPS; k++) {
                tm = ta + (tb - ta) * fa / (fa - fb);
                fm = impostor_f(map, base_layer, center, o + d * tm);
                if abs(fm) > 1e29 {
                    break;
                }
                if (fm < 0.0) == (fa < 0.0) {
                    ta = tm;
                    fa = fm;
                    if kept == 1 {
                        fb *= 0.5;
                    }
                    kept = 1;
                } else {
                    tb = tm;
                    fb = fm;
                    if kept == -1 {
                        fa *= 0.5;
                    }
                    kept = -1;
                }
            }
            if abs(fm) <= tolerance {
                hit.found = true;
                hit.t = tm;
                hit.position = o + d * tm;
                hit.normal = normalize(impostor_fetch_at(map, base_layer, hit.position - center).xyz);
                return hit;
            }
        }
        t_prev = t_step;
        f_prev = f_step;
    }
    return hit;
}
