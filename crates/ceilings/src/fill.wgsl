// Fill probes: additive-blend (or replace) fill of a colour target by full-screen
// triangles or by small triangles that tile the target, one layer per instance. Every
// layer covers each pixel exactly once (the small triangles are the two halves of
// `cell_px`-square cells, a watertight tiling), so the fragments of a draw are
// width x height x layers, which the count frame checks against pipeline statistics.

struct FillParams {
    // Target size in pixels.
    target_px: vec2<f32>,
    // Side of the square cells the small triangles halve (pixels).
    cell_px: f32,
    // Cells per row of the small-triangle tiling.
    cells_x: u32,
}

@group(0) @binding(0) var<uniform> params: FillParams;

struct FillOut {
    @builtin(position) clip: vec4<f32>,
    // Per layer, so the fragment shader returns something the rasterizer carried
    // (a constant colour would let a driver skip the varyings altogether).
    @location(0) @interpolate(flat) value: f32,
}

// A tiny value per fragment keeps a sum of thousands of layers well inside half-float
// range (RGBA16F saturates at 65,504).
fn layer_value(layer: u32) -> f32 {
    return 1e-4 * f32(1u + (layer & 7u));
}

// One triangle over the whole target: (-1,-1), (3,-1), (-1,3) in clip space.
@vertex
fn vs_fullscreen(@builtin(vertex_index) vi: u32, @builtin(instance_index) layer: u32) -> FillOut {
    let xy = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u)) * 2.0 - 1.0;
    var out: FillOut;
    out.clip = vec4<f32>(xy, 0.0, 1.0);
    out.value = layer_value(layer);
    return out;
}

// Triangle vi / 3 of the tiling: cell t / 2, lower-left half when t is even.
@vertex
fn vs_small(@builtin(vertex_index) vi: u32, @builtin(instance_index) layer: u32) -> FillOut {
    let t = vi / 3u;
    let corner = vi % 3u;
    let cell = t / 2u;
    let origin = vec2<f32>(f32(cell % params.cells_x), f32(cell / params.cells_x)) * params.cell_px;
    // Lower-left half: (0,0), (1,0), (0,1); upper-right half: (1,0), (1,1), (0,1).
    var lower = array<vec2<f32>, 3>(vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0), vec2<f32>(0.0, 1.0));
    var upper = array<vec2<f32>, 3>(vec2<f32>(1.0, 0.0), vec2<f32>(1.0, 1.0), vec2<f32>(0.0, 1.0));
    var unit = lower[corner];
    if (t & 1u) == 1u {
        unit = upper[corner];
    }
    let px = origin + unit * params.cell_px;
    var out: FillOut;
    out.clip = vec4<f32>(px / params.target_px * 2.0 - 1.0, 0.0, 1.0);
    out.value = layer_value(layer);
    return out;
}

// A triangle of zero area: the per-draw probe's draws rasterize nothing, so what they
// cost is the draw itself.
@vertex
fn vs_empty(@builtin(vertex_index) vi: u32) -> FillOut {
    var out: FillOut;
    out.clip = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    out.value = f32(vi);
    return out;
}

@fragment
fn fs_fill(in: FillOut) -> @location(0) vec4<f32> {
    return vec4<f32>(in.value, in.value, in.value, 1.0);
}
