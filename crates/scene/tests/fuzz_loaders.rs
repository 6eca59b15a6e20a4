//! Seeded fuzzing of the mesh loaders (OBJ, glTF, GLB) and of the scene parser
//! (issue 18): a few hundred mutations of valid files, each loaded through
//! `Scene::load` under `catch_unwind`. Every load must return (no panic) within a
//! bounded time, and every error must name the scene file (and the mesh file, for a
//! mesh error) with a non-empty reason.
//!
//! The generator is SplitMix64 (`common/split_mix.rs`, shared with the harness's parser
//! fuzz test), rather than `rand_xoshiro` or `proptest`: the mutations need only a
//! seeded stream of integers, and a new dev-dependency would change the workspace's
//! Cargo.lock.
//! Run with `cargo test -p caustics-scene --test fuzz_loaders -- --nocapture` to see
//! the counts; `FUZZ_SEED=<n>` picks another seed (default 18).

mod common;
#[path = "common/split_mix.rs"]
mod split_mix;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;
use std::time::{Duration, Instant};

use caustics_scene::{Scene, SceneError, builtin_dir};
use common::*;
use serde_json::{Value, json};
use split_mix::{SplitMix, env_or};

/// The longest one load may take (debug build, 2 busy cores; loads take milliseconds).
const MAX_LOAD: Duration = Duration::from_secs(5);

/// Numbers that break things: NaN, infinities, huge, negative zero, huge indices.
const NUMBERS: &[&str] = &[
    "NaN",
    "nan",
    "inf",
    "-inf",
    "1e30",
    "-1e30",
    "1e20",
    "3.5e38",
    "1e39",
    "-0",
    "0",
    "-1",
    "4294967295",
    "4294967296",
    "-2147483648",
    "99999999999999999999",
    "1e-45",
    "2",
];

/// Lines an OBJ from elsewhere may hold.
const OBJ_LINES: &[&str] = &[
    "f 1 2 99999999999",
    "f 1 2",
    "f 1",
    "f 0 1 2",
    "f -1 -2 -3",
    "f -100 1 2",
    "f 1/2/3/4 1 2",
    "f 1/99999999999999999999/1 2 3",
    "f 1//99 2//1 3//1",
    "v 1e30 1e30 1e30",
    "v NaN 0 0",
    "v 1 2",
    "v 1 2 3 0",
    "v 1 2 3 4 5",
    "vn 0 0 0",
    "vn 1e38 1e38 1e38",
    "vt 0",
    "mtllib ../../../../etc/passwd",
    "usemtl nothing",
    "o",
    "g",
    "l 1 2 3",
    "p 1",
    "s off",
    "f 1 1 1",
    "f 1 2 3 4 5 6 7 8 9 10 11 12",
];

/// Text mutations: bit flips, truncation, number replacement, line edits.
fn mutate_text(rng: &mut SplitMix, data: &[u8], extra_lines: &[&str]) -> (Vec<u8>, &'static str) {
    let mut d = data.to_vec();
    match rng.below(7) {
        0 => {
            for _ in 0..1 + rng.below(4) {
                if !d.is_empty() {
                    let i = rng.below(d.len());
                    d[i] ^= 1 << rng.below(8);
                }
            }
            (d, "bit flips")
        }
        1 => {
            d.truncate(rng.below(d.len() + 1));
            (d, "truncation")
        }
        2 => {
            let spans = number_spans(&d);
            if spans.is_empty() {
                return (d, "number replacement (none)");
            }
            for _ in 0..1 + rng.below(3) {
                let spans = number_spans(&d);
                let (a, b) = *rng.pick(&spans);
                let n = rng.pick(NUMBERS).as_bytes();
                d.splice(a..b, n.iter().copied());
            }
            (d, "number replacement")
        }
        k => {
            let mut lines: Vec<Vec<u8>> = d.split(|&b| b == b'\n').map(<[u8]>::to_vec).collect();
            let n = lines.len();
            let what = match k {
                3 => {
                    let i = rng.below(n);
                    let l = lines[i].clone();
                    lines.insert(i, l);
                    "duplicated line"
                }
                4 => {
                    lines.remove(rng.below(n));
                    "removed line"
                }
                5 => {
                    let (i, j) = (rng.below(n), rng.below(n));
                    lines.swap(i, j);
                    "swapped lines"
                }
                _ if !extra_lines.is_empty() => {
                    let l = rng.pick(extra_lines).as_bytes().to_vec();
                    lines.insert(rng.below(n + 1), l);
                    "inserted line"
                }
                _ => {
                    lines.truncate(rng.below(n) + 1);
                    "cut lines"
                }
            };
            (lines.join(&b'\n'), what)
        }
    }
}

