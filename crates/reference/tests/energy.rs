//! Energy conservation through a glass sphere, measured two ways: the power the
//! photons bring to the floor (test hook) and the rendered image integrated over a
//! camera looking straight down.

use std::f64::consts::PI;
use std::path::Path;

use caustics_reference::{Reference, ReferenceOptions};
use caustics_scene::Scene;

const SCENE: &str = r#"{"name": "energy",
    "camera": {"eye": [3, 10, 0], "target": [3, 0, 0], "up": [0, 0, 1],
               "fov_y_deg": 11.421186, "width": 32, "height": 32},
    "lights": [{"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1]}],
    "materials": {"glass": {"type": "dielectric", "ior": 1.5},
                  "floor": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
    "objects": [
      {"shape": {"type": "sphere", "center": [0, 2, 0], "radius": 1}, "material": "glass"},
      {"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [2000, 2000]}, "material": "floor"}
    ]}"#;

/// Exact unpolarized Fresnel reflectance from air into `n` at incidence cos_i.
fn fresnel_r(cos_i: f64, n: f64) -> f64 {
    let sin_t = (1.0 - cos_i * cos_i).sqrt() / n;
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let rs = (cos_i - n * cos_t) / (cos_i + n * cos_t);
    let rp = (n * cos_i - cos_t) / (n * cos_i + cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// Power (W) reaching the floor under a vertical beam of irradiance 1 through a
/// sphere of radius 1 and index n, every order of internal reflection included (as
/// the tracer does: it picks reflection with probability R at every interface, up to
/// 64 events). At impact parameter b (sin θi = b), order k = 0 is the external
/// reflection (fraction R, deviation π − 2θi), order k ≥ 1 leaves after k − 1 internal
/// reflections (fraction T²R^(k−1), all at the same angle θt, deviation
/// 2(θi − θt) + (k−1)(π − 2θt)); it reaches the (huge) floor iff it leaves going down,
/// cos(deviation) > 0. Integrated over the disc with the midpoint rule.
fn floor_power(n: f64) -> f64 {
    let steps = 200_000;
    let mut total = 0.0;
    for i in 0..steps {
        let b = (i as f64 + 0.5) / steps as f64;
        let ti = b.asin();
        let tt = (b / n).asin();
        let r = fresnel_r(ti.cos(), n);
        let t = 1.0 - r;
        let mut frac = if (PI - 2.0 * ti).cos() > 0.0 { r } else { 0.0 };
        let mut carried = t * t;
        for k in 1..64 {
            let dev = 2.0 * (ti - tt) + (k as f64 - 1.0) * (PI - 2.0 * tt);
            if dev.cos() > 0.0 {
                frac += carried;
            }
            carried *= r;
        }
        total += frac * 2.0 * PI * b / steps as f64;
    }
    total
}

#[test]
fn caustic_power_matches_fresnel_integral() {
    let scene = Scene::from_json_str(SCENE, Path::new("energy.json")).expect("valid");
    let reference = Reference::new(&scene).expect("prepares");
    let opts = ReferenceOptions {
        photons: 1 << 20,
        ..Default::default()
    };
    let all = reference
        .caustic_power(&opts, &|_, _| true)
        .expect("traces");
    let expected = floor_power(1.5);
    eprintln!(
        "floor power {:.5} W vs {expected:.5} W (cross-section π = {PI:.5})",
        all[0]
    );
    // Bernoulli noise of ~1M photons is ~2e-4 relative; 1% is the issue's bound.
    assert!(
        (all[0] / expected - 1.0).abs() < 0.01,
        "{} vs {expected}",
        all[0]
    );
    assert!(
        (all[0] / expected - 1.0).abs() < 2e-3,
        "{} vs {expected}",
        all[0]
    );

    // The image of a floor region seen straight down from height H = 10 (no
    // occlusion by the sphere there): each pixel's radiance times H²·A_pix·π/ρ is the
    // power landing in its footprint (sensor.rs docs: cos θx = cos θc, d = H/cos θc).
    let h = 10.0f64;
    let tan_half = (0.5 * scene.camera.fov_y_deg as f64).to_radians().tan();
    let half = h * tan_half;
    let r = reference.render(&opts, &|_| {}).expect("renders");
    let a_pix = (2.0 * tan_half / 32.0).powi(2);
    let from_image: f64 =
        r.caustic.pixels.iter().map(|p| p[0] as f64).sum::<f64>() * h * h * a_pix * PI / 0.5;
    let in_view = reference
        .caustic_power(&opts, &|_, p| {
            ((p.x as f64) - 3.0).abs() < half && (p.z as f64).abs() < half
        })
        .expect("traces");
    eprintln!(
        "power in view: image {from_image:.7} W, photons {:.7} W",
        in_view[0]
    );
    assert!(
        in_view[0] > 0.003 * expected,
        "the view must hold caustic light"
    );
    // Same photons both ways: equal up to f32 rounding of the splats.
    assert!(
        (from_image / in_view[0] - 1.0).abs() < 1e-4,
        "{from_image} vs {}",
        in_view[0]
    );
}
