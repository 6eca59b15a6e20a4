//! Time in scene files: motions pose the rest geometry at any instant, waves travel
//! at their phase speed, old files keep their hashes, and bad motions are refused with
//! the JSON path of the bad value.

use std::path::Path;

use caustics_scene::{GRAVITY_M_S2, Light, Scene, SceneError, Shape, Vec3, builtin_dir};

/// A rolling glass ball, a spot light circling above it and a travelling wave.
const MOVING: &str = r#"{
  "name": "moving",
  "time": 0.5,
  "camera": {"eye": [0, 3, 5], "target": [0, 0, 0], "up": [0, 1, 0],
             "fov_y_deg": 40, "width": 64, "height": 48},
  "lights": [{"type": "spot", "position": [1, 4, 0], "direction": [0, -1, 0],
              "intensity": [10, 10, 10], "cone_deg": 30,
              "motion": {"angular_velocity_deg": [0, 90, 0], "pivot": [0, 4, 0]}}],
  "materials": {
    "glass": {"type": "dielectric", "ior": 1.5},
    "water": {"type": "dielectric", "ior": 1.33},
    "floor": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}
  },
  "objects": [
    {"shape": {"type": "sphere", "center": [0, 1, 0], "radius": 1}, "material": "glass",
     "motion": {"velocity": [0.4, 0, 0], "angular_velocity_deg": [0, 0, -22.918]}},
    {"shape": {"type": "heightfield", "center": [0, 3, 0], "size": [2, 2], "resolution": [8, 8],
               "waves": [{"amplitude": 0.02, "wavelength": 0.5, "direction": [1, 0]},
                         {"amplitude": 0.01, "wavelength": 0.8, "direction": [0, 1], "speed_m_s": 0.25}]},
     "material": "water"},
    {"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [20, 20]}, "material": "floor",
     "motion": {"keyframes": [{"time": 0, "translate": [0, 0, 0]}, {"time": 1, "translate": [0, -1, 0]}]}}
  ]
}"#;

fn load(json: &str) -> Result<Scene, SceneError> {
    Scene::from_json_str(json, Path::new("scenes/moving.json"))
}

fn sphere_center(s: &Scene) -> Vec3 {
    match s.objects[0].shape {
        Shape::Sphere { center, .. } => center,
        _ => panic!("object 0 is the sphere"),
    }
}

