//! The photon hit image's light paths beyond the default one (`bounces`,
//! `reflections`, the `photon_hits` crate doc), through `caustic-triangles`, which
//! reads the hits and per-vertex irradiance back: the Fresnel reflection's own sheet
//! carries the analytic irradiance, the default sheet is untouched by the extension,
//! and with enough bounces a glass sphere delivers all the light that enters it. On
//! whatever adapter the machine has (lavapipe on CI; no adapter fails, never skips).

use caustic_triangles::photon_hits::{PhotonHit, PhotonHitConfig};
use caustic_triangles::{CausticTrianglesParams, VertexArea};
use caustics_scene::Scene;
use caustics_testing::scene;

mod common;
use caustics_testing::fresnel_reflectance as fresnel;
use common::run_concrete;

fn params(resolution: u32, bounces: u32, reflections: bool) -> CausticTrianglesParams {
    CausticTrianglesParams {
        hits: PhotonHitConfig {
            resolution,
            cube_size: 256,
            distance_map_size: 512,
            bounces,
            reflections,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// A 45° glass quad (an open refractor) 1 m above a floor turns a light travelling
/// along +x: its Fresnel reflection goes straight down, keeping the beam's
/// cross-section, so E_floor = R(45°) · E on the reflection sheet's vertices.
fn tilted_glass() -> Scene {
    scene(&serde_json::json!({
        "name": "tilted_glass",
        "description": "a 45° glass surface over a floor: the Fresnel-reflection sheet's check",
        "camera": {"eye": [0, 0.5, 2], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 50, "width": 48, "height": 36},
        "lights": [{"type": "directional", "direction": [1, 0, 0], "irradiance": [1, 2, 0.5]}],
        "materials": {
            "glass": {"type": "dielectric", "ior": 1.5},
            "floor": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}
        },
        "objects": [
            {"shape": {"type": "quad", "center": [0, 1, 0], "normal": [-1, -1, 0], "size": [0.5, 0.5]}, "material": "glass"},
            {"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [6, 6]}, "material": "floor"}
        ]
    }))
}

#[test]
fn fresnel_reflection_sheet_carries_the_reflected_irradiance() {
    let n = 40usize;
    let (gpu, m) = run_concrete(tilted_glass(), &params(n as u32, 0, true));
    let hits = m.photon_hits();
    assert_eq!((hits.faces, hits.sheets, hits.layers), (1, 2, 2));
    let hit = hits.read_hits(&gpu.ctx).expect("hits");
    let e_v = m
        .read_vertex_irradiance(&gpu.ctx)
        .expect("vertex irradiance");
    let r = fresnel(std::f64::consts::FRAC_1_SQRT_2, 1.0 / 1.5);
    let want = [1.0, 2.0, 0.5].map(|e| r * e);
    // Interior vertices of the reflection sheet (layer 1): all eight neighbours valid.
    let at = |x: usize, y: usize| n * n + y * n + x;
    let (mut checked, mut worst) = (0, 0.0f64);
    for y in 1..n - 1 {
        for x in 1..n - 1 {
            if !(y - 1..=y + 1).all(|j| (x - 1..=x + 1).all(|i| hit[at(i, j)].valid())) {
                continue;
            }
            // Straight down from the mirror-like reflection: the floor under the quad.
            assert!(
                hit[at(x, y)].position[1].abs() < 1e-3,
                "{:?}",
                hit[at(x, y)]
            );
            for c in 0..3 {
                worst = worst.max((e_v[at(x, y)][c] as f64 - want[c]).abs() / want[c]);
            }
            checked += 1;
        }
    }
    let counters = caustics_method::CausticsMethod::counters(&m, &gpu.ctx).expect("counters");
    eprintln!(
        "reflection sheet: {checked} interior vertices, worst relative error {worst:.2e}, R = {r:.4}; {counters:?}"
    );
    assert!(checked > 300, "only {checked} interior vertices");
    // 1 %: the hits come from the receivers' distance map (the flat mirror test's bound).
    assert!(worst < 0.01, "worst vertex irradiance error {worst}");
    // The reflection's hits are counted on their own, and within the total.
    let reflected = counters["photon_hits_fresnel_reflection"];
    assert_eq!(
        reflected,
        hit[n * n..].iter().filter(|h| h.valid()).count() as u64
    );
    assert_eq!(
        counters["photon_hits"],
        hit.iter().filter(|h| h.valid()).count() as u64
    );
    assert_eq!(counters["photon_texels"], 2 * (n * n) as u64);
}

#[test]
fn the_papers_sheet_is_the_same_with_the_extended_paths() {
    // The ring under its point light (one face) and a refracting sphere (two
    // interfaces): sheet 0 of the extended image is the paper's image, bit for bit.
    for name in ["sphere_on_plane", "ring"] {
        let scene = caustics_testing::builtin(name, 32, 24);
        let (gpu, paper) = run_concrete(scene.clone(), &params(32, 0, false));
        let (gpu_ext, extended) = run_concrete(scene, &params(32, 3, true));
        let paper_hits = paper.photon_hits().read_hits(&gpu.ctx).expect("hits");
        let ext = extended.photon_hits();
        let ext_hits = ext.read_hits(&gpu_ext.ctx).expect("hits");
        let sheet0 = (ext.faces * 32 * 32) as usize;
        assert_eq!(paper_hits.len(), sheet0, "{name}");
        let differing = paper_hits
            .iter()
            .zip(&ext_hits[..sheet0])
            .filter(|(a, b)| {
                // A mirror's hits that went on to further reflections leave the
                // paper's invalid slot (second bounce) valid; nothing else changes.
                a != b && !(a.ids[2] == 4 && b.valid())
            })
            .count();
        assert_eq!(
            differing, 0,
            "{name}: sheet 0 differs in {differing} texels"
        );
    }
}

/// Σ flux of the valid hits of every sheet (W, channel 1).
fn delivered(hits: &[PhotonHit]) -> f64 {
    hits.iter()
        .filter(|h| h.valid())
        .map(|h| h.flux[1] as f64)
        .sum()
}

#[test]
fn enough_bounces_deliver_all_the_light_entering_a_glass_sphere() {
    // A point light beside a glass sphere, inside a diffuse sphere that catches every
    // ray: the light entering the glass is I · Ω, Ω = 2π (1 − cos α), sin α = R / D.
    let (radius, distance, intensity) = (0.5f64, 1.5f64, 2.0f64);
    let scene = scene(&serde_json::json!({
        "name": "enclosed_sphere",
        "description": "a glass sphere and a point light inside a diffuse sphere",
        "camera": {"eye": [0, 0, 2.5], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 60, "width": 32, "height": 24},
        "lights": [{"type": "point", "position": [0, distance, 0], "intensity": [intensity, intensity, intensity]}],
        "materials": {
            "glass": {"type": "dielectric", "ior": 1.5},
            "wall": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}
        },
        "objects": [
            {"shape": {"type": "sphere", "center": [0, 0, 0], "radius": radius}, "material": "glass"},
            {"shape": {"type": "sphere", "center": [0, 0, 0], "radius": 4}, "material": "wall"}
        ]
    }));
    let sin_a = radius / distance;
    let entering = intensity * 2.0 * std::f64::consts::PI * (1.0 - (1.0 - sin_a * sin_a).sqrt());
    let mut ratios = Vec::new();
    for (bounces, reflection) in [(0, false), (0, true), (8, true)] {
        let (gpu, m) = run_concrete(scene.clone(), &params(96, bounces, reflection));
        let hits = m.photon_hits().read_hits(&gpu.ctx).expect("hits");
        let counters = caustics_method::CausticsMethod::counters(&m, &gpu.ctx).expect("counters");
        let ratio = delivered(&hits) / entering;
        eprintln!(
            "bounces {bounces}, reflection {reflection}: delivered / entering {ratio:.4}; {counters:?}"
        );
        // Every ray leaving the glass meets the wall; a sphere never traps light.
        for lost in ["photons_no_receiver", "photons_no_exit"] {
            assert_eq!(counters[lost], 0, "{lost}");
        }
        // Every bounce order and the reflection sheet: each counter has its doc.
        caustics_testing::assert_counters_documented(
            &caustics_method::registry_entry::<caustic_triangles::CausticTriangles>(),
            &counters,
        );
        ratios.push(ratio);
    }
    // The paper's path: T_in · T_out. Over a sphere's disk the mean Fresnel reflectance
    // of glass (n = 1.5) is about 9 % per interface (grazing rays near the silhouette
    // reflect most), so (1 − 0.09)² ≈ 0.83 of the light comes out refracted twice.
    assert!((0.80..0.86).contains(&ratios[0]), "{ratios:?}");
    // The first interface's reflection adds its ~9 %.
    assert!(ratios[1] > ratios[0] + 0.07, "{ratios:?}");
    // Eight internal reflections leave under 1e-6 of the light inside; what remains is
    // the light view's discretization of the sphere's solid angle (96² texels, the
    // silhouette's texels are in or out by their centre): 1 %.
    assert!((0.99..1.01).contains(&ratios[2]), "{ratios:?}");
}

#[test]
fn splat_orphans_adds_exactly_the_light_no_triangle_carries() {
    // The bumpy glass ball: total internal reflection isolates many hits of a coarse
    // photon image, whose light the paper's discard rule loses. Without orphans, then
    // with them as one texel each, then as `orphan_kernel_px` = 5 texels a side.
    let scene = caustics_testing::builtin("bumpy_glass", 32, 24);
    let mut flux = Vec::new();
    let mut orphans = (0u64, [0.0f64; 3]);
    for (splat_orphans, kernel) in [(false, 1), (true, 1), (true, 5)] {
        let mut p = params(64, 0, false);
        p.splat_orphans = splat_orphans;
        p.orphan_kernel_px = kernel;
        let (gpu, m) = run_concrete(scene.clone(), &p);
        let atlas = m.caustic_map().read_atlas(&gpu.ctx).expect("atlas");
        flux.push(caustics_testing::photon_hits::flux_on_floor(
            m.caustic_map(),
            &atlas,
            0.0,
        ));
        let counters = caustics_method::CausticsMethod::counters(&m, &gpu.ctx).expect("counters");
        let hits = m.photon_hits().read_hits(&gpu.ctx).expect("hits");
        let e_v = m.read_vertex_irradiance(&gpu.ctx).expect("irradiance");
        let marked: Vec<&PhotonHit> = hits
            .iter()
            .zip(&e_v)
            .filter(|(_, e)| e[3] == 1.0)
            .map(|(h, _)| h)
            .collect();
        // Marked exactly where counted, and only valid hits.
        assert_eq!(
            counters["photon_hits_without_triangles"],
            marked.len() as u64
        );
        assert!(marked.iter().all(|h| h.valid()));
        let mut sum = [0.0f64; 3];
        for h in &marked {
            for (total, flux) in sum.iter_mut().zip(h.flux) {
                *total += flux as f64;
            }
        }
        orphans = (marked.len() as u64, sum);
    }
    let (count, orphan_flux) = orphans;
    eprintln!(
        "bumpy_glass, 64² hits: {count} orphans carrying {orphan_flux:?} W; map flux without {:?}, with one texel {:?}, with 5² texels {:?}",
        flux[0], flux[1], flux[2]
    );
    assert!(count > 50, "only {count} orphans");
    // The one-texel kernel is normalized at its centre (splatting's 2e-3 bound); each
    // texel of the wider one takes its own footprint on the receiver's tangent plane at
    // the hit (splat_kernel.wgsl), exact on this flat floor (lavapipe: the two add the
    // same flux to 1e-7). Bound: 2e-3 for both.
    for (with, bound) in [(&flux[1], 2e-3), (&flux[2], 2e-3)] {
        for c in 0..3 {
            let added = with[c] - flux[0][c];
            let rel = (added - orphan_flux[c]).abs() / orphan_flux[c];
            assert!(
                rel < bound,
                "channel {c}: added {added} W, orphans {} W",
                orphan_flux[c]
            );
        }
    }
}

#[test]
fn third_vertex_areas_and_orphan_splats_deliver_every_hit() {
    // The barycentric ΔA (a third of the kept triangles' area) with the orphans splatted:
    // the map holds the flux of every valid hit; the default fan ΔA gives edge vertices
    // n/6 of theirs, which on the bumpy ball's speckled hit image is a visible share.
    let scene = caustics_testing::builtin("bumpy_glass", 32, 24);
    let mut ratios = Vec::new();
    for vertex_area in [VertexArea::Fan, VertexArea::Third] {
        let mut p = params(64, 0, false);
        p.splat_orphans = true;
        p.vertex_area = vertex_area;
        let (gpu, m) = run_concrete(scene.clone(), &p);
        let atlas = m.caustic_map().read_atlas(&gpu.ctx).expect("atlas");
        let on_floor =
            caustics_testing::photon_hits::flux_on_floor(m.caustic_map(), &atlas, 0.0)[1];
        let hits = m.photon_hits().read_hits(&gpu.ctx).expect("hits");
        ratios.push(on_floor / delivered(&hits));
    }
    eprintln!(
        "map flux / valid hits' flux: fan {:.4}, third {:.4}",
        ratios[0], ratios[1]
    );
    // Rasterizing triangles into cube-map texels (coverage by texel centre, Gouraud
    // in between) and the one-texel splats' centre normalization: 1 %.
    assert!((ratios[1] - 1.0).abs() < 0.01, "{ratios:?}");
    assert!(ratios[0] < ratios[1] - 0.02, "{ratios:?}");
}

/// A glass ball under a directional light above a floor, with or without an
/// index-matched slab (an open dielectric of index 1: no Fresnel reflection, no bend)
/// between them.
fn ball_over_slab(slab: bool) -> Scene {
    let mut objects = vec![
        serde_json::json!({"shape": {"type": "sphere", "center": [0, 1, 0], "radius": 0.3}, "material": "glass"}),
        serde_json::json!({"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [6, 6]}, "material": "floor"}),
    ];
    if slab {
        objects.push(serde_json::json!({"shape": {"type": "quad", "center": [0, 0.4, 0], "normal": [0, 1, 0], "size": [4, 4]}, "material": "matched"}));
    }
    scene(&serde_json::json!({
        "name": "ball_over_slab",
        "description": "a glass ball over a floor, an index-matched slab between them: the chain check",
        "camera": {"eye": [0, 2, 2], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 50, "width": 48, "height": 36},
        "lights": [{"type": "directional", "direction": [0.2, -1, 0.1], "irradiance": [1, 1, 1]}],
        "materials": {
            "glass": {"type": "dielectric", "ior": 1.5},
            "matched": {"type": "dielectric", "ior": 1.0},
            "floor": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}
        },
        "objects": objects
    }))
}

/// A chain (`bounces` > 0): the ball's light meets the slab, another specular object,
/// and is traced on exactly through it. Through an index-matched slab it must land
/// where and with what it lands without the slab, texel for texel; without bounces
/// (the paper's one hit image per generator) it is dropped there.
#[test]
fn a_chain_through_an_index_matched_slab_lands_as_without_it() {
    let ball_hits = |slab: bool, bounces: u32| {
        let (gpu, m) = run_concrete(ball_over_slab(slab), &params(48, bounces, false));
        let counters = caustics_method::CausticsMethod::counters(&m, &gpu.ctx).expect("counters");
        // The ball is the first generator.
        let hits = m.pairs()[0]
            .photon_hits()
            .read_hits(&gpu.ctx)
            .expect("hits");
        (hits, counters)
    };
    let (alone, alone_counters) = ball_hits(false, 1);
    let (dropped, dropped_counters) = ball_hits(true, 0);
    let (chained, chained_counters) = ball_hits(true, 1);
    let valid = |h: &[PhotonHit]| h.iter().filter(|h| h.valid()).count();
    eprintln!(
        "valid hits: alone {}, slab without bounces {}, chained {}; chained counters {chained_counters:?}",
        valid(&alone),
        valid(&dropped),
        valid(&chained)
    );
    // The paper's path stops at the slab: none of the ball's sheet-0 light lands.
    let sheet0 = 48 * 48;
    assert_eq!(valid(&dropped[..sheet0]), 0);
    assert!(dropped_counters["photons_specular_receiver"] as usize > sheet0 / 4);
    assert_eq!(alone_counters.get("photon_hits_chained"), Some(&0));
    // With a bounce each texel lands as it does without the slab.
    assert!(valid(&alone[..sheet0]) > sheet0 / 4, "{}", valid(&alone));
    let (mut chained_count, mut worst_position_m, mut worst_flux) = (0u64, 0.0f32, 0.0f32);
    for (i, (a, c)) in alone.iter().zip(&chained).enumerate() {
        assert_eq!(a.valid(), c.valid(), "texel {i}: {a:?} vs {c:?}");
        if !a.valid() {
            continue;
        }
        if c.ids[1] != a.ids[1] {
            chained_count += 1;
        }
        let d = (0..3)
            .map(|k| (a.position[k] - c.position[k]).abs())
            .fold(0.0, f32::max);
        worst_position_m = worst_position_m.max(d);
        worst_flux = worst_flux.max((a.flux[1] - c.flux[1]).abs() / a.flux[1]);
    }
    eprintln!(
        "{chained_count} chained hits; worst landing offset {worst_position_m:.2e} m, worst relative flux {worst_flux:.2e}"
    );
    assert_eq!(chained_counters["photon_hits_chained"], chained_count);
    assert!(chained_count as usize > sheet0 / 4);
    // Without the slab the landing comes from the receivers' distance map (its
    // search tolerance, 2e-3 of the map's reach); through it, from the exact BVH
    // (lavapipe: 5.6e-4 m apart at most, the flux equal).
    assert!(worst_position_m < 2e-3, "{worst_position_m}");
    // Index 1: the slab transmits everything (Fresnel 0).
    assert!(worst_flux < 1e-6, "{worst_flux}");
}
