//! `caustics reproduce` and `merge` for real on lavapipe with a tiny experiment: the
//! summary, plots and Bencher file are written; shards merged equal the unsharded run
//! on every deterministic figure; bad input fails before anything is written.

use std::path::{Path, PathBuf};
use std::process::Command;

use caustics::compare::{CompareArgs, compare};
use caustics::reproduce::{MergeArgs, ReproduceArgs, merge, read_manifest, reproduce};
use caustics::summary::read_summary;

const TINY: &str = r#"{
  "name": "tiny",
  "description": "two scenes, two methods, a sweep; 32x24",
  "resolution": {"width": 32, "height": 24},
  "frames": 2,
  "warmup": 0,
  "reference": {"photons": 20000, "seed": 1, "batches": 4},
  "runs": [
    {"label": "pinhole", "scenes": ["ring", "sphere_on_plane"], "methods": ["pinhole"],
     "params": {"samples": [50, 100], "cube_size": 32, "samples_per_pass": 50}},
    {"label": "wavefront", "scenes": ["ring", "sphere_over_water"], "methods": ["wavefront", "pinhole"],
     "params": {}}
  ],
  "paper": {"source": "none", "hardware": "imaginary GPU",
            "figures": [{"scene": "ring", "method": "pinhole", "params": {"samples": 50},
                         "measure": "method_gpu_ms", "value": 42, "note": "made up"}]}
}"#;

fn setup() -> (tempfile::TempDir, PathBuf) {
    let tmp = tempfile::tempdir().expect("tempdir");
    let exp = tmp.path().join("experiments");
    std::fs::create_dir_all(&exp).expect("mkdir");
    std::fs::write(exp.join("tiny.json"), TINY).expect("write");
    (tmp, exp)
}

fn args(tmp: &Path, exp: &Path, out: &str, shard: Option<&str>) -> ReproduceArgs {
    ReproduceArgs {
        name: "tiny".into(),
        scale: 1.0,
        out: tmp.join(out),
        shard: shard.map(str::to_owned),
        references: tmp.join("references"),
        ceilings: tmp.join("ceilings"),
        no_render_references: false,
        experiments: Some(exp.to_path_buf()),
        adapter: None,
        keep_exr: false,
        summary_only: false,
        fresh: false,
        allow_dirty: false,
        time_budget_s: None,
    }
}

/// `caustics compare BASE NEW --no-timings` with no tolerance on counts and errors.
fn strict_compare(base: &Path, new: &Path) -> caustics::compare::Report {
    compare(&CompareArgs {
        base: base.to_path_buf(),
        new: new.to_path_buf(),
        time_threshold: 0.05,
        alpha: 0.01,
        count_tolerance: 0.0,
        error_tolerance: 0.0,
        noise_k: 0.0,
        no_timings: true,
        verbose: false,
        wide: false,
        across_adapters: false,
        html: None,
    })
    .expect("compare")
}

/// Everything in the summary but the timings (GPU and wall), machine and build.
fn deterministic(dir: &Path) -> Vec<serde_json::Value> {
    let s = read_summary(dir).expect("summary");
    s.runs
        .iter()
        .map(|r| {
            let mut v = serde_json::to_value(r).expect("json");
            let o = v.as_object_mut().expect("object");
            o.remove("method_gpu_ms");
            o.remove("frame_gpu_ms");
            o.remove("pass_gpu_ms");
            o.remove("wall");
            v
        })
        .collect()
}

