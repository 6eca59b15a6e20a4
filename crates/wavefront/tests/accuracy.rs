//! `wavefront` (Wallace 2016) on the GPU, on whatever adapter the machine has (lavapipe
//! on CI; without an adapter these fail with the install hint, never skip): the analytic
//! radiance under flat water and a flat mirror, the CPU reference on a refracting
//! sphere (default and with its reflections as further sheets), a glass mesh, chains (two
//! lenses; a ball over wavy water), a mirror tube's second reflections, a bumpy glass
//! ball's torn triangles drawn as points (`splat_orphans`), and the counters, passes and
//! fill counts of a water pool.

use caustics_testing::{
    Bounds, Gpu, HdrImage, Measured, TEST_REFERENCE, artifacts, builtin, compare,
    refracting_sphere, refracting_sphere_with, scene,
};

fn nonzero_pixels(img: &HdrImage) -> usize {
    img.pixels
        .iter()
        .filter(|p| p.iter().any(|&c| c > 0.0))
        .count()
}

#[test]
fn water_pool_gives_a_finite_nonempty_caustic_with_consistent_counts_passes_and_fill() {
    let gpu = Gpu::new(builtin("water_pool", 320, 240));
    let mut method = gpu.method(
        &caustics_method::registry_entry::<wavefront::Wavefront>(),
        serde_json::json!({}),
    );
    let measured = gpu.measure(method.as_mut(), 1, 3);
    let surface = gpu.surface();
    let lit = nonzero_pixels(&surface);
    assert!(
        lit > surface.pixels.len() / 4,
        "only {lit} caustic pixels of {}",
        surface.pixels.len()
    );
    assert!(surface.sum_luminance() > 0.0);
    assert!(
        measured.counter("kept_triangles") > 0,
        "{:?}",
        measured.counters
    );
    assert_eq!(
        measured.counter("triangles"),
        255 * 255 * 2,
        "the 256² water grid"
    );
    caustics_testing::assert_counters_documented(
        &caustics_method::registry_entry::<wavefront::Wavefront>(),
        &measured.counters,
    );

    // Timestamps: lavapipe has them, so every pass of every measured frame has a time,
    // none rejected.
    assert!(measured.timestamps, "adapter without timestamp queries");
    assert_eq!(measured.frames.len(), 3);
    for f in &measured.frames {
        assert_eq!(f.rejected_timestamps, 0);
        for p in &f.passes {
            assert!(p.gpu_ms.is_some(), "no time for {}", p.name);
        }
    }
    let names = measured.pass_names();
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
    let (stats, fill) = splat_statistics_vs_heatmap(&measured);
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
/// large (flat-water scene: a 9² grid over 12 m seen from 0.9 m, triangles of tens of
/// thousands of pixels at 320x240). Measured on lavapipe (Mesa 22.3.6, llvmpipe 4x4
/// blocks): 0.0845 (83888 invocations for 76800 fragments); 2x2-quad hardware sees less.
const LARGE_TRIANGLE_HELPER_MARGIN: f64 = 0.10;

/// (pipeline-statistics fragment invocations of `wavefront/splat`, heatmap sum),
/// with heatmap <= statistics checked.
fn splat_statistics_vs_heatmap(measured: &Measured) -> (f64, f64) {
    let stats = measured
        .fragment_invocations("wavefront/splat")
        .expect("pipeline statistics of the splat pass on this adapter") as f64;
    let fill = measured.fill_total() as f64;
    assert!(fill > 0.0, "empty heatmap");
    assert!(
        stats >= fill,
        "statistics {stats} < heatmap {fill}: the counter saw fragments the GPU did not shade"
    );
    (stats, fill)
}

/// Checks every pixel of the central half of `surface` against `expected(channel)`
/// within `bound` (relative), writing the images on failure.
fn central_half_matches(surface: &HdrImage, expected: [f64; 3], bound: f64, what: &str) -> usize {
    let (w, h) = (surface.width, surface.height);
    let mut want = surface.clone();
    let (mut worst, mut at, mut checked) = (0.0f64, (0, 0, 0), 0);
    for y in h / 4..3 * h / 4 {
        for x in w / 4..3 * w / 4 {
            let p = surface.get(x, y);
            for c in 0..3 {
                let rel = (p[c] as f64 - expected[c]).abs() / expected[c];
                if rel > worst {
                    (worst, at) = (rel, (x, y, c));
                }
            }
            want.set(x, y, expected.map(|v| v as f32));
            checked += 1;
        }
    }
    let (x, y, c) = at;
    eprintln!(
        "{what}: {checked} pixels, worst relative error {:.4}%",
        worst * 100.0
    );
    artifacts!(what).ensure(worst < bound, "surface", surface, &want, || {
        format!(
            "{what}: pixel ({x},{y}) channel {c}: {} vs analytic {} ({:.3}%)",
            surface.get(x, y)[c],
            expected[c],
            worst * 100.0
        )
    });
    checked
}

#[test]
fn flat_water_gives_the_analytic_floor_radiance_within_one_percent() {
    let dir_vec = [0.5f64, -1.0, 0.3];
    let len = dir_vec.iter().map(|v| v * v).sum::<f64>().sqrt();
    let cos_theta = 1.0 / len;
    let (ior, albedo, irradiance) = (1.33f64, [0.8f64, 0.6, 0.4], [1.0f64, 2.0, 0.5]);
    let scene = scene(&serde_json::json!({
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
    }));
    let gpu = Gpu::new(scene);
    let mut method = gpu.method(
        &caustics_method::registry_entry::<wavefront::Wavefront>(),
        serde_json::json!({}),
    );
    let measured = gpu.measure(method.as_mut(), 0, 1);
    let surface = gpu.surface();

    let (stats, fill) = splat_statistics_vs_heatmap(&measured);
    let margin = (stats - fill) / stats;
    eprintln!("flat water: splat statistics {stats}, heatmap {fill}, helper margin {margin:.4}");
    assert!(
        margin <= LARGE_TRIANGLE_HELPER_MARGIN,
        "statistics {stats} vs heatmap {fill}: margin {margin:.4}"
    );

    // ρ/π · T(θ) · E · cos θ: a parallel beam through a flat interface onto a parallel
    // floor keeps its footprint. Every pixel of the central half sees the floor under
    // the flat water. 1 %: the method is exact here up to float rounding of the area
    // ratio (measured on lavapipe: 0.0026 %).
    let t = 1.0 - caustics_testing::fresnel_reflectance(cos_theta, 1.0 / ior);
    let expected =
        [0, 1, 2].map(|c| albedo[c] / std::f64::consts::PI * t * irradiance[c] * cos_theta);
    let (w, h) = (surface.width, surface.height);
    let checked = central_half_matches(&surface, expected, 0.01, "flat_water");
    assert_eq!(checked, (w / 2 * h / 2) as usize);
}

#[test]
fn flat_mirror_gives_the_analytic_reflected_radiance_within_one_percent() {
    let (reflectance, albedo, irradiance) =
        ([0.9f64, 0.7, 0.5], [0.8f64, 0.6, 0.4], [1.0f64, 2.0, 0.5]);
    // A vertical mirror (normal +x) under light travelling along (-1, -1, 0): the
    // reflected beam travels along (1, -1, 0) and meets the floor at 45 degrees.
    let scene = scene(&serde_json::json!({
        "name": "flat_mirror",
        "description": "a vertical mirror reflecting a directional light onto a floor",
        "camera": {"eye": [1, 2, 0], "target": [1, 0, 0], "up": [0, 0, -1], "fov_y_deg": 40, "width": 160, "height": 120},
        "lights": [{"type": "directional", "direction": [-1, -1, 0], "irradiance": irradiance}],
        "materials": {"mirror": {"type": "mirror", "reflectance": reflectance}, "floor": {"type": "diffuse", "albedo": albedo}},
        "objects": [
            {"shape": {"type": "quad", "center": [0, 1.5, 0], "normal": [1, 0, 0], "size": [3, 6]}, "material": "mirror"},
            {"shape": {"type": "quad", "center": [2, 0, 0], "normal": [0, 1, 0], "size": [4, 6]}, "material": "floor"}
        ]
    }));
    let gpu = Gpu::new(scene);
    let mut method = gpu.method(
        &caustics_method::registry_entry::<wavefront::Wavefront>(),
        serde_json::json!({"grid": 64}),
    );
    let measured = gpu.measure(method.as_mut(), 0, 1);
    assert_eq!(measured.counter("dropped_path_mismatch"), 0);
    // ρ/π · R · E · cos 45°; 1 %, the method being exact on a flat mirror as on flat
    // water (measured on lavapipe: 0.0010 %).
    let cos_floor = std::f64::consts::FRAC_1_SQRT_2;
    let expected = [0, 1, 2]
        .map(|c| albedo[c] / std::f64::consts::PI * reflectance[c] * irradiance[c] * cos_floor);
    central_half_matches(&gpu.surface(), expected, 0.01, "flat_mirror");
}

#[test]
fn refracting_sphere_is_close_to_the_cpu_reference() {
    let c = refracting_sphere(&caustics_method::registry_entry::<wavefront::Wavefront>());
    // Bounds a margin above lavapipe's figures at 96×72, 16 samples per pixel
    // (flux 0.910, relMSE after flux 2.2e-4 (one pixel off: 6.5e-3), HDR-FLIP after flux 0.417):
    // the light the glass sphere reflects, which the method (like its paper) does not
    // follow, is short in the flux and sets most of HDR-FLIP; no flux above 1.02; relMSE
    // about twice the figure, refusing the image moved by one pixel (the whole why:
    // `caustics_testing::refracting_sphere`).
    c.check(
        &artifacts!(),
        &Bounds {
            flux: 0.85..1.02,
            rel_mse_after_flux: 5e-4,
            hdr_flip_after_flux: 0.47,
        },
    );
}

fn wavefront_info() -> caustics_method::MethodInfo {
    caustics_method::registry_entry::<wavefront::Wavefront>()
}

/// The light the glass sphere reflects, off its outside (`reflections`) and inside it
/// (`bounces`), as further sheets of the wavefront: the halo the default path misses.
#[test]
fn refracting_sphere_with_its_reflections_is_close_to_the_cpu_reference() {
    let c = refracting_sphere_with(
        &wavefront_info(),
        serde_json::json!({"bounces": 2, "reflections": true}),
    );
    assert_eq!(c.measured.counter("sheets"), 4, "{:?}", c.measured.counters);
    // Lavapipe, 96×72, 16 spp: flux 0.947, relMSE after flux 3.7e-5 (one pixel off:
    // 5.5e-3), HDR-FLIP after flux 0.069, against 0.910 and 0.417 on the default path
    // (`refracting_sphere_is_close_to_the_cpu_reference`): the halo is there. The flux
    // bound sits above the default's figure; no more than 1.02 (the sheets partition
    // the light, none counted twice); relMSE and HDR-FLIP about 1.5-3x the figures.
    c.check(
        &artifacts!(),
        &Bounds {
            flux: 0.93..1.02,
            rel_mse_after_flux: 1e-4,
            hdr_flip_after_flux: 0.10,
        },
    );
}

/// A triangle-mesh glass object (the cushion's smooth-normal OBJ) traced through the
/// scene BVH, with the adjoint shading-normal factor, against the reference.
#[test]
fn glass_mesh_is_close_to_the_cpu_reference() {
    let c = compare(
        &wavefront_info(),
        builtin("glass_cushion", 96, 72),
        serde_json::json!({"bounces": 2, "reflections": true}),
        &TEST_REFERENCE,
        4,
    );
    assert!(c.measured.counter("bvh_triangles") > 1000);
    // Lavapipe, 96×72, 16 spp: flux 0.941, relMSE after flux 7.4e-4 (one pixel off:
    // 1.9e-2), HDR-FLIP after flux 0.220. What is short is light that leaves after more
    // than two internal reflections or in sheets torn by the facets (a triangle needs
    // its three vertices on one path). Bounds: 0.90..1.02, about twice relMSE, HDR-FLIP
    // +25 %.
    c.check(
        &artifacts!(),
        &Bounds {
            flux: 0.90..1.02,
            rel_mse_after_flux: 1.5e-3,
            hdr_flip_after_flux: 0.27,
        },
    );
}

/// Two glass spheres under a spot light: each sphere's wavefront passes through the
/// other where their light meets it (a chain), and neither counts the other's light.
#[test]
fn chain_of_two_lenses_is_close_to_the_cpu_reference() {
    let c = compare(
        &wavefront_info(),
        builtin("two_lenses", 96, 72),
        serde_json::json!({"reflections": true}),
        &TEST_REFERENCE,
        4,
    );
    assert_eq!(c.measured.counter("sheets"), 4);
    assert!(c.measured.counter("vertices_missed_generator") > 0);
    // Lavapipe, 96×72, 16 spp: flux 0.986, relMSE after flux 5.0e-5 (one pixel off:
    // 2.5e-3), HDR-FLIP after flux 0.069. A sphere counting the other's light would put
    // the flux well above 1; bounds 0.95..1.02, twice relMSE, HDR-FLIP +30 %.
    c.check(
        &artifacts!(),
        &Bounds {
            flux: 0.95..1.02,
            rel_mse_after_flux: 1e-4,
            hdr_flip_after_flux: 0.09,
        },
    );
}

/// A glass ball over wavy water: the ball's wavefront refracts through the ball, then
/// through the water surface (a heightfield, traced through the scene BVH) to the pool
/// floor, beside the water's own wavefront: a caustic of a caustic.
#[test]
fn ball_over_water_chain_is_close_to_the_cpu_reference() {
    let c = compare(
        &wavefront_info(),
        builtin("sphere_over_water", 96, 72),
        serde_json::json!({}),
        &TEST_REFERENCE,
        4,
    );
    assert_eq!(c.measured.counter("sheets"), 2);
    // More vertices land than the 256² water grid has: the ball's rays reach the floor
    // through the water.
    assert!(
        c.measured.counter("vertices_landed") > 256 * 256,
        "{:?}",
        c.measured.counters
    );
    // Lavapipe, 96×72, 16 spp: flux 0.994, relMSE after flux 2.6e-2 (one pixel off:
    // 0.26; the reference's own noise, 6.6 % mean relative standard error, sets most of
    // it), HDR-FLIP after flux 0.080. Bounds: 0.95..1.03 (the ball's light is ~5 % of
    // the pool's), twice relMSE, HDR-FLIP +25 %.
    c.check(
        &artifacts!(),
        &Bounds {
            flux: 0.95..1.03,
            rel_mse_after_flux: 5e-2,
            hdr_flip_after_flux: 0.10,
        },
    );
}

/// A tall mirror tube under a point light above its rim: light entering the top
/// reflects off the inner wall and often meets the opposite wall again, which the
/// default path drops (Wallace's one event) and `bounces` follows.
#[test]
fn mirror_tube_rehits_are_followed_with_bounces() {
    let tube = scene(&serde_json::json!({
        "name": "mirror_tube",
        "description": "a tall open mirror cylinder on a floor, a point light above its rim",
        "camera": {"eye": [0, 4.5, 0.6], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 30, "width": 96, "height": 72},
        "lights": [{"type": "point", "position": [0.3, 2.6, 0], "intensity": [10, 10, 10]}],
        "materials": {"chrome": {"type": "mirror", "reflectance": [0.9, 0.9, 0.9]}, "floor": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}},
        "objects": [
            {"shape": {"type": "cylinder", "center": [0, 1, 0], "axis": [0, 1, 0], "radius": 0.5, "height": 2}, "material": "chrome"},
            {"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [4, 4]}, "material": "floor"}
        ]
    }));
    let once = compare(
        &wavefront_info(),
        tube.clone(),
        serde_json::json!({}),
        &TEST_REFERENCE,
        4,
    );
    let more = compare(
        &wavefront_info(),
        tube,
        serde_json::json!({"bounces": 4}),
        &TEST_REFERENCE,
        4,
    );
    assert!(once.measured.counter("vertices_rehit") > 0);
    assert_eq!(once.measured.counter("vertices_landed_after_rehit"), 0);
    assert!(more.measured.counter("vertices_landed_after_rehit") > 0);
    let (f1, f2) = (
        once.errors.flux_ratio.unwrap_or(f64::NAN),
        more.errors.flux_ratio.unwrap_or(f64::NAN),
    );
    eprintln!("tube flux: default {f1:.4}, bounces=4 {f2:.4}");
    // Lavapipe, 96×72: the default path delivers 0.515 of the reference's flux,
    // bounces=4 0.982 (relMSE after flux 1.1e-2, one pixel off 0.20; HDR-FLIP after
    // flux 0.012). Bounds: the default below 0.7, bounces 0.95..1.02, twice relMSE,
    // HDR-FLIP 0.03.
    assert!(f1 < 0.7 && f2 > f1, "default {f1}, bounces=4 {f2}");
    more.check(
        &artifacts!(),
        &Bounds {
            flux: 0.95..1.02,
            rel_mse_after_flux: 2.2e-2,
            hdr_flip_after_flux: 0.03,
        },
    );
}

/// A glass ball with high-frequency bumps: its total internal reflections speckle the
/// wavefront, and Wallace's rule drops every triangle whose vertices part (one on
/// another sheet, or on another path). `splat_orphans` draws the landed vertices of
/// those triangles as one-pixel points of a third of the triangle's flux each.
#[test]
fn bumpy_glass_orphans_bring_back_the_torn_light() {
    let paths = serde_json::json!({"bounces": 2, "reflections": true});
    let mut with_orphans = paths.clone();
    with_orphans["splat_orphans"] = true.into();
    let torn = compare(
        &wavefront_info(),
        builtin("bumpy_glass", 96, 72),
        paths,
        &TEST_REFERENCE,
        4,
    );
    let whole = compare(
        &wavefront_info(),
        builtin("bumpy_glass", 96, 72),
        with_orphans.clone(),
        &TEST_REFERENCE,
        4,
    );
    // The same triangles are dropped either way; only the orphans pass differs.
    assert!(!torn.measured.counters.contains_key("orphan_corners"));
    assert_eq!(
        whole.measured.counter("dropped_invalid_vertex"),
        torn.measured.counter("dropped_invalid_vertex")
    );
    assert!(whole.measured.counter("orphan_corners") > 10_000);
    assert!(
        !torn
            .measured
            .pass_names()
            .contains(&"wavefront/orphan_points")
    );
    assert!(
        whole
            .measured
            .pass_names()
            .contains(&"wavefront/orphan_points")
    );
    // classify.wgsl's draw lists: the splat issues three vertices per kept triangle and
    // the orphans one point per landed corner of a dropped triangle, nothing else (the
    // image is that of drawing every triangle and dropping the rest, in the same order:
    // `the_compute_splat_matches_the_hardware_splat_and_repeats_itself` checks the
    // list's splat against the compute path, which reads the per-triangle verdicts).
    for run in [&torn, &whole] {
        assert_eq!(
            run.measured.vertex_invocations("wavefront/splat"),
            Some(3 * run.measured.counter("kept_triangles")),
            "{:?}",
            run.measured.counters
        );
    }
    assert_eq!(
        whole.measured.vertex_invocations("wavefront/orphan_points"),
        Some(whole.measured.counter("orphan_corners"))
    );
    let (f1, f2) = (torn.flux(), whole.flux());
    eprintln!(
        "bumpy glass: torn flux {f1:.4}, relMSE after flux {:.3e}, HDR-FLIP after flux {:.4}; with orphans flux {f2:.4}",
        torn.errors.rel_mse_after_flux.unwrap_or(f64::NAN),
        torn.hdr_flip()
    );
    // Lavapipe, 96×72, 16 spp: without orphans flux 0.694 (relMSE after flux 7.6e-4,
    // HDR-FLIP after flux 0.363), with them 0.933 (relMSE after flux 3.8e-4, one pixel
    // off 3.3e-3; HDR-FLIP after flux 0.360): the light the torn triangles carried, in
    // the right place (HDR-FLIP, set by the speckle's dots and the reference's noise,
    // hardly moves). What is still short leaves after more than two internal
    // reflections. Bounds: torn below 0.8, whole 0.90..1.02 (no light twice: the
    // points take a third of a triangle per corner, in the sheet the corner landed
    // in), twice relMSE, HDR-FLIP +15 %.
    assert!(f1 < 0.8, "without orphans {f1}");
    whole.check(
        &artifacts!(),
        &Bounds {
            flux: 0.90..1.02,
            rel_mse_after_flux: 8e-4,
            hdr_flip_after_flux: 0.42,
        },
    );

    // `orphan_kernel_px` spreads each point over a Gaussian of that many pixels (sigma),
    // normalised over the square of pixels it covers: the same points, the same flux
    // (the receiver is flat around the caustic), fewer lone bright pixels.
    let mut spread = with_orphans.clone();
    spread["orphan_kernel_px"] = 1.5.into();
    let spread = compare(
        &wavefront_info(),
        builtin("bumpy_glass", 96, 72),
        spread,
        &TEST_REFERENCE,
        4,
    );
    assert_eq!(
        spread.measured.counter("orphan_corners"),
        whole.measured.counter("orphan_corners")
    );
    // Six vertices per point: the two triangles of its kernel's quad.
    assert_eq!(
        spread
            .measured
            .vertex_invocations("wavefront/orphan_points"),
        Some(6 * whole.measured.counter("orphan_corners"))
    );
    let f3 = spread.flux();
    eprintln!(
        "bumpy glass, orphans spread (sigma 1.5 px): flux {f3:.4}, relMSE {:.3e} (points {:.3e}), HDR-FLIP {:.4} (points {:.4})",
        spread.errors.rel_mse,
        whole.errors.rel_mse,
        spread.hdr_flip(),
        whole.hdr_flip()
    );
    // Lavapipe, 96×72, 16 spp: flux 0.9309 against 0.9330 as points, relMSE 2.75e-4
    // against 3.25e-4, HDR-FLIP after flux 0.355 against 0.360 (here set mostly by this
    // small reference's 4.3 % noise; on all-methods' 128×96 extended setting, 8
    // bounces, sigma 1-2 px took a converged reference's HDR-FLIP from 0.22 to 0.19-0.20).
    // Bounds: flux within 1 % of the points', relMSE below 0.9× theirs, HDR-FLIP no
    // higher.
    assert!(
        (f3 / f2 - 1.0).abs() < 0.01,
        "flux {f3} against {f2} as points"
    );
    assert!(
        spread.hdr_flip() <= whole.hdr_flip(),
        "HDR-FLIP {} against {} as points",
        spread.hdr_flip(),
        whole.hdr_flip()
    );
    assert!(
        spread.errors.rel_mse < 0.9 * whole.errors.rel_mse,
        "relMSE {} against {} as points",
        spread.errors.rel_mse,
        whole.errors.rel_mse
    );
}

/// The scoring frame traces and classifies the sheets once, then only splats them for
/// each sub-pixel camera (`Frame::reuses_light_side`): pixel for pixel the image of
/// whole sub-frames, with every sheet kind and the orphan points on.
#[test]
fn scoring_reuses_the_traced_sheets_exactly() {
    let gpu = Gpu::new(builtin("sphere_on_plane", 64, 48));
    let mut method = gpu.method(
        &wavefront_info(),
        serde_json::json!({"grid": 128, "bounces": 2, "reflections": true, "splat_orphans": true}),
    );
    let scored = gpu.assert_light_side_reuse_is_exact(method.as_mut(), 2);
    assert!(
        scored.surface.sum_luminance() > 0.0,
        "a black caustic proves nothing"
    );
}

/// Several lights: the ball under two suns renders the sum of the ball under each sun
/// alone (a sheet per light and generator), counters summed.
#[test]
fn wavefront_lights_add_up() {
    caustics_testing::lights::lights_add_up(
        &caustics_method::registry_entry::<wavefront::Wavefront>(),
        serde_json::json!({"grid": 64}),
        &["sheets", "source_vertices"],
    );
}

/// `raster=compute` against the hardware splat on the same traced sheets (water_pool,
/// a 256² wavefront mesh, 160×120): the pixels the compute path covers are the
/// rasterizer's fragments but for centres on a shared edge (lavapipe: 13,609 of 13,610),
/// the lit pixels the same but for a few on the caustic's boundary (1 of 11,891), the
/// image's total luminance within 1e-3 (4.4e-4) and all but 3 % of the lit pixels'
/// values within 1e-3 (177 of 35,673, 0.5 %). The rest are where the hardware path's area ratio, from screen-space
/// derivatives of positions metres from the origin that differ by millimetres across a
/// pixel quad, loses f32 digits on thin triangles (up to 42 % there); the compute path
/// takes it from the triangle's own edge vectors. The same image bit for bit on the
/// next frame, and again with every footprint walked by workgroups or, past the list's
/// room, by the triangle's own invocation (`raster_small_footprint = 0`).
#[test]
fn the_compute_splat_matches_the_hardware_splat_and_repeats_itself() {
    let gpu = Gpu::new(builtin("water_pool", 160, 120));
    let info = caustics_method::registry_entry::<wavefront::Wavefront>();
    let mut hardware = gpu.method(&info, serde_json::json!({}));
    let hw = gpu.measure(hardware.as_mut(), 0, 1);
    let hw_image = gpu.surface();
    let mut compute = gpu.method(&info, serde_json::json!({"raster": "compute"}));
    let cs = gpu.measure(compute.as_mut(), 0, 1);
    let cs_image = gpu.surface();

    let fragments = hw.fill_total();
    let covered = cs.counter("raster_pixels_covered");
    eprintln!("hardware fragments {fragments}, compute pixels covered {covered}");
    assert!(fragments > 10_000, "only {fragments} splat fragments");
    assert!(
        covered.abs_diff(fragments) * 1000 <= fragments,
        "compute covered {covered} pixels, the rasterizer {fragments} fragments"
    );
    assert_eq!(cs.counter("kept_triangles"), hw.counter("kept_triangles"));

    let lit = |p: &[f32; 3]| p.iter().any(|&c| c > 0.0);
    let hw_lit = hw_image.pixels.iter().filter(|p| lit(p)).count();
    let (mut one_sided, mut differing, mut past_1e2, mut worst) = (0usize, 0usize, 0usize, 0.0f32);
    for (a, b) in hw_image.pixels.iter().zip(&cs_image.pixels) {
        if lit(a) != lit(b) {
            one_sided += 1;
            continue;
        }
        for c in 0..3 {
            let diff = (a[c] - b[c]).abs();
            if diff > 1e-3 * a[c].abs().max(b[c].abs()) + 1e-6 {
                differing += 1;
                worst = worst.max(diff / a[c].abs().max(b[c].abs()));
            }
            if diff > 1e-2 * a[c].abs().max(b[c].abs()) + 1e-6 {
                past_1e2 += 1;
            }
        }
    }
    let (hw_sum, cs_sum) = (hw_image.sum_luminance(), cs_image.sum_luminance());
    eprintln!(
        "{hw_lit} pixels lit by the hardware path; {one_sided} lit on one path only, \
         {differing} values past 1e-3, {past_1e2} past 1e-2 (worst {worst:.2e}); luminance {hw_sum} vs {cs_sum}"
    );
    assert!(hw_lit > 2000, "only {hw_lit} lit pixels");
    assert!(
        one_sided * 200 <= hw_lit,
        "{one_sided} pixels lit on one path only"
    );
    // Three channels per pixel: 3 % of the lit pixels' values.
    assert!(
        differing * 100 <= 3 * 3 * hw_lit,
        "{differing} values differ past 1e-3"
    );
    assert!(
        (hw_sum - cs_sum).abs() <= 1e-3 * hw_sum,
        "luminance {hw_sum} vs {cs_sum}"
    );

    // Deterministic: the next frame's image is the same bit for bit.
    gpu.frame(compute.as_mut());
    let again = gpu.surface();
    let same = |a: &HdrImage, b: &HdrImage| {
        a.pixels
            .iter()
            .flatten()
            .zip(b.pixels.iter().flatten())
            .all(|(x, y)| x.to_bits() == y.to_bits())
    };
    assert!(
        same(&again, &cs_image),
        "the compute splat changed between frames"
    );

    let mut all_large = gpu.method(
        &info,
        serde_json::json!({"raster": "compute", "raster_small_footprint": 0}),
    );
    let large = gpu.measure(all_large.as_mut(), 0, 1);
    let large_image = gpu.surface();
    eprintln!(
        "raster_small_footprint = 0: {} footprints large, {} of them walked by their own invocation",
        large.counter("raster_large_footprints"),
        large.counter("raster_footprints_walked_by_lane")
    );
    assert!(large.counter("raster_footprints_walked_by_lane") > 0);
    assert!(
        large.counter("raster_large_footprints")
            > large.counter("raster_footprints_walked_by_lane")
    );
    assert_eq!(large.counter("raster_pixels_covered"), covered);
    assert!(
        same(&large_image, &cs_image),
        "the large footprints' walk changed the image"
    );
}

#[test]
fn the_compute_splat_is_close_to_the_cpu_reference() {
    // The hardware path's bounds (refracting_sphere_is_close_to_the_cpu_reference): the
    // compute path must score as it does.
    let c = refracting_sphere_with(&wavefront_info(), serde_json::json!({"raster": "compute"}));
    c.check(
        &artifacts!(),
        &Bounds {
            flux: 0.85..1.02,
            rel_mse_after_flux: 5e-4,
            hdr_flip_after_flux: 0.47,
        },
    );
}
