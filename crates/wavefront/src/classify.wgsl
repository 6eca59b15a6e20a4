// Pass 2 of wavefront: keep the triangles whose three vertices are valid, took the
// same specular path (same objects, same sides, in the same order) and land on the
// same side of the same receiver (a triangle spanning two receivers or two paths has
// no single area to take a ratio of). Dropped triangles are counted by reason.
//
// Then the draw lists, so that the camera-side passes touch only what they draw (a
// sheet of a closed refractor keeps a few percent of its triangles; drawing all of them
// and dropping the rest in the vertex shader was most of the splat's time on lavapipe):
// the kept triangles' indices, then (with `splat_orphans`) the landed corners of the
// dropped ones, each list in triangle order. An ordered compaction (counts per
// workgroup, a scan, a scatter), not an atomic append: the splat pass then draws in
// triangle order, so additive blending sums in the same order every frame and the image
// is bit-for-bit deterministic, and the same as drawing every triangle in order.
//
// Kernels, dispatched in order per sheet: `classify_triangles` (one invocation per
// triangle, a workgroup of 64 per chunk), `scan_chunks` (one workgroup), `scatter_chunks`
// (one invocation per chunk).

struct Counters {
    kept: atomic<u32>,
    dropped_invalid_vertex: atomic<u32>,
    dropped_receiver_mismatch: atomic<u32>,
    dropped_path_mismatch: atomic<u32>,
    // Landed vertices of dropped triangles, summed over the triangles (a vertex counts
    // once per dropped triangle it is a corner of): the orphans pass's points.
    orphan_corners: atomic<u32>,
}

// Whether the landed corners of dropped triangles are listed (`splat_orphans`; the list
// then has room for them, 3 words per triangle, else 1).
override SPLAT_ORPHANS: bool;
// Vertices the orphans pass draws per corner: 1 (a point) or 6 (its kernel's quad).
override ORPHAN_VERTICES: u32;

// Triangles per chunk: classify's workgroup size.
const CHUNK: u32 = 64u;
const SCAN_WORKGROUP: u32 = 256u;

@group(1) @binding(0) var<uniform> tp: TraceParams;
@group(1) @binding(1) var<storage, read> traced: array<Traced>;
@group(1) @binding(2) var<storage, read> triangles: array<u32>;
// Per triangle: KEEP_TRIANGLE, or a dropped triangle's landed corners (keep_word()).
@group(1) @binding(3) var<storage, read_write> keep: array<u32>;
@group(1) @binding(4) var<storage, read_write> counters: Counters;
// Per chunk: (kept triangles, orphan corners), then (scan_chunks) where its entries
// of the draw list start.
@group(1) @binding(5) var<storage, read_write> chunks: array<vec2<u32>>;
// The kept triangles' indices, then the orphan corners' vertex indices (3 × triangle
// + corner); read by sheet_draw.wgsl.
@group(1) @binding(6) var<storage, read_write> draw_list: array<u32>;
// Two DrawIndirectArgs (vertex count, instance count, first vertex, first instance):
// the splat's (3 per kept triangle) and the orphans' (one point per corner, starting at
// the first orphan entry of draw_list).
@group(1) @binding(7) var<storage, read_write> draw_args: array<u32, 8>;

var<workgroup> chunk_kept: atomic<u32>;
var<workgroup> chunk_orphans: atomic<u32>;
var<workgroup> scan: array<vec2<u32>, SCAN_WORKGROUP>;

fn chunk_count() -> u32 {
    return (tp.triangle_count + CHUNK - 1u) / CHUNK;
}

