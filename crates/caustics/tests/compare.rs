//! The regression gate is itself tested (STYLE 6): it flags a 10% slowdown outside the
//! noise, a changed fragment count and a worse error (surface and volume, relMSE,
//! HDR-FLIP, flux ratio), does not flag identical runs or a change inside the noise,
//! compares pixel-averaged errors only with pixel-averaged ones (a schema-1 file against
//! a schema-2 one: the 1-spp errors only), and refuses bad folders clearly without
//! writing anything.

use std::path::Path;
use std::process::Command;

use caustics::compare::{CompareArgs, Verdict, compare};
use serde_json::Value;

/// A real result file from the repository, with synthetic per-frame samples.
fn template() -> Value {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../results/foundation/water_pool/wavefront/result.json");
    let mut v: Value =
        serde_json::from_str(&std::fs::read_to_string(&p).expect("template")).expect("json");
    set_times(&mut v, 10.0, 1.0);
    v
}

/// A schema-2 result made from a real schema-1 file with volume errors (fog_sphere,
/// static-grid, 48×36): its errors become the 1-spp errors, and synthetic pixel-averaged
/// errors (smaller, as a 4×4 scoring frame gives) with every schema-2 figure go under
/// `errors`.
fn template_v2() -> Value {
    let mut v = template_v1_volume();
    let one = v["errors"].clone();
    v["schema_version"] = 2.into();
    v["scoring"] = serde_json::json!({"grid": 4, "samples_per_pixel": 16, "wall_ms": 12.5});
    v["errors_1spp"] = one;
    for (which, e) in [("errors_1spp", 1.0), ("errors", 0.6)] {
        for (part, flux) in [("surface", 0.97), ("volume", 1.04)] {
            let x = &mut v[which][part];
            for k in ["rmse", "rel_mse", "flip", "rmse_after_best_scale"] {
                x[k] = (x[k].as_f64().expect(k) * e).into();
            }
            x["flux_ratio"] = flux.into();
            x["flux_ratio_image"] = (flux + 0.01).into();
            x["rel_mse_after_flux"] = (0.8 * e * x["rel_mse"].as_f64().expect("rel")).into();
            x["hdr_flip"] = (0.05 * e).into();
            x["hdr_flip_after_flux"] = (0.045 * e).into();
            x["hdr_flip_start_exposure"] = (-3.0).into();
            x["hdr_flip_stop_exposure"] = 4.5.into();
        }
    }
    v
}

/// The schema-1 file `template_v2` starts from: `ci-smoke`'s fog_sphere/static-grid run as
/// committed at 72437bc (a frozen copy, so re-running the experiment leaves the test alone).
fn template_v1_volume() -> Value {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/result_v1_fog_sphere_static_grid.json");
    let mut v: Value =
        serde_json::from_str(&std::fs::read_to_string(&p).expect("template")).expect("json");
    assert_eq!(v["schema_version"], 1, "the fixture is a schema-1 file");
    assert!(
        v["errors"]["volume"].is_object(),
        "the fixture has volume errors"
    );
    set_times(&mut v, 10.0, 1.0);
    v
}

fn lines_of(a: &CompareArgs) -> Vec<(String, Verdict)> {
    compare(a)
        .expect("compare")
        .lines
        .into_iter()
        .map(|l| (l.measure, l.verdict))
        .collect()
}

fn exit_code(a: &CompareArgs) -> (Option<i32>, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_caustics"))
        .args([
            "compare",
            a.base.to_str().expect("utf8"),
            a.new.to_str().expect("utf8"),
        ])
        .output()
        .expect("run");
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
    )
}

/// Deterministic "noisy" frame times around `centre` × `scale`: ±1% jitter.
fn samples(centre: f64, scale: f64) -> Vec<f64> {
    (0..20)
        .map(|i| scale * centre * (1.0 + 0.01 * (((i * 7) % 11) as f64 - 5.0) / 5.0))
        .collect()
}

fn summary(values: &[f64]) -> Value {
    serde_json::to_value(caustics::stats::summarize(values).expect("samples")).expect("json")
}

fn set_times(v: &mut Value, method_ms: f64, scale: f64) {
    v["timing"]["method_gpu_ms"] = summary(&samples(method_ms, scale));
    v["timing"]["frame_gpu_ms"] = summary(&samples(method_ms + 5.0, scale));
}

