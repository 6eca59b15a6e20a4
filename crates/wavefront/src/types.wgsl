// Types shared by wavefront's passes (trace, classify, splat, orphans).

// One wavefront vertex after tracing.
struct Traced {
    // Light-space start: light-plane point (directional) or unit direction (point/spot).
    old_pos: vec4<f32>,
    // xyz: receiver hit (world); w: +1/-1, the side of the receiver's normal the light arrives on.
    new_pos: vec4<f32>,
    // rgb: flux density carried (W per m² of light plane, or W per sr): emitted × Fresnel transmittances.
    flux: vec4<f32>,
    // x: receiver object (NONE if the vertex is invalid), y: why invalid (0 valid),
    // z: hash of the specular path (each event's object and side).
    info: vec4<u32>,
}

struct TraceParams {
    specular_object: u32,
    light_index: u32,
    source_count: u32,
    triangle_count: u32,
    // Hits a path may make on objects it has already left.
    bounces: u32,
    // Bit k: take the reflection at the path's k-th dielectric interface (this sheet).
    reflect_mask: u32,
    pad0: u32,
    pad1: u32,
}

struct SplatParams {
    // Accept a fragment when |G-buffer position - receiver point| <= tolerance × distance to the eye.
    tolerance: f32,
    pad0: f32,
    pad1: f32,
    pad2: f32,
}

// classify.wgsl's word per triangle: kept, else the corners of the dropped triangle
// that landed (bit 1 + corner), whose light the orphans pass draws.
const KEEP_TRIANGLE: u32 = 1u;

fn landed_corner(corner: u32) -> u32 {
    return 2u << corner;
}

fn keep_word(landed: vec3<bool>) -> u32 {
    return select(0u, landed_corner(0u), landed.x) | select(0u, landed_corner(1u), landed.y) | select(0u, landed_corner(2u), landed.z);
}
