//! `caustics`: render caustic scenes with real-time methods, measure and score them.

use std::process::ExitCode;

use anyhow::Result;
use caustics::cli::{Cli, Command};
use caustics::run::{EXIT_SKIPPED, RunOutcome};
use caustics::{out, outln, registry, run};
use clap::Parser;

fn list() {
    outln!("scenes ({}):", caustics_scene::builtin_dir().display());
    for name in caustics_scene::builtin_names() {
        let desc = caustics_scene::resolve(&name)
            .ok()
            .and_then(|p| caustics_scene::Scene::load(&p).ok())
            .map(|s| s.description)
            .unwrap_or_else(|| "(does not load: run `caustics run` on it for the error)".into());
        outln!("  {name:<20} {desc}");
    }
    outln!("\nmethods:");
    for m in registry::methods() {
        outln!("  {:<20} {}", m.name, m.summary);
        outln!("  {:<20} source: {}", "", m.source);
        outln!("  {:<20} supports: {}", "", m.capabilities.describe());
        for p in (m.params)() {
            let range = p.range.map(|r| format!(" in {r}")).unwrap_or_default();
            outln!(
                "  {:<20}   --param {}={}  {} ({}{range})",
                "",
                p.name,
                p.default,
                p.doc,
                p.kind
            );
        }
        for c in m.counters {
            outln!("  {:<20}   counter {}: {}", "", c.name, c.doc);
        }
    }
}

/// Mesa's Vulkan device-select layer (an implicit layer of every Mesa install) asks the
/// Wayland compositor for the default GPU; where there is no `XDG_RUNTIME_DIR` (a
/// headless machine, CI, ssh) libwayland prints "error: XDG_RUNTIME_DIR is invalid or not
/// set in the environment." twice, which reads as a failure of the run. The layer only
/// reorders adapters, and `--adapter` / `CAUSTICS_ADAPTER` pick ours by name, so there the
/// process replaces itself (exec: same process id, same arguments) with the layer's own
/// off switch, `NODEVICE_SELECT=1`, set. Setting it in-process would need `unsafe`
/// (`std::env::set_var`), which the workspace forbids.
#[cfg(unix)]
fn quiet_mesa_device_select() {
    use std::os::unix::process::CommandExt;
    let runtime_dir_ok =
        std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| std::path::Path::new(&d).is_dir());
    if runtime_dir_ok || std::env::var_os("NODEVICE_SELECT").is_some() {
        return;
    }
    let Ok(exe) = std::env::current_exe() else {
        return;
    };
    // `exec` returns only when it failed (e.g. the binary was rebuilt under us): then the
    // run goes on, with the warning.
    let _ = std::process::Command::new(exe)
        .args(std::env::args_os().skip(1))
        .env("NODEVICE_SELECT", "1")
        .exec();
}

#[cfg(not(unix))]
fn quiet_mesa_device_select() {}

fn main() -> ExitCode {
    quiet_mesa_device_select();
    let cli = Cli::parse();
    let outcome: Result<ExitCode> = match cli.command {
        Command::List => {
            list();
            Ok(ExitCode::SUCCESS)
        }
        Command::Reference(args) => {
            caustics::reference_cmd::reference(&args).map(|()| ExitCode::SUCCESS)
        }
        Command::Reproduce(args) => caustics::reproduce::reproduce(&args).map(|o| {
            if o.failed > 0 {
                eprintln!("{} runs failed (see the summaries)", o.failed);
                ExitCode::FAILURE
            } else {
                ExitCode::SUCCESS
            }
        }),
        Command::Merge(args) => caustics::reproduce::merge(&args).map(|dir| {
            outln!("merged into {}", dir.display());
            ExitCode::SUCCESS
        }),
        Command::Compare(args) => caustics::compare::compare(&args).and_then(|r| {
            if args.wide {
                out!("{}", r.wide_table(args.verbose));
            } else {
                out!("{}", r.table(args.verbose));
            }
            if let Some(page) = &args.html {
                caustics::compare::write_html(page, &args, &r)?;
                outln!("comparison page: {}", page.display());
            }
            Ok(ExitCode::from(r.exit_code()))
        }),
        Command::Ceilings(args) => caustics::ceilings_cmd::ceilings(&args).map(|(record, path)| {
            out!("{}", caustics::ceilings_cmd::table(&record));
            outln!("written to {}", path.display());
            ExitCode::SUCCESS
        }),
        Command::Adapters(args) => caustics::adapters_cmd::adapters(&args).map(|text| {
            out!("{text}");
            ExitCode::SUCCESS
        }),
        Command::Schema { kind } => {
            out!("{}", caustics::schemas::schema_text(kind));
            Ok(ExitCode::SUCCESS)
        }
        Command::Animations { dir } => caustics::animate::side_by_side_file(&dir).map(|path| {
            outln!("animations: {}", path.display());
            ExitCode::SUCCESS
        }),
        Command::Report(args) => caustics::report::report(&args).map(|index| {
            outln!("report: {}", index.display());
            ExitCode::SUCCESS
        }),
        Command::Run(opts) => run::run(&opts).map(|o| match o {
            RunOutcome::Done { dir, result } => {
                print_summary(&dir, &result);
                ExitCode::SUCCESS
            }
            RunOutcome::Animated { dir, result } => {
                print_animation(&dir, &result);
                ExitCode::SUCCESS
            }
            RunOutcome::Skipped { reason } => {
                eprintln!(
                    "skipped: method {} cannot render scene {}: {reason}",
                    opts.method, opts.scene
                );
                ExitCode::from(EXIT_SKIPPED as u8)
            }
        }),
    };
    match outcome {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {}", caustics::error_text(&e));
            ExitCode::FAILURE
        }
    }
}