fn write(dir: &Path, v: &Value) {
    let d = dir.join("runs/default/water_pool/wavefront");
    std::fs::create_dir_all(&d).expect("mkdir");
    std::fs::write(
        d.join("result.json"),
        serde_json::to_vec_pretty(v).expect("json"),
    )
    .expect("write");
}

fn args(base: &Path, new: &Path) -> CompareArgs {
    CompareArgs {
        base: base.into(),
        new: new.into(),
        time_threshold: 0.05,
        alpha: 0.01,
        count_tolerance: 0.0,
        error_tolerance: 0.02,
        noise_k: 0.5,
        no_timings: false,
        verbose: false,
        wide: false,
        across_adapters: false,
        html: None,
    }
}

fn pair(base: &Value, new: &Value) -> (tempfile::TempDir, CompareArgs) {
    let tmp = tempfile::tempdir().expect("tempdir");
    let (b, n) = (tmp.path().join("base"), tmp.path().join("new"));
    write(&b, base);
    write(&n, new);
    let a = args(&b, &n);
    (tmp, a)
}

fn regressions_in(a: &CompareArgs) -> Vec<String> {
    let r = compare(a).expect("compare");
    r.lines
        .iter()
        .filter(|l| l.verdict == Verdict::Regression)
        .map(|l| l.measure.clone())
        .collect()
}

#[test]
fn identical_runs_are_not_flagged() {
    let v = template();
    let (_t, a) = pair(&v, &v);
    let r = compare(&a).expect("compare");
    assert_eq!(r.regressions(), 0, "{}", r.table(true));
    assert_eq!(r.runs, 1);
    assert!(r.lines.len() > 10, "compared too little: {}", r.table(true));
}

#[test]
fn a_ten_percent_slowdown_outside_the_noise_is_flagged() {
    let base = template();
    let mut new = base.clone();
    set_times(&mut new, 10.0, 1.1);
    let (_t, a) = pair(&base, &new);
    let regs = regressions_in(&a);
    assert!(regs.contains(&"method GPU ms".to_owned()), "{regs:?}");
    // Gated off for CI, it is still shown.
    let r = compare(&CompareArgs {
        no_timings: true,
        ..a.clone()
    })
    .expect("compare");
    assert_eq!(r.regressions(), 0, "{}", r.table(false));
    assert!(r.table(false).contains("--no-timings"));
    // A 10% speed-up is better, not a regression.
    let mut faster = base.clone();
    set_times(&mut faster, 10.0, 0.9);
    let (_t, a) = pair(&base, &faster);
    let r = compare(&a).expect("compare");
    assert_eq!(r.regressions(), 0, "{}", r.table(false));
    assert!(r.lines.iter().any(|l| l.verdict == Verdict::Better));
}

#[test]
fn a_slowdown_inside_the_noise_or_below_the_threshold_is_not_flagged() {
    let base = template();
    // 2% slower: significant with this little jitter, but under the 5% minimum effect.
    let mut new = base.clone();
    set_times(&mut new, 10.0, 1.02);
    let (_t, a) = pair(&base, &new);
    assert!(regressions_in(&a).is_empty());
    // 10% slower median but with huge noise: not significant.
    let mut noisy_base = base.clone();
    let wide: Vec<f64> = (0..20).map(|i| 5.0 + (i % 10) as f64).collect();
    let wide_new: Vec<f64> = wide.iter().map(|v| v * 1.1).collect();
    noisy_base["timing"]["method_gpu_ms"] = summary(&wide[..6]);
    let mut noisy_new = base.clone();
    noisy_new["timing"]["method_gpu_ms"] = summary(&wide_new[..6]);
    let (_t, a) = pair(&noisy_base, &noisy_new);
    assert!(!regressions_in(&a).contains(&"method GPU ms".to_owned()));
}

#[test]
fn old_files_without_samples_use_the_percentile_ranges() {
    let mut base = template();
    let mut new = base.clone();
    set_times(&mut new, 10.0, 1.2);
    for v in [&mut base, &mut new] {
        for k in ["method_gpu_ms", "frame_gpu_ms"] {
            v["timing"][k]
                .as_object_mut()
                .expect("obj")
                .remove("values");
        }
    }
    let (_t, a) = pair(&base, &new);
    assert!(regressions_in(&a).contains(&"method GPU ms".to_owned()));
}

