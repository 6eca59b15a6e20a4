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
    // The real-GPU experiments (bench/gpu_check.sh) sit one folder down, outside `all`.
    let gpu = caustics::experiment::names_in(&dir.join("gpu"));
    for n in ["paper-scenes", "paper-scenes-adaptive-beams"] {
        assert!(gpu.contains(&n.to_owned()), "{n} missing from {gpu:?}");
        assert!(
            !names.contains(&n.to_owned()),
            "{n} must stay out of `reproduce all`"
        );
    }
    let runs_of = |name: &str| {
        let e = Experiment::load(&dir.join("gpu").join(format!("{name}.json")), 1.0)
            .unwrap_or_else(|e| panic!("{e}"));
        let mut runs: Vec<String> = e
            .runs
            .iter()
            .map(|r| {
                format!(
                    "{} {}x{} {}/{}",
                    r.key(),
                    r.scene.camera.width,
                    r.scene.camera.height,
                    r.frames,
                    r.warmup
                )
            })
            .collect();
        runs.sort();
        (e, runs)
    };
    for f in resolve("all", &dir.join("gpu")).expect("gpu experiments") {
        let e = Experiment::load(&f, 1.0).unwrap_or_else(|e| panic!("{e}"));
        assert!(!e.runs.is_empty(), "{}", f.display());
    }
    // The adaptive-beams file is paper-scenes' adaptive-beams runs, no more, no fewer, at
    // the same resolution, frames and reference: its results stand in for those runs.
    let (all, all_runs) = runs_of("paper-scenes");
    let (adaptive, adaptive_runs) = runs_of("paper-scenes-adaptive-beams");
    let expected: Vec<String> = all_runs
        .into_iter()
        .filter(|r| r.contains("/adaptive-beams/"))
        .collect();
    assert_eq!(adaptive_runs, expected);
    assert_eq!(adaptive_runs.len(), 8);
    assert_eq!(adaptive.def.reference, all.def.reference);
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
fn representative_light_counts_sweep_into_their_own_runs() {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = write(
        dir.path(),
        "lights",
        r#"{"name": "lights", "runs": [
              {"scenes": ["ring"], "methods": ["wavefront"], "params": {"grid": [64, 128]},
               "representative_lights": [1, 16]},
              {"label": "one", "scenes": ["ring"], "methods": ["splatting"], "representative_lights": 4}
            ]}"#,
    );
    let e = Experiment::load(&p, 1.0).expect("valid");
    let keys: Vec<String> = e.runs.iter().map(|r| r.key()).collect();
    assert_eq!(
        keys,
        [
            "ring/wavefront/grid=64,representative_lights=1",
            "ring/wavefront/grid=64,representative_lights=16",
            "ring/wavefront/grid=128,representative_lights=1",
            "ring/wavefront/grid=128,representative_lights=16",
            "ring/splatting/representative_lights=4",
        ]
    );
    // The method gets its own parameters only; summaries show the count beside them.
    assert_eq!(e.runs[1].representative_lights, Some(16));
    assert!(!e.runs[1].params.contains_key("representative_lights"));
    assert_eq!(
        e.runs[1].shown_params().get("representative_lights"),
        Some(&serde_json::json!(16))
    );
    for (value, expected) in [("0", "got 0"), ("65", "got 65"), ("[]", "non-empty")] {
        let e = load_err(&format!(
            r#"{{"name": "x", "runs": [{{"scenes": ["ring"], "methods": ["wavefront"],
                 "representative_lights": {value}}}]}}"#
        ));
        assert!(
            e.contains("runs[0].representative_lights") && e.contains(expected),
            "{value}: {e}"
        );
    }
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
    let cases: [(&str, &[&str]); 15] = [
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
            r#"{"name": "x", "score_grid_scenes": {"ring": 0}, "runs": [{"scenes": ["ring"], "methods": ["pinhole"]}]}"#,
            &["score_grid_scenes.ring", "1..="],
        ),
        (
            r#"{"name": "x", "score_grid_scenes": {"water_pool": 8}, "runs": [{"scenes": ["ring"], "methods": ["pinhole"]}]}"#,
            &["score_grid_scenes.water_pool", "no run"],
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
fn a_scene_may_be_scored_on_a_finer_grid() {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = write(
        dir.path(),
        "grids",
        r#"{"name": "grids", "score_grid": 2, "score_grid_scenes": {"light_leak": 8},
            "runs": [{"scenes": ["ring", "light_leak"], "methods": ["wavefront"]}]}"#,
    );
    let e = Experiment::load(&p, 1.0).expect("valid");
    let grids: Vec<(&str, u32)> = e
        .runs
        .iter()
        .map(|r| (r.scene.name.as_str(), r.score_grid))
        .collect();
    assert_eq!(grids, [("ring", 2), ("light_leak", 8)]);
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

/// An experiment on ring with pinhole (samples × sampling) and a `figures` list.
fn with_figures(figures: &str) -> String {
    format!(
        r#"{{"name": "x", "runs": [{{"label": "sweep", "scenes": ["ring"], "methods": ["pinhole"],
            "params": {{"samples": [100, 1000], "sampling": ["grid", "random"]}}}}],
            "figures": [{figures}]}}"#
    )
}

