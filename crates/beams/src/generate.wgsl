// Beam generation (Sect. 4): the projected grid in the light's uv space, refined level
// by level by the split oracle (Sect. 4.2), then each leaf triangle becomes one beam
// per light-path family with its beam space, area function and hull (Sect. 4.3).
// The paper refines in a geometry shader with stream-out; here each level is four
// compute dispatches (decide, scan, emit, advance; with a beam budget, `budget` between
// decide and scan; with the vertex cache, gather_lattice, lattice_args and
// trace_lattice before decide) with a deterministic prefix sum instead of stream-out
// order, so the same beams land in the same slots every frame; `emit` leaves a job in
// each leaf beam's slot, and after the last level `emit_beams` (and with splat_orphans
// `emit_orphans`) traces and writes them all, one invocation per record.

@group(1) @binding(6) var<storage, read_write> candidates_a: array<Candidate>;
@group(1) @binding(7) var<storage, read_write> candidates_b: array<Candidate>;
@group(1) @binding(8) var<storage, read_write> actions: array<u32>;
// Per candidate: x, y where its children and its beams go among the level's (`scan`);
// with splat_orphans (u.splat_orphans = 1; else untouched) z: the families its leaf
// traced but emits no beam for while some corner of theirs landed (bit f: family f),
// w: the offset of its first orphan record among the level's. One buffer: a compute
// stage binds at most 16.
@group(1) @binding(9) var<storage, read_write> offsets: array<vec4<u32>>;
@group(1) @binding(10) var<storage, read_write> control: array<atomic<u32>>;
@group(1) @binding(11) var<storage, read_write> beams: array<Beam>;
// With splat_orphans the orphan records (as many slots as beams: max_beams; without it
// a placeholder no kernel touches).
@group(1) @binding(13) var<storage, read_write> orphans: array<Orphan>;
// Indirect arguments: words 0..3 the dispatch over candidates, 4..7 the hull draw,
// 8..11 the orphan point draw, 12..15 the compute rasterizer's dispatch, 16..19 the
// dispatch over the vertices the vertex cache traces (`trace_lattice`), 20..22 and
// 23..25 the dispatches over the beams and orphan records (`emit_beams`,
// `emit_orphans`).
// A group of its own, bound to the real buffer only for the kernels that write it
// (init_grid, lattice_args, advance, finalize): a buffer cannot be storage and indirect
// in the same dispatch, so the indirect ones (trace_lattice, decide, emit, emit_beams,
// emit_orphans) and the others see a placeholder here.
@group(2) @binding(0) var<storage, read_write> indirect_args: array<u32, 26>;
// The vertex cache (u.vertex_cache_side > 0; without it one entry no kernel touches):
// entry 0 counts the generations, entry 1 + y·side + x holds the main path of lattice
// vertex (x, y). See `trace_lattice`.
@group(1) @binding(12) var<storage, read_write> vertex_paths: array<CachedPath>;

// The words of `control` (C_LEVEL, C_COUNT, ...) are declared once in control.rs,
// which prepends their constants to this file.

// An action word is ACTION_SPLIT or the mask of the families a leaf emits (bit f:
// family f, up to FAMILY_INTERNAL + MAX_BOUNCES - 1). With a beam budget a split the
// oracle asks for is ACTION_WANT, with the leaf it would be (mask, families that meet
// no receiver, why it emits nothing) and its priority bin; `resolve` turns it into a
// split or that leaf once the level's threshold bin is known.
const ACTION_SPLIT: u32 = 0x80000000u;
const ACTION_WANT: u32 = 0x40000000u;
const ACTION_MASK: u32 = 0x3FFu;
const ACTION_NO_RECEIVER_SHIFT: u32 = 10u;
const ACTION_DROP_SHIFT: u32 = 14u;
const ACTION_BIN_SHIFT: u32 = 16u;
const DROP_INVALID: u32 = 1u;
const DROP_DISCONTINUITY: u32 = 2u;
const SPLIT_DISCONTINUITY: u32 = 1u;
const SPLIT_ENERGY: u32 = 2u;
const SPLIT_CAMERA: u32 = 4u;
// A split reason only: `split_families` is the override below, not a flag.
const SPLIT_FAMILY: u32 = 8u;
const SPLIT_IRRADIANCE: u32 = 16u;
// Refinement::split_families (see `decide`).
override SPLIT_FAMILIES: bool;
// Split priorities are binned on a log scale: bin = 32·log2(p) + 256, p in 2^-8..2^24
// (control.rs SPLIT_BINS).
const SPLIT_BINS: u32 = 1024u;
const BINS_PER_OCTAVE: u32 = 32u;
const BIN_OF_ONE: f32 = 256.0;
// Camera size (px) given to the base grid's triangles, before the oracle measured one.
const UNMEASURED_SIZE_PX: f32 = 1e6;
// A triangle whose main path would be dropped as a leaf (its corners part ways) loses
// all its light, not a share of it: its priority is its size times this.
const DROPPED_LIGHT_WEIGHT: f32 = 4.0;
// The families the beam budget counts: the main path and the Fresnel reflection, the
// paper's (Sect. 6). The internal reflections `bounces` adds ride along with the leaves
// the budget buys: counting them made the same budget buy fewer leaves the more light
// was followed (fog_sphere at 128x96, 8 bounces, tracer=bvh: 565 main-path beams;
// 1,707 counting these two families only).
const BUDGET_FAMILIES: u32 = 3u;

fn level_parity() -> u32 {
    return atomicLoad(&control[C_LEVEL]) & 1u;
}

fn load_candidate(i: u32) -> Candidate {
    if level_parity() == 0u {
        return candidates_a[i];
    }
    return candidates_b[i];
}

fn store_child(i: u32, c: Candidate) {
    if level_parity() == 0u {
        candidates_b[i] = c;
    } else {
        candidates_a[i] = c;
    }
}

fn set_dispatch(count: u32) {
    indirect_args[0] = (count + 63u) / 64u;
    indirect_args[1] = 1u;
    indirect_args[2] = 1u;
}

@compute @workgroup_size(64)
fn init_grid(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = u.grid;
    let count = 2u * n * n;
    if id.x == 0u {
        atomicStore(&control[C_LEVEL], 0u);
        atomicStore(&control[C_COUNT], count);
        atomicStore(&control[C_BEAM_BASE], 0u);
        atomicStore(&control[C_BEAM_TOTAL], 0u);
        atomicStore(&control[C_CANDIDATES_TOTAL], count);
        set_dispatch(count);
    }
    if id.x >= count {
        return;
    }
    let cell = id.x / 2u;
    let x = f32(cell % n);
    let y = f32(cell / n);
    let s = 1.0 / f32(n);
    let a = vec2<f32>(x, y) * s;
    let b = vec2<f32>(x + 1.0, y) * s;
    let c = vec2<f32>(x, y + 1.0) * s;
    let d = vec2<f32>(x + 1.0, y + 1.0) * s;
    var t: Candidate;
    let size = select(0.0, UNMEASURED_SIZE_PX, u.beam_budget > 0u);
    if VERTEX_CACHE {
        // The corners `decide` traces and, where it may split, the midpoints its
        // oracle traces.
        mark_needed(a);
        mark_needed(b);
        mark_needed(c);
        mark_needed(d);
        mark_corner(a);
        mark_corner(b);
        mark_corner(c);
        mark_corner(d);
        if u.levels > 0u {
            if (id.x & 1u) == 0u {
                mark_midpoints(a, b, c);
            } else {
                mark_midpoints(b, d, c);
            }
        }
    }
    if (id.x & 1u) == 0u {
        t.uv01 = vec4<f32>(a, b);
        t.uv2_level = vec4<f32>(c, 0.0, size);
    } else {
        t.uv01 = vec4<f32>(b, d);
        t.uv2_level = vec4<f32>(c, 0.0, size);
    }
    candidates_a[id.x] = t;
}

// Whether the scene has a positional light (set by lib.rs): only then is the spherical
// triangle's solid angle below compiled in. On lavapipe its code cost a dispatch of
// `emit_beams` about 6 ms whether any invocation ran it or not (water_pool, a
// directional light, at 1024x768: 2.9 ms without it, 8-10 ms with it; one invocation
// per beam, 4,789 beams), and `emit` 2 ms a level where it was tried there.
override POSITIONAL_LIGHTS: bool;

// Flux of a beam whose rays all carried weight 1: the source measure of its uv
// triangle (m² perpendicular to a directional light; sr for a positional light, the
// exact solid angle of the spherical triangle, Van Oosterom & Strackee 1983).
fn source_measure(uv0: vec2<f32>, uv1: vec2<f32>, uv2: vec2<f32>) -> f32 {
    if !POSITIONAL_LIGHTS || u.light_dir_kind.w < 0.5 {
        let e1 = uv1 - uv0;
        let e2 = uv2 - uv0;
        return 0.5 * abs(e1.x * e2.y - e1.y * e2.x) * u.light_power.w;
    }
    let w0 = light_ray(uv0).dir;
    let w1 = light_ray(uv1).dir;
    let w2 = light_ray(uv2).dir;
    let num = abs(dot(w0, cross(w1, w2)));
    let den = 1.0 + dot(w0, w1) + dot(w1, w2) + dot(w2, w0);
    return 2.0 * atan2(num, den);
}

struct Corners {
    p: array<PathEnd, 3>,
}

fn trace_corners(c: Candidate, family: u32) -> Corners {
    var k: Corners;
    var uv = array<vec2<f32>, 3>(c.uv01.xy, c.uv01.zw, c.uv2_level.xy);
    for (var i = 0u; i < 3u; i++) {
        if family == FAMILY_MAIN {
            k.p[i] = main_path(uv[i]);
        } else if CACHE_REFLECTED && family == FAMILY_REFLECTED {
            k.p[i] = cached_path(reflected_entry(lattice_entry(uv[i])));
        } else if FAMILY_TRACER {
            k.p[i] = trace_path(uv[i], family);
        } else {
            // No family is asked for beyond the cached ones (FAMILY_TRACER): a read
            // here would be a bug, counted as a miss.
            k.p[i] = cached_path(0u);
        }
    }
    return k;
}

// The vertex cache --------------------------------------------------------------------
//
// Without it the refinement traces a vertex's main path once for each triangle that has
// it as a corner (up to six), again as the edge midpoint the oracle tests before the
// vertex becomes its children's corner, and again where `emit_beams` writes a leaf's beam. With
// it every vertex of the lattice the grid refines to (grid·2^levels cells a side, where
// every corner and oracle midpoint lies) is traced once per generation, in
// `trace_lattice`, one invocation per vertex: one writer per entry, so what an entry
// holds, and every beam and count after it, does not depend on the order invocations
// run in. The vertices a level needs are marked the level before (`init_grid`: the base
// grid's corners and, with levels to come, its edge midpoints; `emit`: the edge
// midpoints of a split's children), and `decide` and `emit_beams` read them (`main_path`).
// With CACHE_REFLECTED (`reflections` on a scene with a dielectric) the Fresnel
// reflection is cached alike, in a second lattice of entries after the first: it is
// traced for the vertices that become corners (`init_grid`: the base grid's; `emit`: a
// split's new ones), since the leaves of a ranked refinement, and every leaf's beam in
// `emit_beams`, ask for it at their three corners (water_pool at 1024x768, adaptive-beams:
// 8,116 candidates each tracing it three times in `decide`, and leaves again in `emit`,
// against one trace per corner vertex). The internal reflections of `bounces` are
// traced where they are asked for, as without the cache.

