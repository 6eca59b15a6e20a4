//! Scenes for tests: built-in ones at a test's resolution, or a test's own JSON.

use caustics_scene::{Camera, Scene, Vec3};

/// The JSON of built-in scene `name` (`scenes/<name>.json`) with its camera set to
/// `width` × `height`, for a test that changes more (a parameter of an object, a light).
///
/// # Panics
/// If there is no such built-in scene.
pub fn builtin_json(name: &str, width: u32, height: u32) -> serde_json::Value {
    let path = caustics_scene::resolve(name).unwrap_or_else(|e| panic!("built-in scene: {e}"));
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("reading {}: {e}", path.display()));
    let mut json: serde_json::Value =
        serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: not JSON: {e}", path.display()));
    json["camera"]["width"] = width.into();
    json["camera"]["height"] = height.into();
    json
}

/// Built-in scene `name` at `width` × `height` (small images keep GPU tests fast). Its
/// mesh paths resolve as in the file; its hash is that of the resized scene.
///
/// # Panics
/// If there is no such built-in scene or it does not validate.
pub fn builtin(name: &str, width: u32, height: u32) -> Scene {
    let json = builtin_json(name, width, height);
    let source = caustics_scene::builtin_dir().join(format!("{name}.json"));
    Scene::from_json_str(&json.to_string(), &source)
        .unwrap_or_else(|e| panic!("built-in scene {name} at {width}x{height}: {e}"))
}

/// A test's own scene from its JSON (the format of DESIGN "Scene format"); relative mesh
/// paths resolve against the built-in scenes' folder (`scenes/meshes/...`).
///
/// # Panics
/// If it does not validate; the message names the JSON path at fault.
pub fn scene(json: &serde_json::Value) -> Scene {
    let name = json["name"].as_str().unwrap_or("test_scene");
    let source = caustics_scene::builtin_dir().join(format!("{name} (test).json"));
    Scene::from_json_str(&json.to_string(), &source)
        .unwrap_or_else(|e| panic!("test scene {name}: {e}"))
}

/// Where the ray through the centre of pixel (`x`, `y`) meets the horizontal plane at
/// height `y_plane`, if it travels towards it (nothing in between is tested).
pub fn plane_hit(camera: &Camera, x: u32, y: u32, y_plane: f32) -> Option<Vec3> {
    let (o, d) = camera.ray_through_pixel(x as f32 + 0.5, y as f32 + 0.5);
    let t = (y_plane - o.y) / d.y;
    (t.is_finite() && t > 0.0).then(|| o + d * t)
}

/// Exact unpolarized Fresnel reflectance (DESIGN "Conventions") at incidence `cos_i`,
/// `eta` = n_i / n_t; 1 under total internal reflection. Computed here, independently
/// of the shaders, for the tests' analytic answers.
pub fn fresnel_reflectance(cos_i: f64, eta: f64) -> f64 {
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (rs * rs + rp * rp)
}
