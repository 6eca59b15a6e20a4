//! The scene's triangle BVH traced on the GPU (`scene_closest_hit` of
//! triangle_bvh.wgsl) against a search over every triangle and the analytic floor on the
//! CPU, on whatever adapter the machine has (lavapipe on CI; without one these fail with
//! the install hint).

use caustics_gpu::pass::{ComputePass, Shader};
use caustics_gpu::readback::read_buffer_bytes;
use caustics_gpu::wgpu::{self, util::DeviceExt};
use caustics_gpu::{
    AdapterChoice, FrameMode, GpuContext, GpuScene, PassProfiler, Renderer, RendererOptions,
    shader, triangle_bvh,
};
use caustics_scene::{Scene, Vec3};

const TRACE_TEST_WGSL: &str = r#"
struct Ray { origin: vec4<f32>, dir: vec4<f32> }
struct Out { t: f32, object: u32, pad0: u32, pad1: u32, ns: vec4<f32>, ng: vec4<f32> }
@group(1) @binding(0) var<storage, read> rays: array<Ray>;
@group(1) @binding(1) var<storage, read_write> hits: array<Out>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&rays) { return; }
    let r = rays[id.x];
    // w of the origin: the object to skip (as f32; -1 none).
    let skip = select(u32(r.origin.w), NONE, r.origin.w < 0.0);
    let h = scene_closest_hit(r.origin.xyz, r.dir.xyz, 1e-4, skip);
    hits[id.x] = Out(h.t, h.object, 0u, 0u, vec4<f32>(h.ns, 0.0), vec4<f32>(h.ng, 0.0));
}
"#;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuHit {
    t: f32,
    object: u32,
    _pad: [u32; 2],
    ns: [f32; 4],
    ng: [f32; 4],
}

fn small_builtin(name: &str) -> Scene {
    let src = caustics_scene::resolve(name).expect("built-in scene");
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&src).expect("read")).expect("JSON");
    json["camera"]["width"] = 32.into();
    json["camera"]["height"] = 24.into();
    // The mesh path is relative to the scene file: keep the file where it is.
    Scene::from_json_str(&json.to_string(), &src).expect("scene")
}

