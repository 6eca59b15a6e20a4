//! `static-grid` (Liktor & Dachsbacher 2010: beams from a regular projected grid,
//! bounding prisms) on the GPU, on whatever adapter the machine has (lavapipe on CI;
//! without an adapter these fail with the install hint, never skip): its counters, and
//! its error against the CPU reference. (The beam pipeline's analytic checks are in
//! `beams`' own tests.)

use caustics_testing::{Bounds, Gpu, TEST_REFERENCE, artifacts, builtin, compare};

#[test]
fn static_grid_counts_its_beams_and_refuses_refinement_parameters() {
    let gpu = Gpu::new(builtin("sphere_on_plane", 64, 48));
    let info = caustics_method::registry_entry::<static_grid::StaticGrid>();
    let mut method = gpu.method(
        &info,
        serde_json::json!({"light_resolution": 256, "grid": 16}),
    );
    let c = gpu.measure(method.as_mut(), 0, 1).counters;
    caustics_testing::assert_counters_documented(&info, &c);
    assert_eq!(c["base_triangles"], 512);
    assert_eq!(
        c["beams"], c["beams_level_0"],
        "a static grid has one level"
    );
    assert_eq!(c["hull_triangles"], 8 * c["beams"]);
    assert_eq!(
        c["splits_discontinuity"] + c["splits_energy"] + c["splits_camera"],
        0
    );
    let e = gpu
        .try_method(
            &caustics_method::registry_entry::<static_grid::StaticGrid>(),
            serde_json::json!({"levels": 2}),
        )
        .err()
        .expect("static-grid has no levels")
        .to_string();
    assert!(
        e.contains("levels") && e.contains("known parameters"),
        "{e}"
    );
}

#[test]
fn static_grid_on_sphere_on_plane_is_close_to_the_reference() {
    let c = compare(
        &caustics_method::registry_entry::<static_grid::StaticGrid>(),
        builtin("sphere_on_plane", 96, 72),
        serde_json::json!({"light_resolution": 256}),
        &TEST_REFERENCE,
        4,
    );
    // Bounds a margin above lavapipe's figures at 96×72, 16 samples per pixel (flux
    // 0.917, relMSE after flux 3.2e-3 (one pixel off: 8.9e-3), HDR-FLIP after flux 0.148):
    // the 2010 baseline's static 64² grid is not refined where the sphere's silhouette
    // and the focus would need it (adaptive-beams' oracle splits there): beams that
    // straddle the silhouette are dropped (counter dropped_discontinuity), light short
    // in the flux, and the focus is coarse (the relMSE). The beams do follow the light
    // the ball reflects, so HDR-FLIP is low. The relMSE bound is 1.5× the figure, below
    // the image moved by one pixel.
    eprintln!("counters: {:?}", c.measured.counters);
    c.check(
        &artifacts!(),
        &Bounds {
            flux: 0.85..1.05,
            rel_mse_after_flux: 5e-3,
            hdr_flip_after_flux: 0.20,
        },
    );
    assert_eq!(
        c.measured.counter("overflow_beams") + c.measured.counter("overflow_candidates"),
        0
    );
}

/// The glass sphere against the CPU reference (`caustics_testing::refracting_sphere`,
/// 96×72, 16 samples per pixel) with the paper's light paths and with `bounces` = 2:
/// the light reflected twice inside the ball comes in as beams of its own (the light
/// reflected once goes back up). The gain is small and the test says so: the beam
/// methods already follow the first interface's reflection (`reflections`, the bulk
/// of the reference's halo), and what the static grid still misses is the beams it
/// drops at the silhouette (dropped_discontinuity), which no light path brings back.
/// Lavapipe: paper flux 0.9177, HDR-FLIP after flux 0.1467; bounces 2: flux 0.9180,
/// relMSE after flux 3.2e-3 (one pixel off: 8.8e-3), HDR-FLIP after flux 0.1456. Both
/// must improve (deterministic on one adapter); the bounds sit a margin above the
/// extended figures.
#[test]
fn extended_light_paths_bring_the_glass_sphere_closer_to_the_reference() {
    let info = caustics_method::registry_entry::<static_grid::StaticGrid>();
    let paper = caustics_testing::refracting_sphere_with(&info, serde_json::json!({}));
    let extended =
        caustics_testing::refracting_sphere_with(&info, serde_json::json!({"bounces": 2}));
    eprintln!(
        "paper: flux {:.4}, HDR-FLIP after flux {:.4}; bounces 2: flux {:.4}, HDR-FLIP after flux {:.4}; internal-reflection beams {}",
        paper.flux(),
        paper.hdr_flip(),
        extended.flux(),
        extended.hdr_flip(),
        extended.measured.counter("beams_path_internal_2")
    );
    assert!(extended.measured.counter("beams_path_internal_2") > 0);
    assert!(
        extended.flux() > paper.flux() && extended.hdr_flip() < paper.hdr_flip(),
        "bounces did not help: flux {} -> {}, HDR-FLIP {} -> {}",
        paper.flux(),
        extended.flux(),
        paper.hdr_flip(),
        extended.hdr_flip()
    );
    extended.check(
        &artifacts!(),
        &Bounds {
            flux: 0.90..1.02,
            rel_mse_after_flux: 5e-3,
            hdr_flip_after_flux: 0.16,
        },
    );
}