#[test]
fn a_changed_fragment_count_or_counter_is_flagged() {
    let base = template();
    let mut new = base.clone();
    let f = new["fragments"]["method_total"].as_u64().expect("u64");
    new["fragments"]["method_total"] = (f + 1).into();
    new["counters"]["kept_triangles"] = 5.into();
    let (_t, a) = pair(&base, &new);
    let regs = regressions_in(&a);
    assert!(regs.contains(&"fragments (method)".to_owned()), "{regs:?}");
    assert!(
        regs.contains(&"counter kept_triangles".to_owned()),
        "{regs:?}"
    );
    // A stated tolerance admits the one-fragment change but not the counter.
    let regs = regressions_in(&CompareArgs {
        count_tolerance: 0.01,
        ..a
    });
    assert!(!regs.contains(&"fragments (method)".to_owned()), "{regs:?}");
    assert!(
        regs.contains(&"counter kept_triangles".to_owned()),
        "{regs:?}"
    );
}

#[test]
fn errors_are_gated_against_the_reference_noise() {
    let mut base = template_v2();
    let rmse = base["errors"]["surface"]["rmse"].as_f64().expect("rmse");
    // A noisy reference: σ_ref = 20% of the RMSE.
    let noise = 0.2 * rmse;
    base["errors"]["reference_noise_rms"] = noise.into();
    // Inside half the reference noise (and above the 2% relative tolerance): no change.
    let mut within = base.clone();
    within["errors"]["surface"]["rmse"] = (rmse + 0.4 * noise).into();
    let (_t, a) = pair(&base, &within);
    assert!(regressions_in(&a).is_empty());
    // Beyond it: worse.
    let mut worse = base.clone();
    worse["errors"]["surface"]["rmse"] = (rmse + 2.0 * noise + 0.1 * rmse).into();
    worse["errors"]["surface"]["flip"] = 0.2.into();
    let (_t, a) = pair(&base, &worse);
    let regs = regressions_in(&a);
    assert!(regs.contains(&"error RMSE".to_owned()), "{regs:?}");
    assert!(regs.contains(&"error FLIP".to_owned()), "{regs:?}");
    // A schema-1 file's errors are its 1-spp errors, gated under that name.
    let base = template();
    let mut worse = base.clone();
    worse["errors"]["surface"]["flip"] = 0.2.into();
    let (_t, a) = pair(&base, &worse);
    assert_eq!(regressions_in(&a), vec!["error 1spp FLIP".to_owned()]);
}

#[test]
fn equal_files_compare_equal_on_every_error_figure() {
    let v = template_v2();
    let (_t, a) = pair(&v, &v);
    let lines = lines_of(&a);
    assert!(lines.iter().all(|l| l.1 == Verdict::Same), "{lines:?}");
    for m in [
        "error relMSE",
        "error HDR-FLIP",
        "error flux ratio",
        "error relMSE after flux",
        "error volume relMSE",
        "error volume HDR-FLIP",
        "error volume flux ratio",
        "error 1spp volume relMSE",
        "error 1spp HDR-FLIP",
    ] {
        assert!(
            lines.iter().any(|l| l.0 == m),
            "{m} not compared: {lines:?}"
        );
    }
    assert_eq!(exit_code(&a).0, Some(0));
}

#[test]
fn a_synthetic_volume_regression_is_caught_with_exit_2() {
    let base = template_v2();
    let mut new = base.clone();
    let v = &mut new["errors"]["volume"];
    v["rel_mse"] = (1.5 * v["rel_mse"].as_f64().expect("rel")).into();
    v["hdr_flip"] = 0.08.into();
    let (_t, a) = pair(&base, &new);
    assert_eq!(
        regressions_in(&a),
        vec![
            "error volume relMSE".to_owned(),
            "error volume HDR-FLIP".to_owned()
        ]
    );
    let (code, stdout) = exit_code(&a);
    assert_eq!(code, Some(2), "{stdout}");
    assert!(stdout.contains("error volume relMSE"), "{stdout}");
    // Volume errors gone from NEW: a regression too.
    let mut gone = base.clone();
    gone["errors"]["volume"] = Value::Null;
    let (_t, a) = pair(&base, &gone);
    assert_eq!(regressions_in(&a), vec!["error volume".to_owned()]);
}

