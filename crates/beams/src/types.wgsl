// Types and beam-space geometry shared by the beam passes (generate, rasterize).
// Mirrored by the #[repr(C)] structs of gpu_types.rs, whose tests check every field
// against naga's layout of these.

// MAX_SPECULAR, MAX_LEVELS and MAX_BOUNCES are prepended from the Rust constants (lib.rs).

// One caustic generator object: its impostor slot holds its distance map.
struct SpecularSlot {
    // xyz: impostor centre (m); w: reach (m).
    center_reach: vec4<f32>,
    // rgb: mirror reflectance (1 for dielectrics).
    color: vec4<f32>,
    object: u32,
    // MAT_DIELECTRIC or MAT_MIRROR.
    kind: u32,
    // 1: a closed surface (sphere, mesh): light refracted in leaves through its impostor.
    closed: u32,
    ior: f32,
}

struct BeamUniforms {
    // Light G-buffer clip space to world (to rebuild the light ray through a uv).
    light_inv_view_proj: mat4x4<f32>,
    // xyz: direction of a directional light; w: 0 directional, 1 point/spot.
    light_dir_kind: vec4<f32>,
    // xyz: position of a point/spot light; w: start of the extinction path of a
    // directional light (dot(x, dir) of the plane photons start from, as the reference).
    light_pos_start: vec4<f32>,
    // rgb: irradiance (directional, W/m²) or intensity (W/sr); w: source measure of
    // the whole uv square (m² for a directional light; unused for positional ones).
    light_power: vec4<f32>,
    // rgb: sigma_t (1/m); w: 1 if the scene has a medium.
    sigma_t: vec4<f32>,
    // rgb: sigma_s (1/m); w: Henyey-Greenstein g.
    sigma_s_g: vec4<f32>,
    // xyz: receivers' impostor centre; w: its reach.
    receivers: vec4<f32>,
    specular: array<SpecularSlot, MAX_SPECULAR>,
    specular_count: u32,
    grid: u32,
    levels: u32,
    max_beams: u32,
    // Split oracle (Sect. 4.2): enable bits (1 discontinuity, 2 energy, 4 camera).
    split_flags: u32,
    split_cos_normal: f32,
    split_depth_slope: f32,
    split_energy: f32,
    split_camera_px: f32,
    // Camera: radians per pixel (vertical).
    pixel_angle: f32,
    // 1: also emit the Fresnel-reflected beams of dielectrics.
    reflections: u32,
    // 1: tight 6-triangle hulls (Sect. 4.3), 0: bounding prisms (Ernst et al.).
    tight_hulls: u32,
    // A(y) is clamped to >= A(0) / max_focus (a point-sampled focus is singular).
    max_focus: f32,
    // Soft-particle fade distance for volume caustics (m, 0 = off).
    soft_depth: f32,
    // Search tolerance of the impostor traces, relative to each impostor's reach.
    impostor_tolerance: f32,
    // World extent of the scene (m): the longest a beam is extruded.
    scene_reach: f32,
    // Photon-hit difference (camera pixels) at edge midpoints that splits.
    split_hit_px: f32,
    // Further specular events beyond the paper's path (`bounces`, path.wgsl).
    bounces: u32,
    // 1: exact tracing through the scene's BVH and analytic shapes (`tracer` = bvh),
    // 0: the light G-buffer and distance impostors (the paper's).
    exact_trace: u32,
    // ... and that fraction of the landing edge's length too (relative; 0 = off).
    split_hit_rel: f32,
    // Beams to aim for: the splits of a level are ranked by priority (0 = every split).
    beam_budget: u32,
    // 1: the landed corners of the families a leaf drops are written as orphan records
    // and drawn as points (`splat_orphans`).
    splat_orphans: u32,
    // The scene light (index into group 0's `lights`) these beams carry.
    light_index: u32,
    // Vertices a side of the vertex cache's lattice, grid·2^levels + 1 (0: no cache;
    // generate.wgsl `trace_lattice`).
    vertex_cache_side: u32,
}

// A triangle of the projected grid in the light's uv space: uv01 corners 0 and 1,
// uv2_level corner 2, the level and (with beam_budget) the camera size in pixels of
// the triangle's light where the oracle last measured it (its parent's; generate.wgsl).
struct Candidate {
    uv01: vec4<f32>,
    uv2_level: vec4<f32>,
}

// One caustic beam (Sect. 4.3 beam space): base vertices v_i on the last specular
// surface, edge directions d_i scaled so that dot(d_i, n) = 1, the area function
// A(y) = a0 + a1 y + a2 y² of the cross-section parallel to the base at height y,
// per-vertex flux and extrusion heights, and the hull to rasterize.
struct Beam {
    // xyz: v_i; w: a_i (A(y) coefficients).
    v: array<vec4<f32>, 3>,
    // xyz: d_i / dot(d_i, n); w: height at which edge i meets a receiver (m).
    d: array<vec4<f32>, 3>,
    // rgb: flux Φ_i (W) of the beam if every ray carried vertex i's weight; w of
    // flux[0]: the light-path family (path.wgsl FAMILY_*), of flux[1]: generators met
    // again, of flux[2]: total internal reflections (both summed over the corners).
    flux: array<vec4<f32>, 3>,
    // xyz: unit base normal n (the beam's y axis); w: extrusion height y_max (m).
    n: vec4<f32>,
    // The hull's six points (base 3, top 3).
    hull: array<vec4<f32>, 6>,
    // 24 4-bit point indices (8 outward triangles); w: 1 tight, 0 prism.
    tris: vec4<u32>,
}