/// The bumpy glass ball (20,480 triangles, vertex normals up to 42° off the radial)
/// with the paper's tracer and with exact tracing (`tracer` = bvh): the distance
/// impostor of a surface with bumps misplaces exit points and normals, so corner paths
/// leave in wrong directions or not at all; traced through the scene BVH with the
/// adjoint shading-normal factor, more beams land and the flux rises. What the static
/// 64² grid still drops is the beams whose corners part ways on the bumps (one corner
/// totally reflected inside, its neighbours out: dropped_discontinuity, about a third
/// of the candidates), which only refinement or a finer grid brings back. Lavapipe,
/// 64×48, 16 spp: impostor flux 0.495 (2,197 main beams), bvh flux 0.572 (2,540),
/// relMSE after flux 3.9e-3 (one pixel off: 8.9e-3), HDR-FLIP after flux 0.543; the
/// bounds sit a margin around the exact figures.
#[test]
fn exact_tracing_brings_a_bumpy_glass_mesh_closer_to_the_reference() {
    let info = caustics_method::registry_entry::<static_grid::StaticGrid>();
    let run = |tracer: &str| {
        compare(
            &info,
            builtin("bumpy_glass", 64, 48),
            serde_json::json!({"light_resolution": 512, "tracer": tracer}),
            &TEST_REFERENCE,
            4,
        )
    };
    let (paper, exact) = (run("impostor"), run("bvh"));
    let beams = |c: &caustics_testing::Comparison| c.measured.counter("beams_path_main");
    eprintln!(
        "impostor: flux {:.4}, {} main beams; bvh: flux {:.4}, {} main beams, counters {:?}",
        paper.flux(),
        beams(&paper),
        exact.flux(),
        beams(&exact),
        exact.measured.counters
    );
    assert!(
        exact.flux() > paper.flux() + 0.01 && beams(&exact) > beams(&paper),
        "exact tracing did not help: flux {} -> {}, main beams {} -> {}",
        paper.flux(),
        exact.flux(),
        beams(&paper),
        beams(&exact)
    );
    // The passes it no longer needs are not recorded.
    let passes = exact.measured.pass_names();
    assert!(
        !passes
            .iter()
            .any(|p| p.ends_with("/impostors") || p.ends_with("/light_gbuffer")),
        "{passes:?}"
    );
    exact.check(
        &artifacts!(),
        &Bounds {
            flux: 0.54..0.65,
            rel_mse_after_flux: 6e-3,
            hdr_flip_after_flux: 0.60,
        },
    );
}

