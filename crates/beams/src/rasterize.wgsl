// Beam rasterization (Sect. 5): each beam's hull is drawn from the camera with its
// front faces culled, so every covered pixel runs the fragment shader once per beam,
// which shades it with the beam (beam_shading.wgsl). Without a medium the pass is
// depth-culled (lib.rs `HullRaster::build`): a back face in front of the visible
// surface lights nothing and is rejected before the shader, whose attribute line below
// then also forces the test early.

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) @interpolate(flat) beam: u32,
}

@vertex
fn vs_beam(@builtin(vertex_index) vi: u32) -> VsOut {
    let beam = vi / 24u;
    let corner = vi % 24u;
    // Read through the buffer: a Beam value indexed by a variable is written into a
    // temporary to be indexed (generate.wgsl `size_px`).
    let index = (beams[beam].tris[corner / 8u] >> (4u * (corner % 8u))) & 15u;
    let p = beams[beam].hull[index].xyz;
    var o: VsOut;
    o.clip = frame.view_proj * vec4<f32>(p, 1.0);
    o.world = p;
    o.beam = beam;
    return o;
}

@fragment // fs_beam
fn fs_beam(in: VsOut) -> BeamOut {
    count_fragment(in.clip);
    let eye = frame.eye.xyz;
    return shade_beam(beams[in.beam], vec2<u32>(in.clip.xy), normalize(in.world - eye));
}
