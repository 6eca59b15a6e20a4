//! Distance impostors traced on the GPU against analytic intersections, on whatever
//! adapter the machine has (lavapipe on CI; without one these fail with the install hint).

use caustics_gpu::impostor::IMPOSTOR_TRACE_WGSL;
use caustics_gpu::pass::{ComputePass, Shader};
use caustics_gpu::readback::read_buffer_bytes;
use caustics_gpu::wgpu::{self, util::DeviceExt};
use caustics_gpu::{
    AdapterChoice, FrameMode, GpuContext, GpuScene, ImpostorPass, PassProfiler, Renderer,
    RendererOptions, shader,
};
use caustics_scene::{Scene, Vec3};

const TRACE_TEST_WGSL: &str = r#"
struct Ray { origin: vec4<f32>, dir: vec4<f32> }
struct Params { center: vec4<f32>, t_max: f32, tolerance: f32, count: u32, _pad: u32 }
@group(0) @binding(0) var map: texture_2d_array<f32>;
@group(0) @binding(1) var ids: texture_2d_array<u32>;
@group(0) @binding(2) var<storage, read> rays: array<Ray>;
@group(0) @binding(3) var<storage, read_write> hits: array<vec4<f32>>;
@group(0) @binding(4) var<uniform> params: Params;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.count { return; }
    let r = rays[id.x];
    let h = impostor_trace(map, params.center.xyz, r.origin.xyz, r.dir.xyz, 1e-4, params.t_max, params.tolerance);
    let object = impostor_object(ids, h.position - params.center.xyz);
    hits[id.x] = vec4<f32>(h.position, select(-1.0, f32(object), h.found));
}
"#;

struct Traced {
    position: Vec3,
    object: Option<u32>,
}

/// Traces `rays` (origin, unit direction) against an impostor of `objects` around
/// `center` (None: the objects' own centre) in sphere_on_plane.
fn trace(objects: &[usize], center: Option<Vec3>, rays: &[(Vec3, Vec3)]) -> Vec<Traced> {
    trace_in("sphere_on_plane", objects, center, rays)
}

fn trace_in(
    scene_name: &str,
    objects: &[usize],
    center: Option<Vec3>,
    rays: &[(Vec3, Vec3)],
) -> Vec<Traced> {
    let src = caustics_scene::resolve(scene_name).expect("built-in scene");
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&src).expect("read")).expect("JSON");
    json["camera"]["width"] = 32.into();
    json["camera"]["height"] = 24.into();
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = tmp.path().join("scene.json");
    std::fs::write(&path, json.to_string()).expect("write");
    let scene = Scene::load(&path).expect("scene");
    let ctx =
        GpuContext::new(&AdapterChoice::from_flag_or_env(None)).unwrap_or_else(|e| panic!("{e}"));
    let gpu_scene = GpuScene::upload(&ctx, scene.into(), Default::default()).expect("upload");
    let renderer = Renderer::new(&ctx, gpu_scene, RendererOptions::default()).expect("renderer");
    let pass = ImpostorPass::new(&ctx).expect("impostor pass");
    let impostor = match center {
        Some(c) => pass.impostor_around(&ctx, renderer.scene(), objects, c, 256),
        None => pass.impostor(&ctx, renderer.scene(), objects, 256),
    }
    .expect("impostor");

    let device = &ctx.device;
    let shader = Shader::new(
        &ctx,
        "trace test",
        shader::compose(&format!("{IMPOSTOR_TRACE_WGSL}\n{TRACE_TEST_WGSL}")),
    )
    .expect("trace test shader");
    let ray_data: Vec<[f32; 8]> = rays
        .iter()
        .map(|(o, d)| [o.x, o.y, o.z, 0.0, d.x, d.y, d.z, 0.0])
        .collect();
    let ray_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("rays"),
        contents: bytemuck::cast_slice(&ray_data),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let hit_buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("hits"),
        size: (rays.len() * 16) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let c = impostor.center;
    let mut params = [0u32; 8];
    params[..4].copy_from_slice(&bytemuck::cast::<[f32; 4], [u32; 4]>([c.x, c.y, c.z, 0.0]));
    // A long search range (4× what any ray needs): coarse steps must still find hits.
    params[4] = (8.0 * impostor.reach).to_bits();
    params[5] = 1e-3f32.to_bits();
    params[6] = rays.len() as u32;
    let param_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("params"),
        contents: bytemuck::cast_slice(&params),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let trace = ComputePass::builder(&ctx, "test/trace", &shader)
        .bind(
            0,
            &[
                ("map", &impostor.normal_distance.view),
                ("ids", &impostor.object_ids.view),
                ("rays", &ray_buffer),
                ("hits", &hit_buffer),
                ("params", &param_buffer),
            ],
        )
        .kernels(&["main"])
        .build()
        .expect("trace pass");
    let mut profiler = PassProfiler::new(&ctx, 1);
    let mut frame = renderer
        .begin_frame(&mut profiler, FrameMode::Timed)
        .expect("frame");
    pass.record(&mut frame, "test/impostor", renderer.scene(), &impostor)
        .expect("record");
    {
        let mut cp = trace.begin(&mut frame).expect("compute pass");
        cp.dispatch("main", [(rays.len() as u32).div_ceil(64), 1, 1])
            .expect("dispatch");
    }
    frame.submit(&ctx).expect("submit");
    let bytes =
        read_buffer_bytes(&ctx, &hit_buffer, (rays.len() * 16) as u64, "hits").expect("read hits");
    let hits: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&bytes);
    hits.iter()
        .map(|h| Traced {
            position: Vec3::new(h[0], h[1], h[2]),
            object: (h[3] >= 0.0).then_some(h[3] as u32),
        })
        .collect()
}