// A vertex's main path (a PathEnd in words, floats as their bits), and the generation
// it was last needed in and traced in.
struct CachedPath {
    origin_valid: vec4<u32>,
    dir_t_end: vec4<u32>,
    weight_signature: vec4<u32>,
    first_normal_depth: vec4<u32>,
    first_point_object: vec4<u32>,
    light_dir_end_object: vec4<u32>,
    first_slot: u32,
    rehits: u32,
    tir: u32,
    needed: u32,
    traced: u32,
}

fn pack_path(p: PathEnd, generation: u32) -> CachedPath {
    var c: CachedPath;
    c.origin_valid = vec4<u32>(bitcast<vec3<u32>>(p.origin), u32(p.valid));
    c.dir_t_end = vec4<u32>(bitcast<vec3<u32>>(p.dir), bitcast<u32>(p.t_end));
    c.weight_signature = vec4<u32>(bitcast<vec3<u32>>(p.weight), p.signature);
    c.first_normal_depth = vec4<u32>(bitcast<vec3<u32>>(p.first_normal), bitcast<u32>(p.first_depth));
    c.first_point_object = vec4<u32>(bitcast<vec3<u32>>(p.first_point), p.first_object);
    c.light_dir_end_object = vec4<u32>(bitcast<vec3<u32>>(p.light_dir), p.end_object);
    c.first_slot = p.first_slot;
    c.rehits = p.rehits;
    c.tir = p.tir;
    c.needed = generation;
    c.traced = generation;
    return c;
}

fn unpack_path(c: CachedPath) -> PathEnd {
    var p: PathEnd;
    p.valid = c.origin_valid.w != 0u;
    p.origin = bitcast<vec3<f32>>(c.origin_valid.xyz);
    p.dir = bitcast<vec3<f32>>(c.dir_t_end.xyz);
    p.t_end = bitcast<f32>(c.dir_t_end.w);
    p.weight = bitcast<vec3<f32>>(c.weight_signature.xyz);
    p.signature = c.weight_signature.w;
    p.first_normal = bitcast<vec3<f32>>(c.first_normal_depth.xyz);
    p.first_depth = bitcast<f32>(c.first_normal_depth.w);
    p.first_point = bitcast<vec3<f32>>(c.first_point_object.xyz);
    p.first_object = c.first_point_object.w;
    p.light_dir = bitcast<vec3<f32>>(c.light_dir_end_object.xyz);
    p.end_object = c.light_dir_end_object.w;
    p.first_slot = c.first_slot;
    p.rehits = c.rehits;
    p.tir = c.tir;
    return p;
}

// This generation's stamp: `finalize` counts the generations in entry 0, so an entry
// stamped in an earlier frame (or by another light) reads as not traced.
fn cache_generation() -> u32 {
    return vertex_paths[0].traced + 1u;
}

// The entry of the lattice vertex at uv (every corner and midpoint the refinement makes
// is one: dyadic fractions of the base grid's cells).
fn lattice_entry(uv: vec2<f32>) -> u32 {
    let cells = f32(u.vertex_cache_side - 1u);
    let q = vec2<u32>(round(clamp(uv, vec2<f32>(0.0), vec2<f32>(1.0)) * cells));
    return 1u + q.y * u.vertex_cache_side + q.x;
}

fn mark_needed(uv: vec2<f32>) {
    vertex_paths[lattice_entry(uv)].needed = cache_generation();
}

// The Fresnel reflection's entry of the vertex whose main-path entry is `i`.
fn reflected_entry(i: u32) -> u32 {
    return i + u.vertex_cache_side * u.vertex_cache_side;
}

// Marks a vertex that is a candidate's corner: with CACHE_REFLECTED its Fresnel
// reflection is traced before the level's `decide` reads it.
fn mark_corner(uv: vec2<f32>) {
    if CACHE_REFLECTED {
        vertex_paths[reflected_entry(lattice_entry(uv))].needed = cache_generation();
    }
}

// Marks the edge midpoints of the triangle (p0, p1, p2): the oracle traces them.
fn mark_midpoints(p0: vec2<f32>, p1: vec2<f32>, p2: vec2<f32>) {
    mark_needed(0.5 * (p0 + p1));
    mark_needed(0.5 * (p1 + p2));
    mark_needed(0.5 * (p2 + p0));
}

// Whether the vertex cache is on (u.vertex_cache_side > 0): compiled in, so that
// `decide` and `emit_beams` hold no copy of the tracer for the main path (on lavapipe an
// invocation pays for every instruction of its kernel, the branches it does not take
// too).
override VERTEX_CACHE: bool;

// Whether the vertex cache also holds the Fresnel reflection (see above).
override CACHE_REFLECTED: bool;

// Whether a leaf may ask for a family the cache does not hold (the internal reflections
// of `bounces`; the Fresnel reflection of a dielectric where it is not cached): only
// then do `decide` and `emit_beams` hold a copy of the path tracer, which on lavapipe costs
// its kernel's every invocation whether it runs or not.
override FAMILY_TRACER: bool;

// The path cached in entry i (traced this generation: every vertex the refinement reads
// is marked before it is read; a miss is counted, and reads as a path that is not
// valid).
fn cached_path(i: u32) -> PathEnd {
    if vertex_paths[i].traced == cache_generation() {
        return unpack_path(vertex_paths[i]);
    }
    atomicAdd(&control[C_VERTEX_CACHE_MISSES], 1u);
    var none: PathEnd;
    none.valid = false;
    none.first_object = NONE;
    none.first_slot = NONE;
    none.end_object = NONE;
    return none;
}

// The main path of the vertex at uv: with the cache, what `trace_lattice` traced (every
// vertex the refinement reads is marked before it is read: a miss is counted, and reads
// as a path that is not valid), else traced here.
fn main_path(uv: vec2<f32>) -> PathEnd {
    if VERTEX_CACHE {
        return cached_path(lattice_entry(uv));
    }
    return trace_path(uv, FAMILY_MAIN);
}

// Before a level's `decide`, three dispatches: `gather_lattice` (direct, over the
// lattice of the level's midpoints, (grid·2^min(level+1, levels) + 1)² vertices) lists
// every vertex marked this generation and not yet traced, `lattice_args` sizes the
// dispatch, `trace_lattice` (indirect, one invocation per listed vertex) traces each at
// its exact lattice uv. The gather visits each vertex once, so each is listed (and
// traced) once; only the tracing kernel holds the tracer, and it runs for the vertices
// that need it, not the whole lattice. The list lives in `offsets` (four entries to a
// candidate's vec4), free until `decide` writes it.
@compute @workgroup_size(64)
fn gather_lattice(@builtin(global_invocation_id) id: vec3<u32>) {
    let shift = min(atomicLoad(&control[C_LEVEL]) + 1u, u.levels);
    let side = (u.grid << shift) + 1u;
    if id.x >= side * side {
        return;
    }
    let q = vec2<u32>(id.x % side, id.x / side) << vec2<u32>(u.levels - shift);
    let generation = cache_generation();
    // Its main path, then (CACHE_REFLECTED) its Fresnel reflection's entry.
    let families = select(1u, 2u, CACHE_REFLECTED);
    for (var f = 0u; f < families; f++) {
        var i = 1u + q.y * u.vertex_cache_side + q.x;
        if f == 1u {
            i = reflected_entry(i);
        }
        if vertex_paths[i].needed != generation || vertex_paths[i].traced == generation {
            continue;
        }
        let k = atomicAdd(&control[C_LATTICE_LISTED], 1u);
        // Past the list's room a vertex stays untraced, and reads count as misses.
        if k < 4u * u.max_beams {
            offsets[k >> 2u][k & 3u] = i;
        }
    }
}

@compute @workgroup_size(1)
fn lattice_args() {
    let n = min(atomicLoad(&control[C_LATTICE_LISTED]), 4u * u.max_beams);
    atomicStore(&control[C_LATTICE_TRACE], n);
    atomicStore(&control[C_LATTICE_LISTED], 0u);
    indirect_args[16] = (n + 63u) / 64u;
    indirect_args[17] = 1u;
    indirect_args[18] = 1u;
}

@compute @workgroup_size(64)
fn trace_lattice(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= atomicLoad(&control[C_LATTICE_TRACE]) {
        return;
    }
    let i = offsets[id.x >> 2u][id.x & 3u];
    // A main-path entry, or past the first lattice a Fresnel reflection's.
    let lattice = u.vertex_cache_side * u.vertex_cache_side;
    let reflected = i > lattice;
    let v = select(i, i - lattice, reflected) - 1u;
    let q = vec2<u32>(v % u.vertex_cache_side, v / u.vertex_cache_side);
    let uv = vec2<f32>(q) / f32(u.vertex_cache_side - 1u);
    // One call site: lavapipe pays for every inlined copy of the tracer.
    let family = select(FAMILY_MAIN, FAMILY_REFLECTED, reflected);
    vertex_paths[i] = pack_path(trace_path(uv, family), cache_generation());
    if !reflected {
        atomicAdd(&control[C_VERTEX_PATHS], 1u);
    }
}

fn corners_geometry(k: Corners) -> BeamGeometry {
    return beam_geometry(k.p[0].origin, k.p[1].origin, k.p[2].origin,
                         k.p[0].dir, k.p[1].dir, k.p[2].dir);
}

// Extrusion heights of the edges: where each meets its receiver (Sect. 4.3).
fn end_heights(k: Corners, g: BeamGeometry) -> vec3<f32> {
    return vec3<f32>(k.p[0].t_end * dot(k.p[0].dir, g.n),
                     k.p[1].t_end * dot(k.p[1].dir, g.n),
                     k.p[2].t_end * dot(k.p[2].dir, g.n));
}

// All three corners valid and on the same path (same objects met, same receiver).
fn consistent(k: Corners) -> bool {
    return k.p[0].valid && k.p[1].valid && k.p[2].valid
        && k.p[0].signature == k.p[1].signature && k.p[0].signature == k.p[2].signature
        && k.p[0].end_object == k.p[1].end_object && k.p[0].end_object == k.p[2].end_object;
}

// Without a medium a beam that meets no receiver adds nothing to any image.
fn lands(k: Corners) -> bool {
    return u.sigma_t.w > 0.5 || k.p[0].end_object != NONE;
}

// Some corner's path is valid and reaches a receiver: a family that emits no beam
// still has light there (splat_orphans draws it as points).
fn any_landed(corners: Corners) -> bool {
    var k = corners;
    var landed = false;
    for (var i = 0u; i < 3u; i++) {
        landed = landed || (k.p[i].valid && k.p[i].end_object != NONE);
    }
    return landed;
}

// Families a leaf emits: bit 0 the main path, bit 1 the Fresnel reflection, bit
// FAMILY_INTERNAL + j - 1 the light reflected j times inside the first object
// (`bounces`; Sect. 6 makes the reflected beam on the same refined grid, and so are
// these: the split oracle looks at the main path only), how many consistent
// families meet no receiver (the caller counts them where the triangle is a leaf), and
// the orphans: the families traced that emit no beam while some corner landed.
struct Leaf {
    mask: u32,
    no_receiver: u32,
    orphans: u32,
    // With SPLIT_FAMILIES: the light of the orphaned families beyond the main path,
    // relative to the light's (a third of each landed corner's weight, summed over
    // them): what a split would keep in beams.
    orphan_share: f32,
    // With CLIP_LEAVES: how many clipped beams each family that parts ways emits
    // instead (CLIP_BITS per family f at bit CLIP_BITS·f: `clip_count`).
    clips: u32,
}

// The landed corners' weight over the light's, a third each (write_orphan's shares).
fn landed_share(corners: Corners) -> f32 {
    var k = corners;
    var w = 0.0;
    for (var i = 0u; i < 3u; i++) {
        if k.p[i].valid && k.p[i].end_object != NONE {
            w += luminance(k.p[i].weight);
        }
    }
    return w / (3.0 * max(luminance(u.light_power.xyz), 1e-20));
}