#[test]
fn reproduce_then_shards_merged_equal_the_unsharded_run() {
    let (tmp, exp) = setup();
    let t = tmp.path();
    let whole = reproduce(&args(t, &exp, "whole", None)).expect("reproduce");
    assert_eq!(whole.failed, 0);
    let dir = t.join("whole/tiny");
    let s = read_summary(&dir).expect("summary");
    // 2 scenes x 2 sample counts, then ring and sphere_over_water x 2 methods.
    assert_eq!(s.runs.len(), 8);
    assert_eq!((s.done, s.skipped, s.failed), (7, 1, 0), "{:?}", s.runs);
    let skipped = s
        .runs
        .iter()
        .find(|r| r.status == "skipped")
        .expect("one skip");
    assert_eq!(skipped.key, "sphere_over_water/pinhole/default");
    assert!(
        skipped
            .reason
            .as_deref()
            .is_some_and(|r| r.contains("both specular"))
    );
    // References were rendered on demand (one per scene the runs can use) and scored.
    let manifest = read_manifest(&dir).expect("manifest");
    assert_eq!(
        manifest.rendered_references.len(),
        3,
        "{:?}",
        manifest.rendered_references
    );
    for r in s.runs.iter().filter(|r| r.status == "done") {
        assert!(r.errors.is_some() && r.fragments.is_some(), "{}", r.key);
        assert!(r.method_gpu_ms.is_some(), "{}", r.key);
        // Where the run's time went: positive phases that add up to its total.
        let w = r
            .wall
            .as_ref()
            .unwrap_or_else(|| panic!("{}: no wall", r.key));
        let phases = w.setup_s + w.frames_s + w.scoring_frame_s + w.errors_s + w.writing_s;
        assert!(
            w.total_s > 0.0 && w.frames_s > 0.0 && w.errors_s > 0.0,
            "{w:?}"
        );
        assert!(
            (phases - w.total_s).abs() < 1e-6 * w.total_s.max(1.0),
            "{w:?}"
        );
    }
    let md = std::fs::read_to_string(dir.join("summary.md")).expect("summary.md");
    let time = md
        .split("## Where the time went")
        .nth(1)
        .expect("a time section");
    assert!(
        manifest
            .rendered_references
            .iter()
            .all(|r| r.ends_with(" s)") && time.contains(r.as_str())),
        "{:?} in {time}",
        manifest.rendered_references
    );
    // The paper's figure sits beside its run.
    let ring50 = s
        .runs
        .iter()
        .find(|r| r.key.starts_with("ring/pinhole/cube_size=32,samples=50"))
        .expect("run");
    assert_eq!(ring50.paper.len(), 1);
    let md = std::fs::read_to_string(dir.join("summary.md")).expect("md");
    assert!(
        md.contains("paper (imaginary GPU)") && md.contains("method_gpu_ms 42"),
        "{md}"
    );
    assert!(
        md.contains("sphere_over_water/pinhole/default | skipped"),
        "{md}"
    );
    for p in [
        "plots/error_vs_time_ring.png",
        "plots/hdr_flip_vs_time_ring.png",
        "plots/fragments.png",
        "bmf.json",
    ] {
        assert!(dir.join(p).is_file(), "{p} missing");
    }
    let bmf: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("bmf.json")).expect("bmf")).expect("json");
    let m = &bmf["tiny/ring/wavefront/default"];
    assert!(m["method_gpu_ms"]["value"].is_number(), "{bmf}");
    assert!(
        m["method_gpu_ms"]["lower_value"].as_f64() <= m["method_gpu_ms"]["upper_value"].as_f64()
    );
    assert!(m["fragments"]["value"].is_number() && m["rmse_after_best_scale"]["value"].is_number());
    // The headline figures of the pixel-averaged frame, and the timed frame's beside them.
    for k in [
        "flux_ratio",
        "rel_mse",
        "rel_mse_after_flux",
        "hdr_flip",
        "rel_mse_1spp",
        "hdr_flip_1spp",
        "rel_mse_aliasing",
    ] {
        assert!(m[k]["value"].is_number(), "{k} missing: {m}");
    }
    assert!(
        md.contains("| spp | flux | flux (image) | relMSE |") && md.contains("aliasing"),
        "{md}"
    );
    // EXRs are dropped by default, PNGs kept.
    let run = dir.join(ring50.dir.as_deref().expect("dir"));
    assert!(run.join("composite.png").is_file());
    let exr: Vec<_> = std::fs::read_dir(&run)
        .expect("run folder")
        .filter_map(|e| e.ok().map(|e| e.file_name()))
        .filter(|n| n.to_string_lossy().ends_with(".exr"))
        .collect();
    assert!(exr.is_empty(), "EXRs left without --keep-exr: {exr:?}");

    // The summary can be rewritten from the files alone, identically.
    let before = std::fs::read(dir.join("summary.json")).expect("summary");
    std::fs::remove_file(dir.join("summary.md")).expect("rm");
    reproduce(&ReproduceArgs {
        summary_only: true,
        ..args(t, &exp, "whole", None)
    })
    .expect("summary only");
    assert_eq!(
        before,
        std::fs::read(dir.join("summary.json")).expect("summary")
    );
    assert!(dir.join("summary.md").is_file());

    // A time budget: the runs complete from before are kept, no other starts once it is
    // spent (`not_run`, with a summary), and the same command again does only those.
    let copy = |name: &str| {
        let to = t.join(name);
        std::fs::create_dir_all(&to).expect("mkdir");
        let ok = Command::new("cp")
            .args([
                "-a",
                dir.to_str().expect("utf8"),
                to.to_str().expect("utf8"),
            ])
            .status()
            .expect("cp");
        assert!(ok.success());
        to.join("tiny")
    };
    let budget_dir = copy("budget");
    let ring50_rel = ring50.dir.as_deref().expect("dir");
    std::fs::remove_dir_all(budget_dir.join(ring50_rel)).expect("rm run");
    let o = reproduce(&ReproduceArgs {
        time_budget_s: Some(0.0),
        ..args(t, &exp, "budget", None)
    })
    .expect("budgeted reproduce");
    assert_eq!(o.failed, 0);
    let b = read_summary(&budget_dir).expect("summary");
    // The skipped run has no folder either: it waits too.
    assert_eq!((b.done, b.skipped, b.not_run), (6, 0, 2), "{:?}", b.runs);
    assert!(!budget_dir.join(ring50_rel).exists(), "a run started");
    let m = read_manifest(&budget_dir).expect("manifest");
    let waiting = m
        .runs
        .iter()
        .find(|r| r.key == ring50.key)
        .expect("ring50 in the manifest");
    assert_eq!(waiting.status, caustics::reproduce::NOT_RUN);
    assert!(
        waiting
            .reason
            .as_deref()
            .is_some_and(|r| r.contains("--time-budget-s 0")),
        "{waiting:?}"
    );
    let md = std::fs::read_to_string(budget_dir.join("summary.md")).expect("md");
    assert!(md.contains("2 not run (listed under Not run)"), "{md}");
    reproduce(&args(t, &exp, "budget", None)).expect("resumed");
    assert_eq!(deterministic(&dir), deterministic(&budget_dir));

    // A reproduction killed before its manifest: --summary-only summarizes the runs
    // whose result.json exists and lists the others as not run.
    let killed_dir = copy("killed");
    std::fs::remove_file(killed_dir.join("manifest.json")).expect("rm manifest");
    std::fs::remove_file(killed_dir.join("summary.json")).expect("rm summary");
    std::fs::remove_file(killed_dir.join(ring50_rel).join("result.json")).expect("rm result");
    // Under another --scale its runs would be labelled with sizes they do not have: an
    // error naming a run's file and the flag, and nothing written.
    let wrong_scale = reproduce(&ReproduceArgs {
        summary_only: true,
        scale: 0.5,
        ..args(t, &exp, "killed", None)
    })
    .expect_err("another scale than the runs were made at")
    .to_string();
    assert!(
        wrong_scale.contains("result.json") && wrong_scale.contains("--scale 0.5"),
        "{wrong_scale}"
    );
    assert!(!killed_dir.join("manifest.json").exists());
    reproduce(&ReproduceArgs {
        summary_only: true,
        ..args(t, &exp, "killed", None)
    })
    .expect("summary of an interrupted reproduction");
    let k = read_summary(&killed_dir).expect("summary");
    assert_eq!((k.done, k.failed, k.not_run), (6, 0, 2), "{:?}", k.runs);
    let m = read_manifest(&killed_dir).expect("manifest written");
    assert!(
        m.runs
            .iter()
            .any(|r| r.key == ring50.key && r.status == caustics::reproduce::NOT_RUN)
    );

    // The HTML report: self-contained (every image it shows lies beside it).
    let index = caustics::report::report(&caustics::report::ReportArgs {
        dir: t.join("whole"),
        out: Some(t.join("report")),
        references: t.join("references"),
    })
    .expect("report");
    let html = std::fs::read_to_string(&index).expect("index");
    assert!(
        html.contains("ring/pinhole/cube_size=32,samples=50") && html.contains("imaginary GPU")
    );
    // The landing page: the gallery shows the scene's reference beside the runs, the
    // glossary every column and the methods' counters.
    assert!(
        html.contains("/references/ring_"),
        "no reference image in the gallery"
    );
    assert!(html.contains("id=glossary") && html.contains("<dt>relMSE</dt>"));
    assert!(
        html.contains("data-ok=pending hidden"),
        "the image check shows on the page"
    );
    let srcs: Vec<&str> = html
        .split("src=\"")
        .skip(1)
        .filter_map(|s| s.split('"').next())
        .collect();
    assert!(srcs.len() >= 7 * 3, "{srcs:?}");
    for src in srcs {
        assert!(t.join("report").join(src).is_file(), "{src} not copied");
    }
    let e = caustics::report::report(&caustics::report::ReportArgs {
        dir: t.join("nothing-here"),
        out: Some(t.join("report2")),
        references: t.join("references"),
    })
    .expect_err("no folder");
    assert!(format!("{e:#}").contains("nothing-here"), "{e:#}");
    assert!(!t.join("report2").exists());

    // Shards (references now cached), merged.
    for k in ["1/3", "2/3", "3/3"] {
        let o = reproduce(&args(t, &exp, &format!("shard{}", &k[..1]), Some(k))).expect("shard");
        assert_eq!(o.failed, 0);
    }
    let shards: Vec<PathBuf> = (1..=3).map(|k| t.join(format!("shard{k}/tiny"))).collect();
    let merged = merge(&MergeArgs {
        shards: shards.clone(),
        out: t.join("merged"),
        experiments: Some(exp.clone()),
    })
    .expect("merge");
    assert_eq!(deterministic(&dir), deterministic(&merged));
    // And run by run, counts and errors are identical.
    let report = strict_compare(&dir, &merged);
    assert_eq!(report.regressions(), 0, "{}", report.table(true));
    assert_eq!(report.runs, 7);

    // Bad merges: a shard missing, one twice, a non-empty output; nothing is written.
    let bad = |shards: Vec<PathBuf>, out: PathBuf, needle: &str| {
        let e = merge(&MergeArgs {
            shards,
            out: out.clone(),
            experiments: Some(exp.clone()),
        })
        .expect_err("bad merge");
        let e = format!("{e:#}");
        assert!(e.contains(needle), "{e}");
    };
    bad(
        shards[..2].to_vec(),
        t.join("m2"),
        "each of the 3 shards exactly once",
    );
    assert!(!t.join("m2").exists());
    bad(
        vec![shards[0].clone(), shards[0].clone(), shards[1].clone()],
        t.join("m3"),
        "exactly once",
    );
    bad(shards.clone(), t.join("merged"), "not empty");
    bad(vec![dir.clone(), shards[0].clone()], t.join("m4"), "shard");
    assert!(!t.join("m4").exists());
    // No temporary file is left anywhere.
    let leftovers = Command::new("find")
        .args([t.to_str().expect("utf8"), "-name", ".*.tmp-*"])
        .output()
        .expect("find");
    assert!(
        leftovers.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&leftovers.stdout)
    );
}

