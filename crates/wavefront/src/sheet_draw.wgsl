// Group 1 of both camera-side passes of wavefront (splat.wgsl and orphans.wgsl): one
// sheet's traced vertices, its triangles and classify's keep flags, and the receiver
// tolerance. One declaration, so both passes bind the same entries (lib.rs
// `Sheet::new`).

@group(1) @binding(0) var<uniform> sp: SplatParams;
@group(1) @binding(1) var<storage, read> traced: array<Traced>;
@group(1) @binding(2) var<storage, read> triangles: array<u32>;
@group(1) @binding(3) var<storage, read> keep: array<u32>;
