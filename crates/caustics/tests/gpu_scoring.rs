//! The scored run of `caustics run` on the GPU: every method gives the same image for
//! the same sub-pixel offset whatever it rendered before (so one offset at the pixel
//! centre repeats the timed frame bit for bit); a scored run writes its files and pass
//! times and stores the pixel-averaged and the 1-spp errors side by side; the errors
//! against a reference (given, or found in the cache by scene hash) say "identical" for
//! the image itself and tell scale from shape; a reference of the wrong size is refused
//! before any write; with the adapter's ceilings record beside it, every timed pass of
//! every method is read against it (its roofline). Runs on lavapipe on CI; without an adapter it fails with the install
//! hint. (Each method's accuracy is tested in its own crate, `tests/accuracy.rs`.)

mod common;

use caustics::reference_cmd::{ReferenceArgs, reference};
use caustics::result::RunResult;
use caustics::run::run;
use caustics_metrics::{HdrImage, read_exr};
use common::{run_dir, run_options, small_scene};

/// The committed ceilings record, filed under this adapter's name in `dir` as this
/// machine's (CI's Mesa and CPU may differ from the machine that measured it: the figures
/// only need to be real).
fn ceilings_for_this_adapter(dir: &std::path::Path) {
    let committed = std::fs::read_dir(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../results/ceilings"),
    )
    .expect("results/ceilings")
    .filter_map(Result::ok)
    .map(|e| e.path())
    .find(|p| p.extension().is_some_and(|e| e == "json"))
    .expect("a committed ceilings record");
    let ctx = caustics_gpu::GpuContext::new(&caustics_gpu::AdapterChoice::from_flag_or_env(None))
        .unwrap_or_else(|e| panic!("{e}"));
    let machine = caustics::machine::machine(&ctx.summary);
    let path = caustics::ceilings_cmd::record_path(dir, &machine);
    std::fs::create_dir_all(dir).expect("ceilings dir");
    // Filed as this machine's: a software adapter's record is only read on its own CPU.
    let mut record: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&committed).expect("read the record"))
            .expect("a JSON record");
    record["machine"] = serde_json::to_value(&machine).expect("machine");
    std::fs::write(&path, serde_json::to_vec_pretty(&record).expect("json"))
        .expect("write the record");
}

#[test]
fn every_method_repeats_its_timed_frame_at_the_pixel_centre() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let ceilings = tmp.path().join("ceilings");
    ceilings_for_this_adapter(&ceilings);
    let scenes = ["sphere_on_plane", "fog_sphere"].map(|s| small_scene(tmp.path(), s, 32, 24));
    for info in caustics::registry::methods() {
        // The first of the two scenes the method renders (fog_sphere has volume caustics).
        let Some(scene) = scenes.iter().find(|p| {
            let scene = caustics_scene::Scene::load(p).expect("scene");
            let defaults = (info.parse)(&serde_json::Value::Null).expect("defaults parse");
            info.supports(&scene, &defaults).is_ok()
        }) else {
            panic!(
                "{} renders neither sphere_on_plane nor fog_sphere",
                info.name
            );
        };
        let mut o = run_options(scene, &tmp.path().join("runs"), info.name, &[]);
        (o.warmup, o.frames, o.score_grid) = (1, 2, 1);
        o.ceilings = ceilings.clone();
        let (dir, result) = run_dir(&o);
        check_roofline(&result);
        let scoring = result.scoring.as_ref().expect("scoring info");
        assert_eq!((scoring.grid, scoring.samples_per_pixel), (1, 1));
        let mut images = vec!["surface"];
        if info.capabilities.volume {
            images.push("volume");
        }
        for image in images {
            let scored = read_exr(&dir.join(format!("{image}.exr"))).expect("scored image");
            let timed = read_exr(&dir.join(format!("{image}_1spp.exr"))).expect("timed image");
            assert!(
                scored.pixels == timed.pixels,
                "{}: the {image} image of the scoring frame at the pixel centre differs from the timed frame's",
                info.name
            );
        }
    }
}

