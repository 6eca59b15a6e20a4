//! Every probe on the machine's adapter (lavapipe on CI; without an adapter this fails
//! with the install hint), small: the work each probe claims is the work the device
//! did, as its pipeline statistics count it, and every figure is a measurement.

use caustics_ceilings::{ProbeKind, ProbeOptions, measure};
use caustics_gpu::{AdapterChoice, GpuContext};

fn small() -> ProbeOptions {
    ProbeOptions {
        width: 64,
        height: 48,
        trials: 3,
        target_ms: 2.0,
        bandwidth_bytes: 1 << 20,
        only: Vec::new(),
    }
}

#[test]
fn every_probe_does_the_work_it_claims() {
    let ctx =
        GpuContext::new(&AdapterChoice::from_flag_or_env(None)).unwrap_or_else(|e| panic!("{e}"));
    let mut started = Vec::new();
    let results = measure(&ctx, &small(), &mut |name| started.push(name.to_owned()))
        .unwrap_or_else(|e| panic!("{e}"));
    let names: Vec<_> = results.iter().map(|r| r.name).collect();
    assert_eq!(names, started, "progress names every probe as it starts");
    for want in [
        "compute_fp32",
        "fill_blend_rgba32f_fullscreen",
        "fill_blend_rgba16f_fullscreen",
        "fill_blend_rgba32f_small",
        "fill_blend_rgba16f_small",
        "fill_unblended_rgba32f_fullscreen",
        "overhead_draw",
        "bandwidth_copy",
        "bandwidth_strided",
        "atomics_storage",
        "overhead_pass",
    ] {
        assert!(names.contains(&want), "{want} missing from {names:?}");
    }
    let pixels = 64.0 * 48.0;
    for r in &results {
        assert_eq!(r.trial_ms.len(), 3, "{}: one time per trial", r.name);
        for &ms in &r.trial_ms {
            let figure = r.figure(ms);
            assert!(
                ms > 0.0 && figure.is_finite() && figure > 0.0,
                "{}: trial {ms} ms, figure {figure}",
                r.name
            );
        }
        assert!(r.scale >= 1, "{}", r.name);
        // No adapter does 1 PFLOP/s or moves 1 PB/s: a figure past that is a kernel
        // the compiler removed or a timestamp that lied (lavapipe's FP32 kernel after
        // a render pass read ~0.02 ms for any loop length).
        if r.kind == ProbeKind::Throughput {
            assert!(
                r.figure(r.trial_ms[0]) < 1e6,
                "{}: {}",
                r.name,
                r.figure(r.trial_ms[0])
            );
        }
        if r.name.starts_with("fill_") {
            // Closed form: every layer covers each pixel once.
            assert_eq!(r.work, pixels * f64::from(r.scale), "{}", r.name);
            if ctx.has_pipeline_statistics() {
                let counted = r.counted_work.expect("fill is counted");
                // Every covered pixel is shaded; helper lanes of partly covered 2x2
                // quads may come on top (at most the quad: 4 per pixel), and a
                // full-screen triangle leaves almost none.
                let bound = if r.name.ends_with("_small") {
                    4.0
                } else {
                    1.25
                };
                assert!(
                    counted >= r.work && counted <= bound * r.work,
                    "{}: {counted} fragment invocations for {} covered pixels",
                    r.name,
                    r.work
                );
            }
        }
        if ["bandwidth_copy", "bandwidth_strided", "atomics_storage"].contains(&r.name)
            && ctx.has_pipeline_statistics()
        {
            // One invocation per element (32 bytes) or per 8 atomics: exactly.
            assert_eq!(r.counted_work, Some(r.work), "{}", r.name);
        }
        match r.name {
            "overhead_pass" => {
                assert_eq!(r.kind, ProbeKind::PerItem);
                assert_eq!(r.work, 64.0, "one profiled frame's worth of passes");
            }
            "overhead_draw" => {
                assert_eq!(r.kind, ProbeKind::PerItem);
                assert_eq!(r.work, 64.0 * f64::from(r.scale));
            }
            _ => assert_eq!(r.kind, ProbeKind::Throughput, "{}", r.name),
        }
    }
    // The bandwidth buffers are 1 MiB: 65,536 elements of 32 bytes moved each.
    let copy = results
        .iter()
        .find(|r| r.name == "bandwidth_copy")
        .expect("copy");
    assert_eq!(copy.work, 65536.0 * 32.0 * f64::from(copy.scale));
}

#[test]
fn only_runs_the_probes_named() {
    let ctx =
        GpuContext::new(&AdapterChoice::from_flag_or_env(None)).unwrap_or_else(|e| panic!("{e}"));
    let options = ProbeOptions {
        only: vec!["atomics".into(), "overhead_pass".into()],
        ..small()
    };
    let results = measure(&ctx, &options, &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    let names: Vec<_> = results.iter().map(|r| r.name).collect();
    assert_eq!(names, ["atomics_storage", "overhead_pass"]);
}