/// Byte ranges of the numbers in `d` (an optional `-`, digits, `.`, exponent).
fn number_spans(d: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < d.len() {
        let starts =
            d[i].is_ascii_digit() || (d[i] == b'-' && d.get(i + 1).is_some_and(u8::is_ascii_digit));
        let after_word =
            i > 0 && (d[i - 1].is_ascii_alphanumeric() || d[i - 1] == b'.' || d[i - 1] == b'_');
        if starts && !after_word {
            let a = i;
            i += 1;
            while i < d.len()
                && (d[i].is_ascii_digit() || matches!(d[i], b'.' | b'e' | b'E' | b'+' | b'-'))
            {
                i += 1;
            }
            out.push((a, i));
        } else {
            i += 1;
        }
    }
    out
}

/// Sets `key` of the object at JSON pointer `parent`, if there is one (an earlier
/// mutation may have removed it).
fn set(g: &mut Value, parent: &str, key: &str, v: Value) {
    if let Some(Value::Object(o)) = g.pointer_mut(parent) {
        o.insert(key.to_string(), v);
    }
}

/// A mutation of a glTF document's structure.
fn mutate_gltf(rng: &mut SplitMix, g: &mut Value) -> &'static str {
    let big = |rng: &mut SplitMix| -> Value {
        json!(*rng.pick(&[
            0u64,
            1,
            2,
            3,
            5,
            7,
            96,
            107,
            109,
            1 << 20,
            1_000_000_000,
            1 << 32,
            1 << 40,
            1 << 53
        ]))
    };
    match rng.below(12) {
        0 => {
            let i = rng.below(3);
            set(g, &format!("/accessors/{}", i), "count", big(rng));
            "accessor count"
        }
        1 => {
            let i = rng.below(3);
            set(g, &format!("/accessors/{}", i), "byteOffset", big(rng));
            "accessor byteOffset"
        }
        2 => {
            let i = rng.below(3);
            set(
                g,
                &format!("/accessors/{}", i),
                "componentType",
                json!(*rng.pick(&[5120, 5121, 5122, 5123, 5125, 5126, 0, 9999])),
            );
            "accessor componentType"
        }
        3 => {
            let i = rng.below(3);
            set(
                g,
                &format!("/accessors/{}", i),
                "type",
                json!(*rng.pick(&["SCALAR", "VEC2", "VEC3", "VEC4", "MAT4", "BOGUS"])),
            );
            "accessor type"
        }
        4 => {
            let i = rng.below(2);
            set(
                g,
                &format!("/bufferViews/{}", i),
                "byteStride",
                json!(*rng.pick(&[0u64, 1, 4, 8, 11, 12, 13, 252, 256, 1 << 31])),
            );
            "byteStride"
        }
        5 => {
            let i = rng.below(2);
            let field = *rng.pick(&["byteLength", "byteOffset"]);
            let v = big(rng);
            set(g, &format!("/bufferViews/{i}"), field, v);
            "bufferView range"
        }
        6 => {
            set(g, &format!("/buffers/{}", 0), "byteLength", big(rng));
            "buffer byteLength"
        }
        7 => {
            let uri = json!(*rng.pick(&[
                "../../etc/passwd",
                "../../../../../../../../etc/passwd",
                "/etc/passwd",
                "file:///etc/passwd",
                "file:sq.bin",
                "http://example.com/x.bin",
                "data:,",
                "data:application/octet-stream;base64,@@@@",
                "data:application/octet-stream;base64,QUJD=",
                "%2e%2e/%2e%2e/etc/passwd",
                "%zz",
                "sq.bin",
                "missing.bin",
                "C:\\windows\\win.ini",
                "",
                ".",
                "sub/../sq.bin",
            ]));
            set(g, "/buffers/0", "uri", uri);
            "buffer uri"
        }
        8 => {
            let i = rng.below(2);
            set(
                g,
                &format!("/nodes/{}", i),
                "children",
                json!(*rng.pick(&[
                    vec![0u64],
                    vec![1],
                    vec![0, 1],
                    vec![1, 1],
                    vec![99],
                    vec![]
                ])),
            );
            "node children"
        }
        9 => {
            let i = rng.below(2);
            let v = *rng.pick(&[0.0, -0.0, 1e-30, 1e10, 1e30, 3e38, -3e38]);
            match rng.below(3) {
                0 => set(g, &format!("/nodes/{i}"), "scale", json!([v, v, v])),
                1 => set(g, &format!("/nodes/{i}"), "translation", json!([v, 0, 0])),
                _ => set(g, &format!("/nodes/{i}"), "rotation", json!([v, 0, 0, 0])),
            }
            "node transform"
        }
        10 => {
            match rng.below(4) {
                0 => set(g, "/meshes/0/primitives/0", "mode", json!(rng.below(8))),
                1 => set(
                    g,
                    "/meshes/0/primitives/0",
                    "indices",
                    json!(*rng.pick(&[0, 1, 2, 99])),
                ),
                2 => set(
                    g,
                    "/meshes/0/primitives/0/attributes",
                    "POSITION",
                    json!(*rng.pick(&[1, 2, 99])),
                ),
                _ => set(
                    g,
                    "/meshes/0/primitives/0/attributes",
                    "NORMAL",
                    json!(*rng.pick(&[0, 2, 99])),
                ),
            }
            "primitive"
        }
        _ => {
            match rng.below(3) {
                0 => set(
                    g,
                    "/scenes/0",
                    "nodes",
                    json!(*rng.pick(&[vec![], vec![1u64], vec![0, 0], vec![0, 1], vec![99]])),
                ),
                1 => set(g, "", "scene", json!(*rng.pick(&[1, 99]))),
                _ => {
                    let keys = [
                        "accessors",
                        "bufferViews",
                        "buffers",
                        "nodes",
                        "meshes",
                        "scenes",
                        "asset",
                    ];
                    let k = *rng.pick(&keys);
                    if let Some(o) = g.as_object_mut() {
                        o.remove(k);
                    }
                }
            }
            "scene graph"
        }
    }
}

