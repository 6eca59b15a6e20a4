//! `pinhole` (Wand & Straßer 2003) on the GPU, on whatever adapter the machine has
//! (lavapipe on CI; without an adapter these fail with the install hint, never skip):
//! the analytic irradiance under a small flat mirror and a small flat water patch, the
//! CPU reference on a refracting sphere, the water pool and a mirror mesh, filtering,
//! seeds and counters on the ring. Small images and few samples keep them fast.

use caustics_scene::Vec3;
use caustics_testing::{
    Bounds, Gpu, HdrImage, Measured, TEST_REFERENCE, artifacts, builtin, compare, plane_hit, scene,
};

/// Renders `scene` with pinhole and JSON `params`: the measured frames and the image.
fn run(scene: caustics_scene::Scene, params: serde_json::Value) -> (HdrImage, Measured) {
    let gpu = Gpu::new(scene);
    let mut method = gpu.method(
        &caustics_method::registry_entry::<pinhole::Pinhole>(),
        params,
    );
    let measured = gpu.measure(method.as_mut(), 0, 1);
    (gpu.surface(), measured)
}

/// A square mirror of side `mirror_size` at 45° one metre above a floor; a directional
/// light of angular radius `light_angle` travelling along +x is reflected straight down.
fn flat_mirror_scene(light: serde_json::Value, mirror_size: f64) -> caustics_scene::Scene {
    scene(&serde_json::json!({
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
    }))
}

