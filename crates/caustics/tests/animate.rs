//! `caustics run --animate` and `--time` on lavapipe: every frame a new instant, scored
//! instants in pairs, the temporal error, and a still instant that matches the sequence.

mod common;

use caustics::animate::{AnimationResult, load};
use caustics::run::{RunOptions, RunOutcome, run};

fn animate(o: &RunOptions) -> (std::path::PathBuf, AnimationResult) {
    match run(o).unwrap_or_else(|e| panic!("caustics run --animate failed: {e:#}")) {
        RunOutcome::Animated { dir, result } => (dir, *result),
        RunOutcome::Done { dir, .. } => panic!("expected a sequence, got {}", dir.display()),
        RunOutcome::Skipped { reason } => panic!("unexpectedly skipped: {reason}"),
    }
}

fn options(scene: &std::path::Path, out: &std::path::Path, method: &str) -> RunOptions {
    RunOptions {
        references: out.join("references"),
        quick_reference_photons: 1_000_000,
        score_grid: 2,
        ..common::run_options(scene, out, method, &[])
    }
}

#[test]
fn a_water_sequence_is_new_at_every_instant_and_a_still_run_repeats_an_instant() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let scene = common::small_scene(tmp.path(), "water_pool", 48, 36);
    let mut o = options(&scene, tmp.path(), "wavefront");
    o.animate = Some("0:0.1:30".into());
    o.reference_every = Some(2);
    let (dir, r) = animate(&o);
    assert_eq!(r.frames.len(), 3);
    let hashes: std::collections::BTreeSet<&str> =
        r.frames.iter().map(|f| f.scene_hash.as_str()).collect();
    assert_eq!(
        hashes.len(),
        3,
        "the waves travel: three instants, three scenes"
    );
    for f in &r.frames {
        assert!(
            f.method_gpu_ms.is_some_and(|ms| ms > 0.0),
            "frame {}",
            f.index
        );
        assert!(f.rebuild_ms > 0.0);
        // Pipelines are compiled by the first instant's rebuild only; the later ones
        // create the method anew on pipelines already compiled.
        assert_eq!(
            f.pipelines_compiled > 0,
            f.index == 0,
            "frame {}: {} pipelines compiled",
            f.index,
            f.pipelines_compiled
        );
        // Frames 0 and 2 are every 2nd; frame 1 is frame 0's partner.
        let e = f
            .errors
            .as_ref()
            .unwrap_or_else(|| panic!("frame {} unscored", f.index));
        let flux = e.flux_ratio.expect("a lit reference");
        assert!(
            (0.8..1.25).contains(&flux),
            "frame {}: flux {flux}",
            f.index
        );
        assert!(dir.join(f.image.as_deref().expect("image")).is_file());
    }
    assert_eq!(
        r.temporal.len(),
        1,
        "one pair (0, 1); frame 2 has no partner"
    );
    let pair = &r.temporal[0];
    assert!((pair.to_s - pair.from_s - 1.0 / 30.0).abs() < 1e-6);
    assert!(pair.error.temporal_rel_rmse.is_finite() && pair.error.still_rel_rmse.is_finite());
    assert!(pair.error.change_ratio.is_some(), "the water moved");
    let reloaded = load(&dir.join("animation.json")).expect("animation.json reads back");
    assert_eq!(reloaded.frames.len(), 3);
    assert!(dir.join("animation.md").is_file());

    // compare pairs sequences: a folder against a copy of itself has no regression; a
    // copy whose temporal error grew 10% has one.
    let copy = tmp.path().join("copy");
    let copy_dir = copy.join("water_pool/wavefront/animation");
    std::fs::create_dir_all(&copy_dir).expect("mkdir");
    let text = std::fs::read_to_string(dir.join("animation.json")).expect("read");
    std::fs::write(copy_dir.join("animation.json"), &text).expect("write");
    let args = |new: &std::path::Path| caustics::compare::CompareArgs {
        base: tmp.path().join("water_pool"),
        new: new.to_owned(),
        time_threshold: 0.05,
        alpha: 0.01,
        count_tolerance: 0.0,
        error_tolerance: 0.02,
        noise_k: 0.5,
        no_timings: true,
        verbose: false,
        wide: false,
        across_adapters: false,
        html: None,
    };
    let same = caustics::compare::compare(&args(&copy.join("water_pool"))).expect("compares");
    assert_eq!((same.runs, same.regressions()), (1, 0));
    let mut worse: serde_json::Value = serde_json::from_str(&text).expect("json");
    let t = worse["temporal_rel_rmse"]
        .as_f64()
        .expect("a temporal error");
    worse["temporal_rel_rmse"] = (t * 1.1).into();
    std::fs::write(copy_dir.join("animation.json"), worse.to_string()).expect("write");
    let report = caustics::compare::compare(&args(&copy.join("water_pool"))).expect("compares");
    assert_eq!(report.regressions(), 1, "{:?}", report.lines);
    assert!(
        report.lines.iter().any(|l| l.measure == "temporal relRMSE"
            && l.verdict == caustics::compare::Verdict::Regression)
    );

    // The same instant as a still run: the same scene, reference and errors.
    let still_of = &r.frames[1];
    let mut still = options(&scene, &tmp.path().join("still"), "wavefront");
    still.references = o.references.clone();
    still.time = Some(still_of.time_s);
    let (_, result) = common::run_dir(&still);
    assert_eq!(result.scene.time_s, Some(still_of.time_s));
    assert_eq!(result.scene.hash, still_of.scene_hash);
    let (a, b) = (
        &result.errors.as_ref().expect("scored").surface,
        still_of.errors.as_ref().expect("scored"),
    );
    assert_eq!(a.rel_mse, b.rel_mse, "same instant, same image, same error");
    assert_eq!(a.flux_ratio, b.flux_ratio);
}

