//! The base renderer against analytic answers, on whatever adapter the machine has
//! (lavapipe on CI; without an adapter these fail with the install hint).
//! Later methods and the CPU reference rely on these conventions lining up.

use std::path::{Path, PathBuf};

use caustics_gpu::readback::{read_rgba32f, read_texture_bytes};
use caustics_gpu::{
    AdapterChoice, DIRECT_REPRESENTATIVE_LIGHTS, FrameMode, GpuContext, GpuScene, PassProfiler,
    Renderer, RendererOptions,
};
use caustics_scene::{Scene, Vec3, Vec4};

fn small_copy(dir: &Path, name: &str, width: u32, height: u32) -> PathBuf {
    let src = caustics_scene::resolve(name).expect("built-in scene");
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&src).expect("read")).expect("JSON");
    json["camera"]["width"] = width.into();
    json["camera"]["height"] = height.into();
    let path = dir.join(format!("{name}.json"));
    std::fs::write(&path, json.to_string()).expect("write");
    path
}

fn render(path: &Path) -> (GpuContext, Renderer) {
    let scene = Scene::load(path).expect("scene");
    let ctx =
        GpuContext::new(&AdapterChoice::from_flag_or_env(None)).unwrap_or_else(|e| panic!("{e}"));
    let gpu_scene = GpuScene::upload(&ctx, scene.into(), Default::default()).expect("upload");
    let renderer = Renderer::new(&ctx, gpu_scene, RendererOptions::default()).expect("renderer");
    let mut profiler = PassProfiler::new(&ctx, 1);
    let frame = renderer
        .begin_frame(&mut profiler, FrameMode::Timed)
        .expect("frame");
    frame.submit(&ctx).expect("submit");
    (ctx, renderer)
}

fn ids(ctx: &GpuContext, texture: &caustics_gpu::wgpu::Texture, layer: u32) -> Vec<[u32; 2]> {
    bytemuck::pod_collect_to_vec(&read_texture_bytes(ctx, texture, layer, "ids").expect("ids"))
}

/// Distance from `center` to the ray `o + t d` (t >= 0), `d` unit.
fn ray_distance(o: Vec3, d: Vec3, center: Vec3) -> f32 {
    let t = (center - o).dot(d).max(0.0);
    (o + t * d - center).length()
}

#[test]
fn camera_gbuffer_and_direct_light_match_the_analytic_scene() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = small_copy(tmp.path(), "sphere_on_plane", 200, 150);
    let (ctx, renderer) = render(&path);
    let scene = &renderer.scene().scene;
    let cam = &scene.camera;
    let gb = renderer.camera_gbuffer();
    let pos = read_rgba32f(&ctx, &gb.position.texture, "position").expect("position");
    let id = ids(&ctx, &gb.ids.texture, 0);
    let direct = read_rgba32f(&ctx, &renderer.targets().direct.texture, "direct").expect("direct");

    let (sphere_c, sphere_r) = (Vec3::new(0.0, 1.5, 0.0), 1.0);
    let light_dir = Vec3::new(0.2, -1.0, 0.1).normalize();
    let lit = 0.8 / std::f32::consts::PI * (-light_dir).dot(Vec3::Y);
    let (mut floor_lit, mut floor_shadow, mut glass) = (0, 0, 0);
    for y in 0..cam.height {
        for x in 0..cam.width {
            let i = (y * cam.width + x) as usize;
            let p = Vec3::new(pos[4 * i], pos[4 * i + 1], pos[4 * i + 2]);
            let hit = pos[4 * i + 3] > 0.5;
            let (o, d) = cam.ray_through_pixel(x as f32 + 0.5, y as f32 + 0.5);
            let rgb = [direct[4 * i], direct[4 * i + 1], direct[4 * i + 2]];
            match (hit, id[i][0]) {
                (true, 1) => {
                    // The G-buffer position is the camera ray's hit on the floor plane.
                    let t = -o.y / d.y;
                    let analytic = o + t * d;
                    assert!(
                        (p - analytic).length() < 1e-3 * t,
                        "pixel ({x},{y}): {p} vs {analytic}"
                    );
                    let miss = ray_distance(p, -light_dir, sphere_c) - sphere_r;
                    if miss > 0.05 {
                        for c in rgb {
                            assert!(
                                (c - lit).abs() < 2e-3 * lit,
                                "lit floor ({x},{y}): {c} vs {lit}"
                            );
                        }
                        floor_lit += 1;
                    } else if miss < -0.05 {
                        assert!(
                            rgb.iter().all(|&c| c == 0.0),
                            "shadowed floor ({x},{y}): {rgb:?}"
                        );
                        floor_shadow += 1;
                    }
                }
                (true, 0) => {
                    // The glass is specular: no L D E light.
                    assert!(rgb.iter().all(|&c| c == 0.0), "glass ({x},{y}): {rgb:?}");
                    glass += 1;
                }
                (false, _) => assert!(rgb.iter().all(|&c| c == 0.0)),
                (true, other) => panic!("unknown object id {other}"),
            }
        }
    }
    assert!(
        floor_lit > 10_000 && floor_shadow > 300 && glass > 1_000,
        "{floor_lit} {floor_shadow} {glass}"
    );
}