#[test]
fn one_sample_on_a_flat_mirror_gives_the_analytic_reflected_irradiance_of_a_light_or_a_sky() {
    let (irradiance, reflectance, albedo) =
        ([1.0f64, 2.0, 0.5], [0.9f64, 0.8, 0.7], [0.8f64, 0.6, 0.4]);
    let alpha = 0.2f64;
    let side = 0.004f64;
    let n = Vec3::new(-1.0, -1.0, 0.0).normalize();
    let (u, v) = caustics_scene::quad_axes(n);
    let centre = Vec3::new(0.0, 1.0, 0.0);
    // The light is a cone of half angle alpha with uniform radiance E / Omega; or a sky
    // of that radiance everywhere (Wand & Straßer's environment map, Fig. 6): through a
    // mirror this small each floor point sees the sky in one direction only, so both
    // give the same floor, the sky's everywhere under the mirror.
    let radiance: Vec<f64> = irradiance
        .iter()
        .map(|e| e / (std::f64::consts::TAU * (1.0 - alpha.cos())))
        .collect();
    let directional = serde_json::json!({"type": "directional", "direction": [1, 0, 0], "irradiance": irradiance});
    let sky = serde_json::json!({"type": "environment", "radiance": [1, 1, 1], "scale": radiance});
    for (light_kind, light) in [("directional", directional), ("environment", sky)] {
        let scene = flat_mirror_scene(light, side);
        let camera = scene.camera.clone();
        for filtering in ["off", "full"] {
            let (surface, measured) = run(
                scene.clone(),
                serde_json::json!({"samples": 1, "light_angle": alpha, "filtering": filtering}),
            );
            assert_eq!(measured.counter("samples"), 1);
            let mut want_image = surface.clone();
            let (mut checked, mut worst, mut at) = (0, 0.0f64, (0, 0, 0, 0.0));
            for j in 0..surface.height {
                for i in 0..surface.width {
                    let Some(x) = plane_hit(&camera, i, j, 0.0) else {
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
                    let want = [0, 1, 2].map(|c| {
                        albedo[c] / std::f64::consts::PI * reflectance[c] * radiance[c] * solid
                    });
                    for c in 0..3 {
                        let rel = (p[c] as f64 - want[c]).abs() / want[c];
                        if rel > worst {
                            (worst, at) = (rel, (i, j, c, want[c]));
                        }
                    }
                    want_image.set(i, j, want.map(|w| w as f32));
                    checked += 1;
                }
            }
            eprintln!(
                "flat mirror, {light_kind} light, filtering={filtering}: {checked} pixels, worst relative error {:.4}%",
                worst * 100.0
            );
            // 1 %: one sample of a flat mirror is a pinhole camera of exactly the mirror's
            // solid angle, so only the midpoint rule and float rounding separate the two
            // (measured on lavapipe: 0.43 %, with and without filtering).
            let (i, j, c, want) = at;
            artifacts!(&format!("flat_mirror_{light_kind}_filtering_{filtering}")).ensure(
            worst < 0.01,
            "surface",
            &surface,
            &want_image,
            || {
                format!(
                    "{light_kind} light, filtering={filtering} pixel ({i},{j}) channel {c}: {} vs analytic {want} ({:.3}%)",
                    surface.get(i, j)[c],
                    worst * 100.0
                )
            },
        );
            assert!(
                checked >= 12,
                "only {checked} pixels inside the light's image"
            );
        }
    }
}

#[test]
fn ring_has_consistent_counters_passes_and_heatmap() {
    let (surface, measured) = run(
        builtin("ring", 64, 48),
        serde_json::json!({"samples": 200, "samples_per_pass": 64}),
    );
    let lit = surface.pixels.iter().filter(|p| p[1] > 0.0).count();
    assert!(lit > 50, "only {lit} caustic pixels");
    let c = &measured.counters;
    caustics_testing::assert_counters_documented(
        &caustics_method::registry_entry::<pinhole::Pinhole>(),
        c,
    );
    assert_eq!(c["samples"], 200);
    assert_eq!(c["passes"], 4, "ceil(200 / 64)");
    // Every receiver fragment of every pass loops over its batch: pairs = pixels × N.
    let receivers = c["receiver_fragments"] / c["passes"];
    assert_eq!(c["receiver_fragments"] % c["passes"], 0);
    assert_eq!(c["sample_pixel_pairs"], receivers * 200);
    assert!(c["texture_fetches"] > 0 && receivers > 1000, "{c:?}");
    // Visibility is traced only for the pairs whose lookup lands on the light: a few
    // percent of the pairs on the ring (0.3% at 96x72 and 1,000 samples), never zero
    // where the caustic is lit.
    assert!(
        c["visibility_tests"] > 0 && c["visibility_tests"] * 10 < c["sample_pixel_pairs"],
        "{c:?}"
    );
    let names = measured.pass_names();
    for want in ["pinhole/prepare_samples", "pinhole/gather"] {
        assert!(names.contains(&want), "{want} missing from {names:?}");
    }
    // The heatmap counts one fragment per pixel and pass of the fullscreen gather.
    assert!(
        measured.fragment_invocations("pinhole/gather").is_some(),
        "pipeline statistics"
    );
    assert_eq!(measured.fill_total(), 64 * 48 * 4);
}

#[test]
fn filtering_changes_the_image_only_where_the_reflector_is_curved() {
    // Flat mirror, many samples: the curvature footprint is zero, so on == off exactly.
    let light =
        serde_json::json!({"type": "point", "position": [-1, 1, 0], "intensity": [5, 5, 5]});
    let flat = flat_mirror_scene(light, 0.5);
    let run_with = |scene: &caustics_scene::Scene, f: &str| {
        run(
            scene.clone(),
            serde_json::json!({"samples": 64, "filtering": f}),
        )
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
    let ring = builtin("ring", 64, 48);
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
    let scene = builtin("ring", 48, 36);
    for strategy in ["random", "grid", "quantized", "neighbor_removal"] {
        let go = |seed: u32| {
            run(
                scene.clone(),
                serde_json::json!({"sampling": strategy, "samples": 50, "seed": seed}),
            )
        };
        let (a, ra) = go(7);
        let (b, _) = go(7);
        let (c, _) = go(8);
        assert_eq!(ra.counter("samples"), 50, "{strategy}");
        assert_eq!(a.pixels, b.pixels, "{strategy}: not deterministic");
        assert_ne!(a.pixels, c.pixels, "{strategy}: the seed changes nothing");
    }
}

#[test]
fn refracting_sphere_focuses_light_under_it_close_to_the_cpu_reference() {
    let c = compare(
        &caustics_method::registry_entry::<pinhole::Pinhole>(),
        builtin("sphere_on_plane", 96, 72),
        serde_json::json!({"samples": 300}),
        &TEST_REFERENCE,
        4,
    );
    // The direct floor radiance is ρ/π·E·cos ≈ 0.25: the focus (sampled at the pixel
    // centres) is much brighter.
    let max = c.timed.pixels.iter().map(|p| p[1]).fold(0.0f32, f32::max);
    assert!(max > 1.0, "no focus under the glass sphere: max {max}");
    // Bounds a margin above lavapipe's figures at 96×72, 16 samples per pixel
    // (flux 0.969, relMSE after flux 1.5e-3 (one pixel off: 1.0e-2), HDR-FLIP after flux 0.394):
    // the method (like its paper) does not follow the light the glass sphere reflects (off
    // its surface, and inside it), which the reference spreads as a dim halo around the
    // focus (see the -expected image of a failure): that light is short in the flux and
    // sets most of HDR-FLIP, whose brighter exposures show the halo (static-grid, which
    // follows the reflection, scores 0.15 here).
    // No flux above 1.02: light the method does not model cannot be there. The relMSE
    // bound is about twice the figure and refuses the image moved by one pixel.
    // 300 point samples on the sphere (the paper's defaults take 1000) leave sampling
    // noise in the shape, hence the larger relMSE bound.
    c.check(
        &artifacts!(),
        &Bounds {
            flux: 0.85..1.02,
            rel_mse_after_flux: 3e-3,
            hdr_flip_after_flux: 0.45,
        },
    );
}

#[test]
fn bad_parameters_are_clear_errors() {
    // (The harness's cli test checks that a refused parameter writes nothing.)
    for (param, needle) in [
        (
            serde_json::json!({"sampling": "hexagonal"}),
            "sampling: expected one of",
        ),
        (serde_json::json!({"samples": 0}), "samples"),
        (
            serde_json::json!({"filtering": "maybe"}),
            "filtering: expected one of",
        ),
        (serde_json::json!({"cube_size": 100}), "cube_size"),
        (serde_json::json!({"light_size": 1}), "known parameters"),
    ] {
        let e = (caustics_method::registry_entry::<pinhole::Pinhole>().parse)(&param)
            .expect_err(&param.to_string());
        let msg = e.to_string();
        assert!(
            msg.contains(needle) && msg.contains("pinhole"),
            "{param}: {msg}"
        );
    }
}

/// One sample of a small flat water patch (n = 1.33) one metre above the floor, under
/// a directional light straight down of angular radius alpha: the paper's single
/// refraction (§5, "underwater scenes"). Below the patch, the irradiance is
/// ∫ (1 - F) η² L cos θ_s cos θ_x / d² dA over the patch: the light's radiance L, the
/// Fresnel transmittance at the water-side angle, and η², by which radiance grows
/// when light enters the denser medium (flux does not: the solid angle shrinks by as
/// much).
#[test]
fn one_sample_on_a_flat_water_patch_gives_the_analytic_refracted_irradiance() {
    let (irradiance, albedo, ior, alpha, side) = (2.0f64, 0.8f64, 1.33f64, 0.2f64, 0.004f64);
    let scene = scene(&serde_json::json!({
        "name": "flat_water_patch",
        "description": "a small flat water patch over a floor: pinhole's single-refraction check",
        "camera": {"eye": [0, 0.9, 1.2], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 30, "width": 64, "height": 48},
        "lights": [{"type": "directional", "direction": [0, -1, 0], "irradiance": [irradiance, irradiance, irradiance]}],
        "materials": {
            "water": {"type": "dielectric", "ior": ior},
            "floor": {"type": "diffuse", "albedo": [albedo, albedo, albedo]}
        },
        "objects": [
            {"shape": {"type": "quad", "center": [0, 1, 0], "normal": [0, 1, 0], "size": [side, side]}, "material": "water"},
            {"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [4, 4]}, "material": "floor"}
        ]
    }));
    let camera = scene.camera.clone();
    let radiance = irradiance / (std::f64::consts::TAU * (1.0 - alpha.cos()));
    let (surface, measured) = run(
        scene,
        serde_json::json!({"samples": 1, "light_angle": alpha, "filtering": "off"}),
    );
    assert_eq!(measured.counter("samples"), 1);
    let mut want_image = surface.clone();
    let (mut checked, mut worst, mut at) = (0, 0.0f64, (0, 0, 0.0));
    for j in 0..surface.height {
        for i in 0..surface.width {
            let Some(x) = plane_hit(&camera, i, j, 0.0) else {
                continue;
            };
            // Well inside the light's image through the water (radius tan(asin(sin α / η))
            // ≈ 0.15 m at 1 m).
            if x.length() > 0.1 {
                continue;
            }
            let m = 20;
            let mut sum = 0.0f64;
            for a in 0..m {
                for b in 0..m {
                    let s = ((a as f64 + 0.5) / m as f64 - 0.5) * side;
                    let t = ((b as f64 + 0.5) / m as f64 - 0.5) * side;
                    let to = [s - x.x as f64, 1.0 - x.y as f64, t - x.z as f64];
                    let d2 = to[0] * to[0] + to[1] * to[1] + to[2] * to[2];
                    // Both cosines are the vertical component (patch and floor are level).
                    let cos = to[1] / d2.sqrt();
                    let transmit = 1.0 - caustics_testing::fresnel_reflectance(cos, ior);
                    sum += transmit * ior * ior * cos * cos / d2 * (side * side) / (m * m) as f64;
                }
            }
            let want = albedo / std::f64::consts::PI * radiance * sum;
            let got = surface.get(i, j)[1] as f64;
            let rel = (got - want).abs() / want;
            if rel > worst {
                (worst, at) = (rel, (i, j, want));
            }
            want_image.set(i, j, [want as f32; 3]);
            checked += 1;
        }
    }
    eprintln!(
        "flat water patch: {checked} pixels, worst relative error {:.4}%",
        worst * 100.0
    );
    // 1 %, as the flat mirror's: one sample of a flat patch is exact up to the midpoint
    // rule and rounding.
    let (i, j, want) = at;
    artifacts!().ensure(worst < 0.01, "surface", &surface, &want_image, || {
        format!(
            "pixel ({i},{j}): {} vs analytic {want} ({:.3}%)",
            surface.get(i, j)[1],
            worst * 100.0
        )
    });
    assert!(checked >= 12, "only {checked} pixels under the patch");
}

/// water_pool, the paper's "underwater scene": one refraction at the wavy heightfield
/// (256² vertices, 131,072 triangles, sampled on its triangles, curvature from their
/// vertex normals), visibility traced through the scene's BVH, against the reference.
#[test]
fn water_pool_is_close_to_the_cpu_reference() {
    let c = compare(
        &caustics_method::registry_entry::<pinhole::Pinhole>(),
        builtin("water_pool", 64, 48),
        serde_json::json!({}),
        &TEST_REFERENCE,
        2,
    );
    eprintln!("counters: {:?}", c.measured.counters);
    // Lavapipe, 64×48, 4 samples per pixel, the paper's 1000 samples: flux 0.959,
    // relMSE after flux 0.106 (one pixel off: 0.278), HDR-FLIP after flux 0.176. The
    // samples are ~13 cm apart on the 4 × 4 m surface, a fraction of the waves' 0.45 to
    // 1.4 m, so the filtered images blur the network's thin lines (the relMSE) but keep
    // its light. Bounds: 0.90..1.02, relMSE 1.5×, HDR-FLIP +25 %.
    c.check(
        &artifacts!(),
        &Bounds {
            flux: 0.90..1.02,
            rel_mse_after_flux: 0.16,
            hdr_flip_after_flux: 0.22,
        },
    );
}

/// The glass cushion's mesh (4,800 triangles, smooth normals) made a mirror under a
/// point light: a triangle-mesh mirror, sampled on its triangles, against the
/// reference.
#[test]
fn mirror_mesh_under_a_point_light_is_close_to_the_cpu_reference() {
    let mut json = caustics_testing::builtin_json("glass_cushion", 64, 48);
    json["name"] = "mirror_cushion".into();
    json["materials"]["glass"] =
        serde_json::json!({"type": "mirror", "reflectance": [0.9, 0.9, 0.9]});
    json["lights"] = serde_json::json!([{"type": "point", "position": [-1.5, 3.5, 1.0], "intensity": [8, 8, 8]}]);
    let c = compare(
        &caustics_method::registry_entry::<pinhole::Pinhole>(),
        scene(&json),
        serde_json::json!({}),
        &TEST_REFERENCE,
        2,
    );
    eprintln!("counters: {:?}", c.measured.counters);
    // Lavapipe, 64×48, 4 samples per pixel: flux 1.000, relMSE after flux 2.6e-4 (one
    // pixel off: 5.8e-4), HDR-FLIP after flux 0.157 (the light's disc, 0.016 rad, blurs
    // the rounded edges' sharp lines a little). Bounds: 0.95..1.05, relMSE 1.5×,
    // HDR-FLIP +25 %.
    c.check(
        &artifacts!(),
        &Bounds {
            flux: 0.95..1.05,
            rel_mse_after_flux: 4e-4,
            hdr_flip_after_flux: 0.20,
        },
    );
}

/// The glass sphere with `reflections`: each sample is also a mirror of Fresnel
/// reflectance, so the dim halo of light the ball reflects (which the paper's path
/// leaves out, and which sets most of the default's HDR-FLIP) is there. Lavapipe,
/// 96×72, 16 spp, 300 samples: paper flux 0.969, HDR-FLIP after flux 0.394; with
/// reflections flux 1.002, relMSE after flux 1.2e-3 (one pixel off: 8.9e-3), HDR-FLIP
/// after flux 0.170. Bounds a margin around the extended figures.
#[test]
fn fresnel_reflection_adds_the_glass_spheres_halo() {
    let info = caustics_method::registry_entry::<pinhole::Pinhole>();
    let run = |reflections: bool| {
        compare(
            &info,
            builtin("sphere_on_plane", 96, 72),
            serde_json::json!({"samples": 300, "reflections": reflections}),
            &TEST_REFERENCE,
            4,
        )
    };
    let (paper, extended) = (run(false), run(true));
    eprintln!(
        "paper: flux {:.4}, HDR-FLIP after flux {:.4}; reflections: flux {:.4}, HDR-FLIP after flux {:.4}",
        paper.flux(),
        paper.hdr_flip(),
        extended.flux(),
        extended.hdr_flip()
    );
    assert!(
        extended.flux() > paper.flux() && extended.hdr_flip() < 0.8 * paper.hdr_flip(),
        "reflections did not add the halo: flux {} -> {}, HDR-FLIP {} -> {}",
        paper.flux(),
        extended.flux(),
        paper.hdr_flip(),
        extended.hdr_flip()
    );
    extended.check(
        &artifacts!(),
        &Bounds {
            flux: 0.95..1.05,
            rel_mse_after_flux: 2e-3,
            hdr_flip_after_flux: 0.21,
        },
    );
}

/// Pinhole's gather is all camera-side: the scoring frame with the light side reused
/// (samples prepared once) is pixel for pixel the image of whole sub-frames.
#[test]
fn scoring_with_the_light_side_reused_is_exact() {
    let gpu = Gpu::new(builtin("ring", 48, 36));
    let mut method = gpu.method(
        &caustics_method::registry_entry::<pinhole::Pinhole>(),
        serde_json::json!({"samples": 100, "cube_size": 64}),
    );
    let scored = gpu.assert_light_side_reuse_is_exact(method.as_mut(), 2);
    assert!(
        scored.surface.sum_luminance() > 0.0,
        "a black caustic proves nothing"
    );
}

/// sphere_on_plane's ball under a sphere light of radius `r` (or the point light of the
/// same far-field intensity π r² L).
fn ball_under(light: serde_json::Value, width: u32, height: u32) -> caustics_scene::Scene {
    let mut json = caustics_testing::builtin_json("sphere_on_plane", width, height);
    json["lights"] = serde_json::json!([light]);
    scene(&json)
}

/// Wand & Straßer §5: "extended light sources at no additional costs". A sphere light is
/// the disc of its radius in the light map, so pinhole with it draws exactly what it
/// draws for the point light of the same intensity whose disc (`light_angle`) is that
/// wide; and its blurred caustic matches the CPU reference's sphere light.
#[test]
fn a_sphere_light_is_the_disc_of_its_radius() {
    let (position, r, radiance) = (Vec3::new(0.6, 5.5, 0.3), 0.25f32, 300.0f32);
    let sphere = serde_json::json!({"type": "sphere", "position": position.to_array(), "radius": r, "radiance": [radiance, radiance, radiance]});
    let intensity = std::f32::consts::PI * r * r * radiance;
    let point = serde_json::json!({"type": "point", "position": position.to_array(), "intensity": [intensity, intensity, intensity]});
    let d = position.distance(Vec3::new(0.0, 1.5, 0.0));
    let params = serde_json::json!({"samples": 300, "reflections": true});
    let (from_sphere, _) = run(ball_under(sphere.clone(), 64, 48), params.clone());
    let mut disc_params = params.clone();
    disc_params["light_angle"] = f64::from((r / d).atan()).into();
    let (from_point, _) = run(ball_under(point, 64, 48), disc_params);
    let (mut diff, mut total) = (0.0f64, 0.0f64);
    for (a, b) in from_sphere.pixels.iter().zip(&from_point.pixels) {
        diff += f64::from((a[1] - b[1]).abs());
        total += f64::from(a[1]);
    }
    assert!(total > 0.0, "no caustic");
    assert!(
        diff / total < 1e-3,
        "sphere light vs its disc: {}",
        diff / total
    );

    let c = compare(
        &caustics_method::registry_entry::<pinhole::Pinhole>(),
        ball_under(sphere, 96, 72),
        params,
        &TEST_REFERENCE,
        4,
    );
    // Bounds a margin above lavapipe's figures at 96×72, 16 samples per pixel (flux
    // 0.913, relMSE after flux 5.4e-3 (one pixel off: 4.9e-2), HDR-FLIP after flux
    // 0.219): the light missing is the paper's (internal reflections), and 300 samples
    // leave sampling noise in the shape, hence a relMSE bound about twice the figure
    // that still refuses the image moved by one pixel.
    c.check(
        &artifacts!(),
        &Bounds {
            flux: 0.88..1.02,
            rel_mse_after_flux: 1e-2,
            hdr_flip_after_flux: 0.3,
        },
    );
}

/// Wand & Straßer's Fig. 6 setting (bench/experiments/wand-fig6.json): the mirror ring
/// under an environment map, a sky with a 3° sun (scenes/extended/ring_under_sky.json),
/// against the CPU reference, which samples the map exactly.
#[test]
fn the_ring_under_an_environment_map_is_close_to_the_cpu_reference() {
    let path = caustics_scene::builtin_dir().join("extended/ring_under_sky.json");
    let mut sky = caustics_scene::Scene::load(&path).expect("scenes/extended/ring_under_sky.json");
    (sky.camera.width, sky.camera.height) = (96, 72);
    let c = compare(
        &caustics_method::registry_entry::<pinhole::Pinhole>(),
        sky,
        serde_json::json!({"samples": 1000}),
        &TEST_REFERENCE,
        4,
    );
    // Bounds a margin above lavapipe's figures at 96×72, 16 samples per pixel (flux
    // 0.884, relMSE after flux 8.1e-3 (one pixel off: 9.9e-2), HDR-FLIP after flux
    // 0.166). The light missing is the paper's one bounce (§5: "only one specular
    // bounce can be handled"): the sky reflected twice inside the ring.
    c.check(
        &artifacts!(),
        &Bounds {
            flux: 0.85..1.02,
            rel_mse_after_flux: 1.6e-2,
            hdr_flip_after_flux: 0.25,
        },
    );
}

/// Several lights: the ball under two suns renders the sum of the ball under each sun
/// alone (one light map and one prepare/gather pair per light), counters summed.
#[test]
fn pinhole_lights_add_up() {
    caustics_testing::lights::lights_add_up(
        &caustics_method::registry_entry::<pinhole::Pinhole>(),
        serde_json::json!({"samples": 200, "cube_size": 64}),
        &[
            "passes",
            "sample_pixel_pairs",
            "visibility_tests",
            "texture_fetches",
        ],
    );
}

/// A sun and a sky in one scene take both specializations of the passes (one
/// prepare/gather pair for the environment, one for the other lights): the ball under
/// both renders the sum of the ball under each alone, counters summed.
#[test]
fn a_sun_and_a_sky_add_up() {
    use caustics_testing::lights::{TWO_SUNS, adds_up, balls_under};
    let sun = serde_json::json!({"type": "directional", "direction": TWO_SUNS[0], "irradiance": [1, 1, 1]});
    let sky = serde_json::json!({"type": "environment", "path": "extended/sky_with_sun.exr"});
    adds_up(
        &caustics_method::registry_entry::<pinhole::Pinhole>(),
        &serde_json::json!({"samples": 200, "cube_size": 64}),
        "a sun and a sky",
        balls_under(&[0.0], &[sun.clone(), sky.clone()]),
        [balls_under(&[0.0], &[sun]), balls_under(&[0.0], &[sky])],
        &[
            "passes",
            "sample_pixel_pairs",
            "visibility_tests",
            "texture_fetches",
        ],
    );
}