/// Every pass with a positive median time is read against the ceilings, in recording
/// order; render passes with counted fragments get a fill share, compute passes their
/// invocation rate, and the bound is the largest share's kind (or `shader`).
fn check_roofline(result: &RunResult) {
    use caustics_ceilings::roofline::{BOUND_SHARE, Bound};
    let method = &result.method.name;
    let roofline = result
        .roofline
        .as_ref()
        .unwrap_or_else(|| panic!("{method}: no roofline with a ceilings record"));
    let timed: Vec<&str> = result
        .timing
        .passes
        .iter()
        .filter(|p| p.gpu_ms.as_ref().is_some_and(|s| s.median > 0.0))
        .map(|p| p.name.as_str())
        .collect();
    let read: Vec<&str> = roofline.passes.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(read, timed, "{method}: every timed pass, in order");
    let fragments = result
        .fragments
        .as_ref()
        .expect("lavapipe counts fragments");
    for p in &roofline.passes {
        let shares = [&p.fill, &p.bandwidth, &p.overhead];
        let largest = shares
            .iter()
            .filter_map(|s| s.as_ref().map(|s| s.fraction))
            .fold(0.0, f64::max);
        assert!(
            p.fraction.is_finite() && p.fraction >= 0.0,
            "{method} {}",
            p.name
        );
        assert_eq!(p.fraction, largest, "{method} {}", p.name);
        assert_eq!(
            p.bound == Bound::Shader,
            largest < BOUND_SHARE,
            "{method} {}: bound {:?} at {largest}",
            p.name,
            p.bound
        );
        let counted = fragments
            .passes
            .iter()
            .find(|f| f.name == p.name)
            .expect("counted");
        if counted.compute_shader_invocations > 0 {
            assert!(
                p.invocations_per_s.is_some_and(|r| r > 0.0),
                "{method} {}",
                p.name
            );
            assert!(
                p.fill.is_none(),
                "{method} {}: a compute pass has no fill",
                p.name
            );
        } else {
            let fill = p
                .fill
                .as_ref()
                .unwrap_or_else(|| panic!("{method} {}: no fill share", p.name));
            assert_eq!(fill.work, counted.fragment_shader_invocations as f64);
        }
        assert!(p.overhead.is_some(), "{method} {}", p.name);
    }
}

