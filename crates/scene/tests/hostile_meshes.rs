//! Meshes from elsewhere are checked before use: each refusal names the scene file,
//! the mesh file, the element and what was expected, within a second (issue 18).

mod common;

use caustics_scene::{Limits, Shape};
use common::*;
use serde_json::json;

fn defaults() -> Limits {
    Limits::default()
}

#[test]
fn obj_with_coordinates_of_1e20_is_refused() {
    // Before the check, `caustics reference` panicked on this file inside obvhs's
    // CWBVH build (bvh2_to_cwbvh.rs, "distribute_left < 7"): the boxes' surface areas
    // overflow f32, the SAH costs become NaN.
    let dir = tempfile::tempdir().expect("tempdir");
    write(
        dir.path(),
        "huge.obj",
        "v 0 0 0\nv 1e20 0 0\nv 0 1e20 0\nf 1 2 3\n",
    );
    let msg = refused(dir.path(), "huge.obj", &defaults());
    assert!(
        msg.contains("vertex 1")
            && msg.contains("100000000000000000000")
            && msg.contains("within ±1e6 m"),
        "{msg}"
    );
}

#[test]
fn gltf_with_a_node_cycle_is_refused() {
    // Before the check, the node walk followed 0 -> 1 -> 0 -> … and allocated until
    // the machine ran out of memory.
    let dir = tempfile::tempdir().expect("tempdir");
    let mut g = gltf_json(Some(&square_data_uri()));
    g["nodes"][1]["children"] = json!([0]);
    write(dir.path(), "cycle.gltf", g.to_string());
    let msg = refused(dir.path(), "cycle.gltf", &defaults());
    assert!(
        msg.contains("node 0 is listed among its own descendants (children 0 -> 1 -> 0)"),
        "{msg}"
    );

    // A node that is its own child.
    g["nodes"][1]["children"] = json!([1]);
    write(dir.path(), "self.gltf", g.to_string());
    let msg = refused(dir.path(), "self.gltf", &defaults());
    assert!(msg.contains("(children 1 -> 1)"), "{msg}");
}

#[test]
fn valid_gltf_and_glb_load_with_node_transforms() {
    let dir = tempfile::tempdir().expect("tempdir");
    write(
        dir.path(),
        "sq.gltf",
        gltf_json(Some(&square_data_uri())).to_string(),
    );
    write(dir.path(), "sq.bin", square_bytes());
    write(
        dir.path(),
        "ext.gltf",
        gltf_json(Some("sq.bin")).to_string(),
    );
    write(dir.path(), "sq.glb", glb(&gltf_json(None), &square_bytes()));
    for name in ["sq.gltf", "ext.gltf", "sq.glb"] {
        let (r, _) = load_mesh_scene(dir.path(), name, None, &defaults());
        let s = r.unwrap_or_else(|e| panic!("{name}: {e}"));
        let Shape::Mesh(m) = &s.objects[0].shape else {
            panic!("{name}: not a mesh")
        };
        // Scale 2 at the child, then the parent's translation (0, 1, 0).
        assert_eq!(
            m.positions[2],
            caustics_scene::Vec3::new(2.0, 3.0, 0.0),
            "{name}"
        );
        assert_eq!(m.indices.len(), 6);
        assert!(m.normals_from_file);
        assert_eq!(m.degenerate_dropped, 0);
    }
}

/// A change to a glTF document.
type Mutation = Box<dyn Fn(&mut serde_json::Value)>;

