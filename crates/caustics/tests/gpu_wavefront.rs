//! GPU tests of the harness and `wavefront`, run for real on whatever adapter the
//! machine has (lavapipe on CI). Without an adapter they fail with the message from
//! `GpuError::NoAdapter`, which says to install mesa-vulkan-drivers.

mod common;

use std::path::Path;

use caustics::result::RunResult;
use caustics::run::{RunOptions, run};
use caustics_metrics::{HdrImage, read_exr};

fn options(scene: &Path, out: &Path) -> RunOptions {
    RunOptions {
        frames: 3,
        warmup: 1,
        ..common::run_options(scene, out, "wavefront", &[])
    }
}

fn nonzero_pixels(img: &HdrImage) -> usize {
    img.pixels
        .iter()
        .filter(|p| p.iter().any(|&c| c > 0.0))
        .count()
}

#[test]
fn water_pool_run_writes_a_finite_nonempty_caustic_with_consistent_counts() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let scene = common::small_scene(tmp.path(), "water_pool", 320, 240);
    let (dir, result) = common::run_dir(&options(&scene, tmp.path()));

    for f in [
        "result.json",
        "surface.exr",
        "direct.exr",
        "composite.png",
        "fill_heatmap.png",
    ] {
        assert!(dir.join(f).is_file(), "{f} missing in {}", dir.display());
    }
    let surface = read_exr(&dir.join("surface.exr")).expect("surface.exr");
    surface
        .check_finite("surface")
        .expect("finite surface caustic");
    let lit = nonzero_pixels(&surface);
    assert!(
        lit > surface.pixels.len() / 4,
        "only {lit} caustic pixels of {}",
        surface.pixels.len()
    );
    assert!(surface.sum_luminance() > 0.0);

    assert!(
        result.counters["kept_triangles"] > 0,
        "{:?}",
        result.counters
    );
    assert_eq!(
        result.counters["triangles"],
        255 * 255 * 2,
        "the 256² water grid"
    );

    // Timestamps: lavapipe has them, so every pass must have a time, none rejected.
    assert!(
        result.timing.timestamps_available,
        "adapter without timestamp queries"
    );
    assert_eq!(result.timing.rejected_timestamps, 0);
    for p in &result.timing.passes {
        let s = p
            .gpu_ms
            .as_ref()
            .unwrap_or_else(|| panic!("no time for {}", p.name));
        assert_eq!(s.samples, 3, "{}", p.name);
    }
    let names: Vec<&str> = result
        .timing
        .passes
        .iter()
        .map(|p| p.name.as_str())
        .collect();
    for want in [
        "base/camera_gbuffer",
        "base/shadow_map",
        "base/direct",
        "wavefront/trace_vertices",
        "wavefront/splat",
    ] {
        assert!(names.contains(&want), "pass {want} missing from {names:?}");
    }

    // The water mesh's triangles are a few pixels wide here, so most invocations are
    // helpers: only the loose bound holds (see `splat_statistics_vs_heatmap`).
    let (stats, fill) = splat_statistics_vs_heatmap(&result);
    assert!(
        stats <= MAX_INVOCATIONS_PER_FRAGMENT * fill,
        "statistics {stats} > {MAX_INVOCATIONS_PER_FRAGMENT} x heatmap {fill}"
    );
}

/// Helper invocations: the rasterizer runs fragment shaders on whole 2x2 quads
/// (hardware) or 4x4 blocks (llvmpipe), and pipeline statistics may count the helper
/// lanes, which never write the fill counter. So heatmap <= statistics <= 16 x heatmap
/// always, and with triangles much larger than a block the two agree closely.
const MAX_INVOCATIONS_PER_FRAGMENT: f64 = 16.0;

/// Largest share of splat-pass invocations the heatmap misses when the triangles are
/// large (flat-water scene: a 9² grid over 12 m seen from 0.9 m, triangles of tens of thousands of
/// pixels at 320x240). Measured on lavapipe (Mesa 22.3.6, llvmpipe 4x4 blocks): 0.0845
/// (83888 invocations for 76800 fragments); 2x2-quad hardware sees less.
const LARGE_TRIANGLE_HELPER_MARGIN: f64 = 0.10;

