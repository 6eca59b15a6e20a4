// Pass 2 of wavefront: keep the triangles whose three vertices are valid, took the
// same specular path (same objects, same sides, in the same order) and land on the
// same side of the same receiver (a triangle spanning two receivers or two paths has
// no single area to take a ratio of), as one flag per triangle. Dropped triangles are
// counted by reason. Flags rather than a compacted list: the splat pass then draws
// in triangle order, so additive blending sums in the same order every frame and
// the image is bit-for-bit deterministic (an atomic compaction order is not).

struct Counters {
    kept: atomic<u32>,
    dropped_invalid_vertex: atomic<u32>,
    dropped_receiver_mismatch: atomic<u32>,
    dropped_path_mismatch: atomic<u32>,
    // Landed vertices of dropped triangles, summed over the triangles (a vertex counts
    // once per dropped triangle it is a corner of): the orphans pass's points.
    orphan_corners: atomic<u32>,
}

@group(1) @binding(0) var<uniform> tp: TraceParams;
@group(1) @binding(1) var<storage, read> traced: array<Traced>;
@group(1) @binding(2) var<storage, read> triangles: array<u32>;
@group(1) @binding(3) var<storage, read_write> keep: array<u32>;
@group(1) @binding(4) var<storage, read_write> counters: Counters;

@compute @workgroup_size(64)
fn classify_triangles(@builtin(global_invocation_id) gid: vec3<u32>) {
    let tri = gid.x;
    if tri >= tp.triangle_count {
        return;
    }
    let a = traced[triangles[3u * tri]];
    let b = traced[triangles[3u * tri + 1u]];
    let c = traced[triangles[3u * tri + 2u]];
    keep[tri] = 0u;
    let landed = u32(a.info.x != NONE) + u32(b.info.x != NONE) + u32(c.info.x != NONE);
    if landed < 3u {
        atomicAdd(&counters.orphan_corners, landed);
    }
    if a.info.x == NONE || b.info.x == NONE || c.info.x == NONE {
        atomicAdd(&counters.dropped_invalid_vertex, 1u);
        return;
    }
    if a.info.x != b.info.x || a.info.x != c.info.x || a.new_pos.w != b.new_pos.w || a.new_pos.w != c.new_pos.w {
        atomicAdd(&counters.dropped_receiver_mismatch, 1u);
        atomicAdd(&counters.orphan_corners, 3u);
        return;
    }
    if a.info.z != b.info.z || a.info.z != c.info.z {
        atomicAdd(&counters.dropped_path_mismatch, 1u);
        atomicAdd(&counters.orphan_corners, 3u);
        return;
    }
    keep[tri] = 1u;
    atomicAdd(&counters.kept, 1u);
}