/// The leaves whose corners part ways on the bumpy glass ball (a third of the
/// candidates, `exact_tracing_brings_a_bumpy_glass_mesh_closer_to_the_reference`) emit
/// no beam and their light is lost, as in the paper; `splat_orphans` draws each landed
/// corner of such a leaf as a one-pixel point of a third of its triangle's flux, into
/// the raw surface caustic before the filter; with `orphan_kernel_px` each point is
/// spread over a Gaussian (six vertices per corner), the same light in fewer dots.
#[test]
fn splat_orphans_bring_back_the_light_of_torn_beams() {
    let info = caustics_method::registry_entry::<static_grid::StaticGrid>();
    let run = |splat_orphans: bool, orphan_kernel_px: f64| {
        compare(
            &info,
            builtin("bumpy_glass", 64, 48),
            serde_json::json!({"light_resolution": 512, "tracer": "bvh",
                "splat_orphans": splat_orphans, "orphan_kernel_px": orphan_kernel_px}),
            &TEST_REFERENCE,
            4,
        )
    };
    let (torn, whole, spread) = (run(false, 0.0), run(true, 0.0), run(true, 1.0));
    eprintln!(
        "torn: flux {:.4}, relMSE after flux {:.3e}, HDR-FLIP after flux {:.4}; with orphans: counters {:?}",
        torn.flux(),
        torn.errors.rel_mse_after_flux.unwrap_or(f64::NAN),
        torn.hdr_flip(),
        whole.measured.counters
    );
    // The same beams either way; the orphans only where asked for.
    assert_eq!(
        whole.measured.counter("beams"),
        torn.measured.counter("beams")
    );
    assert!(!torn.measured.counters.contains_key("orphans"));
    assert!(whole.measured.counter("orphans") > 0);
    assert!(whole.measured.counter("orphan_corners") > whole.measured.counter("orphans"));
    assert_eq!(whole.measured.counter("overflow_orphans"), 0);
    assert!(
        whole
            .measured
            .pass_names()
            .contains(&"static-grid/orphan_points")
    );
    // Lavapipe, 64×48, 16 spp: without orphans flux 0.572 (relMSE after flux 3.9e-3,
    // HDR-FLIP after flux 0.543); with them 0.941 (4,591 records, 7,414 landed corners;
    // relMSE after flux 4.2e-3, one pixel off 8.6e-3; HDR-FLIP after flux 0.480): the
    // torn light is back where it lands, as points (their speckle keeps relMSE where
    // it was). Bounds: a gain of at least 0.25, flux 0.88..1.02 (no light twice: a
    // third of a triangle per landed corner, in the family it landed in), relMSE and
    // HDR-FLIP a margin above the figures.
    assert!(
        whole.flux() > torn.flux() + 0.25,
        "{} -> {}",
        torn.flux(),
        whole.flux()
    );
    whole.check(
        &artifacts!(),
        &Bounds {
            flux: 0.88..1.02,
            rel_mse_after_flux: 6e-3,
            hdr_flip_after_flux: 0.53,
        },
    );
    // The kernel: the same records, each corner drawn as a quad of six vertices (the
    // draw's vertex count is 3 corners x 6 per record, the corners that did not land
    // are clipped), its weights normalised over the pixels it covers.
    for key in ["beams", "orphans", "orphan_corners"] {
        assert_eq!(
            spread.measured.counter(key),
            whole.measured.counter(key),
            "{key}"
        );
    }
    assert_eq!(
        whole
            .measured
            .vertex_invocations("static-grid/orphan_points"),
        Some(3 * whole.measured.counter("orphans"))
    );
    assert_eq!(
        spread
            .measured
            .vertex_invocations("static-grid/orphan_points"),
        Some(18 * whole.measured.counter("orphans"))
    );
    eprintln!(
        "points: flux {:.4}, relMSE after flux {:.3e}, HDR-FLIP after flux {:.4}; \
         sigma 1 px: flux {:.4}, relMSE after flux {:.3e}, HDR-FLIP after flux {:.4}",
        whole.flux(),
        whole.errors.rel_mse_after_flux.unwrap_or(f64::NAN),
        whole.hdr_flip(),
        spread.flux(),
        spread.errors.rel_mse_after_flux.unwrap_or(f64::NAN),
        spread.hdr_flip()
    );
    // Lavapipe, 64x48, 16 spp: points flux 0.9591, relMSE after flux 3.73e-3, HDR-FLIP
    // after flux 0.3601; sigma 1 px: 0.9544, 4.34e-3, 0.3516. At this resolution a
    // pixel is 2 of all-methods' 128x96 pixels, and the kernel also blurs the orphans
    // of the bright focus, which relMSE weighs most (at 128x96, sigma 2: HDR-FLIP
    // 0.363 -> 0.299, relMSE 7.70e-4 -> 8.11e-4). Bounds: the flux within 1.5 % of the
    // points' (the part of a square past an occluder's silhouette or the receiver's
    // edge is not shaded, as the light of a point hidden there is not), HDR-FLIP
    // lower, relMSE below 1.3x the points'.
    assert!(
        (spread.flux() - whole.flux()).abs() < 0.015 * whole.flux(),
        "flux {} with the kernel, {} as points",
        spread.flux(),
        whole.flux()
    );
    assert!(
        spread.hdr_flip() < whole.hdr_flip(),
        "HDR-FLIP {} with the kernel, {} as points",
        spread.hdr_flip(),
        whole.hdr_flip()
    );
    let relmse = |c: &caustics_testing::Comparison| c.errors.rel_mse_after_flux.unwrap_or(f64::NAN);
    assert!(
        relmse(&spread) < 1.3 * relmse(&whole),
        "relMSE {} with the kernel, {} as points",
        relmse(&spread),
        relmse(&whole)
    );
}