/// Each mutation of the valid square glTF and the message it must give.
#[test]
fn gltf_structure_problems_are_refused_by_name() {
    let dir = tempfile::tempdir().expect("tempdir");
    write(dir.path(), "sq.bin", square_bytes());
    let outside = tempfile::tempdir().expect("tempdir");
    write(outside.path(), "secret.bin", square_bytes());
    let secret = outside.path().join("secret.bin");
    let cases: Vec<(&str, Mutation, &str)> = vec![
        (
            "uri up and out",
            Box::new(|g| g["buffers"][0]["uri"] = json!("../../../../../../etc/passwd")),
            "paths may not leave the scene's folder",
        ),
        (
            "absolute uri",
            Box::new(move |g| g["buffers"][0]["uri"] = json!(secret.display().to_string())),
            "expected a relative path",
        ),
        (
            "file: uri",
            Box::new(|g| g["buffers"][0]["uri"] = json!("file:///etc/passwd")),
            "no URI schemes",
        ),
        (
            "http uri",
            Box::new(|g| g["buffers"][0]["uri"] = json!("http://example.com/a.bin")),
            "no URI schemes",
        ),
        (
            "bad base64",
            Box::new(|g| {
                g["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,AAA!")
            }),
            "expected A-Z",
        ),
        (
            "not base64",
            Box::new(|g| g["buffers"][0]["uri"] = json!("data:text/plain,hello")),
            "expected base64",
        ),
        (
            "byteLength past the data",
            Box::new(|g| g["buffers"][0]["byteLength"] = json!(4096)),
            "buffer 0: byteLength 4096",
        ),
        (
            "count past the view",
            Box::new(|g| {
                g["accessors"][0]["count"] = json!(9);
                g["accessors"][1]["count"] = json!(9);
            }),
            "accessor 0 (POSITION of mesh 0 primitive 0 (at node 1)): byteOffset 0 + 9 elements of 12 bytes at stride 12: expected within its bufferView 0 of byteLength 96",
        ),
        (
            "count past the limit",
            Box::new(|g| {
                g["accessors"][0]["count"] = json!(1u64 << 40);
                g["accessors"][1]["count"] = json!(1u64 << 40);
            }),
            "vertices in the mesh file (reached at mesh 0 primitive 0 (at node 1)): 1099511627776, more than the limit of 8388608 (raise it with --max-mesh-vertices",
        ),
        (
            "count 0",
            Box::new(|g| g["accessors"][2]["count"] = json!(0)),
            "count 0: expected at least 1",
        ),
        (
            "stride below the element",
            Box::new(|g| g["bufferViews"][0]["byteStride"] = json!(8)),
            "byteStride 8",
        ),
        (
            "stride not a multiple of 4",
            Box::new(|g| g["bufferViews"][0]["byteStride"] = json!(13)),
            "byteStride 13",
        ),
        (
            "stride on indices",
            Box::new(|g| g["bufferViews"][1]["byteStride"] = json!(4)),
            "a byteStride on an index view",
        ),
        (
            "integer positions",
            Box::new(|g| g["accessors"][0]["componentType"] = json!(5121)),
            "expected VEC3 of FLOAT",
        ),
        (
            "float indices",
            Box::new(|g| g["accessors"][2]["componentType"] = json!(5126)),
            "expected SCALAR of UNSIGNED_BYTE",
        ),
        (
            "unknown component type",
            Box::new(|g| g["accessors"][2]["componentType"] = json!(9999)),
            "not a valid glTF file",
        ),
        (
            "view past the buffer",
            Box::new(|g| g["bufferViews"][1]["byteOffset"] = json!(100)),
            "expected within buffer 0",
        ),
        (
            "index out of range",
            Box::new(|g| {
                g["accessors"][2]["count"] = json!(3);
                g["accessors"][2]["byteOffset"] = json!(0);
                g["accessors"][1]["count"] = json!(4);
                g["accessors"][0]["count"] = json!(2);
                g["accessors"][1]["count"] = json!(2);
            }),
            "index 2 out of range",
        ),
        (
            "indices not a multiple of 3",
            Box::new(|g| g["accessors"][2]["count"] = json!(4)),
            "expected a multiple of 3",
        ),
        (
            "points",
            Box::new(|g| g["meshes"][0]["primitives"][0]["mode"] = json!(0)),
            "expected Triangles",
        ),
        (
            "node with two parents",
            Box::new(|g| {
                g["nodes"] = json!([{"children": [2]}, {"children": [2]}, {"mesh": 0}]);
                g["scenes"][0]["nodes"] = json!([0, 1]);
            }),
            "at most one parent",
        ),
        (
            "root listed twice",
            Box::new(|g| g["scenes"][0]["nodes"] = json!([0, 0])),
            "met twice",
        ),
        (
            "singular node",
            Box::new(|g| g["nodes"][1]["scale"] = json!([0, 1, 1])),
            "singular",
        ),
        (
            "overflowing node transforms",
            Box::new(|g| {
                g["nodes"][0]["scale"] = json!([10, 10, 10]);
                g["nodes"][1]["scale"] = json!([3e38, 3e38, 3e38]);
            }),
            "the transform has a non-finite entry",
        ),
        (
            "number beyond f32",
            Box::new(|g| g["nodes"][1]["translation"] = json!([1e39, 0, 0])),
            "number out of range",
        ),
        (
            "huge node scale",
            Box::new(|g| g["nodes"][1]["scale"] = json!([1e10, 1e10, 1e10])),
            "within ±1e6 m",
        ),
        (
            "no mesh",
            Box::new(|g| {
                if let Some(n) = g["nodes"][1].as_object_mut() {
                    n.remove("mesh");
                }
            }),
            "no mesh primitive",
        ),
        (
            "no scene",
            Box::new(|g| {
                if let Some(n) = g.as_object_mut() {
                    n.remove("scene");
                    n.remove("scenes");
                }
            }),
            "no scene",
        ),
        (
            "sparse",
            Box::new(
                |g| g["accessors"][0]["sparse"] = json!({"count": 1, "indices": {"bufferView": 1, "componentType": 5123}, "values": {"bufferView": 0}}),
            ),
            "sparse",
        ),
        (
            "missing child",
            Box::new(|g| g["nodes"][0]["children"] = json!([7])),
            "not a valid glTF file",
        ),
    ];
    for (k, (what, mutate, expected)) in cases.iter().enumerate() {
        let mut g = gltf_json(Some("sq.bin"));
        mutate(&mut g);
        let name = format!("case{k}.gltf");
        write(dir.path(), &name, g.to_string());
        let msg = refused(dir.path(), &name, &defaults());
        assert!(
            msg.contains(expected),
            "{what}: expected `{expected}` in: {msg}"
        );
    }
}