#[test]
fn a_bad_experiment_fails_before_any_run_or_write() {
    let (tmp, exp) = setup();
    std::fs::write(
        exp.join("broken.json"),
        r#"{"name": "broken", "runs": [{"scenes": ["ring"], "methods": ["splatting-x"]}]}"#,
    )
    .expect("write");
    let out = tmp.path().join("out");
    let bin = env!("CARGO_BIN_EXE_caustics");
    // `all` loads every file first: tiny is valid, broken is not, nothing runs.
    let o = Command::new(bin)
        .args([
            "reproduce",
            "all",
            "--experiments",
            exp.to_str().expect("utf8"),
            "--out",
            out.to_str().expect("utf8"),
        ])
        .output()
        .expect("run");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("broken.json")
            && err.contains("runs[0].methods[0]")
            && err.contains("splatting-x"),
        "{err}"
    );
    assert!(!out.exists(), "reproduce wrote before validating");
    for (flags, needle) in [
        (vec!["tiny", "--shard", "3/2"], "--shard"),
        (vec!["tiny", "--scale", "0"], "--scale"),
        (vec!["nosuch"], "nosuch"),
    ] {
        let mut a = vec![
            "reproduce",
            "--experiments",
            exp.to_str().expect("utf8"),
            "--out",
            out.to_str().expect("utf8"),
        ];
        a.extend(flags);
        let o = Command::new(bin).args(&a).output().expect("run");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(err.contains(needle), "{err}");
        assert!(!out.exists());
    }
}