// Whether some corner's path meets a dielectric first (`closed`: a closed one).
fn some_first_dielectric(corners: Corners, closed: bool) -> bool {
    var k = corners;
    var found = false;
    for (var i = 0u; i < 3u; i++) {
        let slot = k.p[i].first_slot;
        if slot != NONE {
            let s = u.specular[slot];
            found = found || (s.kind == MAT_DIELECTRIC && (!closed || s.closed == 1u));
        }
    }
    return found;
}

fn leaf_mask(c: Candidate, main: Corners) -> Leaf {
    var leaf = Leaf(0u, 0u, 0u, 0.0, 0u);
    if consistent(main) && corners_geometry(main).ok {
        if lands(main) {
            leaf.mask |= 1u;
        } else {
            leaf.no_receiver += 1u;
        }
    } else if any_landed(main) {
        leaf.orphans |= 1u;
        if CLIP_LEAVES {
            leaf.clips |= clip_count(main);
        }
    }
    // The generator all three corners meet first (NONE if they differ or one misses).
    // The reflected and internal families start there, whatever the main path does
    // after it: a main path ended by a total internal reflection at the exit still
    // has its Fresnel reflection at the entry (asking for main.p[0].valid here lost
    // that light: glass_cushion at 128x96, static 128² with tracer=bvh, had 3,820
    // reflected beams instead of 8,076, flux 0.873 instead of 0.891).
    var slot = main.p[0].first_slot;
    if main.p[1].first_slot != slot || main.p[2].first_slot != slot {
        slot = NONE;
    }
    // Where the corners part before that (a silhouette: one misses, or they meet
    // different generators) no family emits a beam, but with splat_orphans the corners
    // that meet a dielectric still carry its reflected and internal light, each along
    // its own path (path.wgsl checks its own first surface): traced, they land as
    // orphans. (Gating these on the shared generator alone lost them: sphere_on_plane
    // at 128x96, static-grid extended, orphans 4,132 -> 3,916, flux 0.979 -> 0.972.)
    let orphans_only = (u.splat_orphans == 1u || CLIP_LEAVES) && slot == NONE;
    let reflected = u.reflections == 1u && ((slot != NONE
        && u.specular[slot].kind == MAT_DIELECTRIC)
        || (orphans_only && some_first_dielectric(main, false)));
    let internal = u.bounces > 0u && ((slot != NONE
        && u.specular[slot].kind == MAT_DIELECTRIC && u.specular[slot].closed == 1u)
        || (orphans_only && some_first_dielectric(main, true)));
    // One loop, one trace: lavapipe runs every inlined copy of the path tracer in
    // every invocation, taken or not.
    for (var family = FAMILY_REFLECTED; family < FAMILY_INTERNAL + u.bounces; family++) {
        if !select(internal, reflected, family == FAMILY_REFLECTED) {
            continue;
        }
        let k = trace_corners(c, family);
        if consistent(k) && corners_geometry(k).ok {
            if lands(k) {
                leaf.mask |= 1u << family;
            } else {
                leaf.no_receiver += 1u;
            }
        } else if any_landed(k) {
            leaf.orphans |= 1u << family;
            if CLIP_LEAVES {
                leaf.clips |= clip_count(k) << (CLIP_BITS * family);
            }
            if SPLIT_FAMILIES {
                leaf.orphan_share += landed_share(k);
            }
        }
    }
    return leaf;
}

// Why a leaf that emits nothing does so (0: it emits a beam, or it is neither).
fn drop_reason(k: Corners, mask: u32) -> u32 {
    if mask != 0u {
        return 0u;
    }
    let valid = u32(k.p[0].valid) + u32(k.p[1].valid) + u32(k.p[2].valid);
    if valid == 0u {
        return DROP_INVALID;
    }
    if !consistent(k) {
        return DROP_DISCONTINUITY;
    }
    return 0u;
}

fn count_drop(reason: u32, no_receiver: u32) {
    if no_receiver > 0u {
        atomicAdd(&control[C_DROPPED_NO_RECEIVER], no_receiver);
    }
    if reason == DROP_INVALID {
        atomicAdd(&control[C_DROPPED_INVALID], 1u);
    } else if reason == DROP_DISCONTINUITY {
        atomicAdd(&control[C_DROPPED_DISCONTINUITY], 1u);
    }
}

// How large the triangle's light looks from the camera (px), the priority scale of a
// discontinuity: the spread of its valid corners' landings (their points on the
// generator where fewer than two land), or half its parent's where fewer than two
// corners are valid.
//
// Written with fixed indices, as are the oracle's other corner tests: SPIR-V cannot
// index an array value by a variable, so naga writes the value (here the three corners'
// paths) into a temporary to index it (k.p[i], or a list filled up to a count), and on
// lavapipe those copies cost far more than the arithmetic. Written as loops, the split
// oracle took 17-22 ms of water_pool's level-2 `decide` at 1024x768 against 0.4-0.5 ms
// to read the corners; with fixed indices 1.2 ms. Values that must be indexed by a
// variable are copied into a `var` once (`Hull`).
fn size_px(c: Candidate, k: Corners) -> f32 {
    let p0 = k.p[0];
    let p1 = k.p[1];
    let p2 = k.p[2];
    var use_p = vec3<bool>(p0.valid && p0.end_object != NONE, p1.valid && p1.end_object != NONE,
                           p2.valid && p2.end_object != NONE);
    var q0 = p0.origin + p0.dir * p0.t_end;
    var q1 = p1.origin + p1.dir * p1.t_end;
    var q2 = p2.origin + p2.dir * p2.t_end;
    if u32(use_p.x) + u32(use_p.y) + u32(use_p.z) < 2u {
        use_p = vec3<bool>(p0.valid, p1.valid, p2.valid);
        q0 = p0.first_point;
        q1 = p1.first_point;
        q2 = p2.first_point;
    }
    let n = u32(use_p.x) + u32(use_p.y) + u32(use_p.z);
    if n < 2u {
        return 0.5 * c.uv2_level.w;
    }
    // The points in corner order, the pairs (0, 1), (0, 2), (1, 2) among them.
    var center = vec3<f32>(0.0);
    if use_p.x { center += q0; }
    if use_p.y { center += q1; }
    if use_p.z { center += q2; }
    var spread = 0.0;
    if use_p.x && use_p.y { spread = max(spread, distance(q0, q1)); }
    if use_p.x && use_p.z { spread = max(spread, distance(q0, q2)); }
    if use_p.y && use_p.z { spread = max(spread, distance(q1, q2)); }
    center /= f32(n);
    return spread / (max(distance(center, frame.eye.xyz), 1e-6) * u.pixel_angle);
}

// Whether corners a and b meet their first surface far apart in orientation (normals
// beyond split_cos_normal) or in depth (more than split_depth_slope times their lateral
// distance): a crease or an occluding edge between them.
fn first_surfaces_part(a: PathEnd, b: PathEnd) -> bool {
    let delta = a.first_point - b.first_point;
    let along = dot(delta, a.light_dir);
    let lateral = length(delta - along * a.light_dir);
    return dot(a.first_normal, b.first_normal) < u.split_cos_normal
        || abs(a.first_depth - b.first_depth) > u.split_depth_slope * max(lateral, 1e-9);
}

// The split oracle (Sect. 4.2): which criteria ask for a split and, with a beam
// budget, how urgently (in pixels of misplaced light over split_hit_px for the
// discontinuity criterion; how far over their thresholds for energy and camera).
struct Split {
    reasons: u32,
    priority: f32,
    size_px: f32,
}

// How wrong a leaf's even irradiance is where its four children (its corners and edge
// midpoints, on the receiver) would spread the light unevenly, as a length in camera
// pixels comparable with a midpoint's deviation: the square root of the pixels
// wholly wrong. Each child carries a quarter of the leaf's flux (equal source
// measures, to first order) over its own landing area a_i, where the leaf spreads it
// over a quarter of the leaf's area A, so on the child's pixels the leaf's irradiance
// is off by (4 a_i / A - 1) relative to the child's (a folded child, a_i < 0, by more
// than the whole light: a focus inside the leaf). The squared relative error summed
// over the children's pixels is what the pixel-averaged relMSE of the image adds up;
// the paper's energy criterion ("convergent beams ... are refined with higher
// priority", Sect. 4.2) asks for the same splits, in units the budget can rank.
fn irradiance_error_px(k: Corners, mids: array<vec3<f32>, 3>) -> f32 {
    let l0 = k.p[0].origin + k.p[0].dir * k.p[0].t_end;
    let l1 = k.p[1].origin + k.p[1].dir * k.p[1].t_end;
    let l2 = k.p[2].origin + k.p[2].dir * k.p[2].t_end;
    let n = cross(l1 - l0, l2 - l0);
    let area2 = length(n);
    if area2 <= 1e-20 {
        return 0.0;
    }
    let normal = n / area2;
    // The children: one at each corner (corner, next edge's midpoint, previous edge's
    // midpoint; mids[i] lies on edge i -> i + 1) and the middle one.
    var tris = array<vec3<f32>, 12>(
        l0, mids[0], mids[2],
        mids[0], l1, mids[1],
        mids[2], mids[1], l2,
        mids[0], mids[1], mids[2],
    );
    var wrong_px2 = 0.0;
    for (var i = 0u; i < 4u; i++) {
        let a = tris[3u * i];
        let b = tris[3u * i + 1u];
        let d = tris[3u * i + 2u];
        let child2 = dot(cross(b - a, d - a), normal);
        let m_per_px = max(distance((a + b + d) / 3.0, frame.eye.xyz) * u.pixel_angle, 1e-12);
        let off = 4.0 * child2 / area2 - 1.0;
        wrong_px2 += off * off * 0.5 * abs(child2) / (m_per_px * m_per_px);
    }
    return sqrt(wrong_px2);
}