// The corners of one light-path family of a leaf that emits no beam for it (its
// corners part ways), with `splat_orphans`: each landed corner is drawn as a one-pixel
// point of a third of the triangle's flux (orphans.wgsl).
struct Orphan {
    // xyz: where corner i lands (m); w: its path length from the beam's start (m).
    point: array<vec4<f32>, 3>,
    // xyz: the unit direction its light arrives along.
    dir: array<vec4<f32>, 3>,
    // rgb: its share of the triangle's flux (W): the corner's weight × the source
    // measure of the triangle / 3.
    flux: array<vec4<f32>, 3>,
    // xyz: the receiver corner i landed on (NONE: it did not land).
    receiver: vec4<u32>,
}

// Extinction over `length_m` of the scene's medium (1 without one). Every pass that
// includes this file declares the uniforms `u`.
fn extinction(length_m: f32) -> vec3<f32> {
    if u.sigma_t.w < 0.5 {
        return vec3<f32>(1.0);
    }
    return exp(-u.sigma_t.xyz * length_m);
}

// Beam-space frame of a base triangle and edge directions.
struct BeamGeometry {
    ok: bool,
    n: vec3<f32>,
    d: array<vec3<f32>, 3>,
    a: vec3<f32>,
}

// Builds the beam space of (v_i, dir_i): n is the base normal oriented along the
// rays; the directions are scaled to unit height. Not ok when a ray runs (nearly)
// parallel to the base or against it: such a beam has no parallel cross-sections.
fn beam_geometry(v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>,
                 d0: vec3<f32>, d1: vec3<f32>, d2: vec3<f32>) -> BeamGeometry {
    var g: BeamGeometry;
    g.ok = false;
    let c = cross(v1 - v0, v2 - v0);
    let len = length(c);
    if len < 1e-12 {
        return g;
    }
    var n = c / len;
    if dot(d0 + d1 + d2, n) < 0.0 {
        n = -n;
    }
    let h = vec3<f32>(dot(d0, n), dot(d1, n), dot(d2, n));
    if min(h.x, min(h.y, h.z)) < 0.02 {
        return g;
    }
    g.n = n;
    g.d[0] = d0 / h.x;
    g.d[1] = d1 / h.y;
    g.d[2] = d2 / h.z;
    // A(y) = ½ n·((E1 + y D1) × (E2 + y D2)), E_k = v_k - v0, D_k = d_k - d0 (Ernst et al.).
    let e1 = v1 - v0;
    let e2 = v2 - v0;
    let f1 = g.d[1] - g.d[0];
    let f2 = g.d[2] - g.d[0];
    g.a = 0.5 * vec3<f32>(
        dot(cross(e1, e2), n),
        dot(cross(e1, f2) + cross(f1, e2), n),
        dot(cross(f1, f2), n),
    );
    g.ok = true;
    return g;
}

fn area_at(a: vec3<f32>, y: f32) -> f32 {
    return a.x + y * (a.y + y * a.z);
}

// Smallest |A(y)| over [0, y_max] (the strongest focus along the beam).
fn min_abs_area(a: vec3<f32>, y_max: f32) -> f32 {
    let a0 = area_at(a, 0.0);
    let a1 = area_at(a, y_max);
    if (a0 > 0.0) != (a1 > 0.0) {
        return 0.0;
    }
    var m = min(abs(a0), abs(a1));
    if abs(a.z) > 1e-20 {
        let ys = -a.y / (2.0 * a.z);
        if ys > 0.0 && ys < y_max {
            let am = area_at(a, ys);
            if (am > 0.0) != (a0 > 0.0) {
                return 0.0;
            }
            m = min(m, abs(am));
        }
    }
    return m;
}

// Barycentric coordinates of x in the beam's cross-section at x's own height.
// Works for flipped cross-sections too (past a focus A(y) < 0): the signed areas keep
// the coordinates in [0, 1] inside.
fn beam_barycentrics(beam: Beam, x: vec3<f32>, y: f32) -> vec3<f32> {
    let n = beam.n.xyz;
    let q0 = beam.v[0].xyz + y * beam.d[0].xyz;
    let q1 = beam.v[1].xyz + y * beam.d[1].xyz;
    let q2 = beam.v[2].xyz + y * beam.d[2].xyz;
    let area2 = dot(cross(q1 - q0, q2 - q0), n);
    if abs(area2) < 1e-30 {
        return vec3<f32>(-1.0);
    }
    let b0 = dot(cross(q1 - x, q2 - x), n) / area2;
    let b1 = dot(cross(q2 - x, q0 - x), n) / area2;
    return vec3<f32>(b0, b1, 1.0 - b0 - b1);
}
