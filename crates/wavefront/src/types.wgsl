// Types shared by wavefront's passes (trace, classify, splat).

// One wavefront vertex after tracing.
struct Traced {
    // Light-space start: light-plane point (directional) or unit direction (point/spot).
    old_pos: vec4<f32>,
    // xyz: receiver hit (world); w: +1/-1, the side of the receiver's normal the light arrives on.
    new_pos: vec4<f32>,
    // rgb: flux density carried (W per m² of light plane, or W per sr): emitted × Fresnel transmittances.
    flux: vec4<f32>,
    // x: receiver object (NONE if the vertex is invalid), y: why invalid (0 valid),
    // z: face of the generator the light met (0 outside, 1 inside).
    info: vec4<u32>,
}

struct TraceParams {
    specular_object: u32,
    light_index: u32,
    source_count: u32,
    triangle_count: u32,
}
