//! The scoring frame (DESIGN "Measuring honestly") on a focus narrower than a pixel,
//! whose box-filtered image is known exactly: averaged over 4×4 sub-pixel offsets it is
//! scored far closer to the pixel-area average the reference computes than one sample
//! at each pixel centre. Runs on whatever adapter the machine has (lavapipe on CI);
//! without one it fails with the install hint.

use std::sync::Arc;

use caustics_gpu::pass::{RasterPass, Shader};
use caustics_gpu::textures::{additive_hdr_target, load_attachment};
use caustics_gpu::{
    AdapterChoice, Frame, GpuContext, GpuScene, Renderer, RendererOptions, ScoreAccumulator,
    shader, wgpu,
};
use caustics_method::{CausticsMethod, Counters, LightSide, MethodError, render_scoring_frame};
use caustics_scene::Scene;
use wgpu::util::DeviceExt;

const FOCUS_WGSL: &str = include_str!("focus.wgsl");
const WIDTH: u32 = 32;
const HEIGHT: u32 = 24;
const EYE_Z: f32 = 5.0;
const FOV_Y_DEG: f32 = 40.0;
/// The focus in continuous pixel coordinates (x0, y0, x1, y1), edges away from every
/// sample position of the 1×1 and 4×4 grids: 2.3 px wide, 0.35 px high.
const FOCUS_PX: [f32; 4] = [10.3, 7.45, 12.6, 7.8];

struct Focus {
    draw: RasterPass,
    /// Frames that recorded the (here empty) light side: what a method skips when
    /// [`Frame::reuses_light_side`].
    light_side_frames: u32,
}

impl CausticsMethod for Focus {
    fn record(&mut self, frame: &mut Frame<'_>) -> Result<(), MethodError> {
        if !frame.reuses_light_side() {
            self.light_side_frames += 1;
        }
        let renderer = frame.renderer;
        let attachments = [load_attachment(&renderer.targets().surface.view)];
        let mut pass = self.draw.begin(frame, &attachments, None)?;
        pass.draw(0..6, 0..1);
        Ok(())
    }
    fn counters(&self, _: &GpuContext) -> Result<Counters, MethodError> {
        Ok(Counters::new())
    }
    fn gpu_memory_bytes(&self) -> u64 {
        0
    }
}

/// World metres per pixel in the plane z = 0.
fn metres_per_pixel() -> f32 {
    2.0 * EYE_Z * (0.5 * FOV_Y_DEG.to_radians()).tan() / HEIGHT as f32
}

fn focus_method(ctx: &GpuContext, renderer: &Renderer) -> Focus {
    let device = &ctx.device;
    let m = metres_per_pixel();
    let to_world = |px: f32, py: f32| {
        [
            (px - 0.5 * WIDTH as f32) * m,
            (0.5 * HEIGHT as f32 - py) * m,
        ]
    };
    let [x0, y1] = to_world(FOCUS_PX[0], FOCUS_PX[1]);
    let [x1, y0] = to_world(FOCUS_PX[2], FOCUS_PX[3]);
    let uniforms: [f32; 8] = [x0, y0, x1, y1, 1.0, 1.0, 1.0, 0.0];
    let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("focus"),
        contents: bytemuck::cast_slice(&uniforms),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let shader =
        Shader::new(ctx, "focus.wgsl", shader::compose_method(FOCUS_WGSL)).expect("shader");
    let draw = RasterPass::builder(ctx, "focus/draw", &shader, "vs_focus")
        .frame(renderer)
        .bind(1, &[("focus", &buffer)])
        .fragment("fs_focus", &[Some(additive_hdr_target())])
        .build()
        .expect("focus pass");
    Focus {
        draw,
        light_side_frames: 0,
    }
}

fn scene(dir: &std::path::Path) -> Scene {
    let json = serde_json::json!({
        "name": "subpixel_focus",
        "camera": {"eye": [0, 0, EYE_Z], "target": [0, 0, 0], "up": [0, 1, 0],
                   "fov_y_deg": FOV_Y_DEG, "width": WIDTH, "height": HEIGHT},
        "lights": [{"type": "directional", "direction": [0, 0, -1], "irradiance": [1, 1, 1]}],
        "materials": {"floor": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
        "objects": [{"shape": {"type": "quad", "center": [0, 0, -1], "normal": [0, 0, 1],
                               "size": [20, 20]}, "material": "floor"}]
    });
    let path = dir.join("subpixel_focus.json");
    std::fs::write(&path, json.to_string()).expect("write scene");
    Scene::load(&path).expect("scene")
}

/// Exact box filter of the focus: radiance × the pixel's covered area.
fn box_filtered(x: u32, y: u32) -> f32 {
    let overlap = |a0: f32, a1: f32, b0: f32, b1: f32| (a1.min(b1) - a0.max(b0)).max(0.0);
    let (x, y) = (x as f32, y as f32);
    overlap(x, x + 1.0, FOCUS_PX[0], FOCUS_PX[2]) * overlap(y, y + 1.0, FOCUS_PX[1], FOCUS_PX[3])
}

fn rmse_against_box_filter(surface_rgba: &[f32]) -> f64 {
    let mut sum = 0.0f64;
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let v = surface_rgba[4 * (y * WIDTH + x) as usize];
            let d = f64::from(v - box_filtered(x, y));
            sum += d * d;
        }
    }
    (sum / (WIDTH * HEIGHT) as f64).sqrt()
}

