//! The checks the two photon-hit methods (`caustic-triangles`, `splatting`) share: both
//! trace their photons with the `photon-hits` crate (light G-buffer, receivers' distance
//! maps, photon image) and look the caustic up from the camera, so the light-leak
//! (distance test), determinism and parameter-error checks are the same with another
//! method. Each takes the method's registry entry and asserts; the test calling it keeps
//! its name.

use caustics_method::MethodInfo;
use caustics_metrics::HdrImage;
use caustics_scene::{Scene, Vec3};
use photon_hits::CausticMap;

use crate::lights::{TWO_SUNS, balls_under_suns};
use crate::{builtin, plane_hit};

/// Small settings of the photon-hit tests, `extra` added: 48² photon image, 128² cube
/// faces.
pub fn small(extra: serde_json::Value) -> serde_json::Value {
    let mut p = serde_json::json!({"resolution": 48, "cube_size": 128, "distance_map_size": 128});
    if let (Some(p), Some(extra)) = (p.as_object_mut(), extra.as_object()) {
        p.extend(extra.clone());
    }
    p
}

pub use crate::lights::render as run;

/// Pixels seeing the floor (y = -3) under the table of `light_leak`: hidden from the
/// glass ball by the table, and out of reach of the light passing the table's edge (it
/// diverges after the focus).
pub fn occluded_floor_pixels(scene: &Scene) -> Vec<(u32, u32)> {
    let cam = &scene.camera;
    (0..cam.height)
        .flat_map(|j| (0..cam.width).map(move |i| (i, j)))
        .filter(|&(i, j)| {
            plane_hit(cam, i, j, -3.0).is_some_and(|p| p.x.abs() < 0.7 && p.z.abs() < 0.7)
        })
        .collect()
}

/// `light_leak` at 64×48 with [`small`] settings: with `distance_test` no light reaches
/// the [`occluded_floor_pixels`]; without it the caustic leaks onto them (more than 1 in
/// green summed), so the scene does show the leak the test removes.
pub fn distance_test_removes_the_light_leak(info: &MethodInfo) {
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
        info,
        scene.clone(),
        small(serde_json::json!({"distance_test": true})),
    );
    let (without, _) = run(
        info,
        scene,
        small(serde_json::json!({"distance_test": false})),
    );
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

/// Two runs of `scene` with [`small`] settings give the same counters, fragment counts
/// and image; the image is not empty, more than 100 photons hit, every one of the 48²
/// photon texels is traced, each of `passes` is timed as `<method>/<pass>`, and every
/// counter has its doc in the method's `Method::COUNTERS`.
pub fn deterministic(info: &MethodInfo, scene: Scene, passes: &[&str]) {
    let floor = format!("no caustic on the {} floor", scene.name);
    let (a, ra) = run(info, scene.clone(), small(serde_json::json!({})));
    let (b, rb) = run(info, scene, small(serde_json::json!({})));
    assert_eq!(ra.counters, rb.counters);
    crate::assert_counters_documented(info, &ra.counters);
    assert!(ra.counter("photon_hits") > 100, "{:?}", ra.counters);
    assert_eq!(ra.counter("photon_texels"), 48 * 48);
    let fa = ra.method_fragments(info.name).expect("pipeline statistics");
    assert_eq!(Some(fa), rb.method_fragments(info.name));
    assert_eq!(a.pixels, b.pixels, "image differs between runs");
    assert!(a.sum_luminance() > 0.0, "{floor}");
    let names = ra.pass_names();
    for pass in passes {
        let want = format!("{}/{pass}", info.name);
        assert!(
            names.contains(&want.as_str()),
            "{want} missing from {names:?}"
        );
    }
}

/// Each `(param, needle)`: the method refuses `param` with a message naming `needle` and
/// the method.
pub fn parameters_refused(info: &MethodInfo, cases: &[(serde_json::Value, &str)]) {
    for (param, needle) in cases {
        let msg = (info.parse)(param)
            .expect_err(&param.to_string())
            .to_string();
        assert!(
            msg.contains(needle) && msg.contains(info.name),
            "{param}: {msg}"
        );
    }
}

/// Σ over the texels of a read-back caustic map `atlas` of E × the texel's area on the
/// floor plane y = `floor_y`: the flux a reconstruction put on the floor (W per channel).
///
/// # Panics
/// Where a lit texel looks away from the floor.
pub fn flux_on_floor(map: &CausticMap, atlas: &[f32], floor_y: f32) -> [f64; 3] {
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

/// One photon hit image per (light, generator) pair (Umenhoffer et al. §4.1), whose
/// camera passes add up: two glass balls 4 m apart render the sum of each alone, and
/// one ball under two suns the sum of each sun alone, within 1e-3 of the image's light
/// (each pair's hit image, maps and cube map are the same as alone; what differs is the
/// other ball in a pair's receivers' distance map, which none of its light meets), with
/// the counters of the parts summed.
pub fn pairs_add_up(info: &MethodInfo) {
    let params = small(serde_json::json!({}));
    let counters = ["photon_texels", "photon_hits"];
    let [a, _] = TWO_SUNS;
    crate::lights::adds_up(
        info,
        &params,
        "two balls",
        balls_under_suns(&[-2.0, 2.0], &[a]),
        [
            balls_under_suns(&[-2.0], &[a]),
            balls_under_suns(&[2.0], &[a]),
        ],
        &counters,
    );
    crate::lights::lights_add_up(info, params, &counters);
}
