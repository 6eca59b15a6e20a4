//! GPU tests of `pinhole` (Wand & Straßer 2003), run for real on whatever adapter the
//! machine has (lavapipe on CI; no adapter is a failure, not a skip). Small images and
//! few samples keep them fast.

mod common;

use std::path::{Path, PathBuf};

use caustics::run::{RunOptions, run};
use caustics_scene::Vec3;

fn options(scene: &Path, out: &Path, params: &[&str]) -> RunOptions {
    RunOptions {
        frames: 2,
        ..common::run_options(scene, out, "pinhole", params)
    }
}

/// A 2 cm square mirror at 45° one metre above a floor; a directional light of angular
/// radius `light_angle` travelling along +x is reflected straight down.
fn flat_mirror_scene(dir: &Path, light: serde_json::Value, mirror_size: f64) -> PathBuf {
    let scene = serde_json::json!({
        "name": "flat_mirror",
        "description": "a small 45° mirror over a floor: the analytic check of pinhole",
        "camera": {"eye": [0, 1.5, 3], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 30, "width": 64, "height": 48},
        "lights": [light],
        "materials": {
            "mirror": {"type": "mirror", "reflectance": [0.9, 0.8, 0.7]},
            "floor": {"type": "diffuse", "albedo": [0.8, 0.6, 0.4]}
        },
        "objects": [
            {"shape": {"type": "quad", "center": [0, 1, 0], "normal": [-1, -1, 0], "size": [mirror_size, mirror_size]}, "material": "mirror"},
            {"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [4, 4]}, "material": "floor"}
        ]
    });
    common::write_scene(dir, "flat_mirror", &scene)
}

/// The floor point (y = 0) seen through the centre of pixel (i, j).
fn floor_point(cam: &caustics_scene::Camera, i: u32, j: u32) -> Option<Vec3> {
    let (o, d) = cam.ray_through_pixel(i as f32 + 0.5, j as f32 + 0.5);
    (d.y < 0.0).then(|| o + d * (-o.y / d.y))
}

#[test]
fn one_sample_on_a_flat_mirror_gives_the_analytic_reflected_irradiance() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let (irradiance, reflectance, albedo) =
        ([1.0f64, 2.0, 0.5], [0.9f64, 0.8, 0.7], [0.8f64, 0.6, 0.4]);
    let alpha = 0.2f64;
    let light = serde_json::json!({"type": "directional", "direction": [1, 0, 0], "irradiance": irradiance});
    let side = 0.004f64;
    let path = flat_mirror_scene(tmp.path(), light, side);
    let scene = caustics_scene::Scene::load(&path).expect("scene");
    let n = Vec3::new(-1.0, -1.0, 0.0).normalize();
    let (u, v) = caustics_scene::quad_axes(n);
    let centre = Vec3::new(0.0, 1.0, 0.0);
    // The light is a cone of half angle alpha with uniform radiance E / Omega.
    let radiance: Vec<f64> = irradiance
        .iter()
        .map(|e| e / (std::f64::consts::TAU * (1.0 - alpha.cos())))
        .collect();
    for filtering in ["off", "full"] {
        let (surface, result) = common::run_surface(&options(
            &path,
            &tmp.path().join(filtering),
            &[
                "samples=1",
                &format!("light_angle={alpha}"),
                &format!("filtering=\"{filtering}\""),
            ],
        ));
        assert_eq!(result.counters["samples"], 1);
        let mut checked = 0;
        let mut worst = 0.0f64;
        for j in 0..surface.height {
            for i in 0..surface.width {
                let Some(x) = floor_point(&scene.camera, i, j) else {
                    continue;
                };
                // Well inside the light's image (radius ~0.2 m): the mirror sees the light
                // at most 3/4 of its angular radius from the light's centre.
                if x.length() > 0.15 {
                    continue;
                }
                // Analytic: R L ∫ cos θ_s cos θ_x / d² dA over the mirror (20×20 midpoint rule).
                let mut solid = 0.0f64;
                let m = 20;
                for a in 0..m {
                    for b in 0..m {
                        let s = ((a as f32 + 0.5) / m as f32 - 0.5) * side as f32;
                        let t = ((b as f32 + 0.5) / m as f32 - 0.5) * side as f32;
                        let p = centre + s * u + t * v;
                        let to = p - x;
                        let d2 = to.length_squared() as f64;
                        let w = to.normalize();
                        let cos_x = w.y as f64;
                        let cos_s = (-w).dot(n) as f64;
                        solid += cos_s * cos_x / d2 * (side * side) / (m * m) as f64;
                    }
                }
                let p = surface.get(i, j);
                for c in 0..3 {
                    let want =
                        albedo[c] / std::f64::consts::PI * reflectance[c] * radiance[c] * solid;
                    let rel = (p[c] as f64 - want).abs() / want;
                    worst = worst.max(rel);
                    assert!(
                        rel < 0.01,
                        "filtering={filtering} pixel ({i},{j}) channel {c}: {} vs analytic {want} ({:.3}%)",
                        p[c],
                        rel * 100.0
                    );
                }
                checked += 1;
            }
        }
        eprintln!(
            "flat mirror, filtering={filtering}: {checked} pixels, worst relative error {:.4}%",
            worst * 100.0
        );
        assert!(
            checked >= 12,
            "only {checked} pixels inside the light's image"
        );
    }
}