/// (pipeline-statistics fragment invocations of `wavefront/splat`, heatmap sum),
/// with heatmap <= statistics checked.
fn splat_statistics_vs_heatmap(result: &RunResult) -> (f64, f64) {
    let frags = result
        .fragments
        .as_ref()
        .expect("pipeline statistics on this adapter");
    let splat = frags
        .passes
        .iter()
        .find(|p| p.name == "wavefront/splat")
        .expect("splat pass statistics");
    let stats = splat.fragment_shader_invocations as f64;
    let fill = frags.fill_total as f64;
    assert!(fill > 0.0, "empty heatmap");
    assert!(
        stats >= fill,
        "statistics {stats} < heatmap {fill}: the counter saw fragments the GPU did not shade"
    );
    (stats, fill)
}

/// Exact unpolarized Fresnel transmittance from air into a dielectric, computed here
/// independently of the shaders.
fn fresnel_transmittance(cos_i: f64, ior: f64) -> f64 {
    let sin_t = (1.0 - cos_i * cos_i).sqrt() / ior;
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let rs = (cos_i - ior * cos_t) / (cos_i + ior * cos_t);
    let rp = (ior * cos_i - cos_t) / (ior * cos_i + cos_t);
    1.0 - 0.5 * (rs * rs + rp * rp)
}

#[test]
fn flat_water_gives_the_analytic_floor_radiance_within_one_percent() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir_vec = [0.5f64, -1.0, 0.3];
    let len = dir_vec.iter().map(|v| v * v).sum::<f64>().sqrt();
    let cos_theta = 1.0 / len;
    let (ior, albedo, irradiance) = (1.33f64, [0.8f64, 0.6, 0.4], [1.0f64, 2.0, 0.5]);
    let scene = serde_json::json!({
        "name": "flat_water",
        "description": "flat water over a floor: the analytic check of wavefront",
        "camera": {"eye": [0, 0.9, 0], "target": [0, 0, 0], "up": [0, 0, -1], "fov_y_deg": 60, "width": 320, "height": 240},
        "lights": [{"type": "directional", "direction": dir_vec, "irradiance": irradiance}],
        "materials": {"water": {"type": "dielectric", "ior": ior}, "floor": {"type": "diffuse", "albedo": albedo}},
        "objects": [
            {"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [6, 6]}, "material": "floor"},
            {"shape": {"type": "heightfield", "center": [0, 1, 0], "size": [12, 12], "resolution": [9, 9],
                       "waves": [{"amplitude": 0.0, "wavelength": 1.0, "direction": [1, 0], "phase": 0}]},
             "material": "water"}
        ]
    });
    let path = tmp.path().join("flat_water.json");
    std::fs::write(&path, serde_json::to_string_pretty(&scene).expect("json")).expect("write");
    let (dir, result) = common::run_dir(&options(&path, tmp.path()));
    let surface = read_exr(&dir.join("surface.exr")).expect("surface.exr");

    let (stats, fill) = splat_statistics_vs_heatmap(&result);
    let margin = (stats - fill) / stats;
    eprintln!("flat water: splat statistics {stats}, heatmap {fill}, helper margin {margin:.4}");
    assert!(
        margin <= LARGE_TRIANGLE_HELPER_MARGIN,
        "statistics {stats} vs heatmap {fill}: margin {margin:.4}"
    );

    let t = fresnel_transmittance(cos_theta, ior);
    let expected: Vec<f64> = (0..3)
        .map(|c| albedo[c] / std::f64::consts::PI * t * irradiance[c] * cos_theta)
        .collect();
    // Every pixel of the central half sees the floor under the flat water.
    let (w, h) = (surface.width, surface.height);
    let mut checked = 0;
    for y in h / 4..3 * h / 4 {
        for x in w / 4..3 * w / 4 {
            let p = surface.get(x, y);
            for c in 0..3 {
                let rel = (p[c] as f64 - expected[c]).abs() / expected[c];
                assert!(
                    rel < 0.01,
                    "pixel ({x},{y}) channel {c}: {} vs analytic {} ({:.3}%)",
                    p[c],
                    expected[c],
                    rel * 100.0
                );
            }
            checked += 1;
        }
    }
    assert_eq!(checked, (w / 2 * h / 2) as usize);
}