/// Traces `rays` (origin, direction, object to skip) through `scene_closest_hit`.
fn trace(scene: Scene, rays: &[(Vec3, Vec3, Option<u32>)]) -> (GpuScene, Vec<GpuHit>) {
    let ctx =
        GpuContext::new(&AdapterChoice::from_flag_or_env(None)).unwrap_or_else(|e| panic!("{e}"));
    let gpu_scene = GpuScene::upload(&ctx, scene.into(), Default::default()).expect("upload");
    let renderer = Renderer::new(&ctx, gpu_scene, RendererOptions::default()).expect("renderer");
    let bvh = renderer.scene().triangle_bvh(&ctx).expect("BVH");
    let source = shader::compose_method(&format!("{}\n{TRACE_TEST_WGSL}", triangle_bvh::wgsl(2)));
    caustics_gpu::assert_wgsl_layout!(source.clone(), GpuHit as "Out" { t, object, ns, ng });
    let shader = Shader::new(&ctx, "bvh trace test", source).expect("shader");
    let device = &ctx.device;
    let ray_data: Vec<[f32; 8]> = rays
        .iter()
        .map(|(o, d, skip)| {
            let s = skip.map_or(-1.0, |k| k as f32);
            [o.x, o.y, o.z, s, d.x, d.y, d.z, 0.0]
        })
        .collect();
    let ray_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("rays"),
        contents: bytemuck::cast_slice(&ray_data),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let size = (rays.len() * std::mem::size_of::<GpuHit>()) as u64;
    let hit_buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("hits"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let pass = ComputePass::builder(&ctx, "test/bvh_trace", &shader)
        .frame(&renderer)
        .bind(1, &[("rays", &ray_buffer), ("hits", &hit_buffer)])
        .bind(
            2,
            &[("bvh_nodes", &bvh.nodes), ("bvh_triangles", &bvh.triangles)],
        )
        .kernels(&["main"])
        .build()
        .expect("pass");
    let mut profiler = PassProfiler::new(&ctx, 1);
    let mut frame = renderer
        .begin_frame(&mut profiler, FrameMode::Timed)
        .expect("frame");
    {
        let mut cp = pass.begin(&mut frame).expect("compute pass");
        cp.dispatch("main", [(rays.len() as u32).div_ceil(64), 1, 1])
            .expect("dispatch");
    }
    frame.submit(&ctx).expect("submit");
    let bytes = read_buffer_bytes(&ctx, &hit_buffer, size, "hits").expect("read hits");
    let hits = bytemuck::pod_collect_to_vec(&bytes);
    // The renderer owns the scene; upload a second copy for the CPU side's meshes.
    let cpu =
        GpuScene::upload(&ctx, renderer.scene().scene.clone(), Default::default()).expect("upload");
    (cpu, hits)
}

/// Closest hit over every triangle of the mesh objects and the analytic floor quad
/// (y = 0, |x|, |z| ≤ 10) of bumpy_glass: `(t, object)`.
fn cpu_closest(scene: &GpuScene, o: Vec3, d: Vec3, skip: Option<u32>) -> Option<(f32, u32)> {
    let mut best: Option<(f32, u32)> = None;
    for (object, (obj, mesh)) in scene.scene.objects.iter().zip(&scene.meshes).enumerate() {
        if Some(object as u32) == skip {
            continue;
        }
        if !triangle_bvh::traced_as_triangles(&obj.shape) {
            let t = -o.y / d.y;
            let p = o + t * d;
            if t > 1e-4 && p.x.abs() <= 10.0 && p.z.abs() <= 10.0 && best.is_none_or(|b| t < b.0) {
                best = Some((t, object as u32));
            }
            continue;
        }
        for k in 0..mesh.triangle_count() {
            if let Some(t) = triangle_bvh::ray_triangle(o, d, mesh.triangle(k))
                .filter(|&t| t > 1e-4 && best.is_none_or(|b| t < b.0))
            {
                best = Some((t, object as u32));
            }
        }
    }
    best
}

/// 4,096 rays from above bumpy_glass's ball towards it and the floor around it: the GPU
/// finds the same first surface as the CPU search over all 20,480 triangles and the
/// floor (t within 1e-3 m where they agree on the object; a ray grazing a triangle edge
/// may differ, at most 0.5 % of them), with unit shading normals on the geometric
/// normal's side; with the ball skipped every ray that hit it reaches the floor.
#[test]
fn gpu_closest_hits_match_a_search_over_every_triangle() {
    let scene = small_builtin("bumpy_glass");
    let ball = Vec3::new(0.0, 1.5, 0.0);
    let n = 64;
    let mut rays = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let target =
                ball + Vec3::new(i as f32 / n as f32 - 0.5, 0.0, j as f32 / n as f32 - 0.5) * 3.0;
            let o = ball + Vec3::new(0.3, 4.0, -0.2);
            rays.push((o, (target - o).normalize(), None));
        }
    }
    let skipped: Vec<_> = rays.iter().map(|&(o, d, _)| (o, d, Some(0))).collect();
    let all: Vec<_> = rays.iter().copied().chain(skipped).collect();
    let (cpu, hits) = trace(scene, &all);
    let (mut agree, mut on_ball, mut differ) = (0, 0, 0);
    for (&(o, d, skip), hit) in all.iter().zip(&hits) {
        let want = cpu_closest(&cpu, o, d, skip);
        let got = (hit.object != u32::MAX).then_some((hit.t, hit.object));
        match (got, want) {
            (Some((t1, o1)), Some((t2, o2))) if o1 == o2 => {
                assert!((t1 - t2).abs() < 1e-3, "t {t1} vs {t2} on object {o1}");
                let ns = Vec3::from_slice(&hit.ns[..3]);
                let ng = Vec3::from_slice(&hit.ng[..3]);
                assert!((ns.length() - 1.0).abs() < 1e-4 && (ng.length() - 1.0).abs() < 1e-4);
                assert!(
                    ns.dot(ng) > 0.0,
                    "shading normal {ns} opposite geometric {ng}"
                );
                agree += 1;
                on_ball += usize::from(o1 == 0);
                assert!(skip.is_none() || o1 != 0, "the skipped ball was hit");
            }
            (None, None) => agree += 1,
            _ => differ += 1,
        }
    }
    assert!(on_ball > 500, "only {on_ball} rays hit the ball");
    assert!(
        differ * 200 <= all.len(),
        "{differ} of {} rays disagree",
        all.len()
    );
    assert!(agree + differ == all.len());
    eprintln!("{agree} rays agree, {differ} differ, {on_ball} on the ball");
}

/// A scene without meshes or heightfields still binds a (one-leaf) tree, and the GPU
/// finds its analytic objects exactly as `intersect_analytic` does.
#[test]
fn analytic_scenes_trace_through_an_empty_tree() {
    let scene = small_builtin("sphere_on_plane");
    let rays = [
        (Vec3::new(0.0, 5.0, 0.0), Vec3::NEG_Y, None),
        (Vec3::new(3.0, 5.0, 0.0), Vec3::NEG_Y, None),
    ];
    let (cpu, hits) = trace(scene, &rays);
    let bvh_triangles = triangle_bvh::FlatBvh::build(&cpu.scene, &cpu.meshes)
        .triangles
        .len();
    assert_eq!(bvh_triangles, 1, "one degenerate triangle");
    // Straight down onto the sphere (centre (0, 1.5, 0), R = 1): t = 5 - 2.5.
    assert_eq!(hits[0].object, 0);
    assert!((hits[0].t - 2.5).abs() < 1e-4, "{}", hits[0].t);
    assert_ne!(hits[1].object, u32::MAX);
    assert_ne!(hits[1].object, 0);
}
