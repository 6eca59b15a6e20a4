//! GPU tests of the photon-hit methods, `caustic-triangles` (Umenhoffer, Patow &
//! Szirmay-Kalos) and `splatting`, run for real on whatever adapter the machine has
//! (lavapipe on CI). Without an adapter they fail with the message of
//! `GpuError::NoAdapter`, which says to install mesa-vulkan-drivers. Small images,
//! photon images and cube maps keep them fast.

mod common;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use caustic_triangles::photon_hits::{self, CausticMap, PhotonHit};
use caustic_triangles::{CausticTriangles, CausticTrianglesParams};
use caustics::run::{RunOptions, RunOutcome, run};
use caustics_gpu::{
    AdapterChoice, FrameMode, GpuContext, GpuScene, PassProfiler, Renderer, RendererOptions,
};
use caustics_method::CausticsMethod;
use caustics_metrics::HdrImage;
use caustics_scene::{Scene, Vec3};
use splatting::{Splatting, SplattingParams};

fn small_builtin(dir: &Path, name: &str, width: u32, height: u32) -> PathBuf {
    common::small_scene(dir, name, width, height)
}

/// Small settings shared by the tests: 48² photon image, 128² cube faces.
const SMALL: [&str; 3] = ["resolution=48", "cube_size=128", "distance_map_size=128"];

fn options(scene: &Path, out: &Path, method: &str, params: &[&str]) -> RunOptions {
    let all: Vec<&str> = SMALL.iter().chain(params).copied().collect();
    raw_options(scene, out, method, &all)
}

/// Options with exactly the parameters given.
fn raw_options(scene: &Path, out: &Path, method: &str, params: &[&str]) -> RunOptions {
    common::run_options(scene, out, method, params)
}

/// The adapter, the uploaded scene and its base renderer (small shadow maps).
fn renderer(path: &Path) -> (GpuContext, Renderer) {
    let ctx =
        GpuContext::new(&AdapterChoice::from_flag_or_env(None)).unwrap_or_else(|e| panic!("{e}"));
    let scene = Arc::new(Scene::load(path).expect("scene"));
    let gpu_scene = GpuScene::upload(&ctx, scene, Default::default()).expect("upload");
    let options = RendererOptions {
        shadow_resolution: 256,
        cube_shadow_resolution: 128,
    };
    let renderer = Renderer::new(&ctx, gpu_scene, options).expect("renderer");
    (ctx, renderer)
}

fn one_frame(ctx: &GpuContext, renderer: &Renderer, method: &mut dyn CausticsMethod) {
    let mut profiler = PassProfiler::new(ctx, 1);
    let mut frame = renderer
        .begin_frame(&mut profiler, FrameMode::Timed)
        .expect("frame");
    method.record(&mut frame).expect("record");
    frame.submit(ctx).expect("submit");
}

