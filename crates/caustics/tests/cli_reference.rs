//! `caustics reference` end to end: bad options fail clearly; a rendered reference
//! lands in the cache, and `caustics run` then scores against it on its own.

use std::path::Path;
use std::process::Command;

mod common;
use common::{caustics, stderr};

fn small_scene(dir: &Path, name: &str, width: u32, height: u32) -> String {
    let src = caustics_scene::resolve(name).expect("built-in");
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(src).expect("read")).expect("json");
    json["camera"]["width"] = width.into();
    json["camera"]["height"] = height.into();
    let path = dir.join(format!("{name}.json"));
    std::fs::write(&path, json.to_string()).expect("write");
    path.display().to_string()
}

#[test]
fn bad_reference_options_fail_clearly() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let refs = tmp.path().to_str().expect("utf-8");
    for (args, needle) in [
        (vec!["--scene", "ring"], "--photons N or --seconds SECONDS"),
        (vec!["--scene", "ring", "--photons", "0"], "--photons"),
        (vec!["--scene", "ring", "--seconds=-3"], "--seconds"),
        (
            vec!["--scene", "ring", "--photons", "10", "--time", "nan"],
            "expected a time in seconds",
        ),
        (
            vec!["--scene", "ring", "--photons", "10", "--batches", "1"],
            "--batches",
        ),
        (
            vec!["--scene", "no_such_scene", "--photons", "10"],
            "no_such_scene",
        ),
        (
            vec!["--scene", "ring", "--photons", "10", "--seconds", "1"],
            "cannot be used with",
        ),
        (
            vec!["--scene", "ring", "--photons", "10", "--resolution", "0x48"],
            "--resolution",
        ),
        (
            vec!["--scene", "ring", "--photons", "10", "--resolution", "64"],
            "WIDTHxHEIGHT",
        ),
    ] {
        let mut all = vec!["reference", "--references", refs];
        all.extend(args.iter());
        let o = caustics(&all);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(stderr(&o).contains(needle), "{args:?}: {}", stderr(&o));
    }
    assert!(
        std::fs::read_dir(tmp.path())
            .expect("read_dir")
            .next()
            .is_none(),
        "nothing may be written"
    );
}

#[test]
fn a_reference_past_the_cpu_memory_budget_is_refused_and_writes_nothing() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let refs = tmp.path().join("references");
    let refs_s = refs.display().to_string();
    for (budget, needles) in [
        // ring at 1024x768 with 16 batches: 22 MB of images before any photon.
        (
            "1",
            vec![
                "1024x768",
                "16 batches",
                "CAUSTICS_CPU_MEMORY_MIB",
                "1.00 MiB",
                "lower camera.width",
            ],
        ),
        (
            "lots",
            vec!["CAUSTICS_CPU_MEMORY_MIB=\"lots\"", "whole number of MiB"],
        ),
    ] {
        let start = std::time::Instant::now();
        let o = Command::new(env!("CARGO_BIN_EXE_caustics"))
            .args(["reference", "--scene", "ring", "--photons", "1000000"])
            .args(["--references", &refs_s])
            .env("CAUSTICS_CPU_MEMORY_MIB", budget)
            .output()
            .expect("run caustics");
        let e = stderr(&o);
        assert!(!o.status.success(), "budget {budget}: succeeded");
        for n in needles {
            assert!(e.contains(n), "budget {budget}: {n:?} missing from: {e}");
        }
        assert!(
            start.elapsed() < std::time::Duration::from_secs(30),
            "budget {budget}: refused after {:?}",
            start.elapsed()
        );
    }
    let written: Vec<_> = walk(&refs);
    assert!(written.is_empty(), "nothing may be written: {written:?}");
}

/// Every file under `dir` (none if it does not exist).
fn walk(dir: &Path) -> Vec<std::path::PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    entries
        .flatten()
        .flat_map(|e| {
            let p = e.path();
            if p.is_dir() { walk(&p) } else { vec![p] }
        })
        .collect()
}