fn split_oracle(c: Candidate, k: Corners, level: u32) -> Split {
    var s = Split(0u, 0.0, 0.0);
    let ranked = u.beam_budget > 0u;
    if ranked {
        s.size_px = size_px(c, k);
    }
    let valid = u32(k.p[0].valid) + u32(k.p[1].valid) + u32(k.p[2].valid);
    // Discontinuities of the specular surfaces: a silhouette (some corners miss),
    // different objects on the way, normals or depths that differ strongly. Their
    // priority is the size of the light they cut (a beam across one loses or
    // misplaces light over all of it).
    if (u.split_flags & SPLIT_DISCONTINUITY) != 0u {
        if valid > 0u && valid < 3u {
            // Only the corners can tell: a corner that misses while another hits is a
            // silhouette; split so the leaves follow it.
            s.reasons |= SPLIT_DISCONTINUITY;
        } else if valid == 3u {
            if !consistent(k) || first_surfaces_part(k.p[0], k.p[1])
                || first_surfaces_part(k.p[1], k.p[2]) || first_surfaces_part(k.p[2], k.p[0]) {
                s.reasons |= SPLIT_DISCONTINUITY;
            }
        }
        if s.reasons != 0u {
            s.priority = s.size_px / u.split_hit_px;
        }
    }
    if valid < 3u {
        return s;
    }
    // Photon-hit differences (Sect. 6): where the light of an edge midpoint lands
    // against the beam's linear prediction (the mean of the corners' landings). A beam
    // spreads its flux evenly over its caustic triangle, so a midpoint off by δ on an
    // edge of length L misplaces O(δ/L) of the beam's irradiance inside it: the split
    // asks for δ beyond split_hit_px camera pixels (where the light lands) and beyond
    // split_hit_rel·L (what a relative error sees). Large beams that bend gently keep
    // their level; small ones that focus, where δ/L grows, are split (the paper's
    // "convergent beams ... are refined with higher priority", Sect. 4.2). Ranked, the
    // priority is the largest δ in pixels over split_hit_px: a beam's squared error
    // summed over its pixels goes as (δ/L)²·(L in px)² = (δ in px)².
    //
    // The same midpoints give the children's landing areas: split_irradiance asks
    // where the leaf's even irradiance is off from its children's by more than
    // split_hit_px pixels' worth of light (`irradiance_error_px`), ranked alike.
    let hits = (u.split_flags & SPLIT_DISCONTINUITY) != 0u;
    let irradiance = (u.split_flags & SPLIT_IRRADIANCE) != 0u;
    // Light misplaced or misspread, in pixels: the rank of every split of a surface
    // caustic (below).
    var misplaced_px = 0.0;
    if (hits || irradiance) && s.reasons == 0u {
        // Corner i's uv, landing, signature and receiver, picked by select() rather
        // than k.p[i] (see size_px); one call of main_path (without the cache, the
        // tracer), and no midpoint past the first that disagrees.
        let uv0 = c.uv01.xy;
        let uv1 = c.uv01.zw;
        let uv2 = c.uv2_level.xy;
        let land0 = k.p[0].origin + k.p[0].dir * k.p[0].t_end;
        let land1 = k.p[1].origin + k.p[1].dir * k.p[1].t_end;
        let land2 = k.p[2].origin + k.p[2].dir * k.p[2].t_end;
        let signatures = vec3<u32>(k.p[0].signature, k.p[1].signature, k.p[2].signature);
        let ends = vec3<u32>(k.p[0].end_object, k.p[1].end_object, k.p[2].end_object);
        var mid0 = vec3<f32>(0.0);
        var mid1 = vec3<f32>(0.0);
        var mid2 = vec3<f32>(0.0);
        var paths_agree = true;
        for (var i = 0u; i < 3u; i++) {
            // Edge i runs from corner i to corner i + 1.
            let uv_i = select(select(uv2, uv1, i == 1u), uv0, i == 0u);
            let uv_j = select(select(uv0, uv2, i == 1u), uv1, i == 0u);
            let land_i = select(select(land2, land1, i == 1u), land0, i == 0u);
            let land_j = select(select(land0, land2, i == 1u), land1, i == 0u);
            let m = main_path(0.5 * (uv_i + uv_j));
            if !m.valid || m.signature != signatures[i] || m.end_object != ends[i] {
                paths_agree = false;
                if hits {
                    s.reasons |= SPLIT_DISCONTINUITY;
                    s.priority = s.size_px / u.split_hit_px;
                }
                break;
            }
            let land_m = m.origin + m.dir * m.t_end;
            if i == 0u {
                mid0 = land_m;
            } else if i == 1u {
                mid1 = land_m;
            } else {
                mid2 = land_m;
            }
            let deviation = distance(land_m, 0.5 * (land_i + land_j));
            let dist = max(distance(land_m, frame.eye.xyz), 1e-6);
            let edge = distance(land_i, land_j);
            misplaced_px = max(misplaced_px, deviation / (dist * u.pixel_angle));
            if hits && deviation > max(u.split_hit_px * dist * u.pixel_angle, u.split_hit_rel * edge) {
                s.reasons |= SPLIT_DISCONTINUITY;
                if !ranked {
                    break;
                }
            }
        }
        let mids = array<vec3<f32>, 3>(mid0, mid1, mid2);
        // Unranked, a deviation ended the loop early (mids incomplete) and the split
        // is asked already.
        if paths_agree && irradiance && (ranked || s.reasons == 0u) && k.p[0].end_object != NONE {
            let spread_px = irradiance_error_px(k, mids);
            misplaced_px = max(misplaced_px, spread_px);
            if spread_px > u.split_hit_px {
                s.reasons |= SPLIT_IRRADIANCE;
            }
        }
        if s.reasons != 0u {
            s.priority = max(s.priority, misplaced_px / u.split_hit_px);
        }
    }
    // Without a medium the image shows only where the light lands, so energy and camera
    // splits are ranked by the light they would place better (misplaced_px), in the
    // units of the other criteria, rather than by how far they pass their own
    // thresholds (a focus factor, a size ratio), which outranked misplaced light:
    // sphere_on_plane at 1024x768, relMSE 2.238e-4 -> 2.136e-4 at the same budget.
    // In a medium the beam's whole body is seen and their own scores rank them.
    let surface_only = u.sigma_t.w < 0.5;
    let g = corners_geometry(k);
    // Beam energy: the flux share of the beam times how strongly it focuses.
    if (u.split_flags & SPLIT_ENERGY) != 0u && g.ok {
        // How much the beam concentrates its flux where it is seen: on the receiver
        // (A(0)/A(y_end)) for surface caustics, at its narrowest (A(0)/min A) in a
        // medium, where the whole beam is visible.
        let ends = end_heights(k, g);
        let a0 = area_at(g.a, 0.0);
        var a_seen = abs(area_at(g.a, (ends.x + ends.y + ends.z) / 3.0));
        if u.sigma_t.w > 0.5 {
            a_seen = min_abs_area(g.a, max(max(ends.x, ends.y), ends.z));
        }
        let focus = a0 / max(a_seen, a0 / u.max_focus);
        // The beam's flux relative to an unrefined beam's: its path's throughput (the
        // corners' weight over the light's) times its area share, 4^-level.
        let mean_w = (k.p[0].weight + k.p[1].weight + k.p[2].weight) / 3.0;
        let relative_flux = luminance(mean_w) / max(luminance(u.light_power.xyz), 1e-20)
            * exp2(-2.0 * f32(level));
        if relative_flux * focus > u.split_energy {
            s.reasons |= SPLIT_ENERGY;
            s.priority = max(s.priority, select(relative_flux * focus / u.split_energy, misplaced_px / u.split_hit_px, surface_only));
        }
    }
    // Camera: the projected size of the beam, measured at the point of its central
    // ray closest to the eye.
    if (u.split_flags & SPLIT_CAMERA) != 0u {
        let center = (k.p[0].origin + k.p[1].origin + k.p[2].origin) / 3.0;
        let dir = normalize(k.p[0].dir + k.p[1].dir + k.p[2].dir);
        let t_end = (k.p[0].t_end + k.p[1].t_end + k.p[2].t_end) / 3.0;
        let eye = frame.eye.xyz;
        let t = clamp(dot(eye - center, dir), 0.0, t_end);
        let dist = max(distance(center + t * dir, eye), 1e-6);
        let size = max(max(distance(k.p[0].origin, k.p[1].origin), distance(k.p[1].origin, k.p[2].origin)),
                       distance(k.p[2].origin, k.p[0].origin));
        if size / (dist * u.pixel_angle) > u.split_camera_px {
            s.reasons |= SPLIT_CAMERA;
            s.priority = max(s.priority, select(size / (dist * u.pixel_angle) / u.split_camera_px, misplaced_px / u.split_hit_px, surface_only));
        }
    }
    return s;
}

fn priority_bin(priority: f32) -> u32 {
    let bin = floor(log2(max(priority, 1e-30)) * f32(BINS_PER_OCTAVE) + BIN_OF_ONE);
    return u32(clamp(bin, 0.0, f32(SPLIT_BINS - 1u)));
}

fn store_size(i: u32, size: f32) {
    if level_parity() == 0u {
        candidates_a[i].uv2_level.w = size;
    } else {
        candidates_b[i].uv2_level.w = size;
    }
}

@compute @workgroup_size(64)
fn decide(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= atomicLoad(&control[C_COUNT]) {
        return;
    }
    let c = load_candidate(id.x);
    let level = u32(c.uv2_level.z);
    let k = trace_corners(c, FAMILY_MAIN);
    let ranked = u.beam_budget > 0u;
    let refinable = level < u.levels;
    var s = Split(0u, 0.0, 0.0);
    if refinable {
        s = split_oracle(c, k, level);
    }
    // The leaf it would be: needed unless the oracle splits it without a budget (a
    // leaf, a ranked split the budget may leave undone, split_families' test). Traced
    // from one place: lavapipe pays for every inlined copy of the path tracer in
    // every invocation, whether it runs or not.
    var leaf = Leaf(0u, 0u, 0u, 0.0, 0u);
    if s.reasons == 0u || ranked {
        leaf = leaf_mask(c, k);
    }
    // split_families, beyond the paper's oracle (Sect. 4.2 looks at the main path):
    // where a further family (the Fresnel reflection, the internal reflections of
    // `bounces`) parts ways at the corners while the main path does not, the leaf
    // would lose that light or, with splat_orphans, draw it as three points of a
    // third of its flux each, bright dots at a coarse level (glass_cushion at
    // 128x96: level-0 leaves whose totally internally reflected light leaves the
    // cushion in different places). Ranked by the light at stake: its share of the
    // light times its size in pixels, the misplacement a discontinuity is ranked
    // by, and as a dropped main path (DROPPED_LIGHT_WEIGHT) where the light would
    // be lost rather than drawn as points (without splat_orphans). Coarse levels
    // take the budget first, so where many coarse leaves tear these splits leave
    // fewer beams for the main caustic's finer levels: bumpy_glass at 64x48, 8
    // bounces, 3,208 beams against 4,833, relMSE 0.00313 against 0.00262 (flux
    // 0.904 -> 0.976); at 128x96 its relMSE falls, 7.79e-4 -> 7.25e-4.
    if SPLIT_FAMILIES && refinable && s.reasons == 0u && (leaf.orphans & ~1u) != 0u {
        s.reasons |= SPLIT_FAMILY;
        s.priority = leaf.orphan_share * s.size_px / u.split_hit_px
            * select(DROPPED_LIGHT_WEIGHT, 1.0, u.splat_orphans == 1u || CLIP_LEAVES);
    }
    if s.reasons != 0u {
        if (s.reasons & SPLIT_DISCONTINUITY) != 0u { atomicAdd(&control[C_SPLIT_DISCONTINUITY], 1u); }
        if (s.reasons & SPLIT_ENERGY) != 0u { atomicAdd(&control[C_SPLIT_ENERGY], 1u); }
        if (s.reasons & SPLIT_CAMERA) != 0u { atomicAdd(&control[C_SPLIT_CAMERA], 1u); }
        if (s.reasons & SPLIT_FAMILY) != 0u { atomicAdd(&control[C_SPLIT_FAMILY], 1u); }
        if (s.reasons & SPLIT_IRRADIANCE) != 0u { atomicAdd(&control[C_SPLIT_IRRADIANCE], 1u); }
        if !ranked {
            actions[id.x] = ACTION_SPLIT;
            return;
        }
        // Ranked: the leaf it would be, should the budget not reach it, and the
        // beams at stake in its split (what it emits as a leaf, at least one).
        // A leaf that drops its main path ranks as the paper's would, clipped or not
        // (CLIP_LEAVES: a clipped edge is a bisected chord, and the clipped beams ride
        // along uncounted, `leaf_budget_cost`; ranking them as kept leaves and counting
        // them, adaptive-beams' relMSE at 128x96 in all-methods' extended setting was
        // 1.9x on sphere_over_water, 1.9x on water_pool and 2.9x on two_lenses).
        var priority = s.priority;
        if (leaf.mask & 1u) == 0u {
            priority = max(priority, DROPPED_LIGHT_WEIGHT * s.size_px / u.split_hit_px);
        }
        let bin = priority_bin(priority);
        let beams = leaf_budget_cost(leaf);
        atomicAdd(&control[C_LEAF_COST], beams);
        atomicAdd(&control[C_SPLIT_HISTOGRAM + bin], max(beams, 1u));
        store_size(id.x, s.size_px);
        store_torn(id.x, leaf);
        actions[id.x] = ACTION_WANT | (bin << ACTION_BIN_SHIFT)
            | (drop_reason(k, emitted(leaf)) << ACTION_DROP_SHIFT)
            | (min(leaf.no_receiver, 15u) << ACTION_NO_RECEIVER_SHIFT) | leaf.mask;
        return;
    }
    finish_leaf(id.x, k, leaf, ranked);
}

