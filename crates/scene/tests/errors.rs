//! Bad scene files: each error names the JSON path and what was expected, and nothing
//! panics.

use std::path::Path;

use caustics_scene::{Scene, SceneError};

/// A valid scene; the cases below break one thing in it.
const GOOD: &str = r#"{
  "name": "good",
  "camera": {"eye": [0, 3, 5], "target": [0, 0, 0], "up": [0, 1, 0],
             "fov_y_deg": 40, "width": 64, "height": 48},
  "lights": [{"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1]}],
  "materials": {
    "glass": {"type": "dielectric", "ior": 1.5},
    "floor": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}
  },
  "objects": [
    {"shape": {"type": "sphere", "center": [0, 1.5, 0], "radius": 1}, "material": "glass"},
    {"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [20, 20]}, "material": "floor"}
  ]
}"#;

fn load(json: &str) -> Result<Scene, SceneError> {
    Scene::from_json_str(json, Path::new("scenes/bad.json"))
}

/// `GOOD` with `from` replaced by `to` (which must occur).
fn with(from: &str, to: &str) -> String {
    assert!(GOOD.contains(from), "test bug: {from:?} not in GOOD");
    GOOD.replacen(from, to, 1)
}

/// Loads `json`, expects an error whose message holds every one of `parts`.
#[track_caller]
fn expect_err(json: &str, parts: &[&str]) -> SceneError {
    let err = match load(json) {
        Ok(_) => panic!("expected an error containing {parts:?}"),
        Err(e) => e,
    };
    let msg = err.to_string();
    assert!(msg.starts_with("scenes/bad.json"), "no file name: {msg}");
    for p in parts {
        assert!(msg.contains(p), "{msg:?} lacks {p:?}");
    }
    err
}

#[test]
fn good_scene_loads() {
    let s = load(GOOD).expect("good scene");
    assert_eq!(s.objects.len(), 2);
    assert_eq!(s.description, "");
}

#[test]
fn main_variant_display_is_file_path_message() {
    let err = expect_err(&with("\"radius\": 1", "\"radius\": -1"), &[]);
    assert_eq!(
        err.to_string(),
        "scenes/bad.json: objects[0].shape.radius: expected a positive number, got -1"
    );
}

#[test]
fn wrong_type() {
    expect_err(
        &with("\"radius\": 1", "\"radius\": \"big\""),
        &[
            "objects[0].shape.radius",
            "invalid type: string \"big\"",
            "line 11",
        ],
    );
    expect_err(
        &with("\"width\": 64", "\"width\": 6.5"),
        &["camera.width", "invalid type"],
    );
    expect_err(
        &with("\"eye\": [0, 3, 5]", "\"eye\": [0, 3]"),
        &["camera.eye", "invalid length 2"],
    );
    expect_err(
        &with(
            "\"albedo\": [0.8, 0.8, 0.8]",
            "\"albedo\": [0.8, true, 0.8]",
        ),
        &["materials.floor.albedo[1]", "invalid type: boolean"],
    );
    expect_err(
        &with("\"lights\": [", "\"lights\": 3, \"x\": ["),
        &["lights", "invalid type"],
    );
}

#[test]
fn unknown_fields() {
    expect_err(
        &with("\"name\": \"good\",", "\"name\": \"good\", \"colour\": 1,"),
        &["colour", "unknown field `colour`"],
    );
    expect_err(
        &with("\"radius\": 1", "\"radius\": 1, \"radious\": 2"),
        &["objects[0].shape.radious", "unknown field `radious`"],
    );
    expect_err(
        &with("\"fov_y_deg\": 40", "\"fov_y_deg\": 40, \"fov\": 40"),
        &["camera.fov", "unknown field `fov`"],
    );
    expect_err(
        &with("\"ior\": 1.5", "\"ior\": 1.5, \"albedo\": [1, 1, 1]"),
        &["materials.glass.albedo", "unknown field"],
    );
}

#[test]
fn unknown_and_missing_types() {
    expect_err(
        &with("\"type\": \"sphere\"", "\"type\": \"cone\""),
        &[
            "objects[0].shape.type",
            "unknown shape type `cone`",
            "sphere",
        ],
    );
    expect_err(
        &with("\"type\": \"directional\"", "\"type\": \"area\""),
        &["lights[0].type", "unknown light type `area`"],
    );
    expect_err(
        &with("\"type\": \"dielectric\", ", ""),
        &["materials.glass", "missing field `type`"],
    );
}

#[test]
fn missing_fields() {
    expect_err(
        &with(", \"radius\": 1", ""),
        &["objects[0].shape", "missing field `radius`"],
    );
    expect_err(
        &with("\"name\": \"good\",", ""),
        &["(root)", "missing field `name`"],
    );
}

#[test]
fn material_references() {
    expect_err(
        &with(", \"material\": \"glass\"", ""),
        &["objects[0].material", "missing material name"],
    );
    expect_err(
        &with("\"material\": \"glass\"", "\"material\": \"glas\""),
        &[
            "objects[0].material",
            "unknown material `glas`",
            "glass, floor",
        ],
    );
    expect_err(
        &with(
            "\"floor\": {\"type\": \"diffuse\"",
            "\"glass\": {\"type\": \"dielectric\", \"ior\": 1.4}, \"floor\": {\"type\": \"diffuse\"",
        ),
        &["materials", "duplicate material name `glass`"],
    );
}

#[test]
fn radius_must_be_positive() {
    expect_err(
        &with("\"radius\": 1", "\"radius\": -1"),
        &[
            "objects[0].shape.radius",
            "expected a positive number, got -1",
        ],
    );
    expect_err(
        &with("\"radius\": 1", "\"radius\": 0"),
        &[
            "objects[0].shape.radius",
            "expected a positive number, got 0",
        ],
    );
    expect_err(
        &with("\"size\": [20, 20]", "\"size\": [20, 0]"),
        &["objects[1].shape.size[1]", "expected a positive number"],
    );
}

#[test]
fn out_of_range_numbers() {
    // serde_json rejects numbers beyond f64.
    expect_err(
        &with("\"radius\": 1", "\"radius\": 1e999"),
        &["objects[0].shape.radius", "number out of range", ":11:"],
    );
    expect_err(
        &with("\"fov_y_deg\": 40", "\"fov_y_deg\": -1e999"),
        &["camera.fov_y_deg", "number out of range"],
    );
    // Finite in f64 but beyond f32: also rejected by the parser, never turned into inf.
    expect_err(
        &with("\"radius\": 1", "\"radius\": 1e300"),
        &["objects[0].shape.radius", "number out of range"],
    );
    expect_err(
        &with("\"eye\": [0, 3, 5]", "\"eye\": [0, -1e300, 5]"),
        &["camera.eye[1]", "number out of range"],
    );
    // JSON has no NaN literal.
    expect_err(
        &with("\"radius\": 1", "\"radius\": NaN"),
        &["objects[0].shape", "expected value", ":11:"],
    );
    expect_err(
        &with("\"fov_y_deg\": 40", "\"fov_y_deg\": Infinity"),
        &["camera.fov_y_deg", "expected value"],
    );
}

#[test]
fn camera_checks() {
    for fov in ["0", "180", "-5"] {
        expect_err(
            &with("\"fov_y_deg\": 40", &format!("\"fov_y_deg\": {fov}")),
            &[
                "camera.fov_y_deg",
                "expected an angle in degrees in (0, 180)",
            ],
        );
    }
    expect_err(
        &with("\"width\": 64", "\"width\": 0"),
        &[
            "camera.width",
            "expected a size in pixels in 1..=16384, got 0",
        ],
    );
    expect_err(
        &with("\"height\": 48", "\"height\": 20000"),
        &["camera.height", "got 20000"],
    );
    expect_err(
        &with("\"width\": 64", "\"width\": -3"),
        &["camera.width", "invalid value"],
    );
    expect_err(
        &with("\"target\": [0, 0, 0]", "\"target\": [0, 3, 5]"),
        &["camera.target", "different from camera.eye"],
    );
    expect_err(
        &with("\"eye\": [0, 3, 5]", "\"eye\": [0, 3, 0]"),
        &["camera.up", "not parallel to the view direction"],
    );
    expect_err(
        &with("\"up\": [0, 1, 0]", "\"up\": [0, 0, 0]"),
        &["camera.up", "non-zero direction"],
    );
}

#[test]
fn light_checks() {
    expect_err(
        &with("\"direction\": [0, -1, 0]", "\"direction\": [0, 0, 0]"),
        &[
            "lights[0].direction",
            "expected a non-zero direction vector, got [0, 0, 0]",
        ],
    );
    expect_err(
        &with("\"irradiance\": [1, 1, 1]", "\"irradiance\": [1, -1, 1]"),
        &[
            "lights[0].irradiance[1]",
            "expected a non-negative number, got -1",
        ],
    );
    expect_err(
        &with(
            "\"lights\": [{\"type\": \"directional\", \"direction\": [0, -1, 0], \"irradiance\": [1, 1, 1]}]",
            "\"lights\": []",
        ),
        &["lights", "expected at least one light"],
    );
    let spot = |cone: &str, falloff: &str| {
        with(
            "{\"type\": \"directional\", \"direction\": [0, -1, 0], \"irradiance\": [1, 1, 1]}",
            &format!(
                "{{\"type\": \"spot\", \"position\": [0, 4, 0], \"direction\": [0, -1, 0], \
                 \"intensity\": [5, 5, 5], \"cone_deg\": {cone}{falloff}}}"
            ),
        )
    };
    load(&spot("30", ", \"falloff_deg\": 5")).expect("valid spot");
    expect_err(
        &spot("0", ""),
        &[
            "lights[0].cone_deg",
            "expected a half angle in degrees in (0, 90], got 0",
        ],
    );
    expect_err(&spot("91", ""), &["lights[0].cone_deg", "got 91"]);
    expect_err(
        &spot("30", ", \"falloff_deg\": 40"),
        &["lights[0].falloff_deg", "[0, cone_deg = 30], got 40"],
    );
    expect_err(
        &with("\"irradiance\": [1, 1, 1]", "\"intensity\": [1, 1, 1]"),
        &["lights[0]", "unknown field `intensity`"],
    );
}

#[test]
fn material_checks() {
    expect_err(
        &with("\"ior\": 1.5", "\"ior\": 0.9"),
        &[
            "materials.glass.ior",
            "expected an index of refraction >= 1, got 0.9",
        ],
    );
    expect_err(
        &with("\"albedo\": [0.8, 0.8, 0.8]", "\"albedo\": [0.8, 1.2, 0.8]"),
        &[
            "materials.floor.albedo[1]",
            "expected a value in [0, 1], got 1.2",
        ],
    );
    expect_err(
        &with(
            "\"floor\": {\"type\": \"diffuse\", \"albedo\": [0.8, 0.8, 0.8]}",
            "\"floor\": {\"type\": \"mirror\", \"reflectance\": [-0.1, 0.8, 0.8]}",
        ),
        &["materials.floor.reflectance[0]", "got -0.1"],
    );
}

#[test]
fn medium_checks() {
    let m = |g: &str, s: &str| {
        with(
            "\"materials\"",
            &format!(
                "\"medium\": {{\"sigma_s\": [{s}, 0.05, 0.05], \"sigma_a\": [0, 0, 0], \"g\": {g}}},\n  \"materials\""
            ),
        )
    };
    load(&m("0.3", "0.05")).expect("valid medium");
    expect_err(
        &m("1", "0.05"),
        &["medium.g", "expected a value in (-1, 1), got 1"],
    );
    expect_err(&m("-1", "0.05"), &["medium.g", "got -1"]);
    expect_err(&m("0", "-0.05"), &["medium.sigma_s[0]", "non-negative"]);
}

#[test]
fn shape_checks() {
    let hf = |res: &str, wave: &str| {
        with(
            "{\"type\": \"sphere\", \"center\": [0, 1.5, 0], \"radius\": 1}",
            &format!(
                "{{\"type\": \"heightfield\", \"center\": [0, 1, 0], \"size\": [4, 4], \
                 \"resolution\": {res}, \"waves\": [{wave}]}}"
            ),
        )
    };
    let ok_wave = "{\"amplitude\": 0.03, \"wavelength\": 0.7, \"direction\": [1, 0.3]}";
    load(&hf("[8, 8]", ok_wave)).expect("valid heightfield");
    expect_err(
        &hf("[1, 8]", ok_wave),
        &[
            "objects[0].shape.resolution[0]",
            "expected a vertex count in 2..=4096, got 1",
        ],
    );
    expect_err(
        &hf("[8, 5000]", ok_wave),
        &["objects[0].shape.resolution[1]", "got 5000"],
    );
    expect_err(
        &hf(
            "[8, 8]",
            "{\"amplitude\": 0.03, \"wavelength\": 0, \"direction\": [1, 0.3]}",
        ),
        &[
            "objects[0].shape.waves[0].wavelength",
            "expected a positive number, got 0",
        ],
    );
    expect_err(
        &hf(
            "[8, 8]",
            "{\"amplitude\": 0.03, \"wavelength\": 0.5, \"direction\": [0, 0]}",
        ),
        &["objects[0].shape.waves[0].direction", "non-zero direction"],
    );
    expect_err(
        &hf(
            "[8, 8]",
            "{\"amplitude\": 0.03, \"wavelength\": 0.5, \"direction\": [1, 0], \"speed\": 1}",
        ),
        &["objects[0].shape.waves[0].speed", "unknown field `speed`"],
    );
    expect_err(
        &with("\"normal\": [0, 1, 0]", "\"normal\": [0, 0, 0]"),
        &["objects[1].shape.normal", "non-zero direction"],
    );
    let cyl = |h: &str| {
        with(
            "{\"type\": \"sphere\", \"center\": [0, 1.5, 0], \"radius\": 1}",
            &format!(
                "{{\"type\": \"cylinder\", \"center\": [0, 0.25, 0], \"axis\": [0, 1, 0], \
                 \"radius\": 1, \"height\": {h}}}"
            ),
        )
    };
    load(&cyl("0.5")).expect("valid cylinder");
    expect_err(&cyl("-0.5"), &["objects[0].shape.height", "positive"]);
    expect_err(
        &with("\"objects\": [", "\"objects\": [], \"x\": ["),
        &["x", "unknown field"],
    );
}

#[test]
fn no_objects() {
    let json = GOOD[..GOOD.find("\"objects\"").expect("objects")].to_string() + "\"objects\": []}";
    expect_err(&json, &["objects", "expected at least one object"]);
}

#[test]
fn malformed_json_reports_line_and_column() {
    let err = expect_err(&with("\"radius\": 1}", "\"radius\": 1"), &[]);
    match err {
        SceneError::Syntax { line, column, .. } => {
            assert!(line >= 11 && column > 0, "line {line} column {column}");
        }
        other => panic!("expected a syntax error, got {other:?}"),
    }
    // The position is the file's, also for errors inside a shape.
    let err = expect_err(
        &with("\"radius\": 1", "\"radius\": 1,"),
        &["objects[0].shape", ":11:"],
    );
    assert!(matches!(err, SceneError::Syntax { .. }), "{err:?}");
    expect_err("{\"name\": \"x\",", &[":1:", "EOF"]);
    expect_err("[1, 2]", &["(root)", "expected a JSON object"]);
    expect_err(&format!("{GOOD} trailing"), &["trailing characters"]);
}

#[test]
fn empty_file() {
    for text in ["", "   \n  "] {
        let err = expect_err(text, &["empty"]);
        assert!(matches!(err, SceneError::Syntax { line: 1, .. }));
    }
}

#[test]
fn mesh_file_problems() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene_path = dir.path().join("scene.json");
    let mesh_scene = |path: &str, extra: &str| {
        with(
            "{\"type\": \"sphere\", \"center\": [0, 1.5, 0], \"radius\": 1}",
            &format!("{{\"type\": \"mesh\", \"path\": \"{path}\"{extra}}}"),
        )
    };
    let load_in_dir = |json: &str| Scene::from_json_str(json, &scene_path);

    let err = load_in_dir(&mesh_scene("meshes/missing.obj", "")).expect_err("missing file");
    let msg = err.to_string();
    assert!(matches!(err, SceneError::Mesh { .. }), "{err:?}");
    assert!(
        msg.contains("objects[0].shape.path")
            && msg.contains("missing.obj")
            && msg.contains("does not exist"),
        "{msg}"
    );

    std::fs::write(
        dir.path().join("bad.obj"),
        "v 0 0 0\nv 1 0 zero\nv 0 1 0\nf 1 2 3\n",
    )
    .expect("write");
    let err = load_in_dir(&mesh_scene("bad.obj", "")).expect_err("malformed obj");
    let msg = err.to_string();
    assert!(
        matches!(err, SceneError::Mesh { .. }) && msg.contains("objects[0].shape.path"),
        "{msg}"
    );

    std::fs::write(dir.path().join("empty.obj"), "# nothing\n").expect("write");
    let err = load_in_dir(&mesh_scene("empty.obj", "")).expect_err("empty obj");
    assert!(err.to_string().contains("no triangles"), "{err}");

    std::fs::write(dir.path().join("x.ply"), "ply\n").expect("write");
    let err = load_in_dir(&mesh_scene("x.ply", "")).expect_err("ply");
    assert!(
        err.to_string().contains("unsupported mesh format `.ply`"),
        "{err}"
    );

    std::fs::write(
        dir.path().join("tri.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 0 -1\nf 1 2 3\n",
    )
    .expect("write");
    load_in_dir(&mesh_scene("tri.obj", "")).expect("valid mesh");
    let err = load_in_dir(&mesh_scene("tri.obj", ", \"transform\": {\"scale\": 0}"))
        .expect_err("zero scale");
    assert!(
        err.to_string()
            .contains("objects[0].shape.transform.scale: expected a positive number, got 0"),
        "{err}"
    );
    let err = load_in_dir(&mesh_scene("tri.obj", ", \"transform\": {\"shear\": 1}"))
        .expect_err("unknown transform field");
    assert!(
        err.to_string().contains("objects[0].shape.transform.shear"),
        "{err}"
    );
}

#[test]
fn missing_scene_file_is_an_io_error() {
    let err = Scene::load(Path::new("/nonexistent/scene.json")).expect_err("io");
    assert!(matches!(err, SceneError::Io { .. }));
    assert!(
        err.to_string()
            .starts_with("/nonexistent/scene.json: cannot read")
    );
}

#[test]
fn camera_exposure_is_optional_and_positive() {
    assert_eq!(load(GOOD).expect("good").camera.exposure, None);
    let s = load(&with("\"height\": 48", "\"height\": 48, \"exposure\": 0.5")).expect("exposure");
    assert_eq!(s.camera.exposure, Some(0.5));
    for bad in ["0", "-2", "\"bright\""] {
        expect_err(
            &with(
                "\"height\": 48",
                &format!("\"height\": 48, \"exposure\": {bad}"),
            ),
            &["camera"],
        );
    }
    expect_err(
        &with("\"height\": 48", "\"height\": 48, \"exposure\": -2"),
        &["camera.exposure", "positive"],
    );
}
