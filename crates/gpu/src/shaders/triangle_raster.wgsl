// Triangle scan conversion for the compute-raster paths (`raster=compute`, issue 17):
// which pixels' centres a triangle covers, and the rasterizer's perspective-correct
// barycentrics there, from its vertices' clip coordinates alone.
//
// A triangle in front of the eye (every w > 0, nearly every caustic triangle) is
// scanned as the rasterizer does: edge functions of its projected vertices in pixels,
// each edge from its own vertices' differences (a triangle a hundredth of a pixel wide,
// a caustic's focus, keeps its digits), screen-space barycentrics λ made
// perspective-correct as λ_i/w_i normalized, and the depth range 0 ≤ z/w ≤ 1 on the
// screen-linear z/w. A triangle with a vertex behind the eye has no bounded projection:
// it is scanned with homogeneous edge functions (Olano & Greer 1997, "Triangle scan
// conversion using 2D homogeneous coordinates") over the whole viewport, without
// clipping: with the clip coordinates c_i = (x, y, w) as the columns of M, the point of
// the triangle's plane on the ray through q = (x_ndc, y_ndc, 1) has the barycentrics
// u / Σu with u = adj(M) q, and lies in front of the eye where Σu has det(M)'s sign.
// Either way a centre exactly on an edge goes to one of the two triangles sharing it (a
// top-left rule on the edge function's gradient); the rasterizer decides such ties on
// its snapped sub-pixel vertices instead, which can move the odd edge pixel from one
// triangle to its neighbour.

// One triangle's footprint in one viewport.
struct TriangleFootprint {
    // 1: every vertex in front of the eye (screen-space scan); 0: homogeneous scan.
    screen: u32,
    // Screen scan: the projected vertices (pixels, y down), twice the signed area, 1/w
    // and z/w of each vertex.
    p0: vec2<f32>,
    p1: vec2<f32>,
    p2: vec2<f32>,
    area2: f32,
    inv_w: vec3<f32>,
    z_over_w: vec3<f32>,
    // Homogeneous scan: edge functions u_i(q) = dot(edge_i, q), each ≥ 0 inside (scaled
    // by det(M)'s sign), and the vertices' clip z and w.
    edge0: vec3<f32>,
    edge1: vec3<f32>,
    edge2: vec3<f32>,
    z: vec3<f32>,
    w: vec3<f32>,
    // Pixels (x0, y0, x1, y1) whose centres it may cover, inclusive; empty if x1 < x0.
    rect: vec4<i32>,
}

// The footprint of the triangle with clip coordinates c0, c1, c2 in a viewport of
// `size` pixels (y down, as wgpu maps clip space onto it); an empty rectangle where the
// triangle misses the clip volume or is seen edge-on (the rasterizer draws nothing).
fn triangle_footprint(c0: vec4<f32>, c1: vec4<f32>, c2: vec4<f32>, size: vec2<f32>) -> TriangleFootprint {
    var f: TriangleFootprint;
    f.rect = vec4<i32>(0, 0, -1, -1);
    let x = vec3<f32>(c0.x, c1.x, c2.x);
    let y = vec3<f32>(c0.y, c1.y, c2.y);
    let z = vec3<f32>(c0.z, c1.z, c2.z);
    let w = vec3<f32>(c0.w, c1.w, c2.w);
    // All three behind the eye, or outside one plane of the clip volume.
    if all(w <= vec3<f32>(0.0)) || all(x > w) || all(x < -w) || all(y > w) || all(y < -w)
        || all(z < vec3<f32>(0.0)) || all(z > w) {
        return f;
    }
    if all(w > vec3<f32>(0.0)) {
        let px = (x / w * 0.5 + 0.5) * size.x;
        let py = (0.5 - y / w * 0.5) * size.y;
        f.screen = 1u;
        f.p0 = vec2<f32>(px.x, py.x);
        f.p1 = vec2<f32>(px.y, py.y);
        f.p2 = vec2<f32>(px.z, py.z);
        f.area2 = cross_2d(f.p1 - f.p0, f.p2 - f.p0);
        if f.area2 == 0.0 {
            return f;
        }
        f.inv_w = 1.0 / w;
        f.z_over_w = z / w;
        // The centres p + 0.5 within the vertices' bounds.
        let lo = vec2<f32>(min(px.x, min(px.y, px.z)), min(py.x, min(py.y, py.z)));
        let hi = vec2<f32>(max(px.x, max(px.y, px.z)), max(py.x, max(py.y, py.z)));
        let first = clamp(ceil(lo - 0.5), vec2<f32>(0.0), size);
        let last = clamp(floor(hi - 0.5), vec2<f32>(-1.0), size - 1.0);
        f.rect = vec4<i32>(vec2<i32>(first), vec2<i32>(last));
        return f;
    }
    let a = c0.xyw;
    let b = c1.xyw;
    let c = c2.xyw;
    let r0 = cross(b, c);
    let det = dot(a, r0);
    if det == 0.0 {
        return f;
    }
    let sign_det = sign(det);
    f.edge0 = r0 * sign_det;
    f.edge1 = cross(c, a) * sign_det;
    f.edge2 = cross(a, b) * sign_det;
    f.z = z;
    f.w = w;
    // A vertex behind the eye: the projection is unbounded.
    f.rect = vec4<i32>(0, 0, i32(size.x) - 1, i32(size.y) - 1);
    return f;
}