/// The GPU, the focus scene's renderer, the focus method and a score accumulator.
fn focus_setup() -> (GpuContext, Renderer, Focus, ScoreAccumulator) {
    let tmp = tempfile::tempdir().expect("tempdir");
    let ctx =
        GpuContext::new(&AdapterChoice::from_flag_or_env(None)).unwrap_or_else(|e| panic!("{e}"));
    let gpu_scene =
        GpuScene::upload(&ctx, Arc::new(scene(tmp.path())), Default::default()).expect("upload");
    let renderer = Renderer::new(&ctx, gpu_scene, RendererOptions::default()).expect("renderer");
    let method = focus_method(&ctx, &renderer);
    let accumulator = ScoreAccumulator::new(&ctx, &renderer).expect("accumulator");
    (ctx, renderer, method, accumulator)
}

#[test]
fn focus_shader_validates() -> Result<(), String> {
    shader::validate_wgsl("focus.wgsl", &shader::compose_method(FOCUS_WGSL))
}

#[test]
fn a_subpixel_focus_scored_over_4x4_offsets_is_5x_closer_to_the_box_filter() {
    let (ctx, renderer, mut method, mut accumulator) = focus_setup();

    let one = render_scoring_frame(
        &ctx,
        &renderer,
        &mut method,
        &mut accumulator,
        1,
        LightSide::Reuse,
    )
    .expect("1x1 scoring frame");
    let sixteen = render_scoring_frame(
        &ctx,
        &renderer,
        &mut method,
        &mut accumulator,
        4,
        LightSide::Reuse,
    )
    .expect("4x4 scoring frame");
    assert_eq!((one.frames, sixteen.frames), (1, 16));

    // Each sub-frame samples the pixel at the offset's position, so every pixel holds
    // the share of the 16 sample positions inside the focus: checked exactly (this is
    // the direction and size of the shift, and the division by N²).
    for (grid, scored) in [(1u32, &one), (4, &sixteen)] {
        let offsets = caustics_gpu::subpixel_offsets(grid);
        for y in 0..HEIGHT {
            for x in 0..WIDTH {
                let inside = offsets
                    .iter()
                    .filter(|o| {
                        let (sx, sy) = (x as f32 + 0.5 + o[0], y as f32 + 0.5 + o[1]);
                        sx > FOCUS_PX[0] && sx < FOCUS_PX[2] && sy > FOCUS_PX[1] && sy < FOCUS_PX[3]
                    })
                    .count();
                let expected = inside as f32 / offsets.len() as f32;
                let got = scored.surface[4 * (y * WIDTH + x) as usize];
                assert!(
                    (got - expected).abs() < 1e-6,
                    "{grid}x{grid}, pixel ({x},{y}): {got}, expected {expected}"
                );
            }
        }
    }

    let (e1, e16) = (
        rmse_against_box_filter(&one.surface),
        rmse_against_box_filter(&sixteen.surface),
    );
    eprintln!("RMSE against the box-filtered focus: 1 spp {e1:.5}, 4x4 {e16:.5}");
    assert!(
        e1 >= 5.0 * e16,
        "pixel-averaged error {e16:.5} is not 5x below the 1-spp error {e1:.5}"
    );
    // The camera is back at the pixel centre: the next 1x1 frame repeats the first.
    let again = render_scoring_frame(
        &ctx,
        &renderer,
        &mut method,
        &mut accumulator,
        1,
        LightSide::Reuse,
    )
    .expect("1x1 again");
    assert_eq!(again.surface, one.surface);
}

#[test]
fn a_scoring_frame_renders_the_light_side_once_and_scores_the_same_image() {
    let (ctx, renderer, mut method, mut accumulator) = focus_setup();

    let each = render_scoring_frame(
        &ctx,
        &renderer,
        &mut method,
        &mut accumulator,
        4,
        LightSide::RenderEach,
    )
    .expect("4x4, light side in every sub-frame");
    assert_eq!(
        method.light_side_frames, 16,
        "every sub-frame is a whole frame"
    );

    method.light_side_frames = 0;
    let reused = render_scoring_frame(
        &ctx,
        &renderer,
        &mut method,
        &mut accumulator,
        4,
        LightSide::Reuse,
    )
    .expect("4x4, light side reused");
    // One whole frame at the pixel centre, then 16 camera-side sub-frames.
    assert_eq!(
        method.light_side_frames, 1,
        "the light side is rendered once"
    );
    assert_eq!(reused.frames, 16, "the priming frame is not averaged");
    assert_eq!(reused.surface, each.surface);
    assert_eq!(
        reused.direct, each.direct,
        "shadow maps kept, direct light the same"
    );
}