#[test]
fn declared_figures_load_with_their_keys_and_measures() {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = write(
        dir.path(),
        "x",
        &with_figures(
            r#"{"name": "grid", "kind": "image_grid", "rows": "param:sampling", "cols": "param:samples", "reference": true},
               {"name": "time", "kind": "line", "x": "counter:sample_pixel_pairs", "y": "pass:gather+prepare_samples",
                "series": ["param:sampling"], "fit": "linear"},
               {"name": "rel", "kind": "line", "x": "param:samples", "y": "hdr_flip", "series": "param:sampling",
                "relative_to": {"params": {"sampling": "grid", "samples": 1000}}},
               {"name": "ratio", "kind": "ratio", "of": "param:sampling", "numerator": "random", "denominator": "grid",
                "measures": ["method_gpu_ms", "volume_rel_mse_1spp", "counter:texture_fetches"]},
               {"name": "t", "kind": "table", "where": [{"params": {"samples": 100}}, {"params": {"filtering": ["full", "off"]}}],
                "columns": ["param:filtering", "fill_max", "pass_fragments:gather", "rel_mse_aliasing"]}"#,
        ),
    );
    let e = Experiment::load(&p, 1.0).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(e.figures.len(), 5);
    assert_eq!(e.figures[0].kind.name(), "image_grid");
    assert_eq!(e.figures[3].title, "param:sampling: random / grid");
}