#[test]
fn timestamps_are_nonzero_and_increase_through_a_frame() {
    use caustics_gpu::{
        AdapterChoice, FrameMode, GpuContext, GpuScene, PassProfiler, Renderer, RendererOptions,
    };
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = common::small_scene(tmp.path(), "sphere_on_plane", 128, 96);
    let scene = caustics_scene::Scene::load(&path).expect("scene");
    let ctx =
        GpuContext::new(&AdapterChoice::from_flag_or_env(None)).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        ctx.has_timestamps(),
        "adapter {} lacks timestamp queries",
        ctx.summary.name
    );
    let gpu_scene = GpuScene::upload(&ctx, scene.into(), Default::default()).expect("upload");
    let renderer = Renderer::new(&ctx, gpu_scene, RendererOptions::default()).expect("renderer");
    let mut profiler = PassProfiler::new(&ctx, 3);
    for _ in 0..3 {
        let frame = renderer
            .begin_frame(&mut profiler, FrameMode::Timed)
            .expect("frame");
        frame.submit(&ctx).expect("submit");
    }
    let frames = profiler.collect(&ctx).expect("collect");
    assert_eq!(frames.len(), 3);
    for f in &frames {
        assert_eq!(f.rejected_timestamps, 0);
        let mut last_end = 0u64;
        for p in &f.passes {
            let (b, e) = p
                .ticks
                .unwrap_or_else(|| panic!("pass {} has no timestamps", p.name));
            assert!(b > 0, "{}: zero begin timestamp", p.name);
            assert!(e >= b, "{}: end {e} before begin {b}", p.name);
            assert!(
                b >= last_end,
                "{}: begins at {b} before the previous pass ended at {last_end}",
                p.name
            );
            last_end = e;
        }
    }
    // Frames run one after another.
    let first_end = frames[0]
        .passes
        .last()
        .and_then(|p| p.ticks)
        .map(|t| t.1)
        .expect("ticks");
    let second_begin = frames[1].passes[0].ticks.map(|t| t.0).expect("ticks");
    assert!(second_begin > first_end);
}

#[test]
fn errors_against_a_reference_are_zero_for_itself_and_tell_scale_from_shape() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let scene = common::small_scene(tmp.path(), "water_pool", 128, 96);
    let (dir, first) = common::run_dir(&options(&scene, &tmp.path().join("a")));
    assert!(first.errors.is_none(), "no reference, no errors");
    let surface = read_exr(&dir.join("surface.exr")).expect("surface.exr");

    // The same image as its own reference: every comparator says "identical".
    let same = tmp.path().join("same.exr");
    caustics_metrics::write_exr(&same, &surface).expect("write reference");
    let mut o = options(&scene, &tmp.path().join("b"));
    o.reference = Some(same);
    let (dir_b, r) = common::run_dir(&o);
    let e = r.errors.expect("errors with a reference").surface;
    assert_eq!(e.rmse, 0.0, "runs are deterministic on one adapter");
    assert_eq!(e.flip, 0.0);
    assert!((e.ssim - 1.0).abs() < 1e-9, "{}", e.ssim);
    assert!(dir_b.join("error.png").is_file());

    // Twice as bright a reference: a pure normalization error, which the best
    // scale explains fully.
    let double = tmp.path().join("double.exr");
    caustics_metrics::write_exr(&double, &surface.scaled(2.0)).expect("write reference");
    o.reference = Some(double);
    o.out = tmp.path().join("c");
    let e = common::run_dir(&o).1.errors.expect("errors").surface;
    assert!(e.rmse > 0.0 && e.flip > 0.0);
    assert!(
        (e.best_scale - 2.0).abs() < 1e-4,
        "best scale {}",
        e.best_scale
    );
    assert!(
        e.rmse_after_best_scale < 1e-4 * e.rmse,
        "{} vs {}",
        e.rmse_after_best_scale,
        e.rmse
    );
}

#[test]
fn a_reference_of_the_wrong_size_is_refused_before_any_write() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let scene = common::small_scene(tmp.path(), "water_pool", 64, 48);
    let reference = tmp.path().join("small.exr");
    caustics_metrics::write_exr(&reference, &HdrImage::new(32, 24)).expect("write");
    let out = tmp.path().join("out");
    let mut o = options(&scene, &out);
    o.reference = Some(reference);
    let e = run(&o).expect_err("size mismatch").to_string();
    assert!(
        e.contains("expected a 64x48 image") && e.contains("got 32x24"),
        "{e}"
    );
    assert!(!out.exists(), "nothing may be written");
}

