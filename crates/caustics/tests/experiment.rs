//! Experiment files: the committed ones load, sweeps expand, and every kind of bad file
//! fails at load with an error naming the file, the field and what was expected.

use std::path::{Path, PathBuf};

use caustics::experiment::{Experiment, Resolution, parse_shard, resolve, slug};

fn write(dir: &Path, name: &str, json: &str) -> PathBuf {
    let p = dir.join(format!("{name}.json"));
    std::fs::write(&p, json).expect("write");
    p
}

fn load_err(json: &str) -> String {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = write(dir.path(), "x", json);
    let e = Experiment::load(&p, 1.0)
        .expect_err("should fail")
        .to_string();
    assert!(e.contains("x.json"), "error does not name the file: {e}");
    e
}

#[test]
fn committed_experiments_load() {
    let dir = caustics::experiment::builtin_dir();
    let names = caustics::experiment::names_in(&dir);
    for n in ["ci-smoke", "wand-fig4", "wallace-water", "all-methods"] {
        assert!(names.contains(&n.to_owned()), "{n} missing from {names:?}");
    }
    for f in resolve("all", &dir).expect("all") {
        let e = Experiment::load(&f, 1.0).unwrap_or_else(|e| panic!("{e}"));
        assert!(!e.runs.is_empty(), "{}", f.display());
    }
}

#[test]
fn sweeps_expand_to_the_cartesian_product_and_scale_applies() {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = write(
        dir.path(),
        "sweep",
        r#"{"name": "sweep", "resolution": {"scale": 0.25}, "frames": 2, "warmup": 0,
            "runs": [
              {"label": "a", "scenes": ["ring", "sphere_on_plane"], "methods": ["pinhole"],
               "params": {"samples": [100, 1000], "sampling": ["grid", "random"], "seed": 3}},
              {"scenes": ["ring"], "methods": ["wavefront"],
               "params": [{"grid": 64}, {"grid": [128, 256]}], "resolution": {"width": 40, "height": 30}}
            ]}"#,
    );
    let e = Experiment::load(&p, 0.5).expect("valid");
    assert_eq!(e.runs.len(), 2 * 4 + 3);
    let first = &e.runs[0];
    assert_eq!(first.key(), "ring/pinhole/samples=100,sampling=grid,seed=3");
    assert_eq!(first.group, "a");
    // ring is 1024x768: x 0.25 x 0.5.
    assert_eq!(
        (first.scene.camera.width, first.scene.camera.height),
        (128, 96)
    );
    let last = e.runs.last().expect("runs");
    assert_eq!(last.key(), "ring/wavefront/grid=256");
    assert_eq!(last.group, "group1");
    assert_eq!(
        (last.scene.camera.width, last.scene.camera.height),
        (20, 15)
    );
    assert_eq!(last.params.get("grid"), Some(&serde_json::json!(256)));
    // Shards partition the runs.
    let mut all: Vec<usize> = (1..=3)
        .flat_map(|k| e.shard(k, 3).into_iter().map(|r| r.index))
        .collect();
    all.sort();
    assert_eq!(all, (0..e.runs.len()).collect::<Vec<_>>());
    assert_eq!(
        Resolution::Scale { scale: 0.5 }.apply(1024, 768, 0.5),
        (256, 192)
    );
}

#[test]
fn stars_select_every_scene_and_method() {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = write(
        dir.path(),
        "star",
        r#"{"name": "star", "runs": [{"scenes": "*", "methods": "*"}]}"#,
    );
    let e = Experiment::load(&p, 1.0).expect("valid");
    let scenes = caustics_scene::builtin_names().len();
    let methods = caustics::registry::methods().len();
    assert_eq!(e.runs.len(), scenes * methods);
}