#[test]
fn a_surface_hdr_flip_regression_is_caught() {
    let base = template_v2();
    let set = |f: f64| {
        let mut v = base.clone();
        v["errors"]["surface"]["hdr_flip"] = (0.03 * f).into();
        v
    };
    let base = set(1.0);
    let (_t, a) = pair(&base, &set(1.1));
    assert_eq!(regressions_in(&a), vec!["error HDR-FLIP".to_owned()]);
    assert_eq!(exit_code(&a).0, Some(2));
    // Within the 2% tolerance: the same; 10% lower: better.
    let (_t, a) = pair(&base, &set(1.01));
    assert!(regressions_in(&a).is_empty());
    let (_t, a) = pair(&base, &set(0.9));
    let lines = lines_of(&a);
    assert!(
        lines.contains(&("error HDR-FLIP".into(), Verdict::Better)),
        "{lines:?}"
    );
}

#[test]
fn a_flux_ratio_is_worse_when_it_moves_away_from_one() {
    let base = template_v2(); // surface flux ratio 0.97
    let with = |f: f64| {
        let mut v = base.clone();
        v["errors"]["surface"]["flux_ratio"] = f.into();
        v
    };
    let verdict = |f: f64| {
        let (_t, a) = pair(&base, &with(f));
        lines_of(&a)
            .into_iter()
            .find(|l| l.0 == "error flux ratio")
            .expect("flux compared")
            .1
    };
    assert_eq!(verdict(0.90), Verdict::Regression, "7% less light");
    assert_eq!(
        verdict(1.06),
        Verdict::Regression,
        "overshoot further from 1"
    );
    assert_eq!(verdict(1.0), Verdict::Better);
    assert_eq!(verdict(0.98), Verdict::Same, "|Δ| inside the tolerance");
}

#[test]
fn schema_1_against_schema_2_compares_the_1spp_errors_only() {
    let v1 = template_v1_volume();
    let v2 = template_v2();
    for (base, new) in [(&v1, &v2), (&v2, &v1)] {
        let (_t, a) = pair(base, new);
        let r = compare(&a).expect("compare");
        assert_eq!(r.regressions(), 0, "{}", r.table(true));
        let info = r
            .lines
            .iter()
            .find(|l| l.measure == "errors (pixel-averaged)")
            .expect("an Info line says what was compared");
        assert_eq!(info.verdict, Verdict::Info);
        assert!(info.change.contains("1-spp"), "{}", info.change);
        // Nothing pixel-averaged is compared with anything 1-spp.
        assert!(
            r.lines
                .iter()
                .filter(|l| l.measure.starts_with("error "))
                .all(|l| l.measure.starts_with("error 1spp ")),
            "{}",
            r.table(true)
        );
        assert!(
            r.lines
                .iter()
                .any(|l| l.measure == "error 1spp volume relMSE" && l.verdict == Verdict::Same),
            "{}",
            r.table(true)
        );
    }
    // The 1-spp errors are still gated across the schemas.
    let mut worse = v2.clone();
    worse["errors_1spp"]["volume"]["rel_mse"] = 0.5.into();
    let (_t, a) = pair(&v1, &worse);
    assert_eq!(
        regressions_in(&a),
        vec!["error 1spp volume relMSE".to_owned()]
    );
    // Pixel-averaged errors of other sample counts are not compared either.
    let mut other = v2.clone();
    other["scoring"]["samples_per_pixel"] = 4.into();
    other["errors"]["surface"]["rel_mse"] = 1.0.into();
    let (_t, a) = pair(&v2, &other);
    let lines = lines_of(&a);
    assert!(
        lines.contains(&("errors (pixel-averaged)".into(), Verdict::Info)),
        "{lines:?}"
    );
    assert!(regressions_in(&a).is_empty(), "{lines:?}");
}

#[test]
fn missing_runs_changed_inputs_and_new_runs() {
    let base = template();
    let tmp = tempfile::tempdir().expect("tempdir");
    let (b, n) = (tmp.path().join("base"), tmp.path().join("new"));
    write(&b, &base);
    // NEW holds another run only.
    let d = n.join("runs/default/ring/wavefront");
    std::fs::create_dir_all(&d).expect("mkdir");
    std::fs::write(
        d.join("result.json"),
        serde_json::to_vec(&base).expect("json"),
    )
    .expect("write");
    let r = compare(&args(&b, &n)).expect("compare");
    assert_eq!(r.regressions(), 1, "{}", r.table(true));
    assert!(r.lines.iter().any(|l| l.verdict == Verdict::New));
    // Same run, other parameters: not comparable, not a regression.
    let mut other = base.clone();
    other["method"]["params"] = serde_json::json!({"grid": 64});
    let (_t, a) = pair(&base, &other);
    assert!(regressions_in(&a).is_empty());
    let r = compare(&a).expect("compare");
    assert_eq!(r.not_comparable(), 1, "{}", r.table(true));
    assert_eq!(r.exit_code(), caustics::compare::EXIT_NOT_COMPARABLE);
}

