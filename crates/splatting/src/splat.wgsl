// Splatting (the caustic-mapping baseline the paper compares against, §2 and Fig. 1):
// each valid photon hit is drawn as a fixed kernel of kernel_px × kernel_px texels
// into the face of the caustic cube map its direction from the centre falls in, with
// additive blending (the kernel and why it conserves energy: photon-hits'
// splat_kernel.wgsl, shared with caustic-triangles).

struct SplatUniform {
    // Kernel side in cube-map texels.
    kernel_px: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(1) @binding(0) var<uniform> cm: CausticMapUniform;
@group(1) @binding(1) var<uniform> su: SplatUniform;
@group(1) @binding(2) var<storage, read> hits: array<PhotonHit>;

// The instance index is the cube face being drawn (one instance per face draw).
@vertex
fn vs_splat(@builtin(vertex_index) vi: u32, @builtin(instance_index) face: u32) -> SplatOut {
    return splat_vertex(hits[vi / 6u], vi % 6u, face, f32(su.kernel_px));
}