/// A diffuse floor under a constant sky of radiance L has radiance ρ·L. The direct
/// image draws the sky as its `DIRECT_REPRESENTATIVE_LIGHTS` median-cut directional
/// lights: exactly their sum (each shadow-mapped, none occluded), which is ρ·L within
/// median cut's error for a uniform sky (8.7 % high at 16 lights, the scene crate's test).
#[test]
fn a_floor_under_a_constant_sky_is_lit_by_its_representative_lights() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = tmp.path().join("sky.json");
    let (albedo, sky) = (0.5f32, Vec3::new(2.0, 1.0, 0.5));
    std::fs::write(
        &path,
        serde_json::json!({
            "name": "floor_under_sky",
            "camera": {"eye": [0, 6, 0.01], "target": [0, 0, 0], "up": [0, 1, 0],
                       "fov_y_deg": 40, "width": 32, "height": 24},
            "lights": [{"type": "environment", "radiance": sky.to_array()}],
            "materials": {"floor": {"type": "diffuse", "albedo": [albedo, albedo, albedo]}},
            "objects": [{"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0],
                                   "size": [20, 20]}, "material": "floor"}]
        })
        .to_string(),
    )
    .expect("write");
    let (ctx, renderer) = render(&path);
    let direct = read_rgba32f(&ctx, &renderer.targets().direct.texture, "direct").expect("direct");
    let lights = renderer.scene().scene.lights[0].representative(DIRECT_REPRESENTATIVE_LIGHTS);
    assert_eq!(lights.len(), DIRECT_REPRESENTATIVE_LIGHTS as usize);
    let expected: Vec3 = lights
        .iter()
        .map(|l| match l {
            caustics_scene::Light::Directional {
                direction,
                irradiance,
            } => *irradiance * (-direction.y).max(0.0) * albedo / std::f32::consts::PI,
            other => panic!("expected directional lights, got {other:?}"),
        })
        .sum();
    let analytic = sky * albedo;
    assert!(
        ((expected - analytic) / analytic).abs().max_element() < 0.1,
        "{expected} vs ρ·L {analytic}"
    );
    for px in direct.chunks_exact(4) {
        let rgb = Vec3::new(px[0], px[1], px[2]);
        assert!(
            ((rgb - expected) / expected).abs().max_element() < 2e-3,
            "{rgb} vs {expected}"
        );
    }
}