/// The README's old example: a baseline at 96×72 against a reproduction at half scale.
/// Every pair is "not comparable" (exit 3, saying which inputs differ), never a list of
/// regressions; nothing else of such a pair is compared.
#[test]
fn runs_at_other_resolutions_or_adapters_are_not_comparable() {
    let base = template();
    let mut half = base.clone();
    half["scene"]["width"] = (base["scene"]["width"].as_u64().expect("w") / 2).into();
    half["scene"]["height"] = (base["scene"]["height"].as_u64().expect("h") / 2).into();
    half["fragments"]["method_total"] = 1.into();
    set_times(&mut half, 10.0, 0.25);
    let (_t, a) = pair(&base, &half);
    let r = compare(&a).expect("compare");
    assert_eq!(r.regressions(), 0, "{}", r.table(true));
    assert_eq!(r.lines.len(), 1, "{}", r.table(true));
    let l = &r.lines[0];
    assert_eq!(l.verdict, Verdict::NotComparable);
    assert!(l.change.contains("resolution"), "{}", l.change);
    assert!(
        l.base.contains(&format!("{}x", base["scene"]["width"])),
        "{}",
        l.base
    );
    let (code, stdout) = exit_code(&a);
    assert_eq!(code, Some(3), "{stdout}");
    assert!(stdout.contains("NOT COMPARABLE"), "{stdout}");
    assert!(stdout.contains("resolution"), "{stdout}");
    // Compact: grouped by run, no line wider than the measures need.
    assert!(stdout.lines().all(|l| l.chars().count() < 120), "{stdout}");

    // A missing run of BASE still regresses, whatever else is not comparable.
    let mut more = base.clone();
    more["scene"]["name"] = "ring".into();
    let d = a.base.join("runs/default/ring/wavefront");
    std::fs::create_dir_all(&d).expect("mkdir");
    std::fs::write(d.join("result.json"), more.to_string()).expect("write");
    assert_eq!(exit_code(&a).0, Some(2));

    // Another adapter (or driver): not comparable unless asked; with --across-adapters
    // counts and errors are gated and timings only shown.
    let mut other = base.clone();
    other["machine"]["adapter"] = "NVIDIA H200".into();
    set_times(&mut other, 10.0, 0.2);
    let (_t, a) = pair(&base, &other);
    let r = compare(&a).expect("compare");
    assert_eq!(r.not_comparable(), 1, "{}", r.table(true));
    assert!(
        r.lines[0].change.contains("adapter"),
        "{}",
        r.lines[0].change
    );
    let r = compare(&CompareArgs {
        across_adapters: true,
        ..a.clone()
    })
    .expect("compare");
    assert_eq!(r.not_comparable() + r.regressions(), 0, "{}", r.table(true));
    assert!(r.lines.len() > 10, "{}", r.table(true));
    let timing = r
        .lines
        .iter()
        .find(|l| l.measure == "method GPU ms")
        .expect("timing line");
    assert_eq!(timing.verdict, Verdict::Info);
    assert!(
        timing.change.contains("different adapters"),
        "{}",
        timing.change
    );
    // The wide table carries each verdict's test.
    assert!(
        r.wide_table(true).contains("Mann-Whitney"),
        "{}",
        r.wide_table(true)
    );
    assert!(!r.table(true).contains("Mann-Whitney"), "{}", r.table(true));
}

fn listing(root: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("read_dir") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push((p.display().to_string(), std::fs::read(&p).expect("read")));
            }
        }
    }
    out.sort();
    out
}

