// Low-pass filter of the surface caustic (Sect. 7): one area function per beam leaves
// small steps at beam boundaries, which the paper hides with a low-pass filter on the
// surface caustic only. A Gaussian of `sigma_px`, restricted to pixels of the same
// object (a caustic must not bleed onto the glass in front of it).

struct FilterUniforms {
    sigma_px: f32,
    radius_px: i32,
    pad0: u32,
    pad1: u32,
}

@group(1) @binding(0) var<uniform> fu: FilterUniforms;
@group(1) @binding(1) var raw_surface: texture_2d<f32>;

@fragment
fn fs_filter(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let p = vec2<i32>(pos.xy);
    let size = vec2<i32>(textureDimensions(raw_surface));
    let object = textureLoad(gbuf_ids, p, 0).x;
    if fu.radius_px <= 0 {
        return textureLoad(raw_surface, p, 0);
    }
    var sum = vec4<f32>(0.0);
    var weight = 0.0;
    let inv = -0.5 / (fu.sigma_px * fu.sigma_px);
    for (var dy = -fu.radius_px; dy <= fu.radius_px; dy++) {
        for (var dx = -fu.radius_px; dx <= fu.radius_px; dx++) {
            let q = p + vec2<i32>(dx, dy);
            if any(q < vec2<i32>(0)) || any(q >= size) {
                continue;
            }
            if textureLoad(gbuf_ids, q, 0).x != object {
                continue;
            }
            let w = exp(f32(dx * dx + dy * dy) * inv);
            sum += w * textureLoad(raw_surface, q, 0);
            weight += w;
        }
    }
    return sum / max(weight, 1e-12);
}