#[test]
fn a_rendered_reference_is_cached_and_used_by_run() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let scene = small_scene(tmp.path(), "water_pool", 64, 48);
    let refs = tmp.path().join("refs");
    let refs_s = refs.to_str().expect("utf-8");
    let o = caustics(&[
        "reference",
        "--scene",
        &scene,
        "--photons",
        "200000",
        "--references",
        refs_s,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let loaded = caustics_scene::Scene::load(Path::new(&scene)).expect("scene");
    let dir = caustics::references::cache_dir(&refs, &loaded);
    for f in ["caustic.exr", "stderr.exr", "meta.json"] {
        assert!(dir.join(f).is_file(), "{f} missing in {}", dir.display());
    }
    let meta = caustics::references::find(&refs, &loaded)
        .expect("valid cache")
        .expect("found");
    assert!(meta.meta.photons >= 200_000);
    assert!(meta.meta.relative_stderr > 0.0 && meta.meta.relative_stderr.is_finite());

    let out = tmp.path().join("out");
    run_from_the_cache(&["--scene", &scene], refs_s, &out);
    let result: serde_json::Value = serde_json::from_slice(
        &std::fs::read(out.join("water_pool").join("wavefront").join("result.json"))
            .expect("result.json"),
    )
    .expect("json");
    assert_eq!(result["errors"]["reference_source"], "cache");
    // Named by its place in the cache, not by this machine's absolute path.
    let reference = result["errors"]["reference"].as_str().expect("reference");
    assert!(
        reference.starts_with("water_pool/") && reference.ends_with("/caustic.exr"),
        "{reference}"
    );
    assert!(!reference.contains(refs_s), "{reference}");
    assert!(result["errors"]["surface"]["rmse"].as_f64().expect("rmse") > 0.0);
    assert!(
        out.join("water_pool")
            .join("wavefront")
            .join("error.png")
            .is_file()
    );
}

/// `--resolution` renders the reference at another camera size, into the cache folder
/// a `caustics run --resolution` of the same size looks in: no scene file to copy.
#[test]
fn a_reference_at_another_resolution_is_found_by_a_run_at_it() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let refs = tmp.path().join("refs");
    let refs_s = refs.to_str().expect("utf-8");
    let o = caustics(&[
        "reference",
        "--scene",
        "ring",
        "--resolution",
        "32x24",
        "--photons",
        "100000",
        "--references",
        refs_s,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut scene = caustics_scene::Scene::load(&caustics_scene::resolve("ring").expect("ring"))
        .expect("scene");
    (scene.camera.width, scene.camera.height) = (32, 24);
    let cached = caustics::references::find(&refs, &scene)
        .expect("valid cache")
        .expect("the 32x24 reference is in the cache");
    assert_eq!((cached.meta.width, cached.meta.height), (32, 24));
    let image = caustics_metrics::read_exr(&cached.dir.join("caustic.exr")).expect("exr");
    assert_eq!((image.width, image.height), (32, 24));

    run_from_the_cache(
        &["--scene", "ring", "--resolution", "32x24"],
        refs_s,
        &tmp.path().join("out"),
    );
}

/// One wavefront frame of the scene `scene_args` name, into `out`, which must be scored
/// against a reference found in the cache at `refs` (none is rendered for it).
fn run_from_the_cache(scene_args: &[&str], refs: &str, out: &Path) {
    let mut args = vec![
        "run",
        "--method",
        "wavefront",
        "--frames",
        "1",
        "--warmup",
        "0",
    ];
    args.extend(scene_args);
    let out = out.to_str().expect("utf-8");
    args.extend([
        "--quick-reference-photons",
        "0",
        "--references",
        refs,
        "--out",
        out,
    ]);
    let o = caustics(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("using cached reference"),
        "{}",
        stderr(&o)
    );
}

/// The README's first command on a fresh clone: no reference anywhere, and the run is
/// still scored, against a quick seeded reference it renders into the cache and says
/// so; the next run uses that one; `--quick-reference-photons 0` renders none.
#[test]
fn a_first_run_renders_a_quick_reference_and_is_scored() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let scene = small_scene(tmp.path(), "ring", 48, 36);
    let refs = tmp.path().join("refs");
    let out = tmp.path().join("out");
    let run = |refs: &Path, extra: &[&str]| {
        let mut args = vec![
            "run",
            "--scene",
            &scene,
            "--method",
            "static-grid",
            "--frames",
            "1",
            "--warmup",
            "0",
            "--score-grid",
            "1",
            "--references",
            refs.to_str().expect("utf-8"),
            "--out",
            out.to_str().expect("utf-8"),
        ];
        args.extend_from_slice(extra);
        let o = caustics(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let result: serde_json::Value = serde_json::from_slice(
            &std::fs::read(out.join("ring/static-grid/result.json")).expect("result.json"),
        )
        .expect("json");
        (stderr(&o), result)
    };
    let (err, result) = run(&refs, &["--quick-reference-photons", "300000"]);
    assert!(
        err.contains("rendering a quick one (300000 photons, seed 1)"),
        "{err}"
    );
    assert!(err.contains("quick reference rendered in"), "{err}");
    assert_eq!(result["errors"]["reference_source"], "cache");
    assert!(
        result["errors"]["surface"]["rel_mse"]
            .as_f64()
            .expect("relMSE")
            > 0.0
    );
    assert!(out.join("ring/static-grid/error.png").is_file());
    let loaded = caustics_scene::Scene::load(Path::new(&scene)).expect("scene");
    let meta = caustics::references::find(&refs, &loaded)
        .expect("valid cache")
        .expect("the quick reference is cached");
    // Rounded up to whole work units, as `caustics reference --photons` rounds.
    assert!(
        meta.meta.photons >= 300_000 && meta.meta.seed == 1,
        "{:?}",
        meta.meta
    );

    // The second run finds it and renders nothing.
    let (err, result) = run(&refs, &["--quick-reference-photons", "300000"]);
    assert!(!err.contains("rendering a quick one"), "{err}");
    assert!(err.contains("using cached reference"), "{err}");
    assert!(result["errors"].is_object());

    // Skipped on request: no reference, no errors, and the run says how to get one.
    let empty = tmp.path().join("empty-refs");
    let (err, result) = run(&empty, &["--quick-reference-photons", "0"]);
    assert!(err.contains("no errors"), "{err}");
    assert!(result["errors"].is_null(), "{}", result["errors"]);
    assert!(!empty.exists(), "nothing rendered into the cache");
}