#[test]
fn the_binary_exits_2_on_a_regression_and_1_on_bad_folders_writing_nothing() {
    let bin = env!("CARGO_BIN_EXE_caustics");
    let base = template();
    let mut new = base.clone();
    set_times(&mut new, 10.0, 1.1);
    let (t, a) = pair(&base, &new);
    let before = listing(t.path());
    let o = Command::new(bin)
        .args([
            "compare",
            a.base.to_str().expect("utf8"),
            a.new.to_str().expect("utf8"),
        ])
        .output()
        .expect("run");
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains("REGRESSION"));
    let o = Command::new(bin)
        .args([
            "compare",
            a.base.to_str().expect("utf8"),
            a.base.to_str().expect("utf8"),
        ])
        .output()
        .expect("run");
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );

    let missing = t.path().join("nope");
    let o = Command::new(bin)
        .args([
            "compare",
            a.base.to_str().expect("utf8"),
            missing.to_str().expect("utf8"),
        ])
        .output()
        .expect("run");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("nope") && err.contains("no such folder"),
        "{err}"
    );

    let empty = t.path().join("empty");
    std::fs::create_dir_all(&empty).expect("mkdir");
    let o = Command::new(bin)
        .args([
            "compare",
            empty.to_str().expect("utf8"),
            a.new.to_str().expect("utf8"),
        ])
        .output()
        .expect("run");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("holds no result.json"), "{err}");

    let corrupt = t.path().join("corrupt/x");
    std::fs::create_dir_all(&corrupt).expect("mkdir");
    std::fs::write(corrupt.join("result.json"), b"{\"schema_version\": 1").expect("write");
    let o = Command::new(bin)
        .args([
            "compare",
            a.base.to_str().expect("utf8"),
            t.path().join("corrupt").to_str().expect("utf8"),
        ])
        .output()
        .expect("run");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("not a result.json"), "{err}");

    let o = Command::new(bin)
        .args([
            "compare",
            "--alpha",
            "2",
            a.base.to_str().expect("utf8"),
            a.new.to_str().expect("utf8"),
        ])
        .output()
        .expect("run");
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--alpha"));

    let mut after = listing(t.path());
    after.retain(|(p, _)| !p.contains("/empty") && !p.contains("/corrupt"));
    assert_eq!(before, after, "compare wrote or changed files");
}

#[test]
fn in_a_reproduce_folder_only_the_manifest_runs_count() {
    let base = template();
    let tmp = tempfile::tempdir().expect("tempdir");
    let (b, n) = (tmp.path().join("base"), tmp.path().join("new"));
    write(&b, &base);
    write(&n, &base);
    // A stale run of an earlier reproduction into NEW, with another fragment count.
    let mut stale = base.clone();
    stale["fragments"]["method_total"] = 1.into();
    let d = n.join("runs/old/water_pool/wavefront");
    std::fs::create_dir_all(&d).expect("mkdir");
    std::fs::write(
        d.join("result.json"),
        serde_json::to_vec(&stale).expect("json"),
    )
    .expect("write");
    let manifest = serde_json::json!({
        "schema_version": 1, "experiment": "x", "experiment_hash": "0", "scale": 1.0,
        "shard": [1, 1], "merged_from": [], "missing_references": [], "rendered_references": [],
        "runs": [{"index": 0, "key": "water_pool/wavefront/default", "status": "done",
                  "dir": "runs/default/water_pool/wavefront", "reason": null}]
    });
    std::fs::write(n.join("manifest.json"), manifest.to_string()).expect("write");
    let r = compare(&args(&b, &n)).expect("compare");
    assert_eq!(r.regressions(), 0, "{}", r.table(true));
    assert!(
        !r.lines.iter().any(|l| l.run.contains("old")),
        "{}",
        r.table(true)
    );
}

/// `--html FILE`: a static page of the comparison with each measure's band drawn (the
/// only file compare writes); a page inside BASE or NEW is refused before any reading.
#[test]
fn the_html_page_shows_bands_and_is_never_written_into_the_inputs() {
    let base = template();
    let mut new = base.clone();
    set_times(&mut new, 10.0, 1.1);
    new["fragments"]["method_total"] = (new["fragments"]["method_total"]
        .as_u64()
        .expect("fragments")
        + 1)
    .into();
    let (t, a) = pair(&base, &new);
    let page = t.path().join("diff.html");
    let r = compare(&a).expect("compare");
    caustics::compare::write_html(&page, &a, &r).expect("html");
    let html = std::fs::read_to_string(&page).expect("page");
    assert!(
        html.contains("<tr class=REGRESSION><td>method GPU ms"),
        "{html}"
    );
    assert!(
        html.contains("<tr class=REGRESSION><td>fragments (method)"),
        "{html}"
    );
    // A timing strip draws every frame of both runs; a count its band and new value.
    assert!(html.matches("<circle").count() >= 40, "{html}");
    assert!(html.contains("<rect"), "{html}");
    assert!(html.contains("Mann-Whitney"), "{html}");

    let inside = a.base.join("diff.html");
    let e = compare(&CompareArgs {
        html: Some(inside.clone()),
        ..a.clone()
    })
    .expect_err("inside BASE");
    assert!(format!("{e:#}").contains("inside BASE"), "{e:#}");
    assert!(!inside.exists());
}
