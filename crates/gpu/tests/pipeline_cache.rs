//! Pipelines compiled once per device (`caustics_gpu::pipeline_cache`): a pass built
//! again reuses its pipeline and still binds and computes its own resources; anything
//! that changes the pipeline (constants, source) compiles anew. On whatever adapter the
//! machine has (lavapipe on CI; without one these fail with the install hint).

use caustics_gpu::pass::{ComputePass, RasterPass, Shader};
use caustics_gpu::readback::{read_buffer_bytes, read_rgba32f};
use caustics_gpu::textures::opaque_target;
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

/// A full-screen triangle whose vertex stage passes on one constant and whose fragment
/// stage writes it beside another: neither has a default, so a pass whose constants
/// did not reach both stages would fail to build.
const RASTER_WGSL: &str = r#"
override VERTEX_VALUE: f32;
override FRAGMENT_VALUE: f32;
struct Out {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) from_vertex: f32,
}
@vertex
fn vs(@builtin(vertex_index) vi: u32) -> Out {
    let uv = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u));
    return Out(vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0), VERTEX_VALUE);
}
@fragment
fn fs(in: Out) -> @location(0) vec4<f32> {
    return vec4<f32>(in.from_vertex, FRAGMENT_VALUE, 0.0, 1.0);
}
"#;

/// Builds the raster pass with `constants`, draws it over a 4x4 target and returns
/// the first texel's (red, green) and what the build compiled or reused.
fn draw_specialized(
    ctx: &GpuContext,
    renderer: &Renderer,
    constants: &[(&str, f64)],
) -> ((f32, f32), PipelineStats) {
    let before = ctx.pipeline_stats();
    let shader = Shader::new(
        ctx,
        "raster cache test",
        shader::compose_method(RASTER_WGSL),
    )
    .expect("shader");
    let pass = RasterPass::builder(ctx, "test/specialized", &shader, "vs")
        .frame(renderer)
        .fragment("fs", &[opaque_target(wgpu::TextureFormat::Rgba32Float)])
        .constants(constants)
        .build()
        .expect("pass");
    let built = ctx.pipeline_stats().since(before);
    let target = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("specialized target"),
        size: wgpu::Extent3d {
            width: 4,
            height: 4,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Float,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let view = target.create_view(&Default::default());
    let mut profiler = PassProfiler::new(ctx, 1);
    let mut frame = renderer
        .begin_frame(&mut profiler, FrameMode::Timed)
        .expect("frame");
    {
        let attachments = [Some(wgpu::RenderPassColorAttachment {
            view: &view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                store: wgpu::StoreOp::Store,
            },
        })];
        let mut rp = pass.begin(&mut frame, &attachments, None).expect("pass");
        rp.draw(0..3, 0..1);
    }
    frame.submit(ctx).expect("submit");
    let texels = read_rgba32f(ctx, &target, "specialized target").expect("read target");
    assert!(
        texels.chunks(4).all(|t| t == &texels[..4]),
        "the full-screen triangle covers the target evenly: {texels:?}"
    );
    ((texels[0], texels[1]), built)
}

#[test]
fn a_raster_pass_is_specialized_in_both_stages_and_each_specialization_compiled_once() {
    let ctx =
        GpuContext::new(&AdapterChoice::from_flag_or_env(None)).unwrap_or_else(|e| panic!("{e}"));
    let renderer = renderer(&ctx);
    let a = [("VERTEX_VALUE", 0.25), ("FRAGMENT_VALUE", 0.5)];
    let b = [("VERTEX_VALUE", 2.0), ("FRAGMENT_VALUE", -3.0)];
    let compiled = PipelineStats {
        compiled: 1,
        reused: 0,
    };
    let reused = PipelineStats {
        compiled: 0,
        reused: 1,
    };
    assert_eq!(
        draw_specialized(&ctx, &renderer, &a),
        ((0.25, 0.5), compiled)
    );
    assert_eq!(
        draw_specialized(&ctx, &renderer, &b),
        ((2.0, -3.0), compiled)
    );
    assert_eq!(draw_specialized(&ctx, &renderer, &a), ((0.25, 0.5), reused));
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