#[test]
fn a_cached_reference_is_found_by_scene_hash_and_used() {
    use caustics::references::{ReferenceMeta, cache_dir, find};
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = common::small_scene(tmp.path(), "water_pool", 64, 48);
    let scene = caustics_scene::Scene::load(&path).expect("scene");
    let root = tmp.path().join("refs");
    assert!(find(&root, &scene).expect("empty cache").is_none());

    // A reference of all-ones radiance with a known standard error.
    let dir = cache_dir(&root, &scene);
    std::fs::create_dir_all(&dir).expect("mkdir");
    let mut ones = HdrImage::new(64, 48);
    ones.pixels.iter_mut().for_each(|p| *p = [1.0; 3]);
    caustics_metrics::write_exr(&dir.join("caustic.exr"), &ones).expect("write");
    caustics_metrics::write_exr(&dir.join("stderr.exr"), &ones.scaled(0.01)).expect("write");
    let meta = ReferenceMeta {
        schema_version: 1,
        scene: scene.name.clone(),
        scene_hash: scene.hash_hex(),
        width: 64,
        height: 48,
        photons: 1000,
        seconds: 1.0,
        photons_per_second: 1000.0,
        seed: 1,
        batches: 16,
        commit: "test".into(),
        relative_stderr: 0.01,
    };
    std::fs::write(
        dir.join("meta.json"),
        serde_json::to_vec(&meta).expect("json"),
    )
    .expect("write");

    let mut o = options(&path, &tmp.path().join("out"));
    o.references = root.clone();
    let (_, r) = common::run_dir(&o);
    let e = r.errors.expect("the cached reference is used");
    assert_eq!(e.reference_source, "cache");
    assert!(e.reference.ends_with("caustic.exr"), "{}", e.reference);
    let noise = e
        .reference_noise_rms
        .expect("stderr.exr beside the reference");
    assert!((noise - 0.01).abs() < 1e-6, "{noise}");

    // A meta.json that does not match the scene is an error, not a silent miss.
    let mut stale = meta.clone();
    stale.scene_hash = "0000000000000000".into();
    std::fs::write(
        dir.join("meta.json"),
        serde_json::to_vec(&stale).expect("json"),
    )
    .expect("write");
    let err = run(&o).expect_err("stale cache").to_string();
    assert!(
        err.contains("meta.json") && err.contains("0000000000000000"),
        "{err}"
    );
}

#[test]
fn flat_mirror_gives_the_analytic_reflected_radiance_within_one_percent() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let (reflectance, albedo, irradiance) =
        ([0.9f64, 0.7, 0.5], [0.8f64, 0.6, 0.4], [1.0f64, 2.0, 0.5]);
    // A vertical mirror (normal +x) under light travelling along (-1, -1, 0): the
    // reflected beam travels along (1, -1, 0) and meets the floor at 45 degrees.
    let scene = serde_json::json!({
        "name": "flat_mirror",
        "description": "a vertical mirror reflecting a directional light onto a floor",
        "camera": {"eye": [1, 2, 0], "target": [1, 0, 0], "up": [0, 0, -1], "fov_y_deg": 40, "width": 160, "height": 120},
        "lights": [{"type": "directional", "direction": [-1, -1, 0], "irradiance": irradiance}],
        "materials": {"mirror": {"type": "mirror", "reflectance": reflectance}, "floor": {"type": "diffuse", "albedo": albedo}},
        "objects": [
            {"shape": {"type": "quad", "center": [0, 1.5, 0], "normal": [1, 0, 0], "size": [3, 6]}, "material": "mirror"},
            {"shape": {"type": "quad", "center": [2, 0, 0], "normal": [0, 1, 0], "size": [4, 6]}, "material": "floor"}
        ]
    });
    let path = tmp.path().join("flat_mirror.json");
    std::fs::write(&path, serde_json::to_string_pretty(&scene).expect("json")).expect("write");
    let mut o = options(&path, tmp.path());
    o.params = vec!["grid=64".into()];
    let (dir, result) = common::run_dir(&o);
    assert_eq!(result.counters["dropped_face_mismatch"], 0);
    let surface = read_exr(&dir.join("surface.exr")).expect("surface.exr");
    let cos_floor = std::f64::consts::FRAC_1_SQRT_2;
    let (w, h) = (surface.width, surface.height);
    for y in h / 4..3 * h / 4 {
        for x in w / 4..3 * w / 4 {
            let p = surface.get(x, y);
            for c in 0..3 {
                let expected =
                    albedo[c] / std::f64::consts::PI * reflectance[c] * irradiance[c] * cos_floor;
                let rel = (p[c] as f64 - expected).abs() / expected;
                assert!(
                    rel < 0.01,
                    "pixel ({x},{y}) channel {c}: {} vs analytic {expected} ({:.3}%)",
                    p[c],
                    rel * 100.0
                );
            }
        }
    }
}
