//! Mesh loading: OBJ with and without normals, transforms, glTF materials.

use std::path::{Path, PathBuf};

use caustics_scene::{Material, Scene, Shape, Vec3};

fn scene_with_mesh(dir: &Path, shape: &str, material: Option<&str>) -> Result<Scene, String> {
    let material = material
        .map(|m| format!(", \"material\": \"{m}\""))
        .unwrap_or_default();
    let json = format!(
        r#"{{
  "name": "mesh_test",
  "camera": {{"eye": [0, 3, 5], "target": [0, 0, 0], "up": [0, 1, 0],
             "fov_y_deg": 40, "width": 64, "height": 48}},
  "lights": [{{"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1]}}],
  "materials": {{"floor": {{"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}},
                 "chrome": {{"type": "mirror", "reflectance": [0.9, 0.9, 0.9]}}}},
  "objects": [{{"shape": {shape}{material}}}]
}}"#
    );
    Scene::from_json_str(&json, &dir.join("scene.json")).map_err(|e| e.to_string())
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write");
    p
}

fn mesh_of(scene: &Scene, i: usize) -> &caustics_scene::Mesh {
    match &scene.objects[i].shape {
        Shape::Mesh(m) => m,
        other => panic!("expected a mesh, got {other:?}"),
    }
}

#[track_caller]
fn close(a: Vec3, b: Vec3) {
    assert!((a - b).length() < 1e-5, "{a} != {b}");
}

#[test]
fn obj_without_normals_gets_smooth_area_weighted_normals() {
    let dir = tempfile::tempdir().expect("tempdir");
    // Two triangles of a unit square in the z = 0 plane, CCW seen from +z, plus a
    // folded third triangle sharing the edge (1,0,0)-(1,1,0) and facing +x.
    write(
        dir.path(),
        "sq.obj",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 1 0 -1\nf 1 2 3\nf 1 3 4\nf 2 5 3\n",
    );
    let s = scene_with_mesh(
        dir.path(),
        r#"{"type": "mesh", "path": "sq.obj"}"#,
        Some("floor"),
    )
    .expect("load");
    let m = mesh_of(&s, 0);
    assert!(!m.normals_from_file);
    assert_eq!(m.normals.len(), m.positions.len());
    for n in &m.normals {
        assert!((n.length() - 1.0).abs() < 1e-5);
    }
    let at = |p: Vec3| {
        m.positions
            .iter()
            .position(|&q| (q - p).length() < 1e-6)
            .map(|i| m.normals[i])
            .expect("vertex")
    };
    close(at(Vec3::new(0.0, 1.0, 0.0)), Vec3::Z);
    // (1,1,0) touches both +z triangles (area 1/2 each) and the +x triangle (area 1/2).
    close(
        at(Vec3::new(1.0, 1.0, 0.0)),
        Vec3::new(1.0, 0.0, 2.0).normalize(),
    );
    // (1,0,0) touches one +z triangle (area 1/2) and the +x triangle (area 1/2).
    close(
        at(Vec3::new(1.0, 0.0, 0.0)),
        Vec3::new(1.0, 0.0, 1.0).normalize(),
    );
    // (0,0,0) touches both +z triangles.
    close(at(Vec3::ZERO), Vec3::Z);
}

#[test]
fn obj_normals_from_file_and_transform() {
    let dir = tempfile::tempdir().expect("tempdir");
    write(
        dir.path(),
        "tri.obj",
        "v 1 0 0\nv 0 1 0\nv 0 0 1\nvn 1 0 0\nvn 0 1 0\nvn 0 0 2\nf 1//1 2//2 3//3\n",
    );
    let load = |transform: &str| {
        let shape = format!(r#"{{"type": "mesh", "path": "tri.obj"{transform}}}"#);
        scene_with_mesh(dir.path(), &shape, Some("chrome")).expect("load")
    };
    let s = load("");
    let m = mesh_of(&s, 0);
    assert!(m.normals_from_file);
    close(m.positions[0], Vec3::X);
    close(m.normals[2], Vec3::Z); // normalized from the file's (0, 0, 2)
    assert!(s.material(&s.objects[0]).is_specular());

    // Scale 2, then Rz 90°, then translate (1, 0, 0): (1,0,0) -> (2,0,0) -> (0,2,0) -> (1,2,0).
    let s =
        load(r#", "transform": {"translate": [1, 0, 0], "rotate_deg": [0, 0, 90], "scale": 2}"#);
    let m = mesh_of(&s, 0);
    close(m.positions[0], Vec3::new(1.0, 2.0, 0.0));
    close(m.normals[0], Vec3::Y);
    close(m.positions[2], Vec3::new(1.0, 0.0, 2.0));
    close(m.normals[2], Vec3::Z);

    // XYZ order: Rx first, then Ry. (0,1,0) -Rx90-> (0,0,1) -Ry90-> (1,0,0).
    let s = load(r#", "transform": {"rotate_deg": [90, 90, 0]}"#);
    let m = mesh_of(&s, 0);
    close(m.positions[1], Vec3::X);
    close(m.normals[1], Vec3::X);

    // Bounds follow the transformed positions.
    let b = s.objects[0].shape.bounds();
    assert!(b.contains(Vec3::X));
    assert!(s.bounds().contains(m.positions[2]));
}

/// Standard base64 (the test builds glTF files with embedded `data:` buffers).
fn base64(bytes: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(A[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// A glTF with one node (translation (0, 1, 0) and `scale`) holding one triangle
/// (0,0,0), (1,0,0), (0,1,0) (CCW from +z) without normals, and the given material.
fn write_gltf(dir: &Path, name: &str, material: &str, scale: [f32; 3]) {
    let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let bytes: Vec<u8> = positions.iter().flat_map(|f| f.to_le_bytes()).collect();
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_materials_ior", "KHR_materials_transmission"],
  "scene": 0,
  "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0, "translation": [0, 1, 0], "scale": [{}, {}, {}]}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "material": 0}}]}}],
  "materials": [{material}],
  "buffers": [{{"byteLength": 36, "uri": "data:application/octet-stream;base64,{}"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                  "min": [0, 0, 0], "max": [1, 1, 0]}}]
}}"#,
        scale[0],
        scale[1],
        scale[2],
        base64(&bytes)
    );
    write(dir, name, &json);
}

#[test]
fn gltf_transmission_and_ior_make_a_dielectric() {
    let dir = tempfile::tempdir().expect("tempdir");
    write_gltf(
        dir.path(),
        "lens.gltf",
        r#"{"name": "glass", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1]},
            "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                           "KHR_materials_ior": {"ior": 1.45}}}"#,
        [1.0, 1.0, 1.0],
    );
    let s = scene_with_mesh(
        dir.path(),
        r#"{"type": "mesh", "path": "lens.gltf", "transform": {"translate": [2, 0, 0]}}"#,
        None,
    )
    .expect("load");
    assert_eq!(s.objects.len(), 1);
    let named = &s.materials[s.objects[0].material];
    assert_eq!(named.name, "lens/glass");
    assert_eq!(named.material, Material::Dielectric { ior: 1.45 });
    assert_eq!(s.materials.len(), 3, "appended after the file's materials");
    let m = mesh_of(&s, 0);
    assert!(!m.normals_from_file);
    // Node translation (0, 1, 0), then the object's translate (2, 0, 0).
    close(m.positions[1], Vec3::new(3.0, 1.0, 0.0));
    close(m.normals[0], Vec3::Z);

    // A "material" in the scene file overrides the glTF one.
    let s = scene_with_mesh(
        dir.path(),
        r#"{"type": "mesh", "path": "lens.gltf"}"#,
        Some("chrome"),
    )
    .expect("load");
    assert_eq!(s.materials[s.objects[0].material].name, "chrome");
    assert_eq!(s.materials.len(), 2);
}

#[test]
fn gltf_base_colour_makes_a_diffuse_and_mirroring_keeps_winding() {
    let dir = tempfile::tempdir().expect("tempdir");
    write_gltf(
        dir.path(),
        "plate.gltf",
        r#"{"pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.4, 0.6, 1], "metallicFactor": 0}}"#,
        [-1.0, 1.0, 1.0],
    );
    let s = scene_with_mesh(
        dir.path(),
        r#"{"type": "mesh", "path": "plate.gltf"}"#,
        None,
    )
    .expect("load");
    let named = &s.materials[s.objects[0].material];
    assert_eq!(named.name, "plate/0");
    assert_eq!(
        named.material,
        Material::Diffuse {
            albedo: Vec3::new(0.2, 0.4, 0.6)
        }
    );
    assert!(s.specular_bounds().is_none());
    let m = mesh_of(&s, 0);
    // Mirrored in x: the winding is flipped back so it stays CCW around the normals.
    let [a, b, c] = [0, 1, 2].map(|k| m.positions[m.indices[k] as usize]);
    assert!((b - a).cross(c - a).dot(m.normals[0]) > 0.0);
    close(m.positions[1], Vec3::new(-1.0, 1.0, 0.0));
}

#[test]
fn gltf_without_transmission_in_a_bad_file_is_a_mesh_error() {
    let dir = tempfile::tempdir().expect("tempdir");
    write(
        dir.path(),
        "broken.gltf",
        "{\"asset\": {\"version\": \"2.0\"}, \"scenes\": [",
    );
    let err = scene_with_mesh(
        dir.path(),
        r#"{"type": "mesh", "path": "broken.gltf"}"#,
        None,
    )
    .expect_err("broken glTF");
    assert!(
        err.contains("objects[0].shape.path") && err.contains("broken.gltf"),
        "{err}"
    );
}
