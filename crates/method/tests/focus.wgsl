// A test "method" for crates/method/tests/scoring.rs: an axis-aligned world-space
// rectangle in the plane z = 0, facing the camera, drawn with constant radiance into
// the surface caustic target through group 0's camera (as every method pass draws), so
// that its box-filtered image is known exactly.

struct Focus {
    // xy: lower-left corner, zw: upper-right corner (m, in the plane z = 0).
    rect: vec4<f32>,
    // Radiance (W·m⁻²·sr⁻¹).
    radiance: vec4<f32>,
}

@group(1) @binding(0) var<uniform> focus: Focus;

@vertex
fn vs_focus(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let corner = array<vec2<u32>, 6>(
        vec2<u32>(0u, 0u), vec2<u32>(1u, 0u), vec2<u32>(1u, 1u),
        vec2<u32>(0u, 0u), vec2<u32>(1u, 1u), vec2<u32>(0u, 1u),
    )[i];
    let x = select(focus.rect.x, focus.rect.z, corner.x == 1u);
    let y = select(focus.rect.y, focus.rect.w, corner.y == 1u);
    return frame.view_proj * vec4<f32>(x, y, 0.0, 1.0);
}

@fragment
fn fs_focus(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    count_fragment(p);
    return vec4<f32>(focus.radiance.rgb, 0.0);
}
