//! `splatting` (the caustic-mapping baseline of the photon-hit papers) on the GPU, on
//! whatever adapter the machine has (lavapipe on CI; without an adapter these fail with
//! the install hint, never skip): flux conservation of every kernel, the CPU reference on
//! a refracting sphere, the distance test against light leaks, determinism. Small
//! images, photon images and cube maps keep them fast.

use caustics_gpu::RendererOptions;
use caustics_scene::{Scene, Vec3};
use caustics_testing::{
    Bounds, Gpu, HdrImage, Measured, TEST_REFERENCE, artifacts, builtin, compare, plane_hit,
};
use photon_hits::{CausticMap, PhotonHit, PhotonHitConfig};
use splatting::{Splatting, SplattingParams};

/// Small settings shared by the tests: 48² photon image, 128² cube faces.
fn small(extra: serde_json::Value) -> serde_json::Value {
    let mut p = serde_json::json!({"resolution": 48, "cube_size": 128, "distance_map_size": 128});
    if let (Some(p), Some(extra)) = (p.as_object_mut(), extra.as_object()) {
        p.extend(extra.clone());
    }
    p
}

/// Renders `scene` through the registry entry: the measured frames and the image.
fn run(scene: Scene, params: serde_json::Value) -> (HdrImage, Measured) {
    let gpu = Gpu::new(scene);
    let mut method = gpu.method(
        &caustics_method::registry_entry::<splatting::Splatting>(),
        params,
    );
    let measured = gpu.measure(method.as_mut(), 0, 1);
    (gpu.surface(), measured)
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
    let options = RendererOptions {
        shadow_resolution: 256,
        cube_shadow_resolution: 128,
    };
    let gpu = Gpu::with_options(builtin("sphere_on_plane", 64, 48), options);
    for kernel_px in [1u32, 4, 16] {
        let params = SplattingParams {
            hits: PhotonHitConfig {
                resolution: 48,
                cube_size: 256,
                distance_map_size: 128,
                ..Default::default()
            },
            kernel_px,
        };
        let mut m = Splatting::new(&gpu.ctx, &gpu.renderer, &params).expect("method");
        gpu.frame(&mut m);
        let hits: Vec<PhotonHit> = m.photon_hits().read_hits(&gpu.ctx).expect("hits");
        let mut photons = [0.0f64; 3];
        for h in hits.iter().filter(|h| h.valid()) {
            for (sum, flux) in photons.iter_mut().zip(h.flux) {
                *sum += flux as f64;
            }
        }
        assert!(photons[1] > 0.5, "little flux: {photons:?}");
        let atlas = m.caustic_map().read_atlas(&gpu.ctx).expect("atlas");
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

#[test]
fn refracting_sphere_is_close_to_the_cpu_reference() {
    let c = compare(
        &caustics_method::registry_entry::<splatting::Splatting>(),
        builtin("sphere_on_plane", 96, 72),
        serde_json::json!({}),
        &TEST_REFERENCE,
        4,
    );
    // Bounds a margin above lavapipe's figures at 96×72, 16 samples per pixel
    // (flux 0.928, relMSE after flux 6.6e-4 (one pixel off: 7.3e-3), HDR-FLIP after flux 0.473):
    // the method (like its paper) does not follow the light the glass sphere reflects (off
    // its surface, and inside it), which the reference spreads as a dim halo around the
    // focus (see the -expected image of a failure): that light is short in the flux and
    // sets most of HDR-FLIP, whose brighter exposures show the halo (static-grid, which
    // follows the reflection, scores 0.15 here).
    // No flux above 1.02: light the method does not model cannot be there. The relMSE
    // bound is about twice the figure and refuses the image moved by one pixel.
    // Splatting's blur (4-texel kernels) and its photon-density noise are the shape
    // error here, hence the larger relMSE bound of the four.
    c.check(
        &artifacts!(),
        &Bounds {
            flux: 0.85..1.02,
            rel_mse_after_flux: 1.5e-3,
            hdr_flip_after_flux: 0.52,
        },
    );
}

/// Pixels seeing the floor (y = -3) under the table of `light_leak`: hidden from the
/// glass ball by the table, and out of reach of the light passing the table's edge (it
/// diverges after the focus).
fn occluded_floor_pixels(scene: &Scene) -> Vec<(u32, u32)> {
    let cam = &scene.camera;
    (0..cam.height)
        .flat_map(|j| (0..cam.width).map(move |i| (i, j)))
        .filter(|&(i, j)| {
            plane_hit(cam, i, j, -3.0).is_some_and(|p| p.x.abs() < 0.7 && p.z.abs() < 0.7)
        })
        .collect()
}

#[test]
fn distance_test_removes_the_light_leak_onto_an_occluded_receiver() {
    let scene = builtin("light_leak", 64, 48);
    let pixels = occluded_floor_pixels(&scene);
    assert!(
        pixels.len() > 30,
        "only {} occluded floor pixels",
        pixels.len()
    );
    let sum =
        |img: &HdrImage| -> f64 { pixels.iter().map(|&(i, j)| img.get(i, j)[1] as f64).sum() };
    let (with, _) = run(
        scene.clone(),
        small(serde_json::json!({"distance_test": true})),
    );
    let (without, _) = run(scene, small(serde_json::json!({"distance_test": false})));
    eprintln!(
        "caustic on the occluded floor {:.4} with the distance test, {:.4} without; whole image {:.4} / {:.4}",
        sum(&with),
        sum(&without),
        with.sum_luminance(),
        without.sum_luminance()
    );
    assert_eq!(sum(&with), 0.0, "light leaks despite the test");
    assert!(
        sum(&without) > 1.0,
        "no leak without the test, the scene shows nothing"
    );
}

#[test]
fn counts_and_images_are_deterministic() {
    let scene = builtin("ring", 64, 48);
    let (a, ra) = run(scene.clone(), small(serde_json::json!({})));
    let (b, rb) = run(scene, small(serde_json::json!({})));
    assert_eq!(ra.counters, rb.counters);
    assert!(ra.counter("photon_hits") > 100, "{:?}", ra.counters);
    assert_eq!(ra.counter("photon_texels"), 48 * 48);
    let fa = ra
        .method_fragments("splatting")
        .expect("pipeline statistics");
    assert_eq!(Some(fa), rb.method_fragments("splatting"));
    assert_eq!(a.pixels, b.pixels, "image differs between runs");
    assert!(a.sum_luminance() > 0.0, "no caustic on the ring floor");
    let names = ra.pass_names();
    for pass in [
        "light_gbuffer",
        "distance_maps",
        "trace_photons",
        "camera_lookup",
    ] {
        let want = format!("splatting/{pass}");
        assert!(
            names.contains(&want.as_str()),
            "{want} missing from {names:?}"
        );
    }
}

#[test]
fn bad_parameters_are_clear() {
    // (The harness's cli test checks that a refused parameter writes nothing.)
    for (param, needle) in [
        (serde_json::json!({"kernel_px": 0}), "kernel_px"),
        (serde_json::json!({"kernel": 3}), "known parameters"),
    ] {
        let msg = (caustics_method::registry_entry::<splatting::Splatting>().parse)(&param)
            .expect_err(&param.to_string())
            .to_string();
        assert!(
            msg.contains(needle) && msg.contains("splatting"),
            "{param}: {msg}"
        );
    }
}