#[test]
fn node_depth_is_limited() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut g = gltf_json(Some(&square_data_uri()));
    let n = 300;
    let nodes: Vec<serde_json::Value> = (0..n)
        .map(|i| {
            if i + 1 < n {
                json!({"children": [i + 1]})
            } else {
                json!({"mesh": 0})
            }
        })
        .collect();
    g["nodes"] = json!(nodes);
    write(dir.path(), "deep.gltf", g.to_string());
    let msg = refused(dir.path(), "deep.gltf", &defaults());
    assert!(
        msg.contains("depth of the node hierarchy") && msg.contains("max_node_depth"),
        "{msg}"
    );
    let deep_ok = Limits {
        max_node_depth: 400,
        ..defaults()
    };
    let (r, _) = load_mesh_scene(dir.path(), "deep.gltf", None, &deep_ok);
    assert!(r.is_ok(), "{:?}", r.err().map(|e| e.to_string()));
}

#[test]
fn glb_container_problems_are_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let good = glb(&gltf_json(None), &square_bytes());
    let mut cases: Vec<(Vec<u8>, &str)> = Vec::new();
    let mut short = good.clone();
    short[8..12].copy_from_slice(&4u32.to_le_bytes()); // length under the header's 12
    cases.push((short, "length 4: expected 20.."));
    let mut long = good.clone();
    long[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
    cases.push((long, "length 4294967295"));
    let mut chunk = good.clone();
    chunk[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    cases.push((chunk, "GLB chunk 0: chunkLength 4294967295"));
    let mut version = good.clone();
    version[4] = 1;
    cases.push((version, "version 1: expected 2"));
    cases.push((good[..10].to_vec(), "10 bytes: expected 12"));
    for (k, (bytes, expected)) in cases.iter().enumerate() {
        let name = format!("c{k}.glb");
        write(dir.path(), &name, bytes);
        let msg = refused(dir.path(), &name, &defaults());
        assert!(msg.contains(expected), "expected `{expected}` in: {msg}");
    }
}

#[test]
fn obj_problems_are_refused_with_their_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let cases = [
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/99999999999999999999/1 2 3\n",
            "line 4, corner `1/99999999999999999999/1`: texture coordinate index",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
            "line 4, corner `4`: vertex index `4` out of range: expected 1..=3",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9223372036854775808\n",
            "vertex index `-9223372036854775808` out of range",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 0 2\n",
            "vertex index `0` out of range",
        ),
        (
            "v 0 0 0\nv 1 0 0\nf 1 2\n",
            "line 3: face with 2 corners: expected at least 3",
        ),
        (
            "v 0 0 0\nv 1 0 NaN\nv 0 1 0\nf 1 2 3\n",
            "vertex 1: position (NaN, NaN, NaN) (in the file (1, 0, NaN))",
        ),
        (
            "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n",
            "line 2: expected `v` and 3 numbers",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nf 1//1 2//1 3//1\n",
            "normal (0, 0, 0): expected a finite non-zero vector",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n",
            "has no triangles (2 degenerate or zero-area faces dropped)",
        ),
        ("# nothing\n", "has no triangles"),
    ];
    write(dir.path(), "latin1.obj", b"v 0 0 0\n# caf\xe9\n");
    let msg = refused(dir.path(), "latin1.obj", &defaults());
    assert!(msg.contains("line 2: expected UTF-8 text"), "{msg}");
    for (k, (text, expected)) in cases.iter().enumerate() {
        let name = format!("c{k}.obj");
        write(dir.path(), &name, text);
        let msg = refused(dir.path(), &name, &defaults());
        assert!(msg.contains(expected), "expected `{expected}` in: {msg}");
    }
}