/// `clip_leaves`: a leaf whose corners part ways keeps each group of corners' light as
/// beams clipped at the bisected boundary (two for a pair, one for a corner alone) in
/// place of losing it (the paper) or drawing it as points (`splat_orphans`). On the
/// bumpy glass ball, whose leaves tear at every bump's fold, the clipped beams bring
/// the light back as beams: more of it than the torn grid, no more than there is, and
/// without the points' speckle.
#[test]
fn clip_leaves_keep_the_light_of_torn_beams_in_beams() {
    let info = caustics_method::registry_entry::<static_grid::StaticGrid>();
    let run = |extra: serde_json::Value| {
        let mut params = serde_json::json!({"light_resolution": 512, "tracer": "bvh"});
        if let (Some(p), Some(extra)) = (params.as_object_mut(), extra.as_object()) {
            p.extend(extra.clone());
        }
        compare(
            &info,
            builtin("bumpy_glass", 64, 48),
            params,
            &TEST_REFERENCE,
            4,
        )
    };
    let torn = run(serde_json::json!({}));
    let clipped = run(serde_json::json!({"clip_leaves": true}));
    let points = run(serde_json::json!({"splat_orphans": true}));
    let report = |c: &caustics_testing::Comparison| {
        format!(
            "flux {:.4}, relMSE after flux {:.3e}, HDR-FLIP after flux {:.4}",
            c.flux(),
            c.errors.rel_mse_after_flux.unwrap_or(f64::NAN),
            c.hdr_flip()
        )
    };
    eprintln!("torn: {}", report(&torn));
    eprintln!(
        "clipped: {}, counters {:?}",
        report(&clipped),
        clipped.measured.counters
    );
    eprintln!("points: {}", report(&points));
    // The grid's own beams are the same; the clipped ones come on top, counted, and
    // their counters only where asked for.
    assert!(!torn.measured.counters.contains_key("beams_clipped"));
    let clips = clipped.measured.counter("beams_clipped");
    assert!(clips > 0);
    assert_eq!(
        clipped.measured.counter("beams"),
        torn.measured.counter("beams") + clips
    );
    assert_eq!(clipped.measured.counter("overflow_beams"), 0);
    assert!(
        clipped.measured.counter("beams_clipped_empty") * 20 < clips,
        "{:?}",
        clipped.measured.counters
    );
    // Lavapipe, 64x48, 16 spp: torn flux 0.577 (relMSE after flux 3.63e-3, HDR-FLIP
    // after flux 0.440); clipped 0.973 (3.86e-3, 0.338; 8,758 clipped beams, 1,395 of
    // them rebased, 119 empty); points 0.959 (3.73e-3, 0.360). Bounds: a gain of at
    // least 0.3, no more light than there is, HDR-FLIP under the points' (beams, not
    // dots), relMSE within 1.15x the points' (a clipped edge is the bisected chord,
    // not the true boundary).
    assert!(
        clipped.flux() > torn.flux() + 0.3 && clipped.flux() < 1.02,
        "{} -> {}",
        torn.flux(),
        clipped.flux()
    );
    assert!(
        clipped.hdr_flip() < points.hdr_flip(),
        "HDR-FLIP {} clipped, {} as points",
        clipped.hdr_flip(),
        points.hdr_flip()
    );
    let relmse = |c: &caustics_testing::Comparison| c.errors.rel_mse_after_flux.unwrap_or(f64::NAN);
    assert!(
        relmse(&clipped) < 1.15 * relmse(&points),
        "relMSE {} clipped, {} as points",
        relmse(&clipped),
        relmse(&points)
    );
}

/// The scoring frame generates the beams once, then rasterizes them (with the orphan
/// points and the surface filter) for each sub-pixel camera (`Frame::reuses_light_side`):
/// pixel for pixel the image of whole sub-frames, surface and volume.
#[test]
fn scoring_reuses_the_generated_beams_exactly() {
    let gpu = Gpu::new(builtin("fog_sphere", 64, 48));
    let info = caustics_method::registry_entry::<static_grid::StaticGrid>();
    let mut method = gpu.method(
        &info,
        serde_json::json!({"light_resolution": 256, "grid": 32, "splat_orphans": true}),
    );
    let scored = gpu.assert_light_side_reuse_is_exact(method.as_mut(), 2);
    assert!(
        scored.surface.sum_luminance() > 0.0,
        "a black caustic proves nothing"
    );
    assert!(
        scored.volume.sum_luminance() > 0.0,
        "a black volume caustic proves nothing"
    );
}

