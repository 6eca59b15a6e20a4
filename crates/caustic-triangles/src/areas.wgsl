// Caustic reconstruction, compute half (§4.2 and the §5 optimization of a separate
// per-vertex pass): first every triangle of the photon hit image is kept or
// discarded and its area on the receiver computed; then each vertex gets the
// irradiance ΔΦ/ΔA of its texel's flux over the receiver area it stands for.
//
// Discard rule: a triangle is drawn only if its three hits are valid, land on the same
// receiver, followed the same specular path, have a non-zero area, and its area on the
// receiver is at most max_stretch × half the mean texel footprint at the generator.
//
// A valid hit none of whose triangles is kept (an orphan: isolated by invalid
// neighbours, e.g. total internal reflection around it) delivers nothing, as in the
// paper; `splat_orphans` draws it as a one-texel splat instead (orphans.wgsl).
//
// ΔA of a vertex = (2 / n) × the summed receiver area of its n kept triangles: one
// photon-image cell's worth of receiver area (six triangles of half a cell around an
// interior vertex). Inside the lit region that is a third of the fan's area, which is
// what Gouraud interpolation needs to conserve energy (a triangle's integral is its
// area times the mean of its three vertex values); at the edge of the lit region it
// keeps the irradiance right instead of doubling it. The paper's "half of the total
// area of the attached triangles" would, on this six-triangle fan, deliver 2/3 of the
// flux. With `vertex_area` = third (AREA_THIRD), ΔA = (1/3) × the summed area instead,
// the barycentric share: Σ over triangles of area × mean vertex value then equals
// Σ over vertices of their flux, so every hit that keeps a triangle delivers all of
// its light, at the price of edge vertices up to 3× (one triangle) brighter than the
// lit region inside.

@group(1) @binding(0) var<uniform> tri: TriUniform;
@group(1) @binding(1) var<storage, read> hits: array<PhotonHit>;
@group(1) @binding(2) var<storage, read_write> tri_area: array<f32>;
@group(1) @binding(3) var<storage, read_write> vertex_irradiance: array<vec4<f32>>;
// One counter per TRI_* reason.
@group(1) @binding(4) var<storage, read_write> tri_counters: array<atomic<u32>>;

@compute @workgroup_size(64)
fn triangle_areas(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = gid.x;
    if t >= triangle_count() {
        return;
    }
    let v = triangle_vertices(t);
    let a = hits[v.x];
    let b = hits[v.y];
    let c = hits[v.z];
    var why = TRI_KEPT;
    var area = 0.0;
    if a.ids.x == NONE || b.ids.x == NONE || c.ids.x == NONE {
        why = TRI_INVALID_VERTEX;
    } else if a.ids.x != b.ids.x || a.ids.x != c.ids.x {
        why = TRI_RECEIVER_MISMATCH;
    } else if a.ids.y != b.ids.y || a.ids.y != c.ids.y {
        why = TRI_PATH_MISMATCH;
    } else {
        area = 0.5 * length(cross(b.position.xyz - a.position.xyz, c.position.xyz - a.position.xyz));
        let source = 0.5 * (a.normal.w + b.normal.w + c.normal.w) / 3.0;
        if area > tri.max_stretch * source {
            why = TRI_STRETCHED;
        } else if area <= 0.0 {
            why = TRI_DEGENERATE;
        }
    }
    tri_area[t] = select(0.0, area, why == TRI_KEPT);
    atomicAdd(&tri_counters[why], 1u);
}

struct FanSum {
    area: f32,
    count: f32,
}

fn add_triangle(s: FanSum, t: u32) -> FanSum {
    let a = tri_area[t];
    if a > 0.0 {
        return FanSum(s.area + a, s.count + 1.0);
    }
    return s;
}

@compute @workgroup_size(64)
fn vertex_irradiance_pass(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = tri.resolution;
    let v = gid.x;
    if v >= tri.layers * n * n {
        return;
    }
    let layer = v / (n * n);
    let k = v % (n * n);
    let x = k % n;
    let y = k / n;
    var s = FanSum(0.0, 0.0);
    if x + 1u < n && y + 1u < n {
        let t = cell_triangle(layer, x, y);
        s = add_triangle(s, t);
        s = add_triangle(s, t + 1u);
    }
    if x >= 1u && y + 1u < n {
        s = add_triangle(s, cell_triangle(layer, x - 1u, y));
    }
    if x >= 1u && y >= 1u {
        let t = cell_triangle(layer, x - 1u, y - 1u);
        s = add_triangle(s, t);
        s = add_triangle(s, t + 1u);
    }
    if x + 1u < n && y >= 1u {
        s = add_triangle(s, cell_triangle(layer, x, y - 1u) + 1u);
    }
    var e = vec3<f32>(0.0);
    // w = 1 marks an orphan: a valid hit whose every triangle was discarded, whose
    // flux no triangle carries (orphans.wgsl splats it when asked).
    var orphan = 0.0;
    if s.count > 0.0 {
        if tri.vertex_area == AREA_THIRD {
            e = hits[v].flux.rgb * 3.0 / s.area;
        } else {
            e = hits[v].flux.rgb * s.count / (2.0 * s.area);
        }
    } else if hits[v].ids.x != NONE {
        orphan = 1.0;
        atomicAdd(&tri_counters[ORPHAN_HITS], 1u);
    }
    vertex_irradiance[v] = vec4<f32>(e, orphan);
}
