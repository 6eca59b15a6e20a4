// Group 1 of the camera-side passes of wavefront (splat.wgsl, orphans.wgsl and
// splat_compute.wgsl): one sheet's traced vertices, its triangles, classify's verdicts
// and draw list, and the receiver tolerance. One declaration, so both passes bind the same entries (lib.rs
// `Sheet::new`).

@group(1) @binding(0) var<uniform> sp: SplatParams;
@group(1) @binding(1) var<storage, read> traced: array<Traced>;
@group(1) @binding(2) var<storage, read> triangles: array<u32>;
@group(1) @binding(3) var<storage, read> keep: array<u32>;
// The kept triangles, then the orphan corners (classify.wgsl's scatter_chunks); the
// raster passes draw from it with classify's indirect arguments.
@group(1) @binding(4) var<storage, read> draw_list: array<u32>;