#[test]
fn a_still_scene_has_no_temporal_error() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let scene = common::small_scene(tmp.path(), "sphere_on_plane", 48, 36);
    let mut o = options(&scene, tmp.path(), "caustic-triangles");
    o.animate = Some("0:2:1".into());
    o.reference_every = Some(1);
    let (_, r) = animate(&o);
    assert_eq!(r.frames.len(), 2);
    assert_eq!(r.frames[0].scene_hash, r.frames[1].scene_hash);
    assert_eq!(r.temporal.len(), 1);
    let e = &r.temporal[0].error;
    // One reference (one scene), a deterministic method: nothing changes.
    assert_eq!(e.temporal_rel_rmse, 0.0, "{e:?}");
    assert_eq!(e.change_ratio, None);
    assert!(e.still_rel_rmse > 0.0, "the method is not the reference");
}

#[test]
fn bad_sequences_are_refused_before_any_work() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let scene = common::small_scene(tmp.path(), "water_pool", 16, 12);
    for (spec, every, says) in [
        ("0:1", None, "expected START:END:FPS"),
        ("1:0:30", None, "END after START"),
        ("0:1:30", Some(0), "--reference-every"),
    ] {
        let mut o = options(&scene, tmp.path(), "wavefront");
        o.animate = Some(spec.into());
        o.reference_every = every;
        let err = format!("{:#}", run(&o).expect_err(spec));
        assert!(err.contains(says), "{spec}: {err}");
    }
    // A motion that leaves the coordinate range is found when posing, before the GPU.
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&scene).expect("scene")).expect("json");
    json["objects"][1]["motion"] = serde_json::json!({"velocity": [0, 0, 1.0e5]});
    let fast = common::write_scene(tmp.path(), "fast", &json);
    let mut o = options(&fast, tmp.path(), "wavefront");
    o.animate = Some("0:30:1".into());
    let err = format!("{:#}", run(&o).expect_err("leaves the range"));
    assert!(
        err.contains("objects[1].motion") && err.contains("at time 10 s"),
        "{err}"
    );
    assert!(!tmp.path().join("water_pool").exists(), "nothing written");
}