fn cross_2d(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return a.x * b.y - a.y * b.x;
}

// Pixels in the footprint's rectangle.
fn footprint_pixels(f: TriangleFootprint) -> u32 {
    return u32(max(f.rect.z - f.rect.x + 1, 0)) * u32(max(f.rect.w - f.rect.y + 1, 0));
}

// Whether an edge function's value `u` (its gradient `gradient`, the function
// oriented to be ≥ 0 inside) keeps its point: inside, or on the edge and the edge on
// the side that owns its points.
fn edge_covers(u: f32, gradient: vec2<f32>) -> bool {
    return u > 0.0 || (u == 0.0 && (gradient.x > 0.0 || (gradient.x == 0.0 && gradient.y > 0.0)));
}

// Screen scan: edge function of the edge from `a` to `b` at `p`, and its gradient,
// oriented by `orientation` (the sign of the triangle's area).
fn screen_edge_covers(a: vec2<f32>, b: vec2<f32>, p: vec2<f32>, orientation: f32) -> vec2<f32> {
    let d = b - a;
    let e = cross_2d(d, p - a) * orientation;
    let covered = edge_covers(e, vec2<f32>(-d.y, d.x) * orientation);
    return vec2<f32>(e, f32(covered));
}

// The perspective-correct barycentrics (xyz) at the centre of pixel `pixel` of a
// viewport of `size` pixels, and w = 1 where the footprint covers that centre within
// the depth range (w = 0 and the rest meaningless elsewhere).
fn footprint_barycentrics(f: TriangleFootprint, pixel: vec2<u32>, size: vec2<f32>) -> vec4<f32> {
    if f.screen == 1u {
        let p = vec2<f32>(pixel) + 0.5;
        let orientation = sign(f.area2);
        // e_i: the edge opposite vertex i, ≥ 0 on the triangle's side.
        let e0 = screen_edge_covers(f.p1, f.p2, p, orientation);
        let e1 = screen_edge_covers(f.p2, f.p0, p, orientation);
        let e2 = screen_edge_covers(f.p0, f.p1, p, orientation);
        if e0.y == 0.0 || e1.y == 0.0 || e2.y == 0.0 {
            return vec4<f32>(0.0);
        }
        let lambda = vec3<f32>(e0.x, e1.x, e2.x) / abs(f.area2);
        let z_ndc = dot(lambda, f.z_over_w);
        if z_ndc < 0.0 || z_ndc > 1.0 {
            return vec4<f32>(0.0);
        }
        let perspective = lambda * f.inv_w;
        return vec4<f32>(perspective / (perspective.x + perspective.y + perspective.z), 1.0);
    }
    let ndc = vec2<f32>(
        (f32(pixel.x) + 0.5) / size.x * 2.0 - 1.0,
        1.0 - (f32(pixel.y) + 0.5) / size.y * 2.0,
    );
    let q = vec3<f32>(ndc, 1.0);
    let u = vec3<f32>(dot(f.edge0, q), dot(f.edge1, q), dot(f.edge2, q));
    let sum = u.x + u.y + u.z;
    // Outside, or the plane's point on this ray behind the eye.
    if !(edge_covers(u.x, f.edge0.xy) && edge_covers(u.y, f.edge1.xy) && edge_covers(u.z, f.edge2.xy))
        || sum <= 0.0 {
        return vec4<f32>(0.0);
    }
    let bary = u / sum;
    let clip_z = dot(bary, f.z);
    if clip_z < 0.0 || clip_z > dot(bary, f.w) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(bary, 1.0);
}
