//! The built-in scenes load, validate and hold what their benchmarks need.

use caustics_scene::{Light, Material, Scene, SceneError, Shape, builtin_names, resolve};

fn load_all() -> Vec<Scene> {
    builtin_names()
        .iter()
        .map(|n| {
            let path = resolve(n).unwrap_or_else(|e| panic!("{n}: {e}"));
            Scene::load(&path).unwrap_or_else(|e| panic!("{n}: {e}"))
        })
        .collect()
}

#[test]
fn every_builtin_scene_loads_and_has_a_caustic_generator() {
    let names = builtin_names();
    for expected in [
        "bumpy_glass",
        "fog_sphere",
        "ring",
        "sphere_on_plane",
        "sphere_over_water",
        "water_pool",
    ] {
        assert!(names.iter().any(|n| n == expected), "missing {expected}");
    }
    for scene in load_all() {
        assert!(
            scene.specular_objects().count() >= 1,
            "{}: no specular object",
            scene.name
        );
        assert!(scene.specular_bounds().is_some());
        assert!(
            !scene.description.is_empty(),
            "{}: no description",
            scene.name
        );
        assert!(!scene.description.contains('\n'));
        assert_eq!((scene.camera.width, scene.camera.height), (1024, 768));
        assert_eq!(
            scene.source.file_stem().and_then(|s| s.to_str()),
            Some(scene.name.as_str()),
            "scene name must match its file name"
        );
        let b = scene.bounds();
        assert!(!b.is_empty() && b.min.is_finite() && b.max.is_finite());
    }
}

#[test]
fn hashes_are_stable_and_distinct() {
    let scenes = load_all();
    let hashes: Vec<String> = scenes.iter().map(Scene::hash_hex).collect();
    for (s, h) in scenes.iter().zip(&hashes) {
        assert_eq!(h.len(), 16);
        assert_eq!(*h, s.hash_hex());
        let again = Scene::load(&s.source).expect("reload");
        assert_eq!(*h, again.hash_hex(), "{}: hash changed on reload", s.name);
    }
    let mut unique = hashes.clone();
    unique.sort();
    unique.dedup();
    assert_eq!(unique.len(), hashes.len());
}

#[test]
fn sphere_on_plane_focus_lands_near_the_floor() {
    let scene = Scene::load(&resolve("sphere_on_plane").expect("resolve")).expect("load");
    let Light::Directional { direction, .. } = scene.lights[0] else {
        panic!("expected a directional light")
    };
    let (center, radius, ior) = scene
        .objects
        .iter()
        .find_map(|o| match (&o.shape, scene.material(o)) {
            (Shape::Sphere { center, radius }, Material::Dielectric { ior }) => {
                Some((*center, *radius, *ior))
            }
            _ => None,
        })
        .expect("glass sphere");
    let focal = ior * radius / (2.0 * (ior - 1.0));
    let focus = center + focal * direction;
    assert!(focus.y.abs() < 0.1, "paraxial focus at y = {}", focus.y);
}

#[test]
fn fog_sphere_has_a_medium_and_water_scenes_a_heightfield() {
    let fog = Scene::load(&resolve("fog_sphere").expect("resolve")).expect("load");
    let m = fog.medium.as_ref().expect("medium");
    assert!(m.sigma_t().min_element() > 0.0);
    for name in ["water_pool", "sphere_over_water"] {
        let s = Scene::load(&resolve(name).expect("resolve")).expect("load");
        let hf = s
            .objects
            .iter()
            .find_map(|o| match &o.shape {
                Shape::Heightfield(h) => Some(h),
                _ => None,
            })
            .expect("heightfield");
        assert_eq!(hf.resolution, [256, 256]);
        // The camera looks from under the water surface.
        assert!(s.camera.eye.y < hf.center.y - hf.max_displacement());
    }
}

#[test]
fn bumpy_glass_mesh_has_file_normals_and_consistent_winding() {
    let s = Scene::load(&resolve("bumpy_glass").expect("resolve")).expect("load");
    let Shape::Mesh(m) = &s.objects[0].shape else {
        panic!("expected a mesh")
    };
    assert!(m.normals_from_file);
    let tris = m.indices.len() / 3;
    assert!((20_000..=40_000).contains(&tris), "{tris} triangles");
    for t in m.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
        let face = (b - a).cross(c - a);
        let n = m.normals[t[0] as usize] + m.normals[t[1] as usize] + m.normals[t[2] as usize];
        assert!(face.dot(n) > 0.0, "triangle wound against its normals");
    }
    let size = std::fs::metadata(&m.path).expect("obj").len();
    assert!(size < 3_000_000);
}

#[test]
fn resolve_names_and_paths() {
    let p = resolve("ring").expect("builtin");
    assert!(p.ends_with("scenes/ring.json"));
    assert_eq!(resolve(p.to_str().expect("utf8")).expect("path"), p);
    match resolve("no_such_scene") {
        Err(e @ SceneError::UnknownScene { .. }) => {
            let msg = e.to_string();
            assert!(
                msg.contains("no_such_scene") && msg.contains("water_pool"),
                "{msg}"
            );
        }
        other => panic!("expected UnknownScene, got {other:?}"),
    }
    assert!(matches!(
        resolve("missing/dir/x.json"),
        Err(SceneError::Io { .. })
    ));
}