/// Two skies make 2 × 16 representative lights: 66 base passes a frame, past the 64 the
/// profiler's results buffers are first sized for. They grow (contents copied), and
/// every pass of every frame still reads back its own timestamps and statistics.
#[test]
fn the_profiler_grows_past_64_passes_a_frame_and_keeps_every_frames_results() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = tmp.path().join("two_skies.json");
    std::fs::write(
        &path,
        serde_json::json!({
            "name": "two_skies",
            "camera": {"eye": [0, 6, 0.01], "target": [0, 0, 0], "up": [0, 1, 0],
                       "fov_y_deg": 40, "width": 32, "height": 24},
            "lights": [{"type": "environment", "radiance": [1, 1, 1]},
                       {"type": "environment", "radiance": [0.5, 0.25, 0.125]}],
            "materials": {"floor": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
            "objects": [{"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0],
                                   "size": [20, 20]}, "material": "floor"}]
        })
        .to_string(),
    )
    .expect("write");
    let scene = Scene::load(&path).expect("scene");
    let ctx =
        GpuContext::new(&AdapterChoice::from_flag_or_env(None)).unwrap_or_else(|e| panic!("{e}"));
    let gpu_scene = GpuScene::upload(&ctx, scene.into(), Default::default()).expect("upload");
    let renderer = Renderer::new(&ctx, gpu_scene, RendererOptions::default()).expect("renderer");
    let modes = [
        FrameMode::Timed,
        FrameMode::Timed,
        FrameMode::Count,
        FrameMode::Timed,
    ];
    let mut profiler = PassProfiler::new(&ctx, modes.len() as u32);
    for mode in modes {
        let frame = renderer.begin_frame(&mut profiler, mode).expect("frame");
        frame.submit(&ctx).expect("submit");
    }
    let frames = profiler.collect(&ctx).expect("collect");
    assert_eq!(frames.len(), modes.len());
    let lights = 2 * DIRECT_REPRESENTATIVE_LIGHTS as usize;
    for (f, (frame, mode)) in frames.iter().zip(modes).enumerate() {
        // clear, camera G-buffer, a shadow map and a direct draw per light.
        assert_eq!(frame.passes.len(), 2 + 2 * lights, "frame {f}");
        assert!(frame.passes.len() > 64);
        assert_eq!(frame.rejected_timestamps, 0, "frame {f}");
        for pass in &frame.passes {
            match mode {
                FrameMode::Timed => {
                    assert!(pass.gpu_ms.is_some(), "frame {f} {}: no time", pass.name);
                    assert!(pass.statistics.is_none());
                }
                _ => {
                    let stats = pass.statistics.as_ref().expect("statistics");
                    if pass.name == "base/direct" {
                        // One full-screen draw: every pixel shaded, plus the 2×2 quads'
                        // helpers along the triangle's edge (lavapipe: 960 of 768).
                        let fragments = stats.fragment_invocations;
                        assert!(
                            (768..=2 * 768).contains(&fragments),
                            "frame {f}: {fragments}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn point_light_cube_gbuffer_sees_the_first_surface_along_each_texel_ray() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = small_copy(tmp.path(), "ring", 64, 48);
    let (ctx, renderer) = render(&path);
    let (view, shadow) = renderer.light(0).expect("one light");
    assert_eq!(view.faces.len(), 6, "a point light renders a cube");
    assert_eq!(shadow.depth.texture.depth_or_array_layers(), 6);
    // A light G-buffer as a method would make one: allocate it for the light's view
    // and record it into a frame.
    let gb = renderer
        .gbuffer_pass()
        .light_gbuffer(&ctx, view)
        .expect("light gbuffer");
    let mut profiler = PassProfiler::new(&ctx, 1);
    let mut frame = renderer
        .begin_frame(&mut profiler, FrameMode::Timed)
        .expect("frame");
    renderer
        .gbuffer_pass()
        .record(&mut frame, "test/light_gbuffer", renderer.scene(), &gb)
        .expect("record");
    frame.submit(&ctx).expect("submit");
    let light = view.origin;
    let res = view.resolution;
    let (ring_c, ring_r, half_h) = (Vec3::new(0.0, 0.25, 0.0), 1.0f32, 0.25f32);
    let mut checked = 0;
    for (face, f) in view.faces.iter().enumerate() {
        let pos = {
            let bytes =
                read_texture_bytes(&ctx, &gb.position.texture, face as u32, "light position")
                    .expect("read");
            bytemuck::pod_collect_to_vec::<u8, f32>(&bytes)
        };
        let id = ids(&ctx, &gb.ids.texture, face as u32);
        let inv = f.view_proj.inverse();
        for ty in (0..res).step_by(37) {
            for tx in (0..res).step_by(37) {
                let i = (ty * res + tx) as usize;
                // The texel centre's ray from the light.
                let ndc = Vec4::new(
                    (tx as f32 + 0.5) / res as f32 * 2.0 - 1.0,
                    1.0 - (ty as f32 + 0.5) / res as f32 * 2.0,
                    0.5,
                    1.0,
                );
                let w = inv * ndc;
                let d = ((w.truncate() / w.w) - light).normalize();
                // First hit, analytically: open cylinder (both sides) or floor plane.
                let mut t_best = f32::INFINITY;
                let mut obj_best = u32::MAX;
                let (oc, dp) = (light - ring_c, Vec3::new(d.x, 0.0, d.z));
                let op = Vec3::new(oc.x, 0.0, oc.z);
                let (a, b, c) = (dp.dot(dp), op.dot(dp), op.dot(op) - ring_r * ring_r);
                let disc = b * b - a * c;
                if a > 1e-9 && disc >= 0.0 {
                    for t in [(-b - disc.sqrt()) / a, (-b + disc.sqrt()) / a] {
                        if t > 0.0 && (oc.y + t * d.y).abs() <= half_h && t < t_best {
                            t_best = t;
                            obj_best = 0;
                        }
                    }
                }
                if d.y < 0.0 {
                    let t = -light.y / d.y;
                    let q = light + t * d;
                    if t < t_best && q.x.abs() <= 5.0 && q.z.abs() <= 5.0 {
                        t_best = t;
                        obj_best = 1;
                    }
                }
                let hit = pos[4 * i + 3] > 0.5;
                if !t_best.is_finite() {
                    assert!(
                        !hit,
                        "face {face} texel ({tx},{ty}) hit nothing analytically"
                    );
                    continue;
                }
                // Skip texels on an edge, where one texel covers two surfaces: the
                // ring's rims, where the ring stands on the floor, and its silhouette.
                let q = light + t_best * d;
                let r_q = Vec3::new(q.x, 0.0, q.z).length();
                let on_edge = match obj_best {
                    0 => q.y < 0.02 || q.y > 0.48 || disc < 0.02 * a,
                    _ => (r_q - ring_r).abs() < 0.02,
                };
                if on_edge {
                    continue;
                }
                let p = Vec3::new(pos[4 * i], pos[4 * i + 1], pos[4 * i + 2]);
                assert!(
                    hit,
                    "face {face} texel ({tx},{ty}) missed object {obj_best}"
                );
                assert_eq!(id[i][0], obj_best, "face {face} texel ({tx},{ty})");
                let analytic = light + t_best * d;
                // Tolerance: the ring is 128 flat segments (sagitta 3e-4 m) seen at grazing angles.
                assert!(
                    (p - analytic).length() < 0.02 * t_best,
                    "face {face} texel ({tx},{ty}): {p} vs {analytic}"
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 100, "only {checked} texels checked");
}

/// Where the segment from `p` to the light crosses the open cylinder x²+z² = 1,
/// 0 <= y <= 0.5 (the ring): the crossing heights.
fn ring_crossings(p: Vec3, light: Vec3) -> Vec<f32> {
    let d = light - p;
    let (a, b, c) = (
        d.x * d.x + d.z * d.z,
        p.x * d.x + p.z * d.z,
        p.x * p.x + p.z * p.z - 1.0,
    );
    let disc = b * b - a * c;
    if a < 1e-12 || disc < 0.0 {
        return vec![];
    }
    [(-b - disc.sqrt()) / a, (-b + disc.sqrt()) / a]
        .into_iter()
        .filter(|t| (0.0..=1.0).contains(t))
        .map(|t| p.y + t * d.y)
        .collect()
}

#[test]
fn point_light_direct_light_is_inverse_square_and_shadowed_by_the_ring_across_cube_faces() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = small_copy(tmp.path(), "ring", 256, 192);
    let (ctx, renderer) = render(&path);
    let cam = &renderer.scene().scene.camera;
    let gb = renderer.camera_gbuffer();
    let pos = read_rgba32f(&ctx, &gb.position.texture, "position").expect("position");
    let id = ids(&ctx, &gb.ids.texture, 0);
    let direct = read_rgba32f(&ctx, &renderer.targets().direct.texture, "direct").expect("direct");
    let (light, intensity, albedo) = (Vec3::new(0.85, 1.0, 0.0), 20.0f32, 0.8f32);
    let (mut lit, mut shadowed) = (0, 0);
    for i in 0..(cam.width * cam.height) as usize {
        if pos[4 * i + 3] < 0.5 || id[i][0] != 1 {
            continue;
        }
        let p = Vec3::new(pos[4 * i], pos[4 * i + 1], pos[4 * i + 2]);
        let value = direct[4 * i];
        let crossings = ring_crossings(p, light);
        // Far from the ring's rims and base (where shadow-map texels straddle edges).
        let off_base = (Vec3::new(p.x, 0.0, p.z).length() - 1.0).abs() > 0.03;
        if off_base && crossings.iter().all(|&y| !(-0.03..=0.53).contains(&y)) {
            let to_light = light - p;
            let r2 = to_light.length_squared();
            let expected =
                albedo / std::f32::consts::PI * intensity * (to_light.y / r2.sqrt()) / r2;
            assert!(
                (value - expected).abs() < 5e-3 * expected,
                "lit floor at {p}: {value} vs {expected}"
            );
            lit += 1;
        } else if crossings.iter().any(|&y| (0.03..0.47).contains(&y)) {
            assert_eq!(value, 0.0, "floor at {p} is behind the ring wall");
            shadowed += 1;
        }
    }
    assert!(
        lit > 5_000 && shadowed > 5_000,
        "lit {lit}, shadowed {shadowed}"
    );
}

/// A sub-pixel camera offset (the scoring frame's) moves the G-buffer's samples to
/// `(i + 0.5 + dx, j + 0.5 + dy)` of the unshifted camera, in the direction the offset
/// names (x right, y down), and back to the pixel centre at `[0, 0]`.
#[test]
fn subpixel_offset_shifts_the_camera_gbuffer_samples() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = small_copy(tmp.path(), "sphere_on_plane", 64, 48);
    let (ctx, renderer) = render(&path);
    let cam = renderer.scene().scene.camera.clone();
    let floor_hit = |px: f32, py: f32| {
        let (o, d) = cam.ray_through_pixel(px, py);
        o + (-o.y / d.y) * d
    };
    for offset in [[0.375f32, -0.125], [-0.25, 0.375], [0.0, 0.0]] {
        renderer.set_subpixel_offset(&ctx.queue, offset);
        let mut profiler = PassProfiler::unmeasured(1);
        let frame = renderer
            .begin_frame(&mut profiler, FrameMode::Score)
            .expect("frame");
        frame.submit(&ctx).expect("submit");
        let gb = renderer.camera_gbuffer();
        let pos = read_rgba32f(&ctx, &gb.position.texture, "position").expect("position");
        let id = ids(&ctx, &gb.ids.texture, 0);
        let mut checked = 0;
        for (x, y) in [(5u32, 44u32), (58, 40), (32, 46), (10, 30)] {
            let i = (y * cam.width + x) as usize;
            if id[i][0] != 1 || pos[4 * i + 3] < 0.5 {
                continue; // not the floor
            }
            let p = Vec3::new(pos[4 * i], pos[4 * i + 1], pos[4 * i + 2]);
            let shifted = floor_hit(x as f32 + 0.5 + offset[0], y as f32 + 0.5 + offset[1]);
            let centre = floor_hit(x as f32 + 0.5, y as f32 + 0.5);
            let moved = (shifted - centre).length();
            assert!(
                (p - shifted).length() < 0.05 * moved.max(1e-2),
                "offset {offset:?}, pixel ({x},{y}): G-buffer {p}, expected {shifted} (centre {centre})"
            );
            checked += 1;
        }
        assert!(checked >= 3, "too few floor pixels checked ({checked})");
    }
}

/// GPU faults are errors, never wgpu's panic: an error raised outside every error
/// scope is reported (once) by the next check, a readback past a buffer's end is an
/// error naming what was read, and a frame on a lost device fails with `DeviceLost`.
#[test]
fn device_faults_are_errors_not_panics() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (ctx, renderer) = render(&small_copy(dir.path(), "sphere_on_plane", 16, 12));
    ctx.check_device("a clean frame").expect("no fault yet");

    // mapped_at_creation needs a size that is a multiple of 4: a validation error
    // outside any scope, which wgpu's default handler would turn into a panic.
    let _bad = ctx
        .device
        .create_buffer(&caustics_gpu::wgpu::BufferDescriptor {
            label: Some("deliberately invalid"),
            size: 3,
            usage: caustics_gpu::wgpu::BufferUsages::MAP_WRITE,
            mapped_at_creation: true,
        });
    let e = ctx
        .check_device("the invalid buffer")
        .expect_err("the uncaptured error is reported");
    assert!(e.to_string().contains("the invalid buffer"), "{e}");
    ctx.check_device("after the report").expect("reported once");

    let small = ctx
        .device
        .create_buffer(&caustics_gpu::wgpu::BufferDescriptor {
            label: Some("small"),
            size: 16,
            usage: caustics_gpu::wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
    let e = caustics_gpu::readback::read_buffer_bytes(&ctx, &small, 64, "sixty-four bytes")
        .expect_err("reading past the end");
    assert!(e.to_string().contains("sixty-four bytes"), "{e}");

    ctx.device.destroy();
    let mut profiler = PassProfiler::new(&ctx, 1);
    let result = renderer
        .begin_frame(&mut profiler, FrameMode::Timed)
        .and_then(|frame| frame.submit(&ctx));
    let e = result.expect_err("a frame on a destroyed device");
    assert!(
        matches!(e, caustics_gpu::GpuError::DeviceLost { .. }),
        "expected DeviceLost, got {e}"
    );
}