#[test]
fn bad_figures_name_the_file_the_field_and_what_was_expected() {
    let cases: &[(&str, &[&str])] = &[
        (
            r#"{"name": "a", "kind": "pie"}"#,
            &[
                "figures[0].kind",
                "image_grid, line, ratio, table",
                "\"pie\"",
            ],
        ),
        (
            r#"{"name": "a", "kind": "image_grid", "rows": "param:samplse"}"#,
            &[
                "figures[0].rows",
                "\"samplse\" is not a parameter of pinhole",
            ],
        ),
        (
            r#"{"name": "a", "kind": "image_grid", "rows": "colour"}"#,
            &["figures[0].rows", "param:<name>", "\"colour\""],
        ),
        (
            r#"{"name": "a", "kind": "table", "where": {"params": {"samplse": 1}}, "columns": ["fps"]}"#,
            &[
                "figures[0].where.params.samplse",
                "not a parameter",
                "pinhole: ",
            ],
        ),
        (
            r#"{"name": "a", "kind": "table", "where": {"params": {"samples": 7}}, "columns": ["fps"]}"#,
            &["figures[0].where", "matches no run"],
        ),
        (
            r#"{"name": "a", "kind": "table", "where": [{"scene": "ring"}, {"scene": "rign"}], "columns": ["fps"]}"#,
            &["figures[0].where[1].scene", "\"rign\"", "ring"],
        ),
        (
            r#"{"name": "a", "kind": "table", "where": {"sceen": "ring"}, "columns": ["fps"]}"#,
            &[
                "figures[0].where.sceen",
                "unknown field",
                "group, scene, method and params",
            ],
        ),
        (
            r#"{"name": "a", "kind": "table", "where": {"group": "swep"}, "columns": ["fps"]}"#,
            &["figures[0].where.group", "\"swep\"", "sweep"],
        ),
        (
            r#"{"name": "a", "kind": "line", "x": "param:samples", "y": "speed"}"#,
            &["figures[0].y", "expected a measure", "\"speed\""],
        ),
        (
            r#"{"name": "a", "kind": "line", "y": "fps"}"#,
            &["figures[0].x", "required"],
        ),
        (
            r#"{"name": "a", "kind": "line", "x": "param:sampling", "y": "fps"}"#,
            &["figures[0].x", "param:sampling is not a number", "grid"],
        ),
        (
            r#"{"name": "a", "kind": "line", "x": "fps", "y": "fps", "fit": "cubic"}"#,
            &["figures[0].fit", "\"linear\"", "\"cubic\""],
        ),
        (
            r#"{"name": "a", "kind": "line", "x": "fps", "y": "fps", "relative_to": {"params": {"samples": 3}}}"#,
            &["figures[0].relative_to", "matches no run"],
        ),
        (
            r#"{"name": "a", "kind": "image_grid", "fit": "linear"}"#,
            &[
                "figures[0].fit",
                "not a field of kind \"image_grid\"",
                "rows, cols, image, reference",
            ],
        ),
        (
            r#"{"name": "a", "kind": "image_grid", "cols": "param:samples"}"#,
            &["figures[0]", "fall in one cell"],
        ),
        (
            r#"{"name": "a", "kind": "image_grid", "image": "picture"}"#,
            &["figures[0].image", "caustic, composite"],
        ),
        (
            r#"{"name": "a", "kind": "image_grid", "image": "composite", "reference": true}"#,
            &["figures[0].reference", "\"caustic\""],
        ),
        (
            r#"{"name": "a", "kind": "ratio", "of": "param:sampling", "numerator": "random", "denominator": "quantized", "measures": ["fps"]}"#,
            &[
                "figures[0].denominator",
                "no run of the figure has param:sampling = \"quantized\"",
                "grid, random",
            ],
        ),
        (
            r#"{"name": "a", "kind": "ratio", "of": "param:samples", "numerator": 100, "denominator": 1000, "measures": []}"#,
            &["figures[0].measures", "non-empty"],
        ),
        (
            r#"{"name": "a", "kind": "ratio", "where": [{"params": {"samples": 100, "sampling": "grid"}}, {"params": {"samples": 1000, "sampling": "random"}}],
                "of": "param:samples", "numerator": 100, "denominator": 1000, "measures": ["fps"]}"#,
            &["figures[0]", "no pair of runs"],
        ),
        (
            r#"{"name": "a", "kind": "table", "columns": []}"#,
            &["figures[0].columns", "non-empty"],
        ),
        (
            r#"{"name": "a b", "kind": "table", "columns": ["fps"]}"#,
            &["figures[0].name", "letters, digits"],
        ),
        (
            r#"{"name": "a", "kind": "table", "columns": ["fps"]}, {"name": "a", "kind": "table", "columns": ["fps"]}"#,
            &["figures[1].name", "figures[0]"],
        ),
        (
            r#"{"name": "a", "kind": "table", "columns": ["fps"], "colour": 1}"#,
            &["figures[0]", "colour"],
        ),
    ];
    for (figures, needles) in cases {
        let json = with_figures(figures);
        let e = load_err(&json);
        for n in *needles {
            assert!(e.contains(n), "{figures}\n-> {e}\n(missing {n:?})");
        }
    }
    // A reference column needs one scene a row.
    let e = load_err(
        r#"{"name": "x", "runs": [{"scenes": ["ring", "sphere_on_plane"], "methods": ["pinhole"]}],
            "figures": [{"name": "a", "kind": "image_grid", "reference": true}]}"#,
    );
    assert!(
        e.contains("figures[0].reference") && e.contains("one scene a row"),
        "{e}"
    );
    // relative_to must reach every scene the figure draws.
    let e = load_err(
        r#"{"name": "x", "runs": [{"scenes": ["ring", "sphere_on_plane"], "methods": ["pinhole"], "params": {"samples": [100, 1000]}}],
            "figures": [{"name": "a", "kind": "line", "x": "param:samples", "y": "fps",
                         "relative_to": {"scene": "ring", "params": {"samples": 100}}}]}"#,
    );
    assert!(
        e.contains("figures[0].relative_to") && e.contains("sphere_on_plane"),
        "{e}"
    );
}

