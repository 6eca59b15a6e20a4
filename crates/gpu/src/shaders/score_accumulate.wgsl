// Scoring frames (crates/gpu/src/scoring.rs): adds one sub-pixel-offset frame's three
// radiance targets into running sums, so that N×N offsets averaged give the pixel-area
// (box-filtered) image the reference computes. One invocation per pixel.

@group(0) @binding(0) var direct_in: texture_2d<f32>;
@group(0) @binding(1) var surface_in: texture_2d<f32>;
@group(0) @binding(2) var volume_in: texture_2d<f32>;
@group(0) @binding(3) var<storage, read_write> direct_sum: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> surface_sum: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> volume_sum: array<vec4<f32>>;

@compute @workgroup_size(8, 8, 1)
fn accumulate(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(surface_in);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let i = id.y * size.x + id.x;
    direct_sum[i] += textureLoad(direct_in, id.xy, 0);
    surface_sum[i] += textureLoad(surface_in, id.xy, 0);
    volume_sum[i] += textureLoad(volume_in, id.xy, 0);
}