#[test]
fn ring_run_has_consistent_counters_passes_and_heatmap() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let scene = common::small_scene(tmp.path(), "ring", 64, 48);
    let (surface, result) = common::run_surface(&options(
        &scene,
        tmp.path(),
        &["samples=200", "samples_per_pass=64"],
    ));
    let lit = surface.pixels.iter().filter(|p| p[1] > 0.0).count();
    assert!(lit > 50, "only {lit} caustic pixels");
    let c = &result.counters;
    assert_eq!(c["samples"], 200);
    assert_eq!(c["passes"], 4, "ceil(200 / 64)");
    // Every receiver fragment of every pass loops over its batch: pairs = pixels × N.
    let receivers = c["receiver_fragments"] / c["passes"];
    assert_eq!(c["receiver_fragments"] % c["passes"], 0);
    assert_eq!(c["sample_pixel_pairs"], receivers * 200);
    assert!(c["texture_fetches"] > 0 && receivers > 1000, "{c:?}");
    let names: Vec<&str> = result
        .timing
        .passes
        .iter()
        .map(|p| p.name.as_str())
        .collect();
    for want in ["pinhole/prepare_samples", "pinhole/gather"] {
        assert!(names.contains(&want), "{want} missing from {names:?}");
    }
    // The heatmap counts one fragment per pixel and pass of the fullscreen gather.
    let f = result.fragments.as_ref().expect("pipeline statistics");
    assert_eq!(f.fill_total, 64 * 48 * 4);
}

#[test]
fn filtering_changes_the_image_only_where_the_reflector_is_curved() {
    let tmp = tempfile::tempdir().expect("tempdir");
    // Flat mirror, many samples: the curvature footprint is zero, so on == off exactly.
    let light =
        serde_json::json!({"type": "point", "position": [-1, 1, 0], "intensity": [5, 5, 5]});
    let flat = flat_mirror_scene(tmp.path(), light, 0.5);
    let run_with = |scene: &Path, f: &str| {
        common::run_surface(&options(
            scene,
            &tmp.path().join(f),
            &["samples=64", &format!("filtering=\"{f}\"")],
        ))
        .0
    };
    let off = run_with(&flat, "off");
    assert!(off.sum_luminance() > 0.0);
    assert_eq!(
        off.pixels,
        run_with(&flat, "curvature").pixels,
        "flat mirror"
    );
    // The ring is curved around its axis: the footprint is not zero.
    let ring = common::small_scene(tmp.path(), "ring", 64, 48);
    let off = run_with(&ring, "off");
    let on = run_with(&ring, "curvature");
    let changed = off
        .pixels
        .iter()
        .zip(&on.pixels)
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        changed > 50,
        "curvature filtering changed only {changed} ring pixels"
    );
}

#[test]
fn same_seed_same_image_other_seed_other_image_for_every_strategy() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let scene = common::small_scene(tmp.path(), "ring", 48, 36);
    for strategy in ["random", "grid", "quantized", "neighbor_removal"] {
        let go = |seed: u32, tag: &str| {
            common::run_surface(&options(
                &scene,
                &tmp.path().join(format!("{strategy}-{tag}")),
                &[
                    &format!("sampling=\"{strategy}\""),
                    "samples=50",
                    &format!("seed={seed}"),
                ],
            ))
        };
        let (a, ra) = go(7, "a");
        let (b, _) = go(7, "b");
        let (c, _) = go(8, "c");
        assert_eq!(ra.counters["samples"], 50, "{strategy}");
        assert_eq!(a.pixels, b.pixels, "{strategy}: not deterministic");
        assert_ne!(a.pixels, c.pixels, "{strategy}: the seed changes nothing");
    }
}

#[test]
fn refracting_sphere_focuses_light_under_it() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let scene = common::small_scene(tmp.path(), "sphere_on_plane", 64, 48);
    let (surface, _) = common::run_surface(&options(&scene, tmp.path(), &["samples=300"]));
    let max = surface.pixels.iter().map(|p| p[1]).fold(0.0f32, f32::max);
    // The direct floor radiance is ρ/π·E·cos ≈ 0.25: the focus is much brighter.
    assert!(max > 1.0, "no focus under the glass sphere: max {max}");
}

#[test]
fn bad_parameters_are_clear_errors_and_write_nothing() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let scene = common::small_scene(tmp.path(), "ring", 32, 24);
    for (param, needle) in [
        ("sampling=\"hexagonal\"", "sampling: expected one of"),
        ("samples=0", "samples"),
        ("filtering=\"maybe\"", "filtering: expected one of"),
        ("cube_size=100", "cube_size"),
        ("light_size=1", "known parameters"),
    ] {
        let e = run(&options(&scene, tmp.path(), &[param])).expect_err(param);
        let msg = format!("{e:#}");
        assert!(
            msg.contains(needle) && msg.contains("pinhole"),
            "{param}: {msg}"
        );
    }
    assert!(
        !tmp.path().join("ring").exists(),
        "a failed run wrote results"
    );
}