#[test]
fn a_scene_is_posed_at_its_time_and_at_any_other() -> Result<(), SceneError> {
    let scene = load(MOVING)?;
    assert!(scene.is_animated());
    assert_eq!(scene.time, 0.5);
    // The file's "time": 0.5 s of 0.4 m/s.
    assert!((sphere_center(&scene) - Vec3::new(0.2, 1.0, 0.0)).length() < 1e-6);
    let at2 = scene.at_time(2.0)?;
    assert!((sphere_center(&at2) - Vec3::new(0.8, 1.0, 0.0)).length() < 1e-6);
    // Posing is from the rest geometry, not from the last pose: 2 s then 0.5 s again.
    assert_eq!(at2.at_time(0.5)?, scene);
    // The keyframed floor: halfway down at 0.5 s, held at the last key after 1 s.
    let floor_y = |s: &Scene| match s.objects[2].shape {
        Shape::Quad { center, .. } => center.y,
        _ => panic!("object 2 is the floor"),
    };
    assert!((floor_y(&scene) + 0.5).abs() < 1e-6);
    assert!((floor_y(&at2) + 1.0).abs() < 1e-6);
    // The spot light circles its pivot at 90°/s: a quarter turn in 1 s.
    let at1 = scene.at_time(1.0)?;
    match &at1.lights[0] {
        Light::Spot {
            position,
            direction,
            ..
        } => {
            assert!((*position - Vec3::new(0.0, 4.0, -1.0)).length() < 1e-5);
            assert!((*direction - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-6);
        }
        other => panic!("expected the spot light, got {other:?}"),
    }
    Ok(())
}

#[test]
fn waves_travel_at_their_phase_speed() -> Result<(), SceneError> {
    let scene = load(MOVING)?;
    let field = |s: &Scene| match &s.objects[1].shape {
        Shape::Heightfield(f) => f.clone(),
        _ => panic!("object 1 is the heightfield"),
    };
    let (t0, t1) = (scene.at_time(0.0)?, scene.at_time(0.3)?);
    let (f0, f1) = (field(&t0), field(&t1));
    // Wave 0 alone (the other runs along z): deep water, c = √(g/k) = √(g·λ/2π).
    let c = (GRAVITY_M_S2 * 0.5 / std::f32::consts::TAU).sqrt();
    for x in [-0.7f32, -0.1, 0.35, 0.9] {
        let ahead = f1.height(x + c * 0.3, 0.0) - f1.waves[1].amplitude * f1.waves[1].phase.sin();
        let now = f0.height(x, 0.0) - f0.waves[1].amplitude * f0.waves[1].phase.sin();
        assert!(
            (ahead - now).abs() < 1e-5,
            "x = {x}: the crest should move {c} m/s along +x ({ahead} vs {now})"
        );
    }
    // Wave 1 has a given speed of 0.25 m/s along +z.
    let w1 = |f: &caustics_scene::Heightfield, z: f32| {
        let w = &f.waves[1];
        w.amplitude * (w.wavenumber() * z + w.phase).sin()
    };
    for z in [-0.4f32, 0.2, 0.6] {
        assert!((w1(&f1, z + 0.25 * 0.3) - w1(&f0, z)).abs() < 1e-6);
    }
    Ok(())
}

#[test]
fn still_scenes_and_t_zero_keep_their_hashes() -> Result<(), SceneError> {
    // Hashes of the built-ins at t = 0, as committed results recorded them before
    // scenes had time (results/reproduce/raster-paths, liktor-table1).
    for (name, hash) in [
        ("water_pool", "745888da46eb2ea5"),
        ("sphere_on_plane", "3e7f171c2a996ad4"),
        ("sphere_over_water", "a670a56c40e90ef9"),
        ("ring", "e87b49de795ff13a"),
    ] {
        let scene = Scene::load(&builtin_dir().join(format!("{name}.json")))?;
        assert_eq!(scene.hash_hex(), hash, "{name}");
        assert_eq!(scene.at_time(0.0)?.hash_hex(), hash, "{name}");
    }
    // A still scene looks the same at every instant, so it keeps one hash (one
    // reference); a moving one is another frame at every other instant.
    let still = Scene::load(&builtin_dir().join("sphere_on_plane.json"))?;
    assert!(!still.is_animated());
    assert_eq!(still.at_time(1.5)?.hash_hex(), still.hash_hex());
    let water = Scene::load(&builtin_dir().join("water_pool.json"))?;
    assert!(water.is_animated(), "water_pool's waves travel");
    assert_ne!(water.at_time(0.5)?.hash_hex(), water.hash_hex());
    // A file without motion fields hashes like the same file with them, posed at 0.
    let moving = load(MOVING)?.at_time(0.0)?;
    let bare = load(
        &MOVING
            .replace(r#""time": 0.5,"#, "")
            .replace(
                r#",
              "motion": {"angular_velocity_deg": [0, 90, 0], "pivot": [0, 4, 0]}"#,
                "",
            )
            .replace(
                r#",
     "motion": {"velocity": [0.4, 0, 0], "angular_velocity_deg": [0, 0, -22.918]}"#,
                "",
            )
            .replace(
                r#",
     "motion": {"keyframes": [{"time": 0, "translate": [0, 0, 0]}, {"time": 1, "translate": [0, -1, 0]}]}"#,
                "",
            ),
    )
    ?;
    assert!(bare.is_animated(), "its waves still travel");
    assert_eq!(
        bare.animation.as_ref().map(|a| a.object_motion.clone()),
        Some(vec![None; 3])
    );
    assert_eq!(moving.hash_hex(), bare.hash_hex());
    Ok(())
}

#[track_caller]
fn expect_err(json: &str, parts: &[&str]) {
    let err = match load(json) {
        Ok(_) => panic!("expected an error containing {parts:?}"),
        Err(e) => e.to_string(),
    };
    for p in parts {
        assert!(err.contains(p), "{err:?} should contain {p:?}");
    }
}

#[test]
fn bad_motions_name_the_field() -> Result<(), SceneError> {
    let floor_motion = r#""motion": {"keyframes": [{"time": 0, "translate": [0, 0, 0]}, {"time": 1, "translate": [0, -1, 0]}]}"#;
    expect_err(
        &MOVING.replace(
            floor_motion,
            r#""motion": {"angular_velocity_deg": [10, 0, 0]}"#,
        ),
        &[
            "scenes/moving.json",
            "objects[2].motion",
            "a quad moves by translation only",
        ],
    );
    expect_err(
        &MOVING.replace(
            floor_motion,
            r#""motion": {"keyframes": [{"time": 1}, {"time": 1}]}"#,
        ),
        &[
            "objects[2].motion.keyframes[1].time",
            "after the previous keyframe's 1 s",
        ],
    );
    expect_err(
        &MOVING.replace(floor_motion, r#""motion": {"keyframes": []}"#),
        &["objects[2].motion.keyframes", "expected 1..=4096 keyframes"],
    );
    expect_err(
        &MOVING.replace(
            floor_motion,
            r#""motion": {"keyframes": [{"time": 0}], "velocity": [1, 0, 0]}"#,
        ),
        &["objects[2].motion", "not both"],
    );
    expect_err(
        &MOVING.replace(floor_motion, r#""motion": {}"#),
        &["objects[2].motion", "expected `velocity`"],
    );
    expect_err(
        &MOVING.replace(floor_motion, r#""motion": {"speed": 1}"#),
        &["objects[2]", "unknown field `speed`"],
    );
    expect_err(
        &MOVING.replace(r#""time": 0.5"#, r#""time": 1e9"#),
        &["time", "expected a time in seconds"],
    );
    expect_err(
        &MOVING.replace(r#""speed_m_s": 0.25"#, r#""speed_m_s": 1e9"#),
        &["objects[1].shape.waves[1].speed_m_s", "phase speed"],
    );
    // A directional light has no position to move.
    let directional = MOVING.replace(
        r#"{"type": "spot", "position": [1, 4, 0], "direction": [0, -1, 0],
              "intensity": [10, 10, 10], "cone_deg": 30,"#,
        r#"{"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1],"#,
    );
    assert!(load(&directional).is_ok(), "a directional light may turn");
    expect_err(
        &directional.replace(
            r#""angular_velocity_deg": [0, 90, 0], "pivot": [0, 4, 0]"#,
            r#""velocity": [1, 0, 0]"#,
        ),
        &["lights[0].motion", "a directional light has no position"],
    );
    // Posed far in time, a fast ball leaves the coordinate range.
    let scene = load(&MOVING.replace("[0.4, 0, 0]", "[20, 0, 0]"))?;
    let err = match scene.at_time(9.0e4) {
        Ok(_) => panic!("posed at 9e4 s the ball is 1.8e6 m away"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("objects[0].motion") && err.contains("at time 90000 s"),
        "{err}"
    );
    let err = match scene.at_time(f32::NAN) {
        Ok(_) => panic!("NaN is no instant"),
        Err(e) => e.to_string(),
    };
    assert!(err.contains("time") && err.contains("NaN"), "{err}");
    Ok(())
}