/// Several lights: a ball under two suns renders the sum of the ball under each sun
/// alone (the pipeline runs once per light into the same caustic), counters summed.
#[test]
fn static_grid_lights_add_up() {
    caustics_testing::lights::lights_add_up(
        &caustics_method::registry_entry::<static_grid::StaticGrid>(),
        serde_json::json!({"light_resolution": 256, "grid": 32}),
        &[
            "beams",
            "base_triangles",
            "candidates",
            "hull_triangles",
            "dropped_discontinuity",
        ],
    );
}

/// `vertex_irradiance` (beyond the paper: after Ernst et al.'s smooth interpolation,
/// which Liktor & Dachsbacher's Sect. 7 names beside their one area function per beam)
/// tilts each beam's irradiance towards its neighbours' at its corners, keeping the
/// beam's flux: the same beams, the same light in the image, a different image; with
/// `vertex_irradiance_max = 1` no corner may differ from its beam, which is the paper's
/// image; and the image does not depend on the order the beams were listed at their
/// vertices (scoring sub-frames that generate the beams again draw the same pixels).
/// Lavapipe: light in the image 886.90 -> 886.00, 3,432 of 6,912 pixels changed by over
/// 1 %, `vertex_irradiance_max = 1` equal bit for bit. Bounds: 1 % of the light (a beam
/// partly out of view keeps its flux outside the image too), any pixel moved, 1e-4
/// relative for the untilted image.
#[test]
fn vertex_irradiance_moves_light_within_beams_only() {
    let gpu = Gpu::new(builtin("water_pool", 96, 72));
    let info = caustics_method::registry_entry::<static_grid::StaticGrid>();
    let params = |extra: serde_json::Value| {
        let mut p = serde_json::json!({"light_resolution": 256, "grid": 32});
        p.as_object_mut()
            .expect("an object")
            .extend(extra.as_object().expect("an object").clone());
        p
    };
    let render = |extra: serde_json::Value| {
        let mut method = gpu.method(&info, params(extra));
        let beams = gpu.measure(method.as_mut(), 0, 1).counter("beams");
        (gpu.surface(), beams, method)
    };
    let (paper, paper_beams, _) = render(serde_json::json!({}));
    let (tilted, tilted_beams, mut method) = render(serde_json::json!({"vertex_irradiance": true}));
    let (untilted, _, _) =
        render(serde_json::json!({"vertex_irradiance": true, "vertex_irradiance_max": 1.0}));
    assert_eq!(tilted_beams, paper_beams, "the same beams");
    let (sum_paper, sum_tilted) = (paper.sum_luminance(), tilted.sum_luminance());
    assert!(sum_paper > 0.0, "a black caustic proves nothing");
    // Bounds: each beam keeps its flux exactly; the image may differ where a beam's
    // cross-section is partly out of view or behind the receiver's edge.
    assert!(
        (sum_tilted / sum_paper - 1.0).abs() < 0.01,
        "light in the image: {sum_paper} -> {sum_tilted}"
    );
    let moved = paper
        .pixels
        .iter()
        .zip(&tilted.pixels)
        .filter(|(a, b)| (a[1] - b[1]).abs() > 0.01 * a[1].abs().max(1e-6))
        .count();
    eprintln!(
        "light in the image {sum_paper:.6} -> {sum_tilted:.6}, {moved} of {} pixels moved by over 1%",
        paper.pixels.len()
    );
    assert!(moved > 0, "vertex_irradiance changed no pixel by 1%");
    let worst = paper
        .pixels
        .iter()
        .zip(&untilted.pixels)
        .map(|(a, b)| (a[1] - b[1]).abs() / a[1].abs().max(1e-3))
        .fold(0.0f32, f32::max);
    eprintln!("vertex_irradiance_max = 1 against the paper's image: {worst:e} (relative)");
    assert!(
        worst < 1e-4,
        "vertex_irradiance_max = 1 differs from the paper's image by {worst} (relative)"
    );
    gpu.assert_light_side_reuse_is_exact(method.as_mut(), 2);
}

/// `vertex_irradiance` finds a vertex's beams on the vertex cache's lattice: without it
/// the method is refused with a message that names both parameters.
#[test]
fn vertex_irradiance_needs_the_vertex_cache() {
    let gpu = Gpu::new(builtin("sphere_on_plane", 64, 48));
    let e = gpu
        .try_method(
            &caustics_method::registry_entry::<static_grid::StaticGrid>(),
            serde_json::json!({"vertex_irradiance": true, "vertex_cache": false}),
        )
        .err()
        .expect("refused without the vertex cache")
        .to_string();
    assert!(
        e.contains("vertex_irradiance") && e.contains("vertex_cache=false"),
        "{e}"
    );
}