#[test]
fn a_cached_reference_with_fewer_photons_than_asked_is_rendered_again() {
    use caustics::references::{ReferenceMeta, cache_dir, find};
    let tmp = tempfile::tempdir().expect("tempdir");
    let exp = tmp.path().join("experiments");
    std::fs::create_dir_all(&exp).expect("mkdir");
    std::fs::write(
        exp.join("one.json"),
        r#"{"name": "one", "description": "one run, 32x24", "resolution": {"width": 32, "height": 24},
            "frames": 1, "warmup": 0, "reference": {"photons": 20000, "seed": 1, "batches": 4},
            "runs": [{"label": "ring", "scenes": ["ring"], "methods": ["wavefront"]}]}"#,
    )
    .expect("write");
    let mut a = args(tmp.path(), &exp, "out", None);
    a.name = "one".into();
    // A cached ring reference of 100 photons (all-ones images), as an earlier, cheaper
    // experiment would leave.
    let mut scene = caustics_scene::Scene::load(&caustics_scene::resolve("ring").expect("ring"))
        .expect("scene");
    scene.camera.width = 32;
    scene.camera.height = 24;
    let dir = cache_dir(&a.references, &scene);
    std::fs::create_dir_all(&dir).expect("mkdir");
    let mut ones = caustics_metrics::HdrImage::new(32, 24);
    ones.pixels.iter_mut().for_each(|p| *p = [1.0; 3]);
    for f in ["caustic.exr", "stderr.exr"] {
        caustics_metrics::write_exr(&dir.join(f), &ones).expect("write");
    }
    let meta = ReferenceMeta {
        schema_version: 2,
        transport_version: caustics_reference::TRANSPORT_VERSION,
        scene: scene.name.clone(),
        scene_hash: scene.hash_hex(),
        width: 32,
        height: 24,
        photons: 100,
        seconds: 1.0,
        photons_per_second: 100.0,
        seed: 1,
        batches: 4,
        commit: "test".into(),
        relative_stderr: 0.5,
        time_s: None,
    };
    std::fs::write(
        dir.join("meta.json"),
        serde_json::to_vec(&meta).expect("json"),
    )
    .expect("write");
    let done = reproduce(&a).expect("reproduce");
    assert_eq!(done.failed, 0);
    let cached = find(&a.references, &scene)
        .expect("cache")
        .expect("a reference");
    assert!(cached.meta.photons >= 20000, "{:?}", cached.meta);
    let image = caustics_metrics::read_exr(&cached.caustic()).expect("exr");
    assert_ne!(
        image.pixels, ones.pixels,
        "the 100-photon image is still there"
    );
}

