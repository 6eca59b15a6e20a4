//! The reference against answers computed here, independently of the renderer.
//!
//! Tolerances are k·σ with σ the standard error the renderer reports (per-pixel
//! standard errors from its batches; the mean over a block of n pixels has standard
//! error sqrt(Σσ²)/n since different pixels' batch estimates are uncorrelated up to a
//! negligible multinomial term). k = 3 or 4: a correct renderer fails a 3σ check in
//! about 0.3% of seeds, and every seed here is fixed, so the tests are deterministic.

use std::path::Path;

use caustics_reference::{Reference, ReferenceOptions, ReferenceResult};
use caustics_scene::Scene;

fn scene(json: &str) -> Scene {
    Scene::from_json_str(json, Path::new("test.json")).expect("valid test scene")
}

fn render(scene: &Scene, photons: u64) -> ReferenceResult {
    let r = Reference::new(scene).expect("prepares");
    r.render(
        &ReferenceOptions {
            photons,
            ..Default::default()
        },
        &|_| {},
    )
    .expect("renders")
}

/// Exact unpolarized Fresnel reflectance from air (n = 1) into `n` at incidence cos_i.
fn fresnel_r(cos_i: f64, n: f64) -> f64 {
    let sin_t = (1.0 - cos_i * cos_i).sqrt() / n;
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let rs = (cos_i - n * cos_t) / (cos_i + n * cos_t);
    let rp = (n * cos_i - cos_t) / (n * cos_i + cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// Mean and standard error of the mean of channel 0 over pixels [x0, x1) × [y0, y1).
fn block(r: &ReferenceResult, x0: u32, x1: u32, y0: u32, y1: u32) -> (f64, f64) {
    let (mut sum, mut var, mut n) = (0.0, 0.0, 0.0);
    for y in y0..y1 {
        for x in x0..x1 {
            sum += r.caustic.at(x, y)[0] as f64;
            var += (r.caustic_stderr.at(x, y)[0] as f64).powi(2);
            n += 1.0;
        }
    }
    (sum / n, var.sqrt() / n)
}

/// A flat glass interface (ior 1.5) 1 m above a floor, light at 30° from the normal:
/// the floor under it receives T(30°)·E·cos 30°, so its radiance is ρ/π·T·E·cos θ
/// everywhere the refracted beam lands. The camera sits between glass and floor.
#[test]
fn flat_interface_transmits_fresnel_t() {
    let s = scene(
        r#"{"name": "flat",
        "camera": {"eye": [0, 0.8, 3], "target": [0, 0, 0], "up": [0, 1, 0],
                   "fov_y_deg": 30, "width": 24, "height": 18},
        "lights": [{"type": "directional", "direction": [0.5, -0.8660254, 0], "irradiance": [2, 2, 2]}],
        "materials": {"glass": {"type": "dielectric", "ior": 1.5},
                      "floor": {"type": "diffuse", "albedo": [0.7, 0.7, 0.7]}},
        "objects": [
          {"shape": {"type": "quad", "center": [0, 1, 0], "normal": [0, 1, 0], "size": [4, 4]}, "material": "glass"},
          {"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [8, 8]}, "material": "floor"}
        ]}"#,
    );
    let r = render(&s, 1 << 21);
    let cos = 30f64.to_radians().cos();
    let expected = 0.7 / std::f64::consts::PI * (1.0 - fresnel_r(cos, 1.5)) * 2.0 * cos;
    let (mean, se) = block(&r, 8, 16, 6, 12);
    eprintln!("flat interface: {mean:.5} vs {expected:.5} (σ = {se:.2e})");
    assert!(
        (mean - expected).abs() < 3.0 * se,
        "{mean} vs {expected}, σ {se}"
    );
    assert!(se / expected < 0.01, "too noisy to mean anything: {se}");
}

/// A mirror wall reflects a directional light (30° from vertical) onto the floor:
/// radiance ρ/π·R·E·cos 30° per channel, R = (0.9, 0.6, 0.3).
#[test]
fn mirror_reflects_its_reflectance() {
    let s = scene(
        r#"{"name": "mirror",
        "camera": {"eye": [3, 2, 0], "target": [0.6, 0, 0], "up": [0, 1, 0],
                   "fov_y_deg": 20, "width": 24, "height": 18},
        "lights": [{"type": "directional", "direction": [-0.5, -0.8660254, 0], "irradiance": [1, 1, 1]}],
        "materials": {"chrome": {"type": "mirror", "reflectance": [0.9, 0.6, 0.3]},
                      "floor": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}},
        "objects": [
          {"shape": {"type": "quad", "center": [0, 1, 0], "normal": [1, 0, 0], "size": [4, 2]}, "material": "chrome"},
          {"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [8, 8]}, "material": "floor"}
        ]}"#,
    );
    let r = render(&s, 1 << 20);
    let cos = 30f64.to_radians().cos();
    for (c, refl) in [0.9, 0.6, 0.3].into_iter().enumerate() {
        let expected = 0.8 / std::f64::consts::PI * refl * cos;
        let (mut sum, mut var, mut n) = (0.0, 0.0, 0.0);
        for y in 6..12 {
            for x in 8..16 {
                sum += r.caustic.at(x, y)[c] as f64;
                var += (r.caustic_stderr.at(x, y)[c] as f64).powi(2);
                n += 1.0;
            }
        }
        let (mean, se) = (sum / n, var.sqrt() / n);
        eprintln!("mirror channel {c}: {mean:.5} vs {expected:.5} (σ = {se:.2e})");
        assert!(
            (mean - expected).abs() < 3.0 * se,
            "channel {c}: {mean} vs {expected}, σ {se}"
        );
    }
}
