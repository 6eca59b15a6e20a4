// The scene's meshes and tessellated heightfields in one binary BVH
// (crates/gpu/src/triangle_bvh.rs builds it), and the closest hit of a ray against the
// whole scene: analytic objects exactly, triangles through the tree. Composed after
// common.wgsl and frame.wgsl; `BVH_GROUP` is replaced by the caller's group.

struct BvhNode {
    min: vec3<f32>,
    // Triangles of a leaf; 0 for an inner node (children `first`, `first + 1`).
    count: u32,
    max: vec3<f32>,
    first: u32,
}

struct BvhTriangle {
    // xyz: vertex 0; w: the owning object's index (f32).
    p0: vec4<f32>,
    p1: vec4<f32>,
    p2: vec4<f32>,
    // Unit vertex normals.
    n0: vec4<f32>,
    n1: vec4<f32>,
    n2: vec4<f32>,
}

@group(BVH_GROUP) @binding(0) var<storage, read> bvh_nodes: array<BvhNode>;
@group(BVH_GROUP) @binding(1) var<storage, read> bvh_triangles: array<BvhTriangle>;

// Traversal stack depth: the builder refuses deeper trees (triangle_bvh::MAX_DEPTH).
const BVH_STACK: u32 = 64u;

struct TriangleHit {
    t: f32,
    // NONE: no hit.
    object: u32,
    // Interpolated vertex normal (unit).
    ns: vec3<f32>,
    // The facet's normal (unit), on the side of `ns`.
    ng: vec3<f32>,
}

// Entry and exit distances of a ray through a box (entry > exit: missed).
fn bvh_box(o: vec3<f32>, inv_d: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> vec2<f32> {
    let t0 = (lo - o) * inv_d;
    let t1 = (hi - o) * inv_d;
    let near = min(t0, t1);
    let far = max(t0, t1);
    return vec2<f32>(max(max(near.x, near.y), near.z), min(min(far.x, far.y), far.z));
}

// Closest triangle along o + t·d with t_min < t < t_max, skipping the triangles of
// object `skip` (NONE: none). Möller–Trumbore, both sides.
fn bvh_closest_hit(o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32, skip: u32) -> TriangleHit {
    var hit = TriangleHit(t_max, NONE, vec3<f32>(0.0), vec3<f32>(0.0));
    var best = 0u;
    var best_uv = vec2<f32>(0.0);
    // No component exactly 0, so the slab test never divides by zero.
    let safe_d = select(d, vec3<f32>(1e-20), abs(d) < vec3<f32>(1e-20));
    let inv_d = 1.0 / safe_d;
    var stack: array<u32, BVH_STACK>;
    var top = 1u;
    stack[0] = 0u;
    while top > 0u {
        top -= 1u;
        let node = bvh_nodes[stack[top]];
        let span = bvh_box(o, inv_d, node.min, node.max);
        if span.x > span.y || span.y < t_min || span.x > hit.t {
            continue;
        }
        if node.count == 0u {
            // Nearer child last, so it is popped first.
            let a = bvh_nodes[node.first];
            let b = bvh_nodes[node.first + 1u];
            let ta = bvh_box(o, inv_d, a.min, a.max).x;
            let tb = bvh_box(o, inv_d, b.min, b.max).x;
            if top + 2u > BVH_STACK {
                break;
            }
            if ta < tb {
                stack[top] = node.first + 1u;
                stack[top + 1u] = node.first;
            } else {
                stack[top] = node.first;
                stack[top + 1u] = node.first + 1u;
            }
            top += 2u;
            continue;
        }
        for (var k = node.first; k < node.first + node.count; k++) {
            let tri = bvh_triangles[k];
            if u32(tri.p0.w) == skip {
                continue;
            }
            let e1 = tri.p1.xyz - tri.p0.xyz;
            let e2 = tri.p2.xyz - tri.p0.xyz;
            let p = cross(d, e2);
            let det = dot(e1, p);
            if abs(det) < 1e-12 {
                continue;
            }
            let inv_det = 1.0 / det;
            let s = o - tri.p0.xyz;
            let u = dot(s, p) * inv_det;
            let q = cross(s, e1);
            let v = dot(d, q) * inv_det;
            let t = dot(e2, q) * inv_det;
            if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > t_min && t < hit.t {
                hit.t = t;
                hit.object = u32(tri.p0.w);
                best = k;
                best_uv = vec2<f32>(u, v);
            }
        }
    }
    if hit.object != NONE {
        let tri = bvh_triangles[best];
        let w = vec3<f32>(1.0 - best_uv.x - best_uv.y, best_uv.x, best_uv.y);
        hit.ns = normalize(w.x * tri.n0.xyz + w.y * tri.n1.xyz + w.z * tri.n2.xyz);
        let ng = normalize(cross(tri.p1.xyz - tri.p0.xyz, tri.p2.xyz - tri.p0.xyz));
        hit.ng = select(ng, -ng, dot(ng, hit.ns) < 0.0);
    } else {
        hit.t = NO_HIT;
    }
    return hit;
}

struct SceneHit {
    t: f32,
    // NONE: nothing hit.
    object: u32,
    // Shading normal (unit; the analytic normal of analytic objects, outward).
    ns: vec3<f32>,
    // Geometric normal (unit, on the side of `ns`).
    ng: vec3<f32>,
}

// Closest surface of the whole scene along o + t·d, t > t_min, skipping object `skip`
// (NONE: none): analytic objects exactly, meshes and heightfields through the BVH.
fn scene_closest_hit(o: vec3<f32>, d: vec3<f32>, t_min: f32, skip: u32) -> SceneHit {
    var best = SceneHit(NO_HIT, NONE, vec3<f32>(0.0), vec3<f32>(0.0));
    for (var i = 0u; i < frame.counts.x; i++) {
        if i == skip {
            continue;
        }
        let t = intersect_analytic(o, d, objects[i], t_min);
        if t < best.t {
            best.t = t;
            best.object = i;
        }
    }
    if best.object != NONE {
        let n = analytic_normal(objects[best.object], o + best.t * d);
        best.ns = n;
        best.ng = n;
    }
    let tri = bvh_closest_hit(o, d, t_min, best.t, skip);
    if tri.object != NONE {
        best = SceneHit(tri.t, tri.object, tri.ns, tri.ng);
    }
    return best;
}

// The adjoint shading-normal factor of one specular event of light (adjoint)
// transport with interpolated normals (Veach 1997, §5.3; DESIGN "Conventions"):
// |wi·ns|·|wo·ng| / (|wo·ns|·|wi·ng|), wi towards the light, wo onward; 1 where ns = ng.
// Negative when ns and ng disagree about the side of either direction (the path is
// dropped, as the reference drops it).
fn adjoint_shading_factor(wi: vec3<f32>, wo: vec3<f32>, ns: vec3<f32>, ng: vec3<f32>) -> f32 {
    let i_s = dot(wi, ns);
    let i_g = dot(wi, ng);
    let o_s = dot(wo, ns);
    let o_g = dot(wo, ng);
    if !(i_s * i_g > 0.0 && o_s * o_g > 0.0) {
        return -1.0;
    }
    return abs(i_s * o_g / (o_s * i_g));
}