#[test]
fn a_scored_run_keeps_pixel_averaged_and_1spp_errors_side_by_side() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let scene = small_scene(tmp.path(), "sphere_on_plane", 48, 36);
    let references = tmp.path().join("references");
    reference(&ReferenceArgs {
        scene: Some(scene.display().to_string()),
        photons: Some(1 << 20),
        seconds: None,
        time: None,
        resolution: None,
        out: None,
        references: references.clone(),
        seed: 1,
        batches: 4,
        direct: false,
        bench: false,
        limits: Default::default(),
    })
    .expect("reference");
    let mut o = run_options(&scene, &tmp.path().join("runs"), "wavefront", &[]);
    (o.score_grid, o.exposure, o.references) = (2, None, references);
    (o.warmup, o.frames) = (1, 3);
    o.instrumentation_overhead = true;
    let (dir, result) = run_dir(&o);
    assert_eq!(result.schema_version, caustics::result::SCHEMA_VERSION);
    // --instrumentation-overhead: one bare frame after each timed frame, compared by
    // wall time (no bound on the figure itself: it is a measurement, not a count).
    let inst = result
        .instrumentation
        .as_ref()
        .expect("instrumentation figures");
    assert_eq!(inst.bare_wall_ms.samples, 3);
    assert_eq!(inst.timed_wall_ms.samples, 3);
    assert!(inst.bare_wall_ms.min > 0.0 && inst.count_wall_ms > 0.0);
    let expected = inst.timed_wall_ms.median / inst.bare_wall_ms.median - 1.0;
    assert!((inst.overhead - expected).abs() < 1e-12, "{inst:?}");
    for f in [
        "result.json",
        "surface.exr",
        "direct.exr",
        "composite.png",
        "fill_heatmap.png",
    ] {
        assert!(dir.join(f).is_file(), "{f} missing in {}", dir.display());
    }
    // Timestamps: lavapipe has them, so every pass has a time in every measured frame,
    // none rejected.
    assert!(
        result.timing.timestamps_available,
        "adapter without timestamp queries"
    );
    assert_eq!(result.timing.rejected_timestamps, 0);
    for p in &result.timing.passes {
        let s = p
            .gpu_ms
            .as_ref()
            .unwrap_or_else(|| panic!("no time for {}", p.name));
        assert_eq!(s.samples, 3, "{}", p.name);
    }
    let scoring = result.scoring.as_ref().expect("scoring info");
    assert_eq!((scoring.grid, scoring.samples_per_pixel), (2, 4));
    assert_eq!(result.tone_map.source.as_deref(), Some("reference p99"));
    let (scored, timed) = (
        result.errors.as_ref().expect("pixel-averaged errors"),
        result.errors_1spp.as_ref().expect("1-spp errors"),
    );
    for e in [&scored.surface, &timed.surface] {
        let flux = e.flux_ratio.expect("flux ratio");
        assert!((0.5..2.0).contains(&flux), "flux ratio {flux}");
        assert!(e.hdr_flip.is_some() && e.rel_mse_after_flux.is_some());
    }
    assert!(
        scored.surface != timed.surface,
        "4 offsets and 1 scored the same"
    );

    // A version-1 file (errors scored at 1 spp) reads with its errors moved to
    // errors_1spp, so it is never compared with pixel-averaged errors.
    let text = std::fs::read_to_string(dir.join("result.json")).expect("result.json");
    let mut v1: serde_json::Value = serde_json::from_str(&text).expect("json");
    v1["schema_version"] = 1.into();
    let obj = v1.as_object_mut().expect("object");
    obj.remove("errors_1spp");
    obj.remove("scoring");
    let old = RunResult::from_json(&v1.to_string()).expect("version-1 file");
    assert!(old.errors.is_none());
    assert_eq!(
        old.errors_1spp.as_ref().map(|e| e.surface),
        Some(scored.surface)
    );
}

#[test]
fn errors_against_a_reference_are_zero_for_itself_and_tell_scale_from_shape() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let scene = small_scene(tmp.path(), "water_pool", 128, 96);
    let (dir, first) = run_dir(&run_options(
        &scene,
        &tmp.path().join("a"),
        "wavefront",
        &[],
    ));
    assert!(first.errors.is_none(), "no reference, no errors");
    let surface = read_exr(&dir.join("surface.exr")).expect("surface.exr");

    // The same image as its own reference: every comparator says "identical".
    let same = tmp.path().join("same.exr");
    caustics_metrics::write_exr(&same, &surface).expect("write reference");
    let mut o = run_options(&scene, &tmp.path().join("b"), "wavefront", &[]);
    o.reference = Some(same);
    let (dir_b, r) = run_dir(&o);
    let e = r.errors.expect("errors with a reference").surface;
    assert_eq!(e.rmse, 0.0, "runs are deterministic on one adapter");
    assert_eq!(e.flip, 0.0);
    assert!((e.ssim - 1.0).abs() < 1e-9, "{}", e.ssim);
    assert!(dir_b.join("error.png").is_file());

    // Twice as bright a reference: a pure normalization error, which the best
    // scale explains fully.
    let double = tmp.path().join("double.exr");
    caustics_metrics::write_exr(&double, &surface.scaled(2.0)).expect("write reference");
    o.reference = Some(double);
    o.out = tmp.path().join("c");
    let e = run_dir(&o).1.errors.expect("errors").surface;
    assert!(e.rmse > 0.0 && e.flip > 0.0);
    assert!(
        (e.best_scale - 2.0).abs() < 1e-4,
        "best scale {}",
        e.best_scale
    );
    assert!(
        e.rmse_after_best_scale < 1e-4 * e.rmse,
        "{} vs {}",
        e.rmse_after_best_scale,
        e.rmse
    );
}