#[derive(Default)]
struct Tally {
    tried: usize,
    ok: usize,
    err: usize,
    panics: Vec<String>,
    slowest: Duration,
}

impl Tally {
    /// Loads `scene` (naming `mesh`, if any) and checks the outcome.
    fn load(&mut self, scene: &Path, mesh: Option<&str>, case: &str) {
        self.tried += 1;
        let t = Instant::now();
        let r = catch_unwind(AssertUnwindSafe(|| Scene::load(scene)));
        let took = t.elapsed();
        self.slowest = self.slowest.max(took);
        assert!(took < MAX_LOAD, "{case}: took {took:?}");
        match r {
            Err(p) => {
                let msg = p
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                self.panics.push(format!("{case}: {msg}"));
            }
            Ok(Ok(_)) => self.ok += 1,
            Ok(Err(e)) => {
                self.err += 1;
                let msg = e.to_string();
                let file = scene.file_name().and_then(|f| f.to_str()).unwrap_or("");
                assert!(
                    msg.starts_with(&scene.display().to_string()) && msg.contains(file),
                    "{case}: {msg}"
                );
                if let (SceneError::Mesh { .. }, Some(m)) = (&e, mesh) {
                    assert!(
                        msg.contains(m),
                        "{case}: the message does not name {m}: {msg}"
                    );
                }
                let reason = msg.rsplit(": ").next().unwrap_or("");
                assert!(!reason.trim().is_empty(), "{case}: empty reason: {msg}");
            }
        }
    }
}

