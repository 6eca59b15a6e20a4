// Distance impostor render pass (crates/gpu/src/impostor.rs): one face of the cube
// around the impostor's centre per pass. Keeps, per texel, the surface nearest to the
// centre: its smooth normal (as stored in the mesh) and its distance from the centre.

struct ImpostorView {
    view_proj: mat4x4<f32>,
    // xyz: the impostor's centre; w unused.
    center: vec4<f32>,
}

@group(0) @binding(0) var<uniform> view: ImpostorView;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) object: u32,
}

@vertex
fn vs_main(v: SceneVertexIn) -> VsOut {
    var o: VsOut;
    o.clip = view.view_proj * vec4<f32>(v.position, 1.0);
    o.world = v.position;
    o.normal = v.normal;
    o.object = v.ids.x;
    return o;
}

struct ImpostorOut {
    @location(0) normal_distance: vec4<f32>,
    @location(1) object: u32,
}

@fragment
fn fs_main(i: VsOut) -> ImpostorOut {
    var o: ImpostorOut;
    o.normal_distance = vec4<f32>(normalize(i.normal), length(i.world - view.center.xyz));
    o.object = i.object;
    return o;
}