#[test]
fn unknown_method_scene_and_param_name_file_and_field() {
    let e = load_err(
        r#"{"name": "x", "runs": [{"scenes": ["ring"], "methods": ["pinhole", "static-grud"]}]}"#,
    );
    assert!(
        e.contains("runs[0].methods[1]")
            && e.contains("static-grud")
            && e.contains("known methods"),
        "{e}"
    );
    let e = load_err(r#"{"name": "x", "runs": [{"scenes": ["rign"], "methods": ["pinhole"]}]}"#);
    assert!(e.contains("runs[0].scenes[0]") && e.contains("rign"), "{e}");
    let e = load_err(
        r#"{"name": "x", "runs": [{"scenes": ["ring"], "methods": ["pinhole"], "params": {"samplse": 3}}]}"#,
    );
    assert!(
        e.contains("runs[0].params") && e.contains("samplse") && e.contains("samples"),
        "{e}"
    );
    let e = load_err(
        r#"{"name": "x", "runs": [{"scenes": ["ring"], "methods": ["pinhole"], "params": {"samples": "many"}}]}"#,
    );
    assert!(e.contains("runs[0].params"), "{e}");
    let e = load_err(
        r#"{"name": "x", "runs": [{"scenes": ["missing.json"], "methods": ["pinhole"]}]}"#,
    );
    assert!(
        e.contains("runs[0].scenes[0]") && e.contains("missing.json"),
        "{e}"
    );
}

#[test]
fn malformed_files_are_clear_errors() {
    let cases: [(&str, &[&str]); 13] = [
        (
            r#"{"name": "x", "resolution": {"scale": 0.5, "widht": 3}, "runs": [{"scenes": "*", "methods": "*"}]}"#,
            &["resolution", "widht"],
        ),
        (
            r#"{"name": "x", "resolution": {"width": 64}, "runs": [{"scenes": "*", "methods": "*"}]}"#,
            &["resolution", "\"height\": H"],
        ),
        ("{", &["EOF"]),
        (r#"{"name": "x"}"#, &["runs"]),
        (
            r#"{"name": "y", "runs": [{"scenes": "*", "methods": "*"}]}"#,
            &["name", "\"x\""],
        ),
        (r#"{"name": "x", "runs": []}"#, &["runs", "at least one"]),
        (
            r#"{"name": "x", "frames": 0, "runs": [{"scenes": "*", "methods": "*"}]}"#,
            &["frames", "1..=10000"],
        ),
        (
            r#"{"name": "x", "resolution": {"scale": -1}, "runs": [{"scenes": "*", "methods": "*"}]}"#,
            &["resolution", "(0, 4]"],
        ),
        (
            r#"{"name": "x", "colour": 1, "runs": [{"scenes": "*", "methods": "*"}]}"#,
            &["colour"],
        ),
        (
            r#"{"name": "x", "runs": [{"scenes": "all", "methods": "*"}]}"#,
            &["runs[0].scenes", "\"*\""],
        ),
        (
            r#"{"name": "x", "runs": [{"scenes": ["ring"], "methods": ["pinhole"], "params": {"samples": []}}]}"#,
            &["runs[0].params.samples", "at least one"],
        ),
        (
            r#"{"name": "x", "runs": [{"scenes": ["ring"], "methods": ["pinhole"]}, {"scenes": ["ring"], "methods": ["pinhole"]}]}"#,
            &["already made by runs[0]"],
        ),
        (
            r#"{"name": "x", "runs": [{"scenes": ["ring"], "methods": ["pinhole"]}],
             "paper": {"source": "p", "hardware": "h", "figures": [{"scene": "ring", "method": "pinhole", "measure": "speed", "value": 1}]}}"#,
            &["paper.figures[0].measure", "method_gpu_ms"],
        ),
    ];
    for (json, needles) in cases {
        let e = load_err(json);
        for n in needles {
            assert!(e.contains(n), "{json}\n-> {e}\n(missing {n:?})");
        }
    }
    let e = load_err(
        r#"{"name": "x", "runs": [{"scenes": ["ring"], "methods": ["pinhole"]}],
            "paper": {"source": "p", "hardware": "h", "figures": [{"scene": "ring", "method": "pinhole", "params": {"samples": 7}, "measure": "fps", "value": 1}]}}"#,
    );
    assert!(
        e.contains("paper.figures[0]") && e.contains("matches no run"),
        "{e}"
    );
}

#[test]
fn names_shards_and_slugs() {
    let dir = tempfile::tempdir().expect("tempdir");
    let e = resolve("nope", dir.path())
        .expect_err("unknown")
        .to_string();
    assert!(e.contains("nope"), "{e}");
    assert!(resolve("all", dir.path()).is_err(), "empty folder");
    assert_eq!(parse_shard("2/4").expect("valid"), (2, 4));
    for bad in ["0/4", "5/4", "2", "a/b", "1/0"] {
        let e = parse_shard(bad).expect_err(bad).to_string();
        assert!(e.contains("--shard") && e.contains(bad), "{e}");
    }
    let mut m = serde_json::Map::new();
    assert_eq!(slug(&m), "default");
    m.insert("b".into(), serde_json::json!("x y"));
    m.insert("a".into(), serde_json::json!(0.5));
    assert_eq!(slug(&m), "a=0.5,b=x_y");
}