// A candidate that stays a leaf: its orphans, drops and (ranked) its beams' cost.
fn finish_leaf(i: u32, k: Corners, leaf: Leaf, ranked: bool) {
    store_torn(i, leaf);
    count_drop(drop_reason(k, emitted(leaf)), leaf.no_receiver);
    if ranked {
        atomicAdd(&control[C_LEAF_COST], leaf_budget_cost(leaf));
    }
    actions[i] = leaf.mask;
}

// What a leaf does with the families whose corners part ways, for scan and emit:
// splat_orphans' family mask, or CLIP_LEAVES' clipped beams per family.
fn store_torn(i: u32, leaf: Leaf) {
    if u.splat_orphans == 1u {
        offsets[i].z = leaf.orphans;
    } else if CLIP_LEAVES {
        offsets[i].z = leaf.clips;
    }
}

// The families that reach the image as beams: bit f where family f emits its beam or
// (CLIP_LEAVES) clipped beams.
fn emitted(leaf: Leaf) -> u32 {
    var mask = leaf.mask;
    for (var family = 0u; family < FAMILY_INTERNAL + u.bounces; family++) {
        if clipped_beams(leaf.clips, family) > 0u {
            mask |= 1u << family;
        }
    }
    return mask;
}

// The beams a leaf costs the budget: those of the counted families (BUDGET_FAMILIES).
// Clipped beams (CLIP_LEAVES) ride along, as the internal reflections do.
fn leaf_budget_cost(leaf: Leaf) -> u32 {
    return countOneBits(leaf.mask & BUDGET_FAMILIES);
}

// With a beam budget, between decide and scan: the lowest priority bin whose splits
// still fit the beams left after this level's leaves, a split turning each beam at
// stake into four. Splits of lower priority stay leaves. Coarse levels come first:
// every level takes all it can before the next is looked at, so the grid is refined
// evenly as far as the budget goes and the last of it goes to the splits that matter
// most (modelling how far children would split again spent the budget on a few deep
// regions and left coarse beams elsewhere: at 1024x768 sphere_on_plane's relMSE was
// ten times the even refinement's at the same count). The children's beams are an
// estimate (four per beam at stake), so the budget is a target, not a bound
// (max_beams is the bound).
@compute @workgroup_size(1)
fn budget() {
    // Beams of the counted families written at the coarser levels, and this level's
    // leaves' (BUDGET_FAMILIES).
    let written = atomicLoad(&control[C_BEAMS_PER_FAMILY + FAMILY_MAIN])
        + atomicLoad(&control[C_BEAMS_PER_FAMILY + FAMILY_REFLECTED])
        - atomicLoad(&control[C_BEAMS_CLIPPED_BUDGET]);
    let used = written + atomicLoad(&control[C_LEAF_COST]);
    let left = max(i32(u.beam_budget) - i32(used), 0);
    var first_bin = SPLIT_BINS;
    var extra = 0;
    for (var bin = SPLIT_BINS; bin > 0u; bin--) {
        extra += 3 * i32(atomicLoad(&control[C_SPLIT_HISTOGRAM + bin - 1u]));
        if extra > left {
            break;
        }
        first_bin = bin - 1u;
    }
    atomicStore(&control[C_SPLIT_MIN_BIN], first_bin);
    // The next level starts from an empty histogram.
    for (var bin = 0u; bin < SPLIT_BINS; bin++) {
        atomicStore(&control[C_SPLIT_HISTOGRAM + bin], 0u);
    }
    atomicStore(&control[C_LEAF_COST], 0u);
}

// An action as scan and emit take it: a ranked split is a split if its bin made the
// level's threshold, else the leaf it would be.
fn resolve(a: u32) -> u32 {
    if (a & ACTION_WANT) == 0u {
        return a;
    }
    if ((a >> ACTION_BIN_SHIFT) & (SPLIT_BINS - 1u)) >= atomicLoad(&control[C_SPLIT_MIN_BIN]) {
        return ACTION_SPLIT;
    }
    return a & ACTION_MASK;
}

const SCAN_THREADS: u32 = 256u;
var<workgroup> scan_children: array<u32, 256>;
var<workgroup> scan_beams: array<u32, 256>;
var<workgroup> scan_orphans: array<u32, 256>;

// Children, beams and orphan records candidate i makes.
fn action_counts(i: u32) -> vec3<u32> {
    let a = resolve(actions[i]);
    if a == ACTION_SPLIT {
        return vec3<u32>(4u, 0u, 0u);
    }
    var orphan_records = 0u;
    var clipped = 0u;
    if u.splat_orphans == 1u {
        orphan_records = countOneBits(offsets[i].z);
    } else if CLIP_LEAVES {
        clipped = clipped_total(offsets[i].z);
    }
    return vec3<u32>(0u, countOneBits(a) + clipped, orphan_records);
}

// One workgroup: exclusive prefix sums of children, beams and orphan records over the
// candidates, in candidate order (deterministic slots), with overflow counted, never
// silent.
@compute @workgroup_size(256)
fn scan(@builtin(local_invocation_index) lid: u32) {
    let n = atomicLoad(&control[C_COUNT]);
    let chunk = (n + SCAN_THREADS - 1u) / SCAN_THREADS;
    let start = min(lid * chunk, n);
    let end = min(start + chunk, n);
    var sum = vec3<u32>(0u);
    for (var i = start; i < end; i++) {
        sum += action_counts(i);
    }
    scan_children[lid] = sum.x;
    scan_beams[lid] = sum.y;
    scan_orphans[lid] = sum.z;
    workgroupBarrier();
    // Hillis-Steele inclusive scan over the 256 partial sums.
    for (var step = 1u; step < SCAN_THREADS; step <<= 1u) {
        var add = vec3<u32>(0u);
        if lid >= step {
            add = vec3<u32>(scan_children[lid - step], scan_beams[lid - step], scan_orphans[lid - step]);
        }
        workgroupBarrier();
        scan_children[lid] += add.x;
        scan_beams[lid] += add.y;
        scan_orphans[lid] += add.z;
        workgroupBarrier();
    }
    var running = vec3<u32>(scan_children[lid], scan_beams[lid], scan_orphans[lid]) - sum;
    for (var i = start; i < end; i++) {
        offsets[i].x = running.x;
        offsets[i].y = running.y;
        if u.splat_orphans == 1u {
            offsets[i].w = running.z;
        }
        running += action_counts(i);
    }
    if lid == SCAN_THREADS - 1u {
        if u.splat_orphans == 1u {
            // Orphan records have as many slots as beams (max_beams).
            let orphan_base = atomicLoad(&control[C_ORPHAN_TOTAL]);
            let new_orphans = scan_orphans[lid];
            let orphan_total = min(orphan_base + new_orphans, u.max_beams);
            atomicAdd(&control[C_OVERFLOW_ORPHANS], orphan_base + new_orphans - orphan_total);
            atomicStore(&control[C_ORPHAN_BASE], orphan_base);
            atomicStore(&control[C_ORPHAN_TOTAL], orphan_total);
        }
        let children = scan_children[lid];
        let new_beams = scan_beams[lid];
        let capacity = u.max_beams;
        // Children come four to a split at offsets that are multiples of 4, and `emit`
        // writes a split's four only when all fit: the next list holds whole splits, so
        // a capacity that is not a multiple of 4 must not count the slots of a split
        // that was not written (they would be read as stale candidates).
        let next = min(children, capacity - capacity % 4u);
        atomicAdd(&control[C_OVERFLOW_CANDIDATES], children - next);
        atomicStore(&control[C_NEXT_COUNT], next);
        let base = atomicLoad(&control[C_BEAM_TOTAL]);
        let total = min(base + new_beams, capacity);
        atomicAdd(&control[C_OVERFLOW_BEAMS], base + new_beams - total);
        atomicStore(&control[C_BEAM_BASE], base);
        atomicStore(&control[C_BEAM_TOTAL], total);
        atomicAdd(&control[C_CANDIDATES_TOTAL], next);
    }
}

// Hull (Sect. 4.3) ------------------------------------------------------------------

fn plane_side(p: vec3<f32>, origin: vec3<f32>, m: vec3<f32>) -> f32 {
    return dot(p - origin, m);
}

// Ernst et al.'s touching plane through base edge (a, b): the plane through the edge
// and one top vertex that leaves every top vertex on the inner side (vertex c's side).
// Returns the outward unit normal (xyz) and offset (w).
fn prism_plane(va: vec3<f32>, vb: vec3<f32>, vc: vec3<f32>, top_value: array<vec3<f32>, 3>, n: vec3<f32>, eps: f32) -> vec4<f32> {
    // Indexed by loop counters: a variable (see `Hull`).
    var top = top_value;
    for (var k = 0u; k < 3u; k++) {
        var m = cross(vb - va, top[k] - va);
        let len = length(m);
        if len < 1e-12 {
            continue;
        }
        m /= len;
        if plane_side(vc, va, m) > 0.0 {
            m = -m;
        }
        var ok = true;
        for (var j = 0u; j < 3u; j++) {
            if plane_side(top[j], va, m) > eps {
                ok = false;
            }
        }
        if ok {
            return vec4<f32>(m, dot(m, va));
        }
    }
    var m = normalize(cross(vb - va, n));
    if plane_side(vc, va, m) > 0.0 {
        m = -m;
    }
    return vec4<f32>(m, dot(m, va));
}

fn three_planes(p1: vec4<f32>, p2: vec4<f32>, p3: vec4<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let c23 = cross(p2.xyz, p3.xyz);
    let det = dot(p1.xyz, c23);
    if abs(det) < 1e-6 {
        return fallback;
    }
    return (p1.w * c23 + p2.w * cross(p3.xyz, p1.xyz) + p3.w * cross(p1.xyz, p2.xyz)) / det;
}

// The one vertex of `others` whose plane with edge (a, b) has all six hull points on
// one side; NONE if there is none or more than one (then the paper reverts to prisms).
fn tight_vertex(h: ptr<function, Hull>, a: u32, b: u32, first_other: u32, eps: f32) -> u32 {
    let pts = &(*h).pts;
    var found = NONE;
    var count = 0u;
    for (var k = first_other; k < first_other + 3u; k++) {
        let m0 = cross((*pts)[b] - (*pts)[a], (*pts)[k] - (*pts)[a]);
        let len = length(m0);
        if len < 1e-12 {
            continue;
        }
        let m = m0 / len;
        var pos = false;
        var neg = false;
        for (var j = 0u; j < 6u; j++) {
            let s = plane_side((*pts)[j], (*pts)[a], m);
            pos = pos || s > eps;
            neg = neg || s < -eps;
        }
        if !(pos && neg) {
            found = k;
            count += 1u;
        }
    }
    return select(NONE, found, count == 1u);
}

// The hull's points and triangles are read by loop counters and computed indices, so
// the functions below take it by pointer and copy array arguments into variables once:
// an array value indexed by a variable is written into a temporary to be indexed (see
// `size_px`).
struct Hull {
    pts: array<vec3<f32>, 6>,
    tri: array<vec3<u32>, 8>,
    tight: bool,
}