#[test]
fn figures_description_and_paper_do_not_change_what_the_runs_are_made_from() {
    let dir = tempfile::tempdir().expect("tempdir");
    let load = |json: &str| {
        let p = write(dir.path(), "x", json);
        Experiment::load(&p, 1.0).unwrap_or_else(|e| panic!("{e}"))
    };
    let plain = load(&with_figures(
        r#"{"name": "t", "kind": "table", "columns": ["fps"]}"#,
    ));
    let redrawn = load(
        &with_figures(r#"{"name": "t2", "kind": "table", "columns": ["fps", "rel_mse"]}"#)
            .replacen(
                "{\"name\": \"x\",",
                "{\"name\": \"x\", \"description\": \"new words\",",
                1,
            ),
    );
    assert_ne!(plain.hash, redrawn.hash);
    assert_eq!(
        plain.runs_hash, redrawn.runs_hash,
        "a figure changed the runs"
    );
    let rerun = load(
        &with_figures(r#"{"name": "t", "kind": "table", "columns": ["fps"]}"#).replacen(
            "{\"name\": \"x\",",
            "{\"name\": \"x\", \"frames\": 4,",
            1,
        ),
    );
    assert_ne!(
        plain.runs_hash, rerun.runs_hash,
        "frames did not change the runs"
    );
}

#[test]
fn the_readmes_copyable_example_loads() {
    let readme = caustics::experiment::builtin_dir().join("README.md");
    let text = std::fs::read_to_string(&readme).expect("README");
    let block = text
        .split("<!-- copyable-example -->")
        .nth(1)
        .and_then(|rest| rest.split("```json\n").nth(1))
        .and_then(|rest| rest.split("\n```").next())
        .expect("a ```json block after <!-- copyable-example -->");
    let dir = tempfile::tempdir().expect("tempdir");
    let p = write(dir.path(), "my-experiment", block);
    let e = Experiment::load(&p, 1.0).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(e.runs.len(), 12);
    assert_eq!(e.figures.len(), 5);
}

#[test]
fn an_animated_experiment_makes_sequences_a_group_may_stay_still() {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = write(
        dir.path(),
        "anim",
        r#"{"name": "anim", "resolution": {"width": 32, "height": 24},
            "animate": {"start_s": 0, "end_s": 1, "fps": 10, "reference_every": 4},
            "runs": [
              {"scenes": ["water_pool"], "methods": ["splatting"]},
              {"label": "still", "scenes": ["water_pool"], "methods": ["wavefront"], "animate": false},
              {"label": "own", "scenes": ["ring"], "methods": ["wavefront"],
               "animate": {"start_s": 0.5, "end_s": 0.7, "fps": 10}}
            ]}"#,
    );
    let e = Experiment::load(&p, 1.0).unwrap_or_else(|e| panic!("{e}"));
    let by_key = |k: &str| {
        e.runs
            .iter()
            .find(|r| r.key() == k)
            .unwrap_or_else(|| panic!("no run {k}"))
    };
    let water = by_key("water_pool/splatting/default")
        .animate
        .expect("the experiment's sequence");
    assert_eq!((water.start_s, water.end_s, water.fps), (0.0, 1.0, 10.0));
    // Every 4th of 10 instants and the one after: 0, 0.1, 0.4, 0.5, 0.8, 0.9 s.
    assert_eq!(water.scored_instants().len(), 6);
    assert!(by_key("water_pool/wavefront/default").animate.is_none());
    let own = by_key("ring/wavefront/default")
        .animate
        .expect("the group's own sequence");
    // Two instants; a quarter of the sequence rounds up to every frame.
    assert_eq!(own.spec().frame_count(), 2);
    assert_eq!(own.reference_every(), 1);
    assert_eq!(own.scored_instants().len(), 2);
}