// The verdict on one triangle, counted: KEEP_TRIANGLE or its landed corners.
fn judge(tri: u32) -> u32 {
    let a = traced[triangles[3u * tri]];
    let b = traced[triangles[3u * tri + 1u]];
    let c = traced[triangles[3u * tri + 2u]];
    let landed = vec3<bool>(a.info.x != NONE, b.info.x != NONE, c.info.x != NONE);
    let landed_word = keep_word(landed);
    if !all(landed) {
        atomicAdd(&counters.orphan_corners, countOneBits(landed_word));
        atomicAdd(&counters.dropped_invalid_vertex, 1u);
        return landed_word;
    }
    if a.info.x != b.info.x || a.info.x != c.info.x || a.new_pos.w != b.new_pos.w || a.new_pos.w != c.new_pos.w {
        atomicAdd(&counters.dropped_receiver_mismatch, 1u);
        atomicAdd(&counters.orphan_corners, 3u);
        return landed_word;
    }
    if a.info.z != b.info.z || a.info.z != c.info.z {
        atomicAdd(&counters.dropped_path_mismatch, 1u);
        atomicAdd(&counters.orphan_corners, 3u);
        return landed_word;
    }
    atomicAdd(&counters.kept, 1u);
    return KEEP_TRIANGLE;
}

@compute @workgroup_size(64)
fn classify_triangles(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(workgroup_id) chunk: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let tri = gid.x;
    var word = 0u;
    if tri < tp.triangle_count {
        word = judge(tri);
        keep[tri] = word;
    }
    // Workgroup memory starts zeroed.
    if word == KEEP_TRIANGLE {
        atomicAdd(&chunk_kept, 1u);
    } else if word != 0u {
        atomicAdd(&chunk_orphans, countOneBits(word));
    }
    workgroupBarrier();
    if lane == 0u {
        chunks[chunk.x] = vec2<u32>(atomicLoad(&chunk_kept), atomicLoad(&chunk_orphans));
    }
}

// Exclusive offsets of every chunk's entries (the orphans after all kept triangles), and
// both draws' arguments. Each invocation sums a run of chunks, the workgroup scans the
// sums (Hillis–Steele), each run is then offset in order.
@compute @workgroup_size(256)
fn scan_chunks(@builtin(local_invocation_index) lane: u32) {
    let n = chunk_count();
    let per = (n + SCAN_WORKGROUP - 1u) / SCAN_WORKGROUP;
    let begin = min(lane * per, n);
    let end = min(begin + per, n);
    var sum = vec2<u32>(0u);
    for (var c = begin; c < end; c++) {
        sum += chunks[c];
    }
    scan[lane] = sum;
    workgroupBarrier();
    for (var step = 1u; step < SCAN_WORKGROUP; step <<= 1u) {
        var add = vec2<u32>(0u);
        if lane >= step {
            add = scan[lane - step];
        }
        workgroupBarrier();
        scan[lane] += add;
        workgroupBarrier();
    }
    let total = scan[SCAN_WORKGROUP - 1u];
    var at = scan[lane] - sum;
    at.y += total.x;
    for (var c = begin; c < end; c++) {
        let counts = chunks[c];
        chunks[c] = at;
        at += counts;
    }
    if lane == 0u {
        draw_args[0] = 3u * total.x;
        draw_args[1] = 1u;
        draw_args[2] = 0u;
        draw_args[3] = 0u;
        draw_args[4] = select(0u, ORPHAN_VERTICES * total.y, SPLAT_ORPHANS);
        draw_args[5] = 1u;
        draw_args[6] = ORPHAN_VERTICES * total.x;
        draw_args[7] = 0u;
    }
}

// Each chunk's entries at its offsets, in triangle (and corner) order.
@compute @workgroup_size(64)
fn scatter_chunks(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = gid.x;
    if c >= chunk_count() {
        return;
    }
    var at = chunks[c];
    let first = c * CHUNK;
    let last = min(first + CHUNK, tp.triangle_count);
    for (var tri = first; tri < last; tri++) {
        let word = keep[tri];
        if word == KEEP_TRIANGLE {
            draw_list[at.x] = tri;
            at.x++;
        } else if SPLAT_ORPHANS {
            for (var corner = 0u; corner < 3u; corner++) {
                if (word & landed_corner(corner)) != 0u {
                    draw_list[at.y] = 3u * tri + corner;
                    at.y++;
                }
            }
        }
    }
}