fn orient_outward(h: ptr<function, Hull>) {
    var c = vec3<f32>(0.0);
    for (var i = 0u; i < 6u; i++) {
        c += (*h).pts[i];
    }
    c /= 6.0;
    for (var t = 0u; t < 8u; t++) {
        let tr = (*h).tri[t];
        let nrm = cross((*h).pts[tr.y] - (*h).pts[tr.x], (*h).pts[tr.z] - (*h).pts[tr.x]);
        if dot(nrm, (*h).pts[tr.x] - c) < 0.0 {
            (*h).tri[t] = vec3<u32>(tr.x, tr.z, tr.y);
        }
    }
}

fn build_hull(v_value: array<vec3<f32>, 3>, top_value: array<vec3<f32>, 3>, n: vec3<f32>, y_max: f32) -> Hull {
    var v = v_value;
    var top = top_value;
    var h: Hull;
    let size = max(max(distance(v[0], v[1]), distance(v[1], v[2])), distance(v[2], v[0]))
        + max(max(distance(top[0], top[1]), distance(top[1], top[2])), distance(top[2], top[0]));
    let eps = 1e-4 * max(size, y_max);
    h.pts[0] = v[0];
    h.pts[1] = v[1];
    h.pts[2] = v[2];
    h.pts[3] = top[0];
    h.pts[4] = top[1];
    h.pts[5] = top[2];
    h.tri[0] = vec3<u32>(0u, 1u, 2u);
    h.tri[1] = vec3<u32>(3u, 4u, 5u);
    h.tight = false;
    if u.tight_hulls == 1u {
        // Sect. 4.3: one triangle per base edge (with a top vertex) and per top edge
        // (with a base vertex): the convex hull of the two triangles when each choice
        // is unique.
        var ok = true;
        for (var e = 0u; e < 3u; e++) {
            let a = e;
            let b = (e + 1u) % 3u;
            let k_top = tight_vertex(&h, a, b, 3u, eps);
            let k_base = tight_vertex(&h, a + 3u, b + 3u, 0u, eps);
            ok = ok && k_top != NONE && k_base != NONE;
            h.tri[2u + e] = vec3<u32>(a, b, select(3u, k_top, k_top != NONE));
            h.tri[5u + e] = vec3<u32>(a + 3u, b + 3u, select(0u, k_base, k_base != NONE));
        }
        h.tight = ok;
    }
    if !h.tight {
        // Ernst et al.'s bounding prism: three touching planes through the base edges,
        // cut by the base plane and the plane parallel to it at y_max.
        var planes: array<vec4<f32>, 3>;
        for (var e = 0u; e < 3u; e++) {
            planes[e] = prism_plane(v[e], v[(e + 1u) % 3u], v[(e + 2u) % 3u], top, n, eps);
        }
        let cap = vec4<f32>(n, dot(n, v[0]) + y_max);
        for (var i = 0u; i < 3u; i++) {
            // Vertex i lies on the planes of edges (i-1, i) and (i, i+1).
            h.pts[3u + i] = three_planes(planes[(i + 2u) % 3u], planes[i], cap, top[i]);
        }
        for (var e = 0u; e < 3u; e++) {
            let a = e;
            let b = (e + 1u) % 3u;
            h.tri[2u + 2u * e] = vec3<u32>(a, b, b + 3u);
            h.tri[3u + 2u * e] = vec3<u32>(a, b + 3u, a + 3u);
        }
    }
    orient_outward(&h);
    return h;
}

fn pack_tris(h: ptr<function, Hull>) -> vec4<u32> {
    var words = vec4<u32>(0u, 0u, 0u, select(0u, 1u, h.tight));
    for (var t = 0u; t < 8u; t++) {
        for (var c = 0u; c < 3u; c++) {
            let i = t * 3u + c;
            words[i / 8u] |= (*h).tri[t][c] << (4u * (i % 8u));
        }
    }
    return words;
}

// `lattice`: which corners are vertices of the grid's lattice (a clipped beam's corners
// on its leaf's edges are not, and keep their beam's own irradiance).
fn write_beam(slot: u32, c: Candidate, k: Corners, family: u32, lattice: vec3<bool>) {
    let g = corners_geometry(k);
    var b: Beam;
    let ends = end_heights(k, g);
    let y_max = max(max(ends.x, ends.y), ends.z);
    let measure = source_measure(c.uv01.xy, c.uv01.zw, c.uv2_level.xy);
    // Fixed indices (see size_px).
    let v = array<vec3<f32>, 3>(k.p[0].origin, k.p[1].origin, k.p[2].origin);
    let top = array<vec3<f32>, 3>(v[0] + y_max * g.d[0], v[1] + y_max * g.d[1], v[2] + y_max * g.d[2]);
    b.v = array<vec4<f32>, 3>(vec4<f32>(v[0], g.a.x), vec4<f32>(v[1], g.a.y), vec4<f32>(v[2], g.a.z));
    b.d = array<vec4<f32>, 3>(vec4<f32>(g.d[0], ends.x), vec4<f32>(g.d[1], ends.y), vec4<f32>(g.d[2], ends.z));
    b.flux = array<vec4<f32>, 3>(vec4<f32>(k.p[0].weight * measure, 0.0), vec4<f32>(k.p[1].weight * measure, 0.0),
                                 vec4<f32>(k.p[2].weight * measure, 0.0));
    let rehits = k.p[0].rehits + k.p[1].rehits + k.p[2].rehits;
    let tir = k.p[0].tir + k.p[1].tir + k.p[2].tir;
    b.flux[0].w = f32(family);
    b.flux[1].w = f32(rehits);
    b.flux[2].w = f32(tir);
    b.n = vec4<f32>(g.n, y_max);
    var h = build_hull(v, top, g.n, y_max);
    b.hull = array<vec4<f32>, 6>(vec4<f32>(h.pts[0], 1.0), vec4<f32>(h.pts[1], 1.0), vec4<f32>(h.pts[2], 1.0),
                                 vec4<f32>(h.pts[3], 1.0), vec4<f32>(h.pts[4], 1.0), vec4<f32>(h.pts[5], 1.0));
    b.tris = pack_tris(&h);
    if VERTEX_IRRADIANCE {
        // The beam is listed at its corners' lattice vertices, and the corners'
        // entries wait in the hull's unused w for `vertex_irradiance`, which replaces
        // them with the corners' irradiance factors.
        var uv = array<vec2<f32>, 3>(c.uv01.xy, c.uv01.zw, c.uv2_level.xy);
        for (var i = 0u; i < 3u; i++) {
            if !lattice[i] {
                b.hull[i].w = bitcast<f32>(NONE);
                continue;
            }
            let entry = lattice_entry(uv[i]);
            b.hull[i].w = bitcast<f32>(entry);
            let r = vertex_list(entry, family);
            let listed = atomicAdd(&control[r], 1u);
            if listed < VERTEX_LIST_SLOTS {
                atomicStore(&control[r + 1u + listed], slot);
            }
        }
    }
    beams[slot] = b;
    atomicAdd(&control[select(C_PRISM, C_TIGHT, h.tight)], 1u);
    if rehits > 0u {
        atomicAdd(&control[C_BEAMS_REHIT], 1u);
    }
    if tir > 0u {
        atomicAdd(&control[C_BEAMS_TIR], 1u);
    }
}

@compute @workgroup_size(64)
fn emit(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= atomicLoad(&control[C_COUNT]) {
        return;
    }
    let raw = actions[id.x];
    let a = resolve(raw);
    let off = offsets[id.x];
    let c = load_candidate(id.x);
    let level = u32(c.uv2_level.z);
    if (raw & ACTION_WANT) != 0u && a != ACTION_SPLIT {
        // A split the budget left undone: a leaf, counted as the oracle's leaves are.
        atomicAdd(&control[C_SPLITS_DEFERRED], 1u);
        count_drop((raw >> ACTION_DROP_SHIFT) & 3u, (raw >> ACTION_NO_RECEIVER_SHIFT) & 15u);
    }
    if a == ACTION_SPLIT {
        if off.x + 4u > u.max_beams {
            return;
        }
        // Midpoint subdivision in uv: the children are traced afresh at the next
        // level (the projected grid, not an interpolation of the parent).
        let p0 = c.uv01.xy;
        let p1 = c.uv01.zw;
        let p2 = c.uv2_level.xy;
        let m01 = 0.5 * (p0 + p1);
        let m12 = 0.5 * (p1 + p2);
        let m20 = 0.5 * (p2 + p0);
        let l = f32(level + 1u);
        // The children inherit the size the oracle measured (0 unranked).
        let size = c.uv2_level.w;
        var t: Candidate;
        t.uv01 = vec4<f32>(p0, m01); t.uv2_level = vec4<f32>(m20, l, size); store_child(off.x, t);
        t.uv01 = vec4<f32>(m01, p1); t.uv2_level = vec4<f32>(m12, l, size); store_child(off.x + 1u, t);
        t.uv01 = vec4<f32>(m20, m12); t.uv2_level = vec4<f32>(p2, l, size); store_child(off.x + 2u, t);
        t.uv01 = vec4<f32>(m01, m12); t.uv2_level = vec4<f32>(m20, l, size); store_child(off.x + 3u, t);
        // The children's corners are this triangle's corners and midpoints, traced;
        // where they may split again, their oracle traces their edge midpoints.
        if VERTEX_CACHE && level + 1u < u.levels {
            mark_midpoints(p0, m01, m20);
            mark_midpoints(m01, p1, m12);
            mark_midpoints(m20, m12, p2);
            mark_midpoints(m01, m12, m20);
        }
        // Its corners' Fresnel reflections were traced at its level; the new ones'.
        mark_corner(m01);
        mark_corner(m12);
        mark_corner(m20);
        return;
    }
    // A leaf: one job per beam and per orphan record it makes, written into the slot
    // the record will take (the candidate's corners, its level and the family), turned
    // into the record after the last level by `emit_beams` and `emit_orphans`, one
    // invocation each. Tracing here would make every candidate of the level pay for
    // the tracer where most of them split (a GPU's wave waits for its slowest lane;
    // on lavapipe every invocation of a kernel pays for the code it holds, taken or
    // not: see POSITIONAL_LIGHTS).
    var slot = atomicLoad(&control[C_BEAM_BASE]) + off.y;
    var orphan_slot = atomicLoad(&control[C_ORPHAN_BASE]) + off.w;
    for (var family = 0u; family < FAMILY_INTERNAL + u.bounces; family++) {
        let job = vec4<f32>(c.uv2_level.xy, f32(level), f32(family));
        if (a & (1u << family)) != 0u {
            if slot < u.max_beams {
                beams[slot].v[0] = c.uv01;
                beams[slot].v[1] = job;
                // Counted here, not when written: `budget` reads the beams of the
                // coarser levels.
                atomicAdd(&control[C_BEAMS_PER_LEVEL + min(level, MAX_LEVELS)], 1u);
                atomicAdd(&control[C_BEAMS_PER_FAMILY + min(family, FAMILY_INTERNAL + MAX_BOUNCES - 1u)], 1u);
            }
            slot += 1u;
        }
        // CLIP_LEAVES: a job per clipped beam, its part (1-based) in the family word.
        if CLIP_LEAVES && u.splat_orphans == 0u {
            let parts = clipped_beams(off.z, family);
            for (var part = 1u; part <= parts; part++) {
                if slot < u.max_beams {
                    beams[slot].v[0] = c.uv01;
                    beams[slot].v[1] = vec4<f32>(job.xyz, f32(family + part * CLIP_PART));
                    atomicAdd(&control[C_BEAMS_PER_LEVEL + min(level, MAX_LEVELS)], 1u);
                    atomicAdd(&control[C_BEAMS_PER_FAMILY + min(family, FAMILY_INTERNAL + MAX_BOUNCES - 1u)], 1u);
                    atomicAdd(&control[C_BEAMS_CLIPPED], 1u);
                    atomicAdd(&control[C_BEAMS_CLIPPED_BUDGET], select(0u, 1u, family <= FAMILY_REFLECTED));
                }
                slot += 1u;
            }
        }
        if u.splat_orphans == 1u && (off.z & (1u << family)) != 0u {
            if orphan_slot < u.max_beams {
                orphans[orphan_slot].point[0] = c.uv01;
                orphans[orphan_slot].point[1] = job;
            }
            orphan_slot += 1u;
        }
    }
}

