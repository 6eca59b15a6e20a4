// Pass 2 of wavefront: keep the triangles whose three vertices are valid and land on
// the same side of the same receiver (a triangle spanning two receivers has no
// single area to take a ratio of), compacting their indices and counting vertices
// into the indirect draw arguments. Dropped triangles are counted by reason.

struct Traced {
    old_pos: vec4<f32>,
    new_pos: vec4<f32>,
    flux: vec4<f32>,
    info: vec4<u32>,
}

struct TraceParams {
    specular_object: u32,
    light_index: u32,
    source_count: u32,
    triangle_count: u32,
}

struct DrawCounters {
    // DrawIndirectArgs: vertex_count, instance_count, first_vertex, first_instance.
    vertex_count: atomic<u32>,
    instance_count: u32,
    first_vertex: u32,
    first_instance: u32,
    dropped_invalid_vertex: atomic<u32>,
    dropped_receiver_mismatch: atomic<u32>,
    pad0: u32,
    pad1: u32,
}

@group(1) @binding(0) var<uniform> tp: TraceParams;
@group(1) @binding(1) var<storage, read> traced: array<Traced>;
@group(1) @binding(2) var<storage, read> triangles: array<u32>;
@group(1) @binding(3) var<storage, read_write> kept: array<u32>;
@group(1) @binding(4) var<storage, read_write> counters: DrawCounters;

@compute @workgroup_size(64)
fn classify_triangles(@builtin(global_invocation_id) gid: vec3<u32>) {
    let tri = gid.x;
    if tri >= tp.triangle_count {
        return;
    }
    let a = traced[triangles[3u * tri]];
    let b = traced[triangles[3u * tri + 1u]];
    let c = traced[triangles[3u * tri + 2u]];
    if a.info.x == NONE || b.info.x == NONE || c.info.x == NONE {
        atomicAdd(&counters.dropped_invalid_vertex, 1u);
        return;
    }
    if a.info.x != b.info.x || a.info.x != c.info.x || a.new_pos.w != b.new_pos.w || a.new_pos.w != c.new_pos.w {
        atomicAdd(&counters.dropped_receiver_mismatch, 1u);
        return;
    }
    let slot = atomicAdd(&counters.vertex_count, 3u) / 3u;
    kept[slot] = tri;
}
