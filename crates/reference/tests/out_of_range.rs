//! A scene built in code with geometry past `MAX_COORDINATE` is refused by
//! `Reference::new`, not left to panic in the BVH build (issue 18: an OBJ at 1e20 made
//! obvhs's CWBVH conversion panic on NaN costs; the scene loader now refuses such
//! files, this guards scenes that do not come from a file).

use caustics_reference::{Reference, ReferenceError};
use caustics_scene::{Scene, Shape, Vec3};

fn scene_with_triangle() -> Scene {
    // The mesh is read while the scene loads, so its folder can go when this returns.
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(
        dir.path().join("t.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .expect("write");
    let json = r#"{
      "name": "t",
      "camera": {"eye": [0, 3, 5], "target": [0, 0, 0], "up": [0, 1, 0],
                 "fov_y_deg": 40, "width": 8, "height": 6},
      "lights": [{"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1]}],
      "materials": {"chrome": {"type": "mirror", "reflectance": [0.9, 0.9, 0.9]},
                    "floor": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}},
      "objects": [{"shape": {"type": "mesh", "path": "t.obj"}, "material": "chrome"},
                  {"shape": {"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0],
                             "size": [4, 4]}, "material": "floor"}]
    }"#;
    Scene::from_json_str(json, &dir.path().join("s.json")).expect("scene")
}

#[test]
fn mesh_vertices_beyond_the_bound_or_nan_are_refused() {
    for bad in [Vec3::new(1e20, 0.0, 0.0), Vec3::new(f32::NAN, 0.0, 0.0)] {
        let mut scene = scene_with_triangle();
        let Shape::Mesh(m) = &mut scene.objects[0].shape else {
            panic!("not a mesh")
        };
        m.positions[1] = bad;
        let err = Reference::new(&scene).err().expect("refused");
        assert!(
            matches!(
                err,
                ReferenceError::OutOfRange {
                    object: 0,
                    kind: "mesh",
                    ..
                }
            ),
            "{err:?}"
        );
        assert!(err.to_string().contains("expected within ±1e6 m"), "{err}");
    }
    assert!(Reference::new(&scene_with_triangle()).is_ok());
}

#[test]
fn analytic_shapes_beyond_the_bound_are_refused() {
    let mut scene = scene_with_triangle();
    scene.objects[1].shape = Shape::Sphere {
        center: Vec3::new(0.0, 2e6, 0.0),
        radius: 1.0,
    };
    let err = Reference::new(&scene).err().expect("refused");
    assert!(
        matches!(
            err,
            ReferenceError::OutOfRange {
                object: 1,
                kind: "sphere",
                ..
            }
        ),
        "{err:?}"
    );
}
