// The compute path's accumulator (rasterize_compute.wgsl) into the targets the hardware
// path blends into: a full-screen pass writes each pixel's surface radiance into the
// raw surface caustic (cleared) and adds its volume radiance to the volume target, and
// zeroes the pixel's words for the next frame. A fragment pass, not a compute one, so
// the volume target (shared with the base renderer) is added to by blending, as on the
// hardware path, without being a storage texture.

@group(1) @binding(0) var<storage, read_write> accum: array<atomic<u32>>;

// As in rasterize_compute.wgsl.
const ACCUM_WORDS: u32 = 12u;

struct ResolveOut {
    @location(0) surface: vec4<f32>,
    @location(1) volume: vec4<f32>,
}

@fragment
fn fs_resolve(@builtin(position) position: vec4<f32>) -> ResolveOut {
    let pixel = vec2<u32>(position.xy);
    let w = (pixel.y * u32(frame.resolution.x) + pixel.x) * ACCUM_WORDS;
    var out: ResolveOut;
    out.surface = vec4<f32>(take_fixed(w), take_fixed(w + 2u), take_fixed(w + 4u), 0.0);
    out.volume = vec4<f32>(take_fixed(w + 6u), take_fixed(w + 8u), take_fixed(w + 10u), 0.0);
    return out;
}
