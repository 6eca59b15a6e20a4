// G-buffer pass (camera and light views): world position, smooth normal with the
// side seen, object and material ids. Specular and diffuse objects alike.

struct View {
    view_proj: mat4x4<f32>,
    // xyz: eye position (perspective) or any point (orthographic); w unused.
    eye: vec4<f32>,
}

@group(0) @binding(0) var<uniform> view: View;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) ids: vec2<u32>,
}

@vertex
fn vs_main(v: SceneVertexIn) -> VsOut {
    var o: VsOut;
    o.clip = view.view_proj * vec4<f32>(v.position, 1.0);
    o.world = v.position;
    o.normal = v.normal;
    o.ids = v.ids;
    return o;
}

struct GOut {
    @location(0) position: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) ids: vec2<u32>,
}

@fragment
fn fs_main(i: VsOut, @builtin(front_facing) front: bool) -> GOut {
    var o: GOut;
    o.position = vec4<f32>(i.world, 1.0);
    o.normal = vec4<f32>(normalize(i.normal), select(-1.0, 1.0, front));
    o.ids = i.ids;
    return o;
}