#[test]
fn bad_sequences_name_the_field() {
    for (animate, field, says) in [
        (
            r#"{"start_s": 1, "end_s": 0.5, "fps": 30}"#,
            "animate.end_s",
            "expected END after START",
        ),
        (
            r#"{"start_s": 0, "end_s": 1, "fps": 0}"#,
            "animate.fps",
            "expected a rate in (0, 1000]",
        ),
        (
            r#"{"start_s": 0, "end_s": 1, "fps": 30, "reference_every": 0}"#,
            "animate.reference_every",
            "expected a positive number of frames",
        ),
        (
            r#"{"start_s": 0, "end_s": 100, "fps": 1000}"#,
            "animate.end_s",
            "1..=10000 frames",
        ),
    ] {
        let e = load_err(&format!(
            r#"{{"name": "x", "animate": {animate},
                "runs": [{{"scenes": ["ring"], "methods": ["wavefront"]}}]}}"#
        ));
        assert!(e.contains(field) && e.contains(says), "{animate}: {e}");
    }
    let e = load_err(
        r#"{"name": "x", "runs": [{"scenes": ["ring"], "methods": ["wavefront"], "animate": true}]}"#,
    );
    assert!(
        e.contains("runs[0].animate") && e.contains("or false"),
        "{e}"
    );
    let e = load_err(
        r#"{"name": "x", "runs": [{"scenes": ["ring"], "methods": ["wavefront"],
            "animate": {"start_s": 0, "end_s": 1, "fps": -3}}]}"#,
    );
    assert!(e.contains("runs[0].animate.fps"), "{e}");
    let e = load_err(
        r#"{"name": "x", "animate": {"start_s": 0, "end_s": 1, "fps": 30, "every": 3},
            "runs": [{"scenes": ["ring"], "methods": ["wavefront"]}]}"#,
    );
    assert!(e.contains("every"), "{e}");
    // An image grid draws still runs' images.
    let e = load_err(
        r#"{"name": "x", "animate": {"start_s": 0, "end_s": 1, "fps": 30},
            "runs": [{"scenes": ["ring"], "methods": ["wavefront"]}],
            "figures": [{"name": "g", "kind": "image_grid", "rows": "scene", "cols": "method"}]}"#,
    );
    assert!(
        e.contains("figures[0].kind") && e.contains("image grid"),
        "{e}"
    );
}

#[test]
fn runs_are_made_scene_by_scene_so_compared_runs_sit_back_to_back() {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = write(
        dir.path(),
        "x",
        r#"{"name": "x", "runs": [
            {"label": "a", "scenes": ["ring", "water_pool"], "methods": ["adaptive-beams"]},
            {"label": "b", "scenes": ["ring", "water_pool"], "methods": ["static-grid"], "params": {"grid": [32, 64]}},
            {"label": "c", "scenes": ["sphere_on_plane", "ring"], "methods": ["pinhole"]}]}"#,
    );
    let e = Experiment::load(&p, 1.0).unwrap_or_else(|e| panic!("{e}"));
    let all: Vec<_> = e.runs.iter().collect();
    let made: Vec<(usize, String)> = caustics::experiment::scene_major(&all)
        .iter()
        .map(|r| (r.index, r.key()))
        .collect();
    let expected: Vec<(usize, String)> = [
        (0, "ring/adaptive-beams/default"),
        (2, "ring/static-grid/grid=32"),
        (3, "ring/static-grid/grid=64"),
        (7, "ring/pinhole/default"),
        (1, "water_pool/adaptive-beams/default"),
        (4, "water_pool/static-grid/grid=32"),
        (5, "water_pool/static-grid/grid=64"),
        (6, "sphere_on_plane/pinhole/default"),
    ]
    .iter()
    .map(|(i, k)| (*i, (*k).to_owned()))
    .collect();
    assert_eq!(made, expected);
    // A shard makes its own runs, scene by scene as its list first names them.
    let shard = e.shard(2, 2);
    let made: Vec<usize> = caustics::experiment::scene_major(&shard)
        .iter()
        .map(|r| r.index)
        .collect();
    assert_eq!(made, vec![1, 5, 3, 7]);
}