/// An experiment whose runs are animated sequences: a still run beside a sequence.
const ANIMATED: &str = r#"{
  "name": "animated",
  "description": "water_pool moving, 3 instants, 32x24",
  "resolution": {"width": 32, "height": 24},
  "frames": 2,
  "warmup": 0,
  "score_grid": 2,
  "reference": {"photons": 200000, "seed": 1, "batches": 4},
  "animate": {"start_s": 0, "end_s": 0.1, "fps": 30, "reference_every": 2},
  "runs": [
    {"label": "moving", "scenes": ["water_pool"], "methods": ["splatting"]},
    {"label": "still", "scenes": ["water_pool"], "methods": ["caustic-triangles"], "animate": false}
  ]
}"#;

#[test]
fn an_animated_experiment_reproduces_resumes_compares_and_reports_its_sequences() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let t = tmp.path();
    let exp = t.join("experiments");
    std::fs::create_dir_all(&exp).expect("mkdir");
    std::fs::write(exp.join("animated.json"), ANIMATED).expect("write");
    let a = ReproduceArgs {
        name: "animated".into(),
        ..args(t, &exp, "out", None)
    };
    let outcome = reproduce(&a).unwrap_or_else(|e| panic!("reproduce: {e:#}"));
    assert_eq!(outcome.failed, 0);
    // Where its time went: three references, then two runs.
    let [time] = outcome.times.as_slice() else {
        panic!("one experiment's time: {:?}", outcome.times)
    };
    assert_eq!((time.runs, time.kept), (2, 0));
    assert!(
        time.references_s > 0.0 && time.total_s > time.references_s,
        "{time:?}"
    );
    let dir = t.join("out").join("animated");
    let m = read_manifest(&dir).expect("manifest");
    let seq = m
        .runs
        .iter()
        .find(|r| r.key == "water_pool/splatting/default")
        .expect("the sequence's run");
    assert_eq!(seq.status, "done", "{:?}", seq.reason);
    let rel = seq.dir.clone().expect("its folder");
    assert_eq!(rel, "runs/default/water_pool/splatting/animation");
    // Instants 0 and 1/30 s (every 2nd and the one after), and 2/30 s: three references
    // of the moving water, the first of which the still run shares.
    assert_eq!(
        m.rendered_references.len(),
        3,
        "{:?}",
        m.rendered_references
    );
    let anim = caustics::animate::load(&dir.join(&rel).join("animation.json")).expect("load");
    assert_eq!(anim.frames.len(), 3);
    assert_eq!(anim.frames.iter().filter(|f| f.errors.is_some()).count(), 3);
    assert_eq!(anim.temporal.len(), 1, "one scored pair: 0 and 1/30 s");

    let s = read_summary(&dir).expect("summary");
    let row = s
        .runs
        .iter()
        .find(|r| r.key == "water_pool/splatting/default")
        .expect("row");
    let q = row.sequence.as_ref().expect("the row's sequence figures");
    assert_eq!((q.frames, q.scored, q.reference_every), (3, 3, 2));
    assert!(
        q.temporal_rel_rmse
            .is_some_and(|v| v.is_finite() && v > 0.0)
    );
    assert!(
        q.flux_ratio.is_some_and(|f| (0.5..2.0).contains(&f)),
        "{q:?}"
    );
    assert_eq!(
        row.method_gpu_ms.map(|g| g.median),
        anim.timing.method_gpu_ms.as_ref().map(|g| g.median),
        "the row's GPU ms are the sequence's, over its instants"
    );
    let still = s
        .runs
        .iter()
        .find(|r| r.key == "water_pool/caustic-triangles/default")
        .expect("still row");
    assert!(still.sequence.is_none() && still.errors.is_some());
    let md = std::fs::read_to_string(dir.join("summary.md")).expect("summary.md");
    assert!(md.contains("## moving: animated sequences"), "{md}");
    assert!(md.contains("## still"), "{md}");
    let bmf: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("bmf.json")).expect("bmf")).expect("json");
    assert!(
        bmf["animated/water_pool/splatting/default"]["temporal_rel_rmse"]["value"].is_number(),
        "{bmf}"
    );

    // The same command again keeps both runs: the sequence is not rendered again.
    let before = std::fs::read(dir.join(&rel).join("animation.json")).expect("read");
    reproduce(&a).unwrap_or_else(|e| panic!("resume: {e:#}"));
    assert_eq!(
        std::fs::read(dir.join(&rel).join("animation.json")).expect("read"),
        before,
        "a complete sequence is kept"
    );
    // A scored instant whose reference left the cache makes the sequence stale: made
    // again, that instant unscored (the experiment may not render references here).
    let refs = t.join("references").join("water_pool");
    let third = anim.frames[2].reference.clone().expect("scored");
    let gone = std::fs::read_dir(&refs)
        .expect("references")
        .flatten()
        .map(|e| e.path())
        .find(|p| third.contains(&*p.file_name().unwrap_or_default().to_string_lossy()))
        .expect("the reference of the third instant");
    std::fs::remove_dir_all(&gone).expect("drop it");
    let no_refs = ReproduceArgs {
        no_render_references: true,
        ..a.clone()
    };
    reproduce(&no_refs).unwrap_or_else(|e| panic!("redo: {e:#}"));
    let redone = caustics::animate::load(&dir.join(&rel).join("animation.json")).expect("load");
    assert_eq!(
        redone.frames.iter().filter(|f| f.errors.is_some()).count(),
        2,
        "made again without the third instant's reference"
    );
    // Its errors at the other instants are those of the first making.
    assert_eq!(
        redone.frames[1].errors.map(|e| e.rel_mse),
        anim.frames[1].errors.map(|e| e.rel_mse)
    );
    assert_eq!(
        redone.tone_map.as_ref().and_then(|t| t.source.as_deref()),
        Some("reference p99")
    );
    // That sequence matches the cache as it is now: kept.
    let before = std::fs::read(dir.join(&rel).join("animation.json")).expect("read");
    reproduce(&no_refs).unwrap_or_else(|e| panic!("resume: {e:#}"));
    assert_eq!(
        std::fs::read(dir.join(&rel).join("animation.json")).expect("read"),
        before,
        "a sequence scored at the instants whose references the cache has is kept"
    );
    // An exposure set in the file makes it stale: made again at that exposure.
    std::fs::write(
        exp.join("animated.json"),
        ANIMATED.replace(
            "\"score_grid\": 2,",
            "\"score_grid\": 2, \"exposure\": 2.0,",
        ),
    )
    .expect("write");
    reproduce(&no_refs).unwrap_or_else(|e| panic!("exposure: {e:#}"));
    let exposed = caustics::animate::load(&dir.join(&rel).join("animation.json")).expect("load");
    let tone = exposed
        .tone_map
        .expect("a scored sequence records its exposure");
    assert_eq!(
        (tone.source.as_deref(), tone.exposure_scale),
        (Some("--exposure"), 2.0)
    );
    std::fs::write(exp.join("animated.json"), ANIMATED).expect("write");

    // A reproduction killed before its manifest: --summary-only finds the sequence done.
    std::fs::remove_file(dir.join("manifest.json")).expect("drop the manifest");
    reproduce(&ReproduceArgs {
        summary_only: true,
        ..a.clone()
    })
    .unwrap_or_else(|e| panic!("summary only: {e:#}"));
    let m = read_manifest(&dir).expect("manifest written from the runs");
    assert!(m.runs.iter().all(|r| r.status == "done"), "{:?}", m.runs);
    assert!(
        read_summary(&dir)
            .expect("summary")
            .runs
            .iter()
            .any(|r| r.sequence.is_some())
    );

    // compare pairs the sequence (and the still run) with itself: nothing changed.
    let report = strict_compare(&dir, &dir);
    assert_eq!(report.regressions(), 0, "{}", report.table(true));
    assert!(
        report.lines.iter().any(|l| l.run.contains("animation")),
        "{}",
        report.table(true)
    );

    // The report shows the sequence with its scored instants' images.
    let index = caustics::report::report(&caustics::report::ReportArgs {
        dir: dir.clone(),
        out: Some(t.join("report")),
        references: t.join("references"),
    })
    .expect("report");
    let html = std::fs::read_to_string(index).expect("index");
    assert!(html.contains("moving: animated sequences"), "report");
    assert!(
        html.contains("caustic_t0.033.png"),
        "the scored instants' images"
    );
}
