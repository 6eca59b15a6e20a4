//! Helpers of the harness's test files: the `caustics` binary run with arguments, a
//! small copy of a built-in scene and the cheapest `caustics run` of it. (The methods' accuracy tests live in their own crates
//! and use `caustics-testing` instead.) A file that uses a subset is its own crate,
//! hence the `dead_code` allowance.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use caustics::result::RunResult;
use caustics::run::{RunOptions, RunOutcome, run};

/// Runs the `caustics` binary with `args` and waits for it.
pub(crate) fn caustics(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_caustics"))
        .args(args)
        .output()
        .expect("run caustics")
}

/// Its standard error, as text.
pub(crate) fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Writes `json` as `<dir>/<name>.json`.
pub(crate) fn write_scene(dir: &Path, name: &str, json: &serde_json::Value) -> PathBuf {
    let path = dir.join(format!("{name}.json"));
    std::fs::write(&path, serde_json::to_string_pretty(json).expect("json")).expect("write");
    path
}

/// A copy of a built-in scene with a smaller camera, for fast tests.
pub(crate) fn small_scene(dir: &Path, name: &str, width: u32, height: u32) -> PathBuf {
    let src = caustics_scene::resolve(name).expect("built-in scene");
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&src).expect("read scene"))
            .expect("scene JSON");
    json["camera"]["width"] = width.into();
    json["camera"]["height"] = height.into();
    write_scene(dir, name, &json)
}

/// One timed frame, no warm-up, no reference cache: the cheapest run of `method`.
pub(crate) fn run_options(scene: &Path, out: &Path, method: &str, params: &[&str]) -> RunOptions {
    RunOptions {
        scene: scene.display().to_string(),
        method: method.into(),
        params: params.iter().map(|s| s.to_string()).collect(),
        param_values: Default::default(),
        limits: Default::default(),
        frames: 1,
        warmup: 0,
        reference: None,
        out: out.to_owned(),
        adapter: None,
        exposure: Some(2.0),
        // The method tests check the method's own image: one scoring offset, at the
        // pixel centre, is that image (tests/gpu_scoring.rs checks it bit for bit).
        score_grid: 1,
        references: out.join("no-reference-cache"),
        quick_reference_photons: 0,
        ceilings: out.join("no-ceilings"),
        instrumentation_overhead: false,
        resolution: None,
        time: None,
        animate: None,
        reference_every: None,
        representative_lights: 0,
    }
}

/// Runs and returns the output folder; a skipped run fails the test.
pub(crate) fn run_dir(o: &RunOptions) -> (PathBuf, RunResult) {
    match run(o).unwrap_or_else(|e| panic!("caustics run failed: {e:#}")) {
        RunOutcome::Done { dir, result } => (dir, *result),
        RunOutcome::Skipped { reason } => panic!("unexpectedly skipped: {reason}"),
        RunOutcome::Animated { dir, .. } => panic!("unexpectedly animated: {}", dir.display()),
    }
}