fn print_animation(dir: &std::path::Path, r: &caustics::animate::AnimationResult) {
    let median = |s: &Option<caustics::stats::Summary>| {
        s.as_ref()
            .map_or("-".to_owned(), |s| format!("{:.3}", s.median))
    };
    outln!(
        "{} / {}: {} frames from {} s at {} FPS on {}",
        r.scene.name,
        r.method.name,
        r.frames.len(),
        r.sequence.start_s,
        r.sequence.fps,
        r.machine.adapter
    );
    outln!(
        "  method GPU ms {} (median), frame GPU ms {}, rebuild CPU ms {}",
        median(&r.timing.method_gpu_ms),
        median(&r.timing.frame_gpu_ms),
        median(&r.rebuild_ms)
    );
    for f in r.frames.iter().filter(|f| f.errors.is_some()) {
        if let Some(e) = &f.errors {
            outln!(
                "  t = {:.4} s: flux {}, relMSE {:.3e}, HDR-FLIP {}",
                f.time_s,
                e.flux_ratio.map_or("-".into(), |v| format!("{v:.3}")),
                e.rel_mse,
                e.hdr_flip.map_or("-".into(), |v| format!("{v:.3}"))
            );
        }
    }
    if let (Some(t), Some(s)) = (r.temporal_rel_rmse, r.still_rel_rmse) {
        outln!(
            "  temporal relRMSE {t:.4} against still relRMSE {s:.4} over {} pairs",
            r.temporal.len()
        );
    }
    outln!("  -> {}", dir.display());
}

fn print_summary(dir: &std::path::Path, r: &caustics::result::RunResult) {
    outln!(
        "{} / {} on {} ({})",
        r.scene.name,
        r.method.name,
        r.machine.adapter,
        r.build.profile
    );
    let bound = |name: &str| {
        r.roofline
            .as_ref()
            .and_then(|rl| rl.passes.iter().find(|p| p.name == name))
            .map_or(String::new(), |p| {
                format!("  {} {:.1}%", p.bound.as_str(), 100.0 * p.fraction)
            })
    };
    for p in &r.timing.passes {
        match &p.gpu_ms {
            Some(s) => outln!(
                "  {:<32} {:>9.3} ms  (p10 {:.3}, p90 {:.3}){}",
                p.name,
                s.median,
                s.p10,
                s.p90,
                bound(&p.name)
            ),
            None => outln!("  {:<32} {:>9} (no timestamps)", p.name, "-"),
        }
    }
    if let Some(s) = &r.timing.method_gpu_ms {
        outln!("  {:<32} {:>9.3} ms", "method total", s.median);
    }
    if let Some(i) = &r.instrumentation {
        outln!(
            "  instrumentation: timed frames {:.3} ms wall against bare frames {:.3} ms: {:+.2}% (count frame {:+.1}%)",
            i.timed_wall_ms.median,
            i.bare_wall_ms.median,
            100.0 * i.overhead,
            100.0 * i.count_frame_overhead
        );
    }
    if let Some(f) = &r.fragments {
        outln!(
            "  fragments: method {} (fill-counted {}, max {}/px)",
            f.method_total,
            f.fill_total,
            f.fill_max
        );
    }
    for (k, v) in &r.counters {
        outln!("  {k}: {v}");
    }
    if let Some(s) = &r.scoring {
        outln!(
            "  scoring frame: {}x{} sub-pixel offsets ({} spp), {:.0} ms wall, not timed",
            s.grid,
            s.grid,
            s.samples_per_pixel,
            s.wall_ms
        );
    }
    let opt = |v: Option<f64>, digits: usize| match v {
        Some(v) => format!("{v:.digits$}"),
        None => "-".to_owned(),
    };
    for (label, report) in [("", &r.errors), (" (1 spp)", &r.errors_1spp)] {
        let Some(report) = report else { continue };
        let images = std::iter::once(("surface", &report.surface))
            .chain(report.volume.as_ref().map(|v| ("volume", v)));
        for (image, e) in images {
            outln!(
                "  {image} errors{label}: flux ratio {} (image {}), relMSE {:.4e} (after flux {}), HDR-FLIP {}, LDR-FLIP {:.4}, RMSE {:.4e}",
                opt(e.flux_ratio, 3),
                opt(e.flux_ratio_image, 3),
                e.rel_mse,
                opt(e.rel_mse_after_flux, 4),
                opt(e.hdr_flip, 4),
                e.flip,
                e.rmse,
            );
        }
    }
    outln!("  written to {}", dir.display());
}
