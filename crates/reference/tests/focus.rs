//! A glass ball lens focuses a vertical beam at the paraxial back focal distance
//! f = nR / (2(n − 1)) from its centre.

use std::path::Path;

use caustics_reference::{Reference, ReferenceOptions, ReferenceResult};
use caustics_scene::{Scene, Vec3};

/// Ball of radius 1, n = 1.5 (f = 1.5) centred at y = 2.5 over a receiver at height
/// `floor_y`, seen from the light's side at an angle (the line of sight passes 1.2 m
/// from the centre, so the ball never hides the axis point (0, floor_y, 0)).
fn render_at(floor_y: f32) -> (Scene, ReferenceResult) {
    let json = format!(
        r#"{{"name": "lens",
        "camera": {{"eye": [0, {eye_y}, 4], "target": [0, {floor_y}, 0], "up": [0, 1, 0],
                   "fov_y_deg": 8, "width": 48, "height": 48}},
        "lights": [{{"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1]}}],
        "materials": {{"glass": {{"type": "dielectric", "ior": 1.5}},
                      "floor": {{"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}}}},
        "objects": [
          {{"shape": {{"type": "sphere", "center": [0, 2.5, 0], "radius": 1}}, "material": "glass"}},
          {{"shape": {{"type": "quad", "center": [0, {floor_y}, 0], "normal": [0, 1, 0], "size": [6, 6]}}, "material": "floor"}}
        ]}}"#,
        eye_y = floor_y + 3.0
    );
    let scene = Scene::from_json_str(&json, Path::new("lens.json")).expect("valid");
    let r = Reference::new(&scene)
        .expect("prepares")
        .render(
            &ReferenceOptions {
                photons: 1 << 20,
                ..Default::default()
            },
            &|_| {},
        )
        .expect("renders");
    (scene, r)
}

/// The brightest pixel and where its centre ray meets the receiver.
fn brightest(scene: &Scene, r: &ReferenceResult, floor_y: f32) -> (f32, Vec3) {
    let (i, v) = r
        .caustic
        .pixels
        .iter()
        .enumerate()
        .map(|(i, p)| (i, p[0]))
        .fold((0, f32::MIN), |a, b| if b.1 > a.1 { b } else { a });
    let (x, y) = (i as u32 % r.caustic.width, i as u32 / r.caustic.width);
    let (o, d) = scene
        .camera
        .ray_through_pixel(x as f32 + 0.5, y as f32 + 0.5);
    let t = (floor_y - o.y) / d.y;
    (v, o + t * d)
}

#[test]
fn ball_lens_focuses_at_paraxial_focal_distance() {
    let f = 1.5 * 1.0 / (2.0 * (1.5 - 1.0));
    let at_focus = 2.5 - f;
    let (scene, r) = render_at(at_focus);
    let (peak, p) = brightest(&scene, &r, at_focus);
    eprintln!("peak {peak:.3} at {p:?}");
    // On the axis, within about two pixel footprints (1.5 cm × 2.5 cm).
    assert!(p.x.abs() < 0.04 && p.z.abs() < 0.06, "peak at {p:?}");
    // Beyond the paraxial focus no ray crosses the axis any more: the receiver
    // at 1.4 f sees a far dimmer peak; ahead of it (0.8 f, inside the axial caustic)
    // the on-axis peak remains but is spread by the aberration.
    let beyond = 2.5 - 1.4 * f;
    let (scene_b, rb) = render_at(beyond);
    let (peak_b, _) = brightest(&scene_b, &rb, beyond);
    eprintln!("peak at 1.4 f: {peak_b:.3}");
    assert!(peak > 3.0 * peak_b, "{peak} vs {peak_b}");
}
