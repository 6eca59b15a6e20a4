//! Files the mesh tests build: a scene JSON naming a mesh, small OBJ and glTF files.

#![allow(dead_code, unreachable_pub)]

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use caustics_scene::{Limits, Scene, SceneError};

/// A scene with one mesh object (and a floor), as JSON text.
pub fn scene_json(mesh_path: &str, material: Option<&str>) -> String {
    let material = material
        .map(|m| format!(", \"material\": \"{m}\""))
        .unwrap_or_default();
    format!(
        r#"{{
  "name": "mesh_test",
  "camera": {{"eye": [0, 3, 5], "target": [0, 0, 0], "up": [0, 1, 0],
             "fov_y_deg": 40, "width": 64, "height": 48}},
  "lights": [{{"type": "directional", "direction": [0, -1, 0], "irradiance": [1, 1, 1]}}],
  "materials": {{"floor": {{"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}},
                 "chrome": {{"type": "mirror", "reflectance": [0.9, 0.9, 0.9]}}}},
  "objects": [{{"shape": {{"type": "mesh", "path": "{mesh_path}"}}{material}}},
              {{"shape": {{"type": "quad", "center": [0, 0, 0], "normal": [0, 1, 0], "size": [10, 10]}},
               "material": "floor"}}]
}}"#
    )
}

/// Writes `bytes` to `dir/name`.
pub fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).expect("write");
    p
}

/// Writes `scene.json` naming `mesh` into `dir` and loads it with `limits`, timing it.
pub fn load_mesh_scene(
    dir: &Path,
    mesh: &str,
    material: Option<&str>,
    limits: &Limits,
) -> (Result<Scene, SceneError>, Duration) {
    let scene = write(dir, "scene.json", scene_json(mesh, material));
    let t = Instant::now();
    let r = Scene::load_with_limits(&scene, limits);
    (r, t.elapsed())
}

/// Loads a scene naming `mesh` and returns the error message, asserting that it
/// names the scene file and the mesh file and came within a second.
#[track_caller]
pub fn refused(dir: &Path, mesh: &str, limits: &Limits) -> String {
    let (r, took) = load_mesh_scene(dir, mesh, Some("chrome"), limits);
    let msg = match r {
        Ok(_) => panic!("{mesh}: expected a refusal, got a scene"),
        Err(e) => e.to_string(),
    };
    assert!(
        took < Duration::from_secs(1),
        "{mesh}: took {took:?}: {msg}"
    );
    assert!(msg.contains("scene.json") && msg.contains(mesh), "{msg}");
    msg
}

/// Standard base64.
pub fn base64(bytes: &[u8]) -> String {
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

/// The binary payload of [`gltf_json`]: a unit square (4 positions, 4 normals) and six
/// u16 indices, 108 bytes.
pub fn square_bytes() -> Vec<u8> {
    let positions: [f32; 12] = [0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.];
    let normals: [f32; 12] = [0., 0., 1., 0., 0., 1., 0., 0., 1., 0., 0., 1.];
    let indices: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut b: Vec<u8> = positions
        .iter()
        .chain(&normals)
        .flat_map(|f| f.to_le_bytes())
        .collect();
    b.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    b
}

/// A valid glTF document (as a JSON value) of a square in two nodes (a parent with a
/// translation, a child with the mesh), its buffer given by `uri` (None: GLB BIN).
pub fn gltf_json(uri: Option<&str>) -> serde_json::Value {
    let mut buffer = serde_json::json!({"byteLength": 108});
    if let Some(u) = uri {
        buffer["uri"] = serde_json::Value::String(u.to_string());
    }
    serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"children": [1], "translation": [0, 1, 0]}, {"mesh": 0, "scale": [2, 2, 2]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.9, 0.9, 1], "metallicFactor": 1, "roughnessFactor": 0}}],
        "buffers": [buffer],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 96, "byteStride": 12},
            {"buffer": 0, "byteOffset": 96, "byteLength": 12}
        ],
        "accessors": [
            {"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 0, "byteOffset": 48, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 1, "byteOffset": 0, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ]
    })
}

/// The data URI of [`square_bytes`].
pub fn square_data_uri() -> String {
    format!(
        "data:application/octet-stream;base64,{}",
        base64(&square_bytes())
    )
}

/// A GLB container of `json` with `bin` as its BIN chunk.
pub fn glb(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).expect("json");
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = Vec::with_capacity(total);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(0x4E4F_534Au32.to_le_bytes());
    out.extend(&j);
    out.extend((b.len() as u32).to_le_bytes());
    out.extend(0x004E_4942u32.to_le_bytes());
    out.extend(&b);
    out
}

/// A small OBJ: a unit cube of quads with normals, in two objects.
pub const CUBE_OBJ: &str = "\
# cube
o top
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
vt 0 0
vt 1 0
vt 1 1
vn 0 0 -1
vn 0 0 1
vn 0 -1 0
vn 0 1 0
vn -1 0 0
vn 1 0 0
f 1//1 4//1 3//1 2//1
f 5/1/2 6/2/2 7/3/2 8/1/2
f 1//3 2//3 6//3 5//3
o bottom
f 4//4 8//4 7//4 3//4
f -8//5 -4//5 -1//5 -5//5
f 2//6 3//6 7//6 6//6
";