#[test]
fn obj_degenerate_faces_are_dropped_and_counted_and_lines_ignored() {
    let dir = tempfile::tempdir().expect("tempdir");
    write(
        dir.path(),
        "d.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\nf 3 3 1\nl 1 2\np 1\n",
    );
    let (r, _) = load_mesh_scene(dir.path(), "d.obj", Some("chrome"), &defaults());
    let s = r.expect("load");
    let Shape::Mesh(m) = &s.objects[0].shape else {
        panic!("not a mesh")
    };
    assert_eq!(m.indices.len(), 3);
    assert_eq!(m.degenerate_dropped, 2);
}

#[test]
fn limits_are_stated_and_can_be_raised() {
    let dir = tempfile::tempdir().expect("tempdir");
    write(dir.path(), "cube.obj", CUBE_OBJ);
    let tight = Limits {
        max_mesh_triangles: 4,
        ..defaults()
    };
    let msg = refused(dir.path(), "cube.obj", &tight);
    assert!(
        msg.contains("triangles in the mesh file") && msg.contains("max_mesh_triangles"),
        "{msg}"
    );
    let tight = Limits {
        max_scene_vertices: 10,
        ..defaults()
    };
    let msg = refused(dir.path(), "cube.obj", &tight);
    assert!(msg.contains("max_scene_vertices"), "{msg}");
    let tight = Limits {
        max_file_bytes: 100,
        ..defaults()
    };
    let msg = refused(dir.path(), "cube.obj", &tight);
    assert!(
        msg.contains("bytes in") && msg.contains("max_file_bytes"),
        "{msg}"
    );
    let (r, _) = load_mesh_scene(dir.path(), "cube.obj", Some("chrome"), &defaults());
    let s = r.expect("cube");
    assert_eq!(
        s.objects[0]
            .shape
            .triangulate(&Default::default())
            .triangle_count(),
        12
    );

    // All the buffers of a glTF file count against max_file_bytes.
    let mut big = square_bytes();
    big.resize(5000, 0);
    write(dir.path(), "big.bin", &big);
    let mut g = gltf_json(Some("big.bin"));
    g["buffers"][0]["byteLength"] = json!(5000);
    write(dir.path(), "big.gltf", g.to_string());
    let tight = Limits {
        max_file_bytes: 3000,
        ..defaults()
    };
    let msg = refused(dir.path(), "big.gltf", &tight);
    assert!(
        msg.contains("big.bin: 5000, more than the limit of 3000"),
        "{msg}"
    );

    // Instances count: the square placed by 3 nodes is 6 triangles.
    let mut g = gltf_json(Some(&square_data_uri()));
    g["nodes"] = json!([{"mesh": 0}, {"mesh": 0, "translation": [3, 0, 0]}, {"mesh": 0, "translation": [6, 0, 0]}]);
    g["scenes"][0]["nodes"] = json!([0, 1, 2]);
    write(dir.path(), "three.gltf", g.to_string());
    let tight = Limits {
        max_mesh_triangles: 5,
        ..defaults()
    };
    let msg = refused(dir.path(), "three.gltf", &tight);
    assert!(msg.contains("mesh 0 primitive 0 (at node 2)"), "{msg}");
}

#[test]
fn analytic_shapes_beyond_the_coordinate_bound_are_refused() {
    let json = scene_json("x.obj", None).replace(
        r#"{"type": "mesh", "path": "x.obj"}"#,
        r#"{"type": "sphere", "center": [1e20, 0, 0], "radius": 1}"#,
    );
    let err = caustics_scene::Scene::from_json_str(&json, std::path::Path::new("s.json"))
        .expect_err("far sphere");
    let msg = err.to_string();
    assert!(
        msg.starts_with("s.json: objects[0].shape: the shape reaches") && msg.contains("±1e6 m"),
        "{msg}"
    );
}