// A record's job as `emit` left it in the record's slot: the leaf's corners (uv) and
// level, and the family.
struct Job {
    c: Candidate,
    family: u32,
}

fn job(uv01: vec4<f32>, uv2_level_family: vec4<f32>) -> Job {
    let c = Candidate(uv01, vec4<f32>(uv2_level_family.xyz, 0.0));
    return Job(c, u32(uv2_level_family.w));
}

// After the last level, one invocation per beam: the leaf's family traced from its
// corners into the slot its job was in. The same slots, in candidate order, every frame.
@compute @workgroup_size(64)
fn emit_beams(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= atomicLoad(&control[C_BEAM_TOTAL]) {
        return;
    }
    let j = job(beams[id.x].v[0], beams[id.x].v[1]);
    let family = j.family % CLIP_PART;
    let k = trace_corners(j.c, family);
    if CLIP_LEAVES && j.family >= CLIP_PART {
        let clipped = clip_leaf(j.c, k, family, j.family / CLIP_PART - 1u);
        if corners_geometry(clipped.k).ok {
            write_beam(id.x, clipped.c, clipped.k, family, clipped.lattice);
            return;
        }
        let moved = rebased(clipped.k);
        if corners_geometry(moved.k).ok && moved.ahead {
            write_beam(id.x, clipped.c, moved.k, family, clipped.lattice);
            atomicAdd(&control[C_BEAMS_REBASED], 1u);
            return;
        }
        let landing = landing_beam(clipped.k);
        if corners_geometry(landing.k).ok && landing.ahead {
            write_beam(id.x, clipped.c, landing.k, family, clipped.lattice);
            atomicAdd(&control[C_BEAMS_LANDING], 1u);
            return;
        }
        write_empty_beam(id.x, k.p[0].origin, family);
        return;
    }
    write_beam(id.x, j.c, k, family, vec3<bool>(true));
}

// Clipped leaves (CLIP_LEAVES, beyond the paper: Sect. 4.1 omits "invalid triangles
// crossing the silhouettes", and refinement only narrows them). A leaf whose corners
// part ways for a family keeps that family's light where its corners agree: each
// group of corners on one path (same objects met, same receiver) emits the part of
// the triangle around it, bounded on the edges to the other corners by the last point
// of the group's path that CLIP_STEPS bisections find. A pair of corners bounds a
// quad (two beams, one bisected point shared), a corner alone a triangle. The light
// between the bisected points of different groups (1/2^CLIP_STEPS of each edge, and
// the strip their chords cut across the triangle) stays lost; a group's path may turn
// into another inside its part, which a beam cannot see, as in any leaf.
override CLIP_LEAVES: bool;
const CLIP_STEPS: u32 = 6u;
// A job's family word is family + part · CLIP_PART, part 1..=3 for a clipped beam
// (0: the leaf's whole beam); families are below 16 (FAMILY_INTERNAL + MAX_BOUNCES).
const CLIP_PART: u32 = 16u;

// Corners a and b follow one path: both valid, the same objects and receiver.
fn same_path(a: PathEnd, b: PathEnd) -> bool {
    return a.valid && b.valid && a.signature == b.signature && a.end_object == b.end_object;
}

// A corner whose light reaches the image (a receiver, or anywhere in a medium).
fn corner_lands(p: PathEnd) -> bool {
    return p.valid && (u.sigma_t.w > 0.5 || p.end_object != NONE);
}

// The clipped beams of a family whose corners part ways: two for a pair on one path
// (a quad), one for each corner alone, none for a corner whose light lands nowhere;
// corners that agree (a leaf that lost its beam to its geometry) make one, the leaf.
fn clip_count(k: Corners) -> u32 {
    let p0 = k.p[0];
    let p1 = k.p[1];
    let p2 = k.p[2];
    let s01 = same_path(p0, p1);
    let s12 = same_path(p1, p2);
    let s20 = same_path(p2, p0);
    if s01 && s12 {
        // The corners agree, and the leaf lost its beam to its geometry: one beam,
        // the whole leaf, rebased (`rebased`).
        return u32(corner_lands(p0));
    }
    if s01 {
        return 2u * u32(corner_lands(p0)) + u32(corner_lands(p2));
    }
    if s12 {
        return 2u * u32(corner_lands(p1)) + u32(corner_lands(p0));
    }
    if s20 {
        return 2u * u32(corner_lands(p2)) + u32(corner_lands(p1));
    }
    return u32(corner_lands(p0)) + u32(corner_lands(p1)) + u32(corner_lands(p2));
}

// Clipped beams of `family` in a leaf's packed counts: CLIP_BITS per family (at most
// 3 beams, FAMILY_INTERNAL + MAX_BOUNCES families in 20 bits).
const CLIP_BITS: u32 = 2u;
fn clipped_beams(clips: u32, family: u32) -> u32 {
    return (clips >> (CLIP_BITS * family)) & 3u;
}

fn clipped_total(clips: u32) -> u32 {
    var total = 0u;
    for (var family = 0u; family < FAMILY_INTERNAL + u.bounces; family++) {
        total += clipped_beams(clips, family);
    }
    return total;
}

// The last point of `inside`'s path on the edge from uv_in towards uv_out: CLIP_STEPS
// bisections, each a trace of the family's path (not the vertex cache: these points
// lie off its lattice).
struct ClipPoint {
    uv: vec2<f32>,
    p: PathEnd,
}

fn clip_edge(uv_in: vec2<f32>, uv_out: vec2<f32>, inside: PathEnd, family: u32) -> ClipPoint {
    var lo = 0.0;
    var hi = 1.0;
    var p = inside;
    for (var step = 0u; step < CLIP_STEPS; step++) {
        let t = 0.5 * (lo + hi);
        let m = trace_path(mix(uv_in, uv_out, t), family);
        if same_path(m, inside) {
            lo = t;
            p = m;
        } else {
            hi = t;
        }
    }
    return ClipPoint(mix(uv_in, uv_out, lo), p);
}

struct Clipped {
    c: Candidate,
    k: Corners,
    lattice: vec3<bool>,
}

// Clipped beam `part` (0-based, in clip_count's order) of a leaf whose corners `k` of
// `family` part ways. Each of its corners is a leaf corner (inner == outer) or the
// clipped point on the edge from corner inner towards corner outer; corners keep the
// leaf's winding.
fn clip_leaf(c: Candidate, corners: Corners, family: u32, part: u32) -> Clipped {
    var k = corners;
    var uv = array<vec2<f32>, 3>(c.uv01.xy, c.uv01.zw, c.uv2_level.xy);
    let s01 = same_path(k.p[0], k.p[1]);
    let s12 = same_path(k.p[1], k.p[2]);
    let s20 = same_path(k.p[2], k.p[0]);
    // Each corner of the part: (inner, outer).
    var spec = array<vec2<u32>, 3>(vec2<u32>(0u, 0u), vec2<u32>(1u, 1u), vec2<u32>(2u, 2u));
    if s01 && s12 {
        // The whole leaf (clip_count).
    } else if s01 || s12 || s20 {
        // The pair (a, a + 1) and the corner alone, b.
        let a = select(select(2u, 1u, s12), 0u, s01);
        let a1 = (a + 1u) % 3u;
        let b = (a + 2u) % 3u;
        var q = part;
        if !corner_lands(k.p[a]) {
            q += 2u;
        }
        if q == 0u {
            spec = array<vec2<u32>, 3>(vec2<u32>(a, a), vec2<u32>(a1, a1), vec2<u32>(a1, b));
        } else if q == 1u {
            spec = array<vec2<u32>, 3>(vec2<u32>(a, a), vec2<u32>(a1, b), vec2<u32>(a, b));
        } else {
            spec = array<vec2<u32>, 3>(vec2<u32>(b, b), vec2<u32>(b, a), vec2<u32>(b, a1));
        }
    } else {
        // Each landed corner alone, in corner order.
        var i = 0u;
        var seen = 0u;
        for (var j = 0u; j < 3u; j++) {
            if corner_lands(k.p[j]) {
                if seen == part {
                    i = j;
                }
                seen += 1u;
            }
        }
        spec = array<vec2<u32>, 3>(vec2<u32>(i, i), vec2<u32>(i, (i + 1u) % 3u), vec2<u32>(i, (i + 2u) % 3u));
    }
    var out: Clipped;
    var out_uv: array<vec2<f32>, 3>;
    for (var v = 0u; v < 3u; v++) {
        let inner = spec[v].x;
        let outer = spec[v].y;
        out.lattice[v] = inner == outer;
        if inner == outer {
            out_uv[v] = uv[inner];
            out.k.p[v] = k.p[inner];
        } else {
            let e = clip_edge(uv[inner], uv[outer], k.p[inner], family);
            out_uv[v] = e.uv;
            out.k.p[v] = e.p;
        }
    }
    out.c = Candidate(vec4<f32>(out_uv[0], out_uv[1]), vec4<f32>(out_uv[2], c.uv2_level.zw));
    return out;
}

// A clipped beam's base is where its corners' paths leave the last specular surface;
// at a silhouette or a fold those points can lie edge-on to the light (a corner's
// direction along or across the base plane: no beam space, Ernst et al.'s heights
// must be positive). The same rays then start on the plane across their mean
// direction through the corner furthest along it (each origin moved forward along its
// own ray, t_end shortened alike): the beam is the same bundle from there on, and
// `ahead` says every corner still meets that plane before its receiver. Of
// sphere_on_plane's clipped main-path beams at 128x96 (static-grid, tracer=bvh,
// reflections=false) 315 of 645 had no beam space at their exit points, 248 of them
// with a direction across the base plane. Of the glass cushion's 22,598 (8 bounces)
// 4,725 are rebased, 1,236 drawn as landing triangles (`landing_beam`) and 1,550
// empty, all of those with zero flux (no bisected point of their group's path left
// their corner).
struct Rebased {
    k: Corners,
    ahead: bool,
}

fn rebased(corners: Corners) -> Rebased {
    var r = Rebased(corners, true);
    let sum = r.k.p[0].dir + r.k.p[1].dir + r.k.p[2].dir;
    if dot(sum, sum) < 1e-12 {
        r.ahead = false;
        return r;
    }
    let m = normalize(sum);
    let plane = max(max(dot(r.k.p[0].origin, m), dot(r.k.p[1].origin, m)), dot(r.k.p[2].origin, m));
    for (var i = 0u; i < 3u; i++) {
        let along = dot(r.k.p[i].dir, m);
        if along <= 0.0 {
            r.ahead = false;
            return r;
        }
        let s = (plane - dot(r.k.p[i].origin, m)) / along;
        r.k.p[i].origin += s * r.k.p[i].dir;
        r.k.p[i].t_end -= s;
        r.ahead = r.ahead && r.k.p[i].t_end > 0.0;
    }
    return r;
}