#[test]
fn a_reference_of_the_wrong_size_is_refused_before_any_write() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let scene = small_scene(tmp.path(), "water_pool", 64, 48);
    let reference = tmp.path().join("small.exr");
    caustics_metrics::write_exr(&reference, &HdrImage::new(32, 24)).expect("write");
    let out = tmp.path().join("out");
    let mut o = run_options(&scene, &out, "wavefront", &[]);
    o.reference = Some(reference);
    let e = run(&o).expect_err("size mismatch").to_string();
    assert!(
        e.contains("expected a 64x48 image") && e.contains("got 32x24"),
        "{e}"
    );
    assert!(!out.exists(), "nothing may be written");
}

#[test]
fn a_cached_reference_is_found_by_scene_hash_and_used() {
    use caustics::references::{ReferenceMeta, cache_dir, find};
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = small_scene(tmp.path(), "water_pool", 64, 48);
    let scene = caustics_scene::Scene::load(&path).expect("scene");
    let root = tmp.path().join("refs");
    assert!(find(&root, &scene).expect("empty cache").is_none());

    // A reference of all-ones radiance with a known standard error.
    let dir = cache_dir(&root, &scene);
    std::fs::create_dir_all(&dir).expect("mkdir");
    let mut ones = HdrImage::new(64, 48);
    ones.pixels.iter_mut().for_each(|p| *p = [1.0; 3]);
    caustics_metrics::write_exr(&dir.join("caustic.exr"), &ones).expect("write");
    caustics_metrics::write_exr(&dir.join("stderr.exr"), &ones.scaled(0.01)).expect("write");
    let meta = ReferenceMeta {
        schema_version: 2,
        transport_version: caustics_reference::TRANSPORT_VERSION,
        scene: scene.name.clone(),
        scene_hash: scene.hash_hex(),
        width: 64,
        height: 48,
        photons: 1000,
        seconds: 1.0,
        photons_per_second: 1000.0,
        seed: 1,
        batches: 16,
        commit: "test".into(),
        relative_stderr: 0.01,
        time_s: None,
    };
    std::fs::write(
        dir.join("meta.json"),
        serde_json::to_vec(&meta).expect("json"),
    )
    .expect("write");

    let mut o = run_options(&path, &tmp.path().join("out"), "wavefront", &[]);
    o.references = root.clone();
    let (_, r) = run_dir(&o);
    let e = r.errors.expect("the cached reference is used");
    assert_eq!(e.reference_source, "cache");
    assert!(e.reference.ends_with("caustic.exr"), "{}", e.reference);
    let noise = e
        .reference_noise_rms
        .expect("stderr.exr beside the reference");
    assert!((noise - 0.01).abs() < 1e-6, "{noise}");

    // A meta.json that does not match the scene is an error, not a silent miss.
    let mut stale = meta.clone();
    stale.scene_hash = "0000000000000000".into();
    std::fs::write(
        dir.join("meta.json"),
        serde_json::to_vec(&stale).expect("json"),
    )
    .expect("write");
    let err = run(&o).expect_err("stale cache").to_string();
    assert!(
        err.contains("meta.json") && err.contains("0000000000000000"),
        "{err}"
    );

    // So is one made by another version of the reference's light transport; and the
    // folder a new render goes to is another one, so no older image is ever found.
    let mut older = meta.clone();
    older.transport_version = caustics_reference::TRANSPORT_VERSION - 1;
    std::fs::write(
        dir.join("meta.json"),
        serde_json::to_vec(&older).expect("json"),
    )
    .expect("write");
    let err = run(&o).expect_err("older transport").to_string();
    assert!(err.contains("reference transport"), "{err}");
    let name = dir.file_name().and_then(|n| n.to_str()).unwrap_or_default();
    assert!(
        name.ends_with(&format!("-t{}", caustics_reference::TRANSPORT_VERSION)),
        "{name}"
    );
}
