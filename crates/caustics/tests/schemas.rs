//! The committed JSON Schemas (`schemas/`) are the ones the Rust types generate, and
//! every committed scene, experiment and result file validates against its schema with
//! an independent validator (`boon`, draft 2020-12). A file the schema refuses is shown
//! with the validator's message, and a schema that accepts garbage is caught by the
//! negative cases.

use std::path::{Path, PathBuf};

use caustics::schemas::{SchemaKind, schema, schema_text};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn validator(kind: SchemaKind) -> (boon::Schemas, boon::SchemaIndex) {
    let mut schemas = boon::Schemas::new();
    let mut compiler = boon::Compiler::new();
    let url = format!("file:///schemas/{}", kind.file_name());
    compiler
        .add_resource(&url, schema(kind))
        .expect("add schema");
    let index = compiler
        .compile(&url, &mut schemas)
        .unwrap_or_else(|e| panic!("{kind:?}: {e}"));
    (schemas, index)
}

fn files(dir: &Path, keep: &dyn Fn(&Path) -> bool, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            files(&p, keep, out);
        } else if keep(&p) {
            out.push(p);
        }
    }
}

#[test]
fn the_committed_schemas_are_the_generated_ones() {
    for kind in SchemaKind::ALL {
        let path = root().join("schemas").join(kind.file_name());
        let committed = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            committed == schema_text(kind),
            "{} is not what the types generate: run `cargo run -p caustics -- schema {} > schemas/{}`",
            path.display(),
            format!("{kind:?}").to_lowercase(),
            kind.file_name()
        );
    }
}

#[test]
fn every_committed_file_validates_against_its_schema() {
    let json = |p: &Path| p.extension().is_some_and(|e| e == "json");
    let mut failures = Vec::new();
    let mut counts = Vec::new();
    for (kind, dir, keep) in [
        (SchemaKind::Scene, "scenes", &json as &dyn Fn(&Path) -> bool),
        (SchemaKind::Experiment, "bench/experiments", &json),
        (SchemaKind::Result, "results", &|p: &Path| {
            p.file_name().is_some_and(|n| n == "result.json")
        }),
        (SchemaKind::Ceilings, "results/ceilings", &json),
        (SchemaKind::Animation, "results", &|p: &Path| {
            p.file_name().is_some_and(|n| n == "animation.json")
        }),
    ] {
        let (schemas, index) = validator(kind);
        let mut list = Vec::new();
        files(&root().join(dir), keep, &mut list);
        if kind == SchemaKind::Scene {
            // Mesh folders hold glTF JSON, which is not a scene.
            list.retain(|p| {
                p.parent() == Some(root().join("scenes").as_path())
                    || p.parent() == Some(root().join("scenes/extended").as_path())
            });
        }
        assert!(!list.is_empty(), "no {kind:?} files under {dir}");
        for p in &list {
            let value: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(p).expect("read"))
                    .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            if let Err(e) = schemas.validate(&value, index) {
                failures.push(format!("{}: {e:#}", p.display()));
            }
        }
        counts.push(format!("{} {kind:?}", list.len()));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    eprintln!("validated {}", counts.join(", "));
}

#[test]
fn the_schemas_refuse_what_the_parsers_refuse() {
    let (scenes, scene) = validator(SchemaKind::Scene);
    let ring: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("scenes/ring.json")).expect("ring"),
    )
    .expect("json");
    assert!(scenes.validate(&ring, scene).is_ok());
    let mut bad = ring.clone();
    bad["camera"]["fov"] = 45.into();
    assert!(
        scenes.validate(&bad, scene).is_err(),
        "an unknown field passed"
    );
    let mut bad = ring.clone();
    bad["lights"][0]["type"] = "area".into();
    assert!(
        scenes.validate(&bad, scene).is_err(),
        "an unknown light type passed"
    );
    let mut bad = ring;
    bad["camera"]["eye"] = serde_json::json!([0, 1]);
    assert!(
        scenes.validate(&bad, scene).is_err(),
        "a 2-vector eye passed"
    );

    let (results, result) = validator(SchemaKind::Result);
    let mut list = Vec::new();
    files(
        &root().join("results/baselines"),
        &|p: &Path| p.file_name().is_some_and(|n| n == "result.json"),
        &mut list,
    );
    let one: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&list[0]).expect("read")).expect("json");
    let mut bad = one.clone();
    bad["timing"]["method_gpu_ms"]["median"] = "fast".into();
    assert!(
        results.validate(&bad, result).is_err(),
        "a string time passed"
    );
    let mut bad = one;
    bad.as_object_mut().expect("object").remove("machine");
    assert!(
        results.validate(&bad, result).is_err(),
        "a result without machine passed"
    );
}

/// The `json` examples of the READMEs (not the annotated `jsonc` ones) are files one can
/// copy: each validates as the scene or experiment it shows.
#[test]
fn the_readme_json_examples_validate() {
    let (scenes, scene) = validator(SchemaKind::Scene);
    let (experiments, experiment) = validator(SchemaKind::Experiment);
    let mut checked = 0;
    for doc in ["README.md", "bench/experiments/README.md"] {
        let text = std::fs::read_to_string(root().join(doc)).expect("readme");
        let mut block: Option<(usize, String)> = None;
        for (i, line) in text.lines().enumerate() {
            match &mut block {
                None if line.trim() == "```json" => block = Some((i + 1, String::new())),
                Some((start, body)) if line.starts_with("```") => {
                    let v: serde_json::Value = serde_json::from_str(body)
                        .unwrap_or_else(|e| panic!("{doc}:{start}: not JSON: {e}"));
                    let checked_as = if v.get("camera").is_some() {
                        scenes.validate(&v, scene).map_err(|e| format!("{e:#}"))
                    } else if v.get("runs").is_some() {
                        experiments
                            .validate(&v, experiment)
                            .map_err(|e| format!("{e:#}"))
                    } else {
                        Ok(())
                    };
                    if let Err(e) = checked_as {
                        panic!("{doc}:{start}: {e}");
                    }
                    checked += 1;
                    block = None;
                }
                Some((_, body)) => {
                    body.push_str(line);
                    body.push('\n');
                }
                None => {}
            }
        }
    }
    assert!(checked >= 2, "checked {checked} examples");
}