// Where even the rebased rays admit no beam space (they spread over more than a
// half-space, or cross before the plane), the light still lands where the corners land:
// the beam is then the landing triangle's, the three corners lifted off their landing
// points against the rays' mean direction by the triangle's size and sent back down
// along it, so its flux lands on the triangle of the corners' landings (ΔΦ/ΔA there,
// as the caustic triangles method draws it). Its in-scattered light is not the true
// rays', so in a medium each corner's flux takes the extinction of the way it skips.
fn landing_beam(corners: Corners) -> Rebased {
    var r = Rebased(corners, false);
    let sum = r.k.p[0].dir + r.k.p[1].dir + r.k.p[2].dir;
    if dot(sum, sum) < 1e-12 || r.k.p[0].end_object == NONE {
        return r;
    }
    let m = normalize(sum);
    let l0 = r.k.p[0].origin + r.k.p[0].dir * r.k.p[0].t_end;
    let l1 = r.k.p[1].origin + r.k.p[1].dir * r.k.p[1].t_end;
    let l2 = r.k.p[2].origin + r.k.p[2].dir * r.k.p[2].t_end;
    let lift = max(max(distance(l0, l1), distance(l1, l2)), max(distance(l2, l0), 1e-4));
    let land = array<vec3<f32>, 3>(l0, l1, l2);
    for (var i = 0u; i < 3u; i++) {
        r.k.p[i].weight *= extinction(max(r.k.p[i].t_end - lift, 0.0));
        r.k.p[i].origin = land[i] - lift * m;
        r.k.p[i].dir = m;
        r.k.p[i].t_end = lift;
    }
    r.ahead = true;
    return r;
}

// A clipped beam too thin for a beam space (corners on a line, or an edge direction
// in its base plane): no light, a hull that covers no pixel, and no lattice corners.
fn write_empty_beam(slot: u32, at: vec3<f32>, family: u32) {
    var b: Beam;
    let up = vec3<f32>(0.0, 1.0, 0.0);
    b.v = array<vec4<f32>, 3>(vec4<f32>(at, 1.0), vec4<f32>(at, 0.0), vec4<f32>(at, 0.0));
    b.d = array<vec4<f32>, 3>(vec4<f32>(up, 0.0), vec4<f32>(up, 0.0), vec4<f32>(up, 0.0));
    b.flux = array<vec4<f32>, 3>(vec4<f32>(0.0, 0.0, 0.0, f32(family)), vec4<f32>(0.0), vec4<f32>(0.0));
    b.n = vec4<f32>(up, 0.0);
    let none = bitcast<f32>(NONE);
    b.hull = array<vec4<f32>, 6>(vec4<f32>(at, none), vec4<f32>(at, none), vec4<f32>(at, none),
                                 vec4<f32>(at, 1.0), vec4<f32>(at, 1.0), vec4<f32>(at, 1.0));
    b.tris = vec4<u32>(0u);
    beams[slot] = b;
    // Counted with the prisms (hulls_tight + hulls_prism = beams) and on its own.
    atomicAdd(&control[C_PRISM], 1u);
    atomicAdd(&control[C_BEAMS_CLIPPED_EMPTY], 1u);
}

// With splat_orphans, after the last level, one invocation per orphan record: the
// corners of a family its leaf traced but emits no beam for while some corner of
// theirs landed (`decide`, offsets[].z).
@compute @workgroup_size(64)
fn emit_orphans(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= atomicLoad(&control[C_ORPHAN_TOTAL]) {
        return;
    }
    let j = job(orphans[id.x].point[0], orphans[id.x].point[1]);
    write_orphan(id.x, j.c, trace_corners(j.c, j.family));
}

// The corners of a family the leaf emits no beam for: each landed corner keeps a third
// of the triangle's flux (the vertex rule of quadrature over it), so the light a
// silhouette or a fold tears off the beams still reaches the receiver, as points.
fn write_orphan(slot: u32, c: Candidate, corners: Corners) {
    var k = corners;
    let share = source_measure(c.uv01.xy, c.uv01.zw, c.uv2_level.xy) / 3.0;
    var o: Orphan;
    o.receiver = vec4<u32>(NONE);
    var landed = 0u;
    for (var i = 0u; i < 3u; i++) {
        let p = k.p[i];
        if p.valid && p.end_object != NONE {
            o.point[i] = vec4<f32>(p.origin + p.dir * p.t_end, p.t_end);
            o.dir[i] = vec4<f32>(p.dir, 0.0);
            o.flux[i] = vec4<f32>(p.weight * share, 0.0);
            o.receiver[i] = p.end_object;
            landed += 1u;
        }
    }
    orphans[slot] = o;
    atomicAdd(&control[C_ORPHAN_CORNERS], landed);
}

// vertex_irradiance (the smooth interpolation of Ernst et al. 2005 that Sect. 7 names
// beside its one area function per beam): `emit_beams` lists each beam at its corners'
// lattice vertices (`write_beam`), and after the last level `vertex_irradiance` gives
// each corner the irradiance where the light lands around its vertex: the flux of the
// beams of its family listed there over their landing area (ΔΦ/ΔA, each beam's A at
// its mean landing height), a flux-weighted mean no focus can blow up (averaging the
// beams' area functions themselves, Ernst's way, cancels where a fold parts
// neighbours: sphere_on_plane at 256x192, static 16², flux ratio 0.867 -> 1.855). The
// corner keeps it as a factor on the beam's own irradiance, clamped to
// [1/vertex_irradiance_max, vertex_irradiance_max], in the hull's unused w (corner i:
// hull[i].w), and the shading interpolates the factors across the beam
// (beam_shading.wgsl `parallel_irradiance`), so the irradiance no longer steps where
// one beam meets the next. A corner at a T-junction (a coarser neighbour's edge
// midpoint) averages over the finer beams only.
override VERTEX_IRRADIANCE: bool;
override VERTEX_IRRADIANCE_MAX: f32;

// The words of lattice vertex `entry` (lattice_entry's) for `family` past the counters.
fn vertex_list(entry: u32, family: u32) -> u32 {
    return C_VERTEX_LISTS + ((entry - 1u) * (FAMILY_INTERNAL + u.bounces) + family) * VERTEX_LIST_WORDS;
}

// The flux (luminance, W) of beam `s` and its area (m²) at its mean landing height,
// clamped as the shading clamps it.
fn beam_landing(s: u32) -> vec2<f32> {
    let flux = luminance(beams[s].flux[0].xyz + beams[s].flux[1].xyz + beams[s].flux[2].xyz) / 3.0;
    let a = vec3<f32>(beams[s].v[0].w, beams[s].v[1].w, beams[s].v[2].w);
    let y = (beams[s].d[0].w + beams[s].d[1].w + beams[s].d[2].w) / 3.0;
    return vec2<f32>(flux, max(abs(area_at(a, y)), abs(a.x) / u.max_focus));
}

@compute @workgroup_size(256)
fn vertex_irradiance(@builtin(global_invocation_id) id: vec3<u32>) {
    let slot = id.x;
    if !VERTEX_IRRADIANCE || slot >= min(atomicLoad(&control[C_BEAM_TOTAL]), u.max_beams) {
        return;
    }
    let family = u32(beams[slot].flux[0].w);
    let own = beam_landing(slot);
    var factor = vec3<f32>(1.0);
    for (var i = 0u; i < 3u; i++) {
        let entry = bitcast<u32>(beams[slot].hull[i].w);
        if entry == NONE {
            continue;
        }
        let r = vertex_list(entry, family);
        let n = min(atomicLoad(&control[r]), VERTEX_LIST_SLOTS);
        // The listed beams in slot order, so that the sums, and the image, are the
        // same on every run whatever order `emit_beams` listed them in.
        var listed: array<u32, VERTEX_LIST_SLOTS>;
        for (var j = 0u; j < n; j++) {
            let s = atomicLoad(&control[r + 1u + j]);
            var k = j;
            while k > 0u && listed[k - 1u] > s {
                listed[k] = listed[k - 1u];
                k -= 1u;
            }
            listed[k] = s;
        }
        var sum = vec2<f32>(0.0);
        for (var j = 0u; j < n; j++) {
            sum += beam_landing(listed[j]);
        }
        // The vertex's irradiance over the beam's own (ΔΦ/ΔA against Φ/A).
        if own.x > 0.0 && sum.y > 0.0 {
            // Clamped (vertex_irradiance_max): where the beams around a vertex differ by
            // more (a focus or a fold between them) a flux-weighted mean moves light
            // across it; there the corner keeps nearer the beam's own irradiance.
            factor[i] = clamp((sum.x / sum.y) / (own.x / own.y), 1.0 / VERTEX_IRRADIANCE_MAX, VERTEX_IRRADIANCE_MAX);
        }
    }
    // The beam keeps its flux (each corner's weight integrates to a third of the
    // cross-section at every height): the factors tilt its irradiance towards its
    // neighbours' and move no light between beams (unnormalised, water_pool at 192x144,
    // static 64²: flux ratio 0.983 -> 1.009, HDR-FLIP 0.154 -> 0.185).
    let lum = vec3<f32>(luminance(beams[slot].flux[0].xyz), luminance(beams[slot].flux[1].xyz),
                        luminance(beams[slot].flux[2].xyz));
    let tilted = dot(factor, lum);
    if tilted > 0.0 {
        factor *= (lum.x + lum.y + lum.z) / tilted;
    }
    // Every read of this beam's entries is done: only this invocation writes its hull,
    // and the others read fluxes, areas and heights.
    beams[slot].hull[0].w = factor.x;
    beams[slot].hull[1].w = factor.y;
    beams[slot].hull[2].w = factor.z;
}

// Moves to the next level's list.
@compute @workgroup_size(1)
fn advance() {
    let next = atomicLoad(&control[C_NEXT_COUNT]);
    atomicStore(&control[C_COUNT], next);
    atomicAdd(&control[C_LEVEL], 1u);
    set_dispatch(next);
    // emit_beams and emit_orphans (after the last level): one invocation per record.
    indirect_args[20] = (atomicLoad(&control[C_BEAM_TOTAL]) + 63u) / 64u;
    indirect_args[21] = 1u;
    indirect_args[22] = 1u;
    indirect_args[23] = (atomicLoad(&control[C_ORPHAN_TOTAL]) + 63u) / 64u;
    indirect_args[24] = 1u;
    indirect_args[25] = 1u;
}

// Vertices the orphan draw takes per corner: 1 (a point) or 6 (orphan_kernel_px's quad).
override ORPHAN_VERTICES: u32;

// Indirect draws: every beam's hull (8 triangles, 24 vertices per beam) and, with
// splat_orphans, every orphan corner (3 points per record); and the compute
// rasterizer's dispatch.
@compute @workgroup_size(1)
fn finalize() {
    if VERTEX_CACHE {
        // The next generation (the next frame, or the next light) stamps its own.
        vertex_paths[0].traced += 1u;
    }
    indirect_args[4] = 24u * atomicLoad(&control[C_BEAM_TOTAL]);
    indirect_args[5] = 1u;
    indirect_args[6] = 0u;
    indirect_args[7] = 0u;
    // One point per orphan corner (a corner that did not land is culled), or the six
    // vertices of its kernel's quad (orphan_kernel_px).
    indirect_args[8] = 3u * ORPHAN_VERTICES * atomicLoad(&control[C_ORPHAN_TOTAL]);
    indirect_args[9] = 1u;
    indirect_args[10] = 0u;
    indirect_args[11] = 0u;
    // raster = compute: workgroups per beam along z, beams in rows of at most 32,768
    // (rasterize_compute.wgsl reads the beam as y · x + x and skips those past the end).
    let beams = atomicLoad(&control[C_BEAM_TOTAL]);
    indirect_args[12] = min(beams, 32768u);
    indirect_args[13] = (beams + 32767u) / 32768u;
    // Workgroups per beam: at most 2,048 loop iterations of 64 pixels each over a
    // rectangle as large as the image (rasterize_compute.wgsl, llvmpipe's loop limit).
    indirect_args[14] = (u32(frame.resolution.x) * u32(frame.resolution.y) + 131071u) / 131072u;
}
