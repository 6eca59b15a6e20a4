//! Extended lights in the reference (issue 16): an environment map and a sphere light,
//! against what their radiometry says in the limits that have closed forms.

use std::path::Path;

use caustics_metrics::HdrImage;
use caustics_reference::{Reference, ReferenceImage, ReferenceOptions};
use caustics_scene::Scene;

fn scene(lights: &str, objects: &str, w: u32, h: u32) -> Scene {
    let json = format!(
        r#"{{
  "name": "extended",
  "camera": {{"eye": [0, 4.5, 6.5], "target": [0, 0.6, 0], "fov_y_deg": 40, "width": {w}, "height": {h}}},
  "lights": [{lights}],
  "materials": {{"glass": {{"type": "dielectric", "ior": 1.5}},
                "floor": {{"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}}}},
  "objects": [{objects}]
}}"#
    );
    Scene::from_json_str(&json, Path::new("tests/extended.json")).expect("valid scene")
}

const FLOOR: &str = r#"{"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [20, 20]}, "material": "floor"}"#;
const BALL: &str =
    r#"{"shape": {"type": "sphere", "center": [0, 1.5, 0], "radius": 1}, "material": "glass"}"#;

fn render(scene: &Scene, photons: u64, direct: bool) -> caustics_reference::ReferenceResult {
    Reference::new(scene)
        .expect("prepares")
        .render(
            &ReferenceOptions {
                photons,
                direct,
                batches: 8,
                ..Default::default()
            },
            &|_| {},
        )
        .expect("renders")
}

fn hdr(img: &ReferenceImage) -> HdrImage {
    HdrImage {
        width: img.width,
        height: img.height,
        pixels: img.pixels.clone(),
    }
}

/// An unoccluded diffuse floor under a sky of constant radiance L receives E = π·L
/// from the hemisphere, so its radiance is ρ/π·E = ρ·L: here 0.8 × 2 = 1.6.
#[test]
fn a_floor_under_a_constant_sky_has_radiance_rho_l() {
    let s = scene(
        r#"{"type": "environment", "radiance": [1, 1, 1], "scale": [2, 2, 2]}"#,
        FLOOR,
        24,
        18,
    );
    let r = render(&s, 1 << 22, true);
    let direct = r.direct.as_ref().expect("asked for");
    // The pixels whose whole area sees the floor (20 x 20 m) inside 9 m of its centre
    // (the top rows look past its far edge).
    let cam = &s.camera;
    let mut values = Vec::new();
    for y in 0..cam.height {
        for x in 0..cam.width {
            let on_floor =
                [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                    .iter()
                    .all(|(dx, dy)| {
                        let (o, d) = cam.ray_through_pixel(x as f32 + dx, y as f32 + dy);
                        let t = -o.y / d.y;
                        let p = o + t * d;
                        t > 0.0 && p.x.abs() < 9.0 && p.z.abs() < 9.0
                    });
            if on_floor {
                values.push(f64::from(direct.at(x, y)[1]));
            }
        }
    }
    assert!(values.len() > 200, "{} floor pixels", values.len());
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let sd = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    eprintln!("constant sky: floor radiance {mean:.4} (pixel sd {sd:.4}) against 1.6");
    assert!(
        (mean - 1.6).abs() < 0.02 * 1.6,
        "mean floor radiance {mean}"
    );
    // No caustic: nothing specular.
    assert!(r.caustic.pixels.iter().all(|p| p[1] == 0.0));
}

/// A sphere light of radius r and radiance L is, from afar, a point light of
/// intensity π r² L: a small one casts the same caustic through the glass ball.
#[test]
fn a_small_sphere_light_casts_the_point_lights_caustic() {
    let objects = format!("{BALL}, {FLOOR}");
    let point = scene(
        r#"{"type": "point", "position": [0.5, 6, 0.3], "intensity": [30, 30, 30]}"#,
        &objects,
        48,
        36,
    );
    let r = 0.01f32;
    let radiance = 30.0 / (std::f32::consts::PI * r * r);
    let sphere = scene(
        &format!(
            r#"{{"type": "sphere", "position": [0.5, 6, 0.3], "radius": {r}, "radiance": [{radiance}, {radiance}, {radiance}]}}"#
        ),
        &objects,
        48,
        36,
    );
    let (a, b) = (
        render(&point, 1 << 22, false),
        render(&sphere, 1 << 22, false),
    );
    let (a, b) = (hdr(&a.caustic), hdr(&b.caustic));
    let flux = caustics_metrics::flux_ratio(&b, &a, None)
        .expect("same size")
        .expect("a lit caustic");
    let region = caustics_metrics::caustic_region(&a);
    let in_region = caustics_metrics::flux_ratio(&b, &a, Some(&region))
        .expect("same size")
        .expect("a lit region");
    eprintln!("sphere light / point light: flux {flux:.4}, over the caustic {in_region:.4}");
    assert!((flux - 1.0).abs() < 0.02, "flux {flux}");
    assert!((in_region - 1.0).abs() < 0.02, "caustic flux {in_region}");
}

/// A sky black but for one small bright patch is a directional light of irradiance
/// L·ΔΩ from the patch: it casts the same caustic, which checks the map's importance
/// sampling and its solid-angle pdf.
#[test]
fn a_sky_with_one_bright_patch_is_a_directional_light() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let (w, h) = (256u32, 128u32);
    // The patch: 2 x 2 pixels at the zenith's side, direction towards the sky
    // (0.2, 1, 0.1) normalized, so the light travels along (−0.2, −1, −0.1).
    let sky = caustics_scene::Vec3::new(0.2, 1.0, 0.1).normalize();
    let (u, v) = caustics_scene::EnvironmentMap::uv(sky);
    let (px, py) = ((u * w as f32) as u32, (v * h as f32) as u32);
    let mut map = HdrImage::new(w, h);
    let mut solid_angle = 0.0f64;
    for y in py..py + 2 {
        for x in px..px + 2 {
            map.pixels[(y * w + x) as usize] = [1000.0, 1000.0, 1000.0];
            // ∫ sin θ dθ dφ over the pixel.
            let (t0, t1) = (
                std::f64::consts::PI * f64::from(y) / f64::from(h),
                std::f64::consts::PI * f64::from(y + 1) / f64::from(h),
            );
            solid_angle += (t0.cos() - t1.cos()) * std::f64::consts::TAU / f64::from(w);
        }
    }
    let path = tmp.path().join("patch.exr");
    caustics_metrics::write_exr(&path, &map).expect("writes");
    // The patch's centre direction (the 2 x 2 block's shared corner).
    let centre = caustics_scene::EnvironmentMap::direction(
        (px + 1) as f32 / w as f32,
        (py + 1) as f32 / h as f32,
    );
    let irradiance = 1000.0 * solid_angle;
    let objects = format!("{BALL}, {FLOOR}");
    let dir = -centre;
    let directional = scene(
        &format!(
            r#"{{"type": "directional", "direction": [{}, {}, {}], "irradiance": [{irradiance}, {irradiance}, {irradiance}]}}"#,
            dir.x, dir.y, dir.z
        ),
        &objects,
        48,
        36,
    );
    let env_json = format!(r#"{{"type": "environment", "path": "{}"}}"#, path.display());
    let env = scene(&env_json, &objects, 48, 36);
    let (a, b) = (
        render(&directional, 1 << 22, false),
        render(&env, 1 << 22, false),
    );
    let (a, b) = (hdr(&a.caustic), hdr(&b.caustic));
    let flux = caustics_metrics::flux_ratio(&b, &a, None)
        .expect("same size")
        .expect("a lit caustic");
    eprintln!("one-patch sky / directional light: flux {flux:.4}");
    // The patch spans ~1.4° of sky: its caustic is the directional one blurred by that
    // much, with the same flux.
    assert!((flux - 1.0).abs() < 0.03, "flux {flux}");
}

#[test]
fn bad_extended_lights_name_the_field() {
    let bad = |light: &str| -> String {
        let json = format!(
            r#"{{"name": "x", "camera": {{"eye": [0, 4, 6], "target": [0, 0, 0], "fov_y_deg": 40, "width": 8, "height": 6}},
              "lights": [{light}], "materials": {{"floor": {{"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}}}},
              "objects": [{FLOOR}]}}"#
        );
        match Scene::from_json_str(&json, Path::new("tests/x.json")) {
            Ok(_) => panic!("{light} loaded"),
            Err(e) => e.to_string(),
        }
    };
    let e = bad(r#"{"type": "sphere", "position": [0, 5, 0], "radius": 0, "radiance": [1, 1, 1]}"#);
    assert!(
        e.contains("lights[0].radius") && e.contains("positive"),
        "{e}"
    );
    let e = bad(r#"{"type": "environment"}"#);
    assert!(
        e.contains("lights[0]") && e.contains("either `path`"),
        "{e}"
    );
    let e = bad(r#"{"type": "environment", "radiance": [1, 1, 1], "path": "sky.exr"}"#);
    assert!(e.contains("not both"), "{e}");
    let e = bad(r#"{"type": "environment", "path": "no_such_sky.exr"}"#);
    assert!(
        e.contains("lights[0].path") && e.contains("no_such_sky.exr"),
        "{e}"
    );
    let e = bad(r#"{"type": "environment", "radiance": [1, -1, 1]}"#);
    assert!(e.contains("lights[0].radiance[1]"), "{e}");
    let e =
        bad(r#"{"type": "environment", "radiance": [1, 1, 1], "motion": {"velocity": [1, 0, 0]}}"#);
    assert!(e.contains("unknown field `motion`"), "{e}");
}
