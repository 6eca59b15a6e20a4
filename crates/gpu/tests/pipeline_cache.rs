//! Pipelines compiled once per device (`caustics_gpu::pipeline_cache`): a pass built
//! again reuses its pipeline and still binds and computes its own resources; anything
//! that changes the pipeline (constants, source) compiles anew. On whatever adapter the
//! machine has (lavapipe on CI; without one these fail with the install hint).

use caustics_gpu::pass::{ComputePass, Shader};
use caustics_gpu::readback::read_buffer_bytes;
use caustics_gpu::wgpu::{self, util::DeviceExt};
use caustics_gpu::{
    AdapterChoice, FrameMode, GpuContext, GpuScene, PassProfiler, PipelineStats, Renderer,
    RendererOptions, shader,
};
use caustics_scene::Scene;

const SCENE: &str = r#"{
  "name": "cache_test",
  "camera": {"eye": [0, 2, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 45, "width": 24, "height": 16},
  "lights": [{"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1]}],
  "materials": {"floor": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
  "objects": [{"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [4, 4]}, "material": "floor"}]
}"#;

/// Reads the frame group (group 0) and its own group 1, with an overridable scale.
const KERNEL_WGSL: &str = r#"
override SCALE: f32 = 1.0;
@group(1) @binding(0) var<uniform> params: vec4<f32>;
@group(1) @binding(1) var<storage, read_write> out: array<f32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&out) { return; }
    out[id.x] = SCALE * params.x * f32(id.x) + frame.resolution.x;
}
"#;

const N: usize = 100;

fn renderer(ctx: &GpuContext) -> Renderer {
    let scene =
        Scene::from_json_str(SCENE, std::path::Path::new("cache_test.json")).expect("scene");
    let gpu_scene = GpuScene::upload(ctx, scene.into(), Default::default()).expect("upload");
    Renderer::new(ctx, gpu_scene, RendererOptions::default()).expect("renderer")
}

/// Builds the kernel's pass anew (its own shader, buffers and bind groups), runs it
/// once and returns `out` and what the build compiled or reused.
fn run_kernel(
    ctx: &GpuContext,
    renderer: &Renderer,
    source: &str,
    param: f32,
    constants: &[(&str, f64)],
) -> (Vec<f32>, PipelineStats) {
    let before = ctx.pipeline_stats();
    let shader = Shader::new(ctx, "cache test", source.to_owned()).expect("shader");
    let params = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("params"),
            contents: bytemuck::cast_slice(&[param, 0.0, 0.0, 0.0]),
            usage: wgpu::BufferUsages::UNIFORM,
        });
    let size = (N * 4) as u64;
    let out = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("out"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let pass = ComputePass::builder(ctx, "test/cache", &shader)
        .frame(renderer)
        .bind(1, &[("params", &params), ("out", &out)])
        .kernels(&["main"])
        .constants(constants)
        .build()
        .expect("pass");
    let built = ctx.pipeline_stats().since(before);
    let mut profiler = PassProfiler::new(ctx, 1);
    let mut frame = renderer
        .begin_frame(&mut profiler, FrameMode::Timed)
        .expect("frame");
    {
        let mut cp = pass.begin(&mut frame).expect("compute pass");
        cp.dispatch("main", [(N as u32).div_ceil(64), 1, 1])
            .expect("dispatch");
    }
    frame.submit(ctx).expect("submit");
    let bytes = read_buffer_bytes(ctx, &out, size, "out").expect("read out");
    (bytemuck::pod_collect_to_vec(&bytes), built)
}

fn expected(scale: f32, param: f32) -> Vec<f32> {
    (0..N).map(|i| scale * param * i as f32 + 24.0).collect()
}

#[test]
fn a_pass_built_again_reuses_its_pipeline_with_its_own_bind_groups() {
    let ctx =
        GpuContext::new(&AdapterChoice::from_flag_or_env(None)).unwrap_or_else(|e| panic!("{e}"));
    let renderer = renderer(&ctx);
    let source = shader::compose_method(KERNEL_WGSL);

    let (first, built) = run_kernel(&ctx, &renderer, &source, 2.0, &[]);
    assert_eq!(first, expected(1.0, 2.0));
    assert_eq!(
        built,
        PipelineStats {
            compiled: 1,
            reused: 0
        }
    );

    // The first pass, its shader and buffers are gone; the second binds new ones
    // through layouts made anew, and the cached pipeline must accept them.
    let (second, built) = run_kernel(&ctx, &renderer, &source, 3.0, &[]);
    assert_eq!(second, expected(1.0, 3.0));
    assert_eq!(
        built,
        PipelineStats {
            compiled: 0,
            reused: 1
        }
    );

    // Another constant is another pipeline: compiled, and its value is used.
    let (scaled, built) = run_kernel(&ctx, &renderer, &source, 3.0, &[("SCALE", 2.0)]);
    assert_eq!(scaled, expected(2.0, 3.0));
    assert_eq!(
        built,
        PipelineStats {
            compiled: 1,
            reused: 0
        }
    );

    // Another source (one character) is another pipeline.
    let changed = source.replace("f32(id.x) +", "f32(id.x) + 1.0 +");
    let (other, built) = run_kernel(&ctx, &renderer, &changed, 3.0, &[]);
    assert_eq!(
        other,
        expected(1.0, 3.0)
            .iter()
            .map(|v| v + 1.0)
            .collect::<Vec<_>>()
    );
    assert_eq!(
        built,
        PipelineStats {
            compiled: 1,
            reused: 0
        }
    );
}

#[test]
fn a_second_renderer_on_the_device_compiles_nothing_and_draws_the_same_frame() {
    let ctx =
        GpuContext::new(&AdapterChoice::from_flag_or_env(None)).unwrap_or_else(|e| panic!("{e}"));
    let first = renderer(&ctx);
    let compiled_first = ctx.pipeline_stats();
    assert!(
        compiled_first.compiled > 0,
        "the base renderer compiles its G-buffer, shadow and direct pipelines"
    );
    let second = renderer(&ctx);
    assert_eq!(
        ctx.pipeline_stats().since(compiled_first),
        PipelineStats {
            compiled: 0,
            reused: compiled_first.compiled
        }
    );
    let draw = |r: &Renderer| {
        let mut profiler = PassProfiler::new(&ctx, 1);
        let frame = r
            .begin_frame(&mut profiler, FrameMode::Timed)
            .expect("frame");
        frame.submit(&ctx).expect("submit");
        caustics_gpu::readback::read_rgba32f(&ctx, &r.targets().direct.texture, "direct image")
            .expect("direct image")
    };
    let image = draw(&first);
    assert!(image.iter().any(|&v| v > 0.0), "the floor is lit");
    assert_eq!(draw(&second), image);
}