#[test]
fn mutated_meshes_and_scenes_never_panic_and_say_what_is_wrong() {
    let seed = env_or("FUZZ_SEED", 18);
    let mut rng = SplitMix(seed);
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let mut tally = Tally::default();
    write(d, "sq.bin", square_bytes());

    // OBJ: the generated cube (150) and the built-in bumpy_glass mesh (20).
    let bumpy =
        std::fs::read(builtin_dir().join("meshes/bumpy_glass.obj")).expect("bumpy_glass.obj");
    let scene = write(d, "scene.json", scene_json("m.obj", Some("chrome")));
    for (seed_file, n, label) in [
        (CUBE_OBJ.as_bytes(), 150, "cube.obj"),
        (&bumpy[..], 20, "bumpy_glass.obj"),
    ] {
        for k in 0..n {
            let (bytes, what) = mutate_text(&mut rng, seed_file, OBJ_LINES);
            write(d, "m.obj", &bytes);
            tally.load(&scene, Some("m.obj"), &format!("{label} #{k} ({what})"));
        }
    }

    // glTF with a data URI or an external buffer (150), as JSON structure mutations
    // and then, one in three, a text mutation on top.
    let scene = write(d, "scene.json", scene_json("m.gltf", None));
    for k in 0..150 {
        let uri = if k % 2 == 0 {
            "sq.bin".to_string()
        } else {
            square_data_uri()
        };
        let mut g = gltf_json(Some(&uri));
        let mut what = vec![mutate_gltf(&mut rng, &mut g)];
        if rng.below(2) == 0 {
            what.push(mutate_gltf(&mut rng, &mut g));
        }
        let mut bytes = serde_json::to_vec(&g).expect("json");
        if rng.below(3) == 0 {
            let (b, w) = mutate_text(&mut rng, &bytes, &[]);
            bytes = b;
            what.push(w);
        }
        write(d, "m.gltf", &bytes);
        tally.load(
            &scene,
            Some("m.gltf"),
            &format!("gltf #{k} ({})", what.join(", ")),
        );
    }

    // GLB (80): structure mutations, or byte mutations of the container.
    let scene = write(d, "scene.json", scene_json("m.glb", None));
    for k in 0..80 {
        let mut g = gltf_json(None);
        let what = if k % 2 == 0 {
            mutate_gltf(&mut rng, &mut g)
        } else {
            "container"
        };
        let mut bytes = glb(&g, &square_bytes());
        if k % 2 == 1 {
            match rng.below(3) {
                0 => {
                    let i = rng.below(28);
                    let v = *rng.pick(&[
                        0u32,
                        1,
                        11,
                        12,
                        19,
                        20,
                        2,
                        0x4E4F_534A,
                        0x004E_4942,
                        u32::MAX,
                        1 << 31,
                    ]);
                    let at = (i / 4) * 4;
                    bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
                }
                1 => bytes.truncate(rng.below(bytes.len() + 1)),
                _ => {
                    let i = rng.below(bytes.len());
                    bytes[i] ^= 1 << rng.below(8);
                }
            }
        }
        write(d, "m.glb", &bytes);
        tally.load(&scene, Some("m.glb"), &format!("glb #{k} ({what})"));
    }

    // Scene files: the built-in scenes (with their meshes beside them) and the mesh
    // scene, 20 text mutations each.
    std::fs::create_dir_all(d.join("meshes")).expect("mkdir");
    std::fs::write(d.join("meshes/bumpy_glass.obj"), &bumpy).expect("copy");
    write(d, "cube.obj", CUBE_OBJ);
    let mut seeds: Vec<Vec<u8>> = caustics_scene::builtin_names()
        .iter()
        .map(|n| std::fs::read(builtin_dir().join(format!("{n}.json"))).expect("scene"))
        .collect();
    seeds.push(scene_json("cube.obj", Some("chrome")).into_bytes());
    let scene = d.join("fuzzed.json");
    for (s, seed_file) in seeds.iter().enumerate() {
        for k in 0..20 {
            let (bytes, what) = mutate_text(&mut rng, seed_file, &[]);
            write(d, "fuzzed.json", &bytes);
            tally.load(&scene, None, &format!("scene {s} #{k} ({what})"));
        }
    }

    println!(
        "fuzz (seed {seed}): {} mutations tried, {} Ok, {} Err, {} panics; slowest load {:?}",
        tally.tried,
        tally.ok,
        tally.err,
        tally.panics.len(),
        tally.slowest
    );
    assert!(
        tally.panics.is_empty(),
        "panics:\n{}",
        tally.panics.join("\n")
    );
    assert!(
        tally.ok > 0 && tally.err > 0,
        "the mutations should give both outcomes"
    );
}