/// Rays leaving the inside of the glass sphere (centre (0, 1.5, 0), R = 1) exit where
/// the analytic sphere says, within 3 mm: the tessellation's sagitta (96 segments: 0.5 mm) plus the
/// bilinear lookup between 256² texels (1.7 mm measured on lavapipe).
#[test]
fn rays_exit_the_sphere_where_the_analytic_sphere_says() {
    let center = Vec3::new(0.0, 1.5, 0.0);
    let mut rays = Vec::new();
    for i in 0..200 {
        let a = i as f32 * 0.61803 * std::f32::consts::TAU;
        let z = 1.0 - 2.0 * (i as f32 + 0.5) / 200.0;
        let d = Vec3::new(
            (1.0 - z * z).sqrt() * a.cos(),
            z,
            (1.0 - z * z).sqrt() * a.sin(),
        );
        // Start off-centre (the refracted ray of a beam never passes the centre).
        let o = center + Vec3::new(0.31, -0.22, 0.17) * (i % 3) as f32;
        rays.push((o, d));
    }
    let hits = trace(&[0], None, &rays);
    let mut worst = 0.0f32;
    for ((o, d), h) in rays.iter().zip(&hits) {
        assert_eq!(
            h.object,
            Some(0),
            "ray from {o} along {d} missed the sphere"
        );
        // Analytic exit: |o + t d - c| = 1.
        let oc = *o - center;
        let b = oc.dot(*d);
        let t = -b + (b * b - (oc.length_squared() - 1.0)).sqrt();
        let err = (h.position - (*o + *d * t)).length();
        worst = worst.max(err);
    }
    eprintln!("worst exit-point error {worst} m");
    assert!(worst < 3e-3, "worst exit-point error {worst} m");
}

/// Umenhoffer's distance map of the environment: the floor (object 1) around the
/// sphere's centre. Rays from the sphere going down land where the plane y = 0 says;
/// rays going up find nothing.
#[test]
fn rays_land_on_the_floor_impostor_around_the_sphere() {
    let center = Vec3::new(0.0, 1.5, 0.0);
    let mut rays = Vec::new();
    for i in 0..100 {
        let a = i as f32 * 0.37;
        let d = Vec3::new(0.6 * a.cos(), -1.0, 0.6 * a.sin() * 0.8).normalize();
        let o = center + Vec3::new(0.2 * a.sin(), -0.9, 0.1);
        rays.push((o, d));
    }
    rays.push((center, Vec3::new(0.1, 1.0, 0.0).normalize()));
    let hits = trace(&[1], Some(center), &rays);
    let mut worst = 0.0f32;
    for ((o, d), h) in rays.iter().zip(&hits).take(100) {
        assert_eq!(h.object, Some(1), "ray from {o} along {d} missed the floor");
        let t = -o.y / d.y;
        worst = worst.max((h.position - (*o + *d * t)).length());
    }
    eprintln!("worst floor-hit error {worst} m");
    assert!(worst < 5e-3, "worst floor-hit error {worst} m");
    assert_eq!(hits[100].object, None, "a ray going up hit the floor");
}

/// The ring's floor seen from the ring's centre, 0.25 m above it: rays leaving the
/// inner wall downwards land where the plane y = 0 says, also those that start above
/// the centre (directions where the map stores nothing) and graze the floor.
#[test]
fn rays_from_the_ring_wall_land_on_the_floor() {
    let center = Vec3::new(0.0, 0.25, 0.0);
    let mut rays = Vec::new();
    for i in 0..64 {
        let a = i as f32 / 64.0 * std::f32::consts::TAU;
        let h = 0.05 + 0.4 * ((i * 7) % 8) as f32 / 7.0;
        let o = Vec3::new(0.999 * a.cos(), h, 0.999 * a.sin());
        let inward = -Vec3::new(a.cos(), 0.0, a.sin());
        let d = (inward + Vec3::new(0.0, -0.2 - 0.1 * (i % 5) as f32, 0.0)).normalize();
        rays.push((o, d));
    }
    let hits = trace_in("ring", &[1], Some(center), &rays);
    let mut worst = 0.0f32;
    let mut missed = 0;
    for ((o, d), h) in rays.iter().zip(&hits) {
        if h.object != Some(1) {
            missed += 1;
            eprintln!("missed: ray from {o} along {d}");
            continue;
        }
        let t = -o.y / d.y;
        worst = worst.max((h.position - (*o + *d * t)).length());
    }
    eprintln!("ring floor: {missed} missed, worst error {worst} m");
    assert_eq!(missed, 0);
    assert!(worst < 5e-3, "worst floor-hit error {worst} m");
}