/// A 1 m glass slab surface (an open refractor, one interface) 1 m above a diffuse
/// floor, under a slanted directional light; the camera sits below the slab, so it sees
/// the floor directly.
fn flat_refractor_scene(dir: &Path, direction: [f64; 3], irradiance: [f64; 3]) -> PathBuf {
    let scene = serde_json::json!({
        "name": "flat_refractor",
        "description": "a flat glass surface over a floor: the analytic check of the photon-hit methods",
        "camera": {"eye": [0, 0.6, 2.2], "target": [0.2, 0, 0], "up": [0, 1, 0], "fov_y_deg": 50, "width": 64, "height": 64},
        "lights": [{"type": "directional", "direction": direction, "irradiance": irradiance}],
        "materials": {
            "glass": {"type": "dielectric", "ior": 1.5},
            "floor": {"type": "diffuse", "albedo": [0.8, 0.6, 0.4]}
        },
        "objects": [
            {"shape": {"type": "quad", "center": [0, 1, 0], "normal": [0, 1, 0], "size": [1, 1]}, "material": "glass"},
            {"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [6, 6]}, "material": "floor"}
        ]
    });
    common::write_scene(dir, "flat_refractor", &scene)
}

/// Exact unpolarized Fresnel reflectance (DESIGN "Conventions"), eta = n_i / n_t.
fn fresnel(cos_i: f64, eta: f64) -> f64 {
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (rs * rs + rp * rp)
}

#[test]
fn flat_refractor_vertices_carry_the_analytic_irradiance() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let irradiance = [1.0f64, 2.0, 0.5];
    let d = Vec3::new(0.4, -1.0, 0.2).normalize();
    let path = flat_refractor_scene(tmp.path(), [d.x as f64, d.y as f64, d.z as f64], irradiance);
    let (ctx, renderer) = renderer(&path);
    let params = CausticTrianglesParams {
        hits: photon_hits::PhotonHitConfig {
            resolution: 40,
            cube_size: 256,
            distance_map_size: 512,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut m = CausticTriangles::new(&ctx, &renderer, &params).expect("method");
    one_frame(&ctx, &renderer, &mut m);
    let hits = m.photon_hits().read_hits(&ctx).expect("hits");
    let e_v = m.read_vertex_irradiance(&ctx).expect("vertex irradiance");
    // A parallel beam through a flat interface onto a parallel floor keeps its
    // footprint: E_floor = T(θ) · E · cos θ.
    let cos_i = -d.y as f64;
    let t = 1.0 - fresnel(cos_i, 1.0 / 1.5);
    let n = params.hits.resolution as usize;
    let valid = |x: usize, y: usize| hits[y * n + x].valid();
    let (mut checked, mut worst) = (0, 0.0f64);
    for y in 1..n - 1 {
        for x in 1..n - 1 {
            // Interior vertices only: all eight neighbours valid, a full fan of six.
            if !(y - 1..=y + 1).all(|j| (x - 1..=x + 1).all(|i| valid(i, j))) {
                continue;
            }
            for c in 0..3 {
                let want = t * irradiance[c] * cos_i;
                let rel = (e_v[y * n + x][c] as f64 - want).abs() / want;
                worst = worst.max(rel);
            }
            checked += 1;
        }
    }
    eprintln!("flat refractor: {checked} interior vertices, worst relative error {worst:.2e}");
    assert!(checked > 400, "only {checked} interior vertices");
    // The hits come from the receivers' distance map (secant search on a 512² map),
    // whose landing points are off by a fraction of a millimetre: cell areas of
    // ~2.5 cm on a side move by well under 1 %.
    assert!(worst < 0.01, "worst vertex irradiance error {worst}");

    // The camera image in the middle of the lit patch: ρ/π · E.
    let rgba =
        caustics_gpu::readback::read_rgba32f(&ctx, &renderer.targets().surface.texture, "surface")
            .expect("surface");
    let albedo = [0.8f64, 0.6, 0.4];
    let (mut px, mut worst_px) = (0, 0.0f64);
    let cam = &renderer.scene().scene.camera;
    for j in 0..64u32 {
        for i in 0..64u32 {
            let (o, dir) = cam.ray_through_pixel(i as f32 + 0.5, j as f32 + 0.5);
            let p = o + dir * (-o.y / dir.y);
            // The lit patch is the slab's 1 m square shifted along the refracted ray.
            let shift = {
                let sin_t = (1.0 - cos_i * cos_i).sqrt() / 1.5;
                sin_t / (1.0 - sin_t * sin_t).sqrt()
            };
            let h = Vec3::new(d.x, 0.0, d.z).normalize() * shift as f32;
            let q = p - h;
            if q.x.abs() > 0.4 || q.z.abs() > 0.4 {
                continue;
            }
            let k = 4 * (j * 64 + i) as usize;
            for c in 0..3 {
                let want = albedo[c] / std::f64::consts::PI * t * irradiance[c] * cos_i;
                worst_px = worst_px.max((rgba[k + c] as f64 - want).abs() / want);
            }
            px += 1;
        }
    }
    eprintln!("flat refractor: {px} pixels, worst relative error {worst_px:.2e}");
    assert!(px > 150, "only {px} pixels inside the lit patch");
    assert!(worst_px < 0.01, "worst pixel radiance error {worst_px}");
}

#[test]
fn flat_mirror_vertices_carry_the_reflected_irradiance() {
    // A 45° mirror 1 m above the floor turns a light travelling along +x straight down:
    // the beam keeps its cross-section, so E_floor = R · E on every interior vertex.
    let tmp = tempfile::tempdir().expect("tempdir");
    let (irradiance, reflectance) = ([1.0f64, 2.0, 0.5], [0.9f64, 0.8, 0.7]);
    let scene = serde_json::json!({
        "name": "flat_mirror",
        "description": "a 45° mirror over a floor: the reflection check of the photon-hit methods",
        "camera": {"eye": [0, 0.5, 2], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 50, "width": 64, "height": 48},
        "lights": [{"type": "directional", "direction": [1, 0, 0], "irradiance": irradiance}],
        "materials": {
            "mirror": {"type": "mirror", "reflectance": reflectance},
            "floor": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}
        },
        "objects": [
            {"shape": {"type": "quad", "center": [0, 1, 0], "normal": [-1, -1, 0], "size": [0.5, 0.5]}, "material": "mirror"},
            {"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [6, 6]}, "material": "floor"}
        ]
    });
    let path = common::write_scene(tmp.path(), "flat_mirror", &scene);
    let (ctx, renderer) = renderer(&path);
    let params = CausticTrianglesParams {
        hits: photon_hits::PhotonHitConfig {
            resolution: 40,
            cube_size: 256,
            distance_map_size: 512,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut m = CausticTriangles::new(&ctx, &renderer, &params).expect("method");
    one_frame(&ctx, &renderer, &mut m);
    let hits = m.photon_hits().read_hits(&ctx).expect("hits");
    let e_v = m.read_vertex_irradiance(&ctx).expect("vertex irradiance");
    let n = params.hits.resolution as usize;
    let valid = |x: usize, y: usize| hits[y * n + x].valid();
    let (mut checked, mut worst) = (0, 0.0f64);
    for y in 1..n - 1 {
        for x in 1..n - 1 {
            if !(y - 1..=y + 1).all(|j| (x - 1..=x + 1).all(|i| valid(i, j))) {
                continue;
            }
            for c in 0..3 {
                let want = reflectance[c] * irradiance[c];
                worst = worst.max((e_v[y * n + x][c] as f64 - want).abs() / want);
            }
            checked += 1;
        }
    }
    eprintln!("flat mirror: {checked} interior vertices, worst relative error {worst:.2e}");
    assert!(checked > 300, "only {checked} interior vertices");
    assert!(worst < 0.01, "worst vertex irradiance error {worst}");
}

/// Σ over the atlas texels of E × the texel's area on the floor plane y = `floor_y`.
fn flux_on_floor(map: &CausticMap, atlas: &[f32], floor_y: f32) -> [f64; 3] {
    let s = map.size;
    let width = 3 * s;
    let mut total = [0.0f64; 3];
    for face in 0..6u32 {
        let inv = map.faces[face as usize].inverse();
        let (ox, oy) = photon_hits::face_origin(face, s);
        for ty in 0..s {
            for tx in 0..s {
                let k = 4 * ((oy + ty) * width + ox + tx) as usize;
                if atlas[k] == 0.0 && atlas[k + 1] == 0.0 && atlas[k + 2] == 0.0 {
                    continue;
                }
                let a = 2.0 * (tx as f32 + 0.5) / s as f32 - 1.0;
                let b = 1.0 - 2.0 * (ty as f32 + 0.5) / s as f32;
                let w = (inv.project_point3(Vec3::new(a, b, 0.5)) - map.center).normalize();
                assert!(w.y < 0.0, "light in a texel looking away from the floor");
                let dist = (floor_y - map.center.y) / w.y;
                let omega = (2.0 / s as f64).powi(2) / (1.0 + (a * a + b * b) as f64).powf(1.5);
                let area = omega * (dist as f64).powi(2) / (-w.y as f64);
                for c in 0..3 {
                    total[c] += atlas[k + c] as f64 * area;
                }
            }
        }
    }
    total
}

#[test]
fn splatting_conserves_the_photon_flux_for_every_kernel() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = small_builtin(tmp.path(), "sphere_on_plane", 64, 48);
    let (ctx, renderer) = renderer(&path);
    for kernel_px in [1u32, 4, 16] {
        let params = SplattingParams {
            hits: photon_hits::PhotonHitConfig {
                resolution: 48,
                cube_size: 256,
                distance_map_size: 128,
                ..Default::default()
            },
            kernel_px,
        };
        let mut m = Splatting::new(&ctx, &renderer, &params).expect("method");
        one_frame(&ctx, &renderer, &mut m);
        let hits: Vec<PhotonHit> = m.photon_hits().read_hits(&ctx).expect("hits");
        let mut photons = [0.0f64; 3];
        for h in hits.iter().filter(|h| h.valid()) {
            for (sum, flux) in photons.iter_mut().zip(h.flux) {
                *sum += flux as f64;
            }
        }
        assert!(photons[1] > 0.5, "little flux: {photons:?}");
        let atlas = m.caustic_map().read_atlas(&ctx).expect("atlas");
        let splatted = flux_on_floor(m.caustic_map(), &atlas, 0.0);
        for c in 0..3 {
            let rel = (splatted[c] - photons[c]).abs() / photons[c];
            eprintln!(
                "kernel {kernel_px} px, channel {c}: splatted {:.5} W, photons {:.5} W ({rel:.2e})",
                splatted[c], photons[c]
            );
            // The kernel is normalized with the solid angle, distance and cosine at its
            // centre; the integral takes each texel's own: a second-order difference.
            assert!(rel < 2e-3, "kernel {kernel_px}: {rel}");
        }
    }
}

/// Floor points (y = -3) seen by the camera under the table of `light_leak`: hidden
/// from the glass ball by the table, and out of reach of the light passing the
/// table's edge (it diverges after the focus).
fn occluded_floor_pixels(scene: &Scene) -> Vec<(u32, u32)> {
    let cam = &scene.camera;
    let mut out = Vec::new();
    for j in 0..cam.height {
        for i in 0..cam.width {
            let (o, d) = cam.ray_through_pixel(i as f32 + 0.5, j as f32 + 0.5);
            if d.y >= 0.0 {
                continue;
            }
            let p = o + d * ((-3.0 - o.y) / d.y);
            if p.x.abs() < 0.7 && p.z.abs() < 0.7 {
                out.push((i, j));
            }
        }
    }
    out
}

#[test]
fn distance_test_removes_the_light_leak_onto_an_occluded_receiver() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = small_builtin(tmp.path(), "light_leak", 64, 48);
    let scene = Scene::load(&path).expect("scene");
    let pixels = occluded_floor_pixels(&scene);
    assert!(
        pixels.len() > 30,
        "only {} occluded floor pixels",
        pixels.len()
    );
    for method in ["caustic-triangles", "splatting"] {
        let sum =
            |img: &HdrImage| -> f64 { pixels.iter().map(|&(i, j)| img.get(i, j)[1] as f64).sum() };
        let (with, _) = common::run_surface(&options(
            &path,
            &tmp.path().join(format!("{method}-on")),
            method,
            &["distance_test=true"],
        ));
        let (without, _) = common::run_surface(&options(
            &path,
            &tmp.path().join(format!("{method}-off")),
            method,
            &["distance_test=false"],
        ));
        eprintln!(
            "{method}: caustic on the occluded floor {:.4} with the distance test, {:.4} without",
            sum(&with),
            sum(&without)
        );
        assert_eq!(sum(&with), 0.0, "{method}: light leaks despite the test");
        assert!(
            sum(&without) > 1.0,
            "{method}: no leak without the test, the scene shows nothing"
        );
        eprintln!(
            "{method}: whole image {:.4} with the test, {:.4} without",
            with.sum_luminance(),
            without.sum_luminance()
        );
    }
}

#[test]
fn counts_and_images_are_deterministic() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = small_builtin(tmp.path(), "ring", 64, 48);
    for method in ["caustic-triangles", "splatting"] {
        let (a, ra) = common::run_surface(&options(&path, &tmp.path().join("a"), method, &[]));
        let (b, rb) = common::run_surface(&options(&path, &tmp.path().join("b"), method, &[]));
        assert_eq!(ra.counters, rb.counters, "{method}");
        assert!(
            ra.counters["photon_hits"] > 100,
            "{method}: {:?}",
            ra.counters
        );
        assert_eq!(ra.counters["photon_texels"], 48 * 48);
        let fa = ra.fragments.as_ref().expect("pipeline statistics");
        let fb = rb.fragments.as_ref().expect("pipeline statistics");
        assert_eq!(fa.method_total, fb.method_total, "{method}");
        assert_eq!(a.pixels, b.pixels, "{method}: image differs between runs");
        assert!(
            a.sum_luminance() > 0.0,
            "{method}: no caustic on the ring floor"
        );
        let names: Vec<&str> = ra.timing.passes.iter().map(|p| p.name.as_str()).collect();
        for pass in [
            "light_gbuffer",
            "distance_maps",
            "trace_photons",
            "camera_lookup",
        ] {
            let want = format!("{method}/{pass}");
            assert!(
                names.contains(&want.as_str()),
                "{want} missing from {names:?}"
            );
        }
    }
}

#[test]
fn bad_parameters_and_unsupported_scenes_are_clear() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = small_builtin(tmp.path(), "sphere_on_plane", 32, 24);
    for (method, param, needle) in [
        ("caustic-triangles", "resolution=1", "resolution"),
        ("caustic-triangles", "max_stretch=0", "max_stretch"),
        ("splatting", "kernel_px=0", "kernel_px"),
        ("splatting", "kernel=3", "known parameters"),
    ] {
        let e = run(&raw_options(&path, tmp.path(), method, &[param])).expect_err(param);
        let msg = format!("{e:#}");
        assert!(
            msg.contains(needle) && msg.contains(method),
            "{param}: {msg}"
        );
    }
    assert!(!tmp.path().join("sphere_on_plane").exists());
    // Two specular objects: one photon hit image follows one generator.
    let two = small_builtin(tmp.path(), "sphere_over_water", 32, 24);
    match run(&options(&two, tmp.path(), "caustic-triangles", &[])).expect("run") {
        RunOutcome::Skipped { reason } => assert!(reason.contains("both specular"), "{reason}"),
        RunOutcome::Done { .. } => panic!("sphere_over_water must be skipped"),
    }
}
