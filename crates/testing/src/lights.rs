//! Several lights and generators: light adds up, so a method's caustic of a scene is
//! the sum of the caustics of its parts rendered alone (each light alone, each
//! generator alone where the method's passes for one do not see the other). The checks
//! every method with several lights shares, taking its registry entry.

use caustics_method::MethodInfo;
use caustics_metrics::HdrImage;
use caustics_scene::Scene;

use crate::{Gpu, Measured};

/// Renders `scene` through the registry entry `info` (JSON `params`): the surface
/// caustic and the measured frames (one frame, no warm-up).
pub fn render(info: &MethodInfo, scene: Scene, params: serde_json::Value) -> (HdrImage, Measured) {
    let gpu = Gpu::new(scene);
    let mut method = gpu.method(info, params);
    let measured = gpu.measure(method.as_mut(), 0, 1);
    (gpu.surface(), measured)
}

/// Glass balls at `x` (each 0.5 m, 1 m above a floor) under directional lights of
/// `directions` (irradiance 1 each), seen at 64×48.
pub fn balls_under_suns(x: &[f64], directions: &[[f64; 3]]) -> Scene {
    let lights: Vec<serde_json::Value> = directions
        .iter()
        .map(
            |d| serde_json::json!({"type": "directional", "direction": d, "irradiance": [1, 1, 1]}),
        )
        .collect();
    balls_under(x, &lights)
}

/// Glass balls at `x` (each 0.5 m, 1 m above a floor) under `lights` (the scene
/// format's JSON; a relative map path is read from `scenes/`), seen at 64×48.
pub fn balls_under(x: &[f64], lights: &[serde_json::Value]) -> Scene {
    let objects: Vec<serde_json::Value> = x
        .iter()
        .map(|x| serde_json::json!({"shape": {"type": "sphere", "center": [x, 1.0, 0], "radius": 0.5}, "material": "glass"}))
        .chain([serde_json::json!({"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [12, 12]}, "material": "floor"})])
        .collect();
    crate::scene(&serde_json::json!({
        "name": "balls_under_suns",
        "description": "glass balls far apart under one or two lights",
        "camera": {"eye": [0, 4, 5], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 60, "width": 64, "height": 48},
        "lights": lights,
        "materials": {
            "glass": {"type": "dielectric", "ior": 1.5},
            "floor": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}
        },
        "objects": objects
    }))
}

/// The two suns of [`lights_add_up`]: from slightly different sides, so their caustics
/// lie apart on the floor.
pub const TWO_SUNS: [[f64; 3]; 2] = [[0.2, -1.0, 0.1], [-0.3, -1.0, 0.0]];

/// `whole` renders the sum of `parts` (each alone) within `1e-3` of the image's light
/// (the blending order of the additive passes differs, nothing else), and each of
/// `counters` is the sum of the parts'. Returns the whole's measured frames.
pub fn adds_up(
    info: &MethodInfo,
    params: &serde_json::Value,
    name: &str,
    whole: Scene,
    parts: [Scene; 2],
    counters: &[&str],
) -> Measured {
    let (whole, rw) = render(info, whole, params.clone());
    let [(p, rp), (q, rq)] = parts.map(|s| render(info, s, params.clone()));
    let mut diff = 0.0f64;
    for ((w, p), q) in whole.pixels.iter().zip(&p.pixels).zip(&q.pixels) {
        diff += (0..3)
            .map(|c| (w[c] as f64 - p[c] as f64 - q[c] as f64).abs())
            .sum::<f64>();
    }
    let total: f64 = whole
        .pixels
        .iter()
        .map(|w| w.iter().map(|&v| v as f64).sum::<f64>())
        .sum();
    let part_total = |img: &HdrImage| -> f64 {
        img.pixels
            .iter()
            .map(|w| w.iter().map(|&v| v as f64).sum::<f64>())
            .sum()
    };
    eprintln!(
        "{name}: |whole - sum of parts| / whole = {:.2e} ({total:.3} summed; parts {:.3} and {:.3})",
        diff / total,
        part_total(&p),
        part_total(&q)
    );
    // Each part must carry light of its own, or the sum says nothing about it.
    assert!(
        part_total(&p) > 0.1 * total && part_total(&q) > 0.1 * total,
        "{name}: a part renders (almost) nothing"
    );
    assert!(
        total > 0.0 && diff / total < 1e-3,
        "{name}: {diff} of {total}"
    );
    for counter in counters {
        assert_eq!(
            rw.counter(counter),
            rp.counter(counter) + rq.counter(counter),
            "{name}: {counter}"
        );
    }
    rw
}

/// One glass ball under [`TWO_SUNS`] renders the sum of the ball under each sun alone,
/// with `counters` summed. Returns the two-sun scene's measured frames.
pub fn lights_add_up(info: &MethodInfo, params: serde_json::Value, counters: &[&str]) -> Measured {
    let [a, b] = TWO_SUNS;
    adds_up(
        info,
        &params,
        "two suns",
        balls_under_suns(&[0.0], &[a, b]),
        [
            balls_under_suns(&[0.0], &[a]),
            balls_under_suns(&[0.0], &[b]),
        ],
        counters,
    )
}
