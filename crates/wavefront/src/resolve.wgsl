// The compute path's accumulator (splat_compute.wgsl) into the surface caustic: a
// full-screen pass adds each pixel's radiance by blending, as the hardware path's
// fragments do, and zeroes the pixel's words for the next frame. A fragment pass, so
// the surface target (the base renderer's) need not be a read-write storage texture.

@group(1) @binding(0) var<storage, read_write> accum: array<atomic<u32>>;

// As in splat_compute.wgsl.
const ACCUM_WORDS: u32 = 6u;

@fragment
fn fs_resolve(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<u32>(position.xy);
    let w = (pixel.y * u32(frame.resolution.x) + pixel.x) * ACCUM_WORDS;
    return vec4<f32>(take_fixed(w), take_fixed(w + 2u), take_fixed(w + 4u), 0.0);
}
