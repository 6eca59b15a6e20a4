//! `caustics reproduce NAME|all` and `caustics merge`: run an experiment's
//! (scene, method, parameter set) list through [`crate::run::run_scene`], one shard of
//! it with `--shard k/n`, and write the per-run results plus a summary
//! (`summary.json`, `summary.md`, `bmf.json`, `plots/`).
//!
//! Layout of `<out>/<experiment>/`:
//!
//! ```text
//! manifest.json                      experiment, file hash, scale, shard, status of every run
//! runs/<params>/<scene>/<method>/    result.json and images of one run (`caustics run`'s layout)
//!   …/<method>/animation/            animation.json of a sequence (the experiment's `animate`)
//! summary.json summary.md bmf.json   written from the manifest and the result files
//! plots/*.png
//! ```
//!
//! **Killed and resumed.** Every file goes through [`caustics_metrics::atomic_write`], a
//! run folder's `result.json` is written last and the experiment folder's
//! `manifest.json` last of all (it is removed when a reproduction starts), so a killed
//! `reproduce` leaves whole files and a folder without a manifest. The same command again
//! keeps every run folder that is complete and made from the same inputs
//! ([`crate::resume`] says which inputs and why), redoes the others from an emptied
//! folder, removes the temporaries the killed process left, and ends with the files an
//! uninterrupted run writes. `--fresh` starts over.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};

use crate::experiment::{Experiment, RunSpec, parse_shard};
use crate::resume::{Completeness, DirLock, Expected};
use crate::run::{RunOptions, RunOutcome, run_scene};

/// Flags of `caustics reproduce`.
#[derive(Clone, Debug, clap::Args)]
pub struct ReproduceArgs {
    /// Experiment name (a file in bench/experiments/), a path to an experiment file, or
    /// `all`.
    pub name: String,
    /// Multiplies every run's resolution (e.g. 0.5 for a quick pass).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f64,
    /// Output root; each experiment goes to DIR/<experiment>/.
    #[arg(long, value_name = "DIR", default_value = "results/reproduce")]
    pub out: PathBuf,
    /// Run only shard k of n (1-based): runs k, k+n, k+2n, ... of the experiment.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    /// Reference cache root.
    #[arg(long, value_name = "DIR", default_value = crate::references::DEFAULT_ROOT)]
    pub references: PathBuf,
    /// Ceilings records: the adapter's record there gives each run's passes their
    /// roofline (`caustics ceilings` measures one).
    #[arg(long, value_name = "DIR", default_value = crate::ceilings_cmd::DEFAULT_ROOT)]
    pub ceilings: PathBuf,
    /// Do not render missing references even where the experiment gives a photon
    /// budget (runs without a reference are made without errors).
    #[arg(long)]
    pub no_render_references: bool,
    /// Folder of experiment files.
    #[arg(long, value_name = "DIR")]
    pub experiments: Option<PathBuf>,
    /// Substring of the adapter name (see `caustics run --adapter`).
    #[arg(long)]
    pub adapter: Option<String>,
    /// Keep the EXR images of every run (by default only PNGs and result.json stay).
    #[arg(long)]
    pub keep_exr: bool,
    /// Run nothing: rewrite summary.md, summary.json, bmf.json, plots/ and figures/ of an
    /// earlier reproduction in the output folder from its manifest and result files (also
    /// after the experiment file changed only in its description, paper or figures).
    #[arg(long, conflicts_with = "shard")]
    pub summary_only: bool,
    /// Start over: remove the experiment folder's earlier runs, plots and summary first
    /// (by default complete runs made from the same inputs are kept: a killed
    /// reproduction resumes). The reference cache is not touched.
    #[arg(long, conflicts_with = "summary_only")]
    pub fresh: bool,
    /// Write runs into a committed folder (e.g. `results/reproduce`) from a source tree
    /// with uncommitted changes outside `results/`; refused by default, since the files
    /// would name a commit they were not made from (they record `dirty` and the diff's
    /// hash).
    #[arg(long)]
    pub allow_dirty: bool,
    /// Start no run after this many seconds from the command's start (every experiment
    /// it names and their references together, so `all` too stops in time): the runs
    /// left are listed as `not_run` and each summary is written from the rest; the same
    /// command again keeps the complete runs and does the others. For a leased GPU or a
    /// CI job with a deadline, where a killed reproduction would leave no summary.
    #[arg(long, value_name = "SECONDS", value_parser = parse_budget_s, conflicts_with = "summary_only")]
    pub time_budget_s: Option<f64>,
}

fn parse_budget_s(s: &str) -> std::result::Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("expected a number of seconds >= 0, got {s:?}")),
    }
}

/// Status of a run the time budget left out (`--time-budget-s`) or an interrupted
/// reproduction never completed (`--summary-only` of a folder without a manifest).
pub const NOT_RUN: &str = "not_run";

/// Bumped when a field of the manifest or summary changes meaning.
pub const MANIFEST_VERSION: u32 = 1;

/// `manifest.json`: which runs a (shard) folder holds and how each ended.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// [`MANIFEST_VERSION`].
    pub schema_version: u32,
    /// Experiment name.
    pub experiment: String,
    /// Hash of the experiment file's bytes.
    pub experiment_hash: String,
    /// Hash of what its runs are made from ([`Experiment::runs_hash`]); absent in
    /// manifests written before it existed.
    #[serde(default)]
    pub runs_hash: Option<String>,
    /// `--scale`.
    pub scale: f64,
    /// `[k, n]`; `[1, 1]` for an unsharded or merged folder.
    pub shard: [usize; 2],
    /// Shards merged into this folder (their `k`), empty unless made by `merge`.
    #[serde(default)]
    pub merged_from: Vec<usize>,
    /// Every run of this shard, in experiment order.
    pub runs: Vec<RunStatus>,
    /// References that were missing and not rendered: `<scene> <w>x<h>`.
    pub missing_references: Vec<String>,
    /// References rendered for this reproduction: `<scene> <w>x<h> (<photons> photons,
    /// <wall> s)` (the seconds absent in manifests written before they were recorded).
    pub rendered_references: Vec<String>,
}

/// How one run ended.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RunStatus {
    /// Position in the experiment.
    pub index: usize,
    /// `<scene>/<method>/<params>`.
    pub key: String,
    /// "done", "skipped", "failed" or [`NOT_RUN`].
    pub status: String,
    /// Folder of `result.json`, relative to the experiment folder (done runs).
    #[serde(default)]
    pub dir: Option<String>,
    /// Why it was skipped, failed or not run.
    #[serde(default)]
    pub reason: Option<String>,
}

/// What `reproduce` did, for the caller's exit code.
#[derive(Debug)]
pub struct Outcome {
    /// The experiment folders written.
    pub dirs: Vec<PathBuf>,
    /// Runs that failed (the rest were written).
    pub failed: usize,
    /// Where each experiment's time went (not for `--summary-only`).
    pub times: Vec<ExperimentTime>,
}

/// The wall time of one experiment of a reproduction.
#[derive(Clone, Debug)]
pub struct ExperimentTime {
    /// Experiment name.
    pub experiment: String,
    /// Runs of this shard.
    pub runs: usize,
    /// Runs kept from an earlier reproduction (not made again).
    pub kept: usize,
    /// Seconds rendering references.
    pub references_s: f64,
    /// Seconds of the runs made now (not the kept ones) in their warm-up, timed and
    /// count frames (result.json's `wall.frames_s`).
    pub timed_frames_s: f64,
    /// Seconds of the runs made now in their scoring frame's sub-pixel frames
    /// (`wall.scoring_frame_s`): with 4×4 or 8×8 offsets, about half of a long reproduction
    /// (52 % of `reproduce all --scale 0.5`'s first three experiments, 39 % to 65 % each).
    pub scoring_frames_s: f64,
    /// Seconds in all (references, runs, summary).
    pub total_s: f64,
    /// Seconds the kept runs took when they were made (their `result.json`'s
    /// `wall.total_s`, a sequence's `animation.json` `wall_s`). With `total_s` it is what
    /// the experiment costs made in one go, which a reproduction resumed over several
    /// `--time-budget-s` passes never prints at once.
    pub kept_runs_s: f64,
    /// Seconds the references found in the cache took to render (their `meta.json`'s
    /// `seconds`): what a fresh cache would add. Each reference counts once per command,
    /// with the first experiment that renders or finds it.
    pub cached_references_s: f64,
}

/// The table `reproduce` prints after more than one experiment: each one's share of the
/// whole, references apart, and of its runs' time the timed frames and the scoring
/// frames (the rest is setup, errors, writing and the summary), slowest first.
pub fn time_table(times: &[ExperimentTime]) -> String {
    use std::fmt::Write as _;
    let all_s: f64 = times.iter().map(|t| t.total_s).sum();
    let refs_s: f64 = times.iter().map(|t| t.references_s).sum();
    let timed_s: f64 = times.iter().map(|t| t.timed_frames_s).sum();
    let scoring_s: f64 = times.iter().map(|t| t.scoring_frames_s).sum();
    let kept_s: f64 = times.iter().map(|t| t.kept_runs_s).sum();
    let cached_s: f64 = times.iter().map(|t| t.cached_references_s).sum();
    let mut out = format!(
        "{} experiments in {all_s:.0} s ({:.1} min; references {refs_s:.0} s, timed frames {timed_s:.0} s, scoring frames {scoring_s:.0} s)",
        times.len(),
        all_s / 60.0
    );
    if kept_s + cached_s > 0.0 {
        // What was made earlier counts where the whole is asked for (a reproduction
        // resumed pass after pass prints only each pass's share).
        let whole_s = all_s + kept_s + cached_s;
        let _ = write!(
            out,
            "; made in one go with an empty reference cache about {whole_s:.0} s ({:.1} min), with the kept runs' {kept_s:.0} s and the cached references' {cached_s:.0} s as long as they took when made",
            whole_s / 60.0
        );
    }
    out.push_str(":\n\n| experiment | runs | kept | references s | timed frames s | scoring frames s | runs and summary s | total s | share | kept runs s (when made) | cached references s (when rendered) |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
    let mut sorted: Vec<&ExperimentTime> = times.iter().collect();
    sorted.sort_by(|a, b| b.total_s.total_cmp(&a.total_s));
    for t in sorted {
        let _ = writeln!(
            out,
            "| {} | {} | {} | {:.0} | {:.0} | {:.0} | {:.0} | {:.0} | {:.0}% | {:.0} | {:.0} |",
            t.experiment,
            t.runs,
            t.kept,
            t.references_s,
            t.timed_frames_s,
            t.scoring_frames_s,
            t.total_s - t.references_s,
            t.total_s,
            100.0 * t.total_s / all_s.max(f64::MIN_POSITIVE),
            t.kept_runs_s,
            t.cached_references_s
        );
    }
    out
}

fn bar(len: u64, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    let style = ProgressStyle::with_template(&format!(
        "{{elapsed_precise}} [{{bar:30}}] {{pos}}/{{len}} {what} (ETA {{eta}}) {{msg}}"
    ))
    .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style.progress_chars("=> "));
    bar
}

/// Runs `caustics reproduce`. Every experiment named is loaded and validated before the
/// first run, so a bad file stops everything before any work or write.
pub fn reproduce(args: &ReproduceArgs) -> Result<Outcome> {
    // --time-budget-s counts from here, across experiments.
    let command_start = Instant::now();
    let dir = args
        .experiments
        .clone()
        .unwrap_or_else(crate::experiment::builtin_dir);
    let shard = args.shard.as_deref().map(parse_shard).transpose()?;
    let files = crate::experiment::resolve(&args.name, &dir)?;
    let experiments = files
        .iter()
        .map(|f| Experiment::load(f, args.scale))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let mut outcome = Outcome {
        dirs: Vec::new(),
        failed: 0,
        times: Vec::new(),
    };
    // The reference folders whose render time this command has counted, rendered or
    // found in the cache: one an earlier experiment rendered, or another found, is not
    // counted again (the whole the time table adds up would have it twice).
    let mut references_counted = BTreeSet::new();
    for e in &experiments {
        let out = args.out.join(&e.def.name);
        if args.summary_only {
            let _lock = DirLock::take(&out)?;
            if !out.join("manifest.json").exists() && out.join("runs").is_dir() {
                // Killed before its manifest (a lease or deadline ran out): summarize the
                // runs that completed, list the others as not run.
                let manifest = interrupted_manifest(e, &out, args.scale)?;
                let n_done = manifest.runs.iter().filter(|r| r.status == "done").count();
                eprintln!(
                    "{}: no manifest.json (an interrupted reproduction): summarizing its {n_done} complete runs of {}, the others listed as not run",
                    out.display(),
                    manifest.runs.len()
                );
                let s = crate::summary::write_all(&out, e, &manifest, &args.references)?;
                write_manifest(&out, &manifest)?;
                outcome.failed += s.failed;
                outcome.dirs.push(out);
                continue;
            }
            let manifest = read_manifest(&out)?;
            let same_file = manifest.experiment_hash == e.hash;
            // A file changed only in its description, paper or figures makes the same runs.
            let same_runs = manifest.runs_hash.as_deref() == Some(e.runs_hash.as_str());
            if !(same_file || same_runs) || manifest.scale != args.scale {
                bail!(
                    "{}: made from another version of {} (its runs, not only its description, paper or figures) or another --scale ({}); run it again",
                    out.join("manifest.json").display(),
                    e.file.display(),
                    manifest.scale
                );
            }
            let s = crate::summary::write_all(&out, e, &manifest, &args.references)?;
            if !same_file {
                // The summary is now the current file's: so is the manifest.
                write_manifest(
                    &out,
                    &Manifest {
                        experiment_hash: e.hash.clone(),
                        ..manifest
                    },
                )?;
            }
            outcome.failed += s.failed;
            eprintln!("{}: summary rewritten", out.join("summary.md").display());
            outcome.dirs.push(out);
            continue;
        }
        refuse_dirty_into_committed(&out, args.allow_dirty)?;
        let (failed, time) = reproduce_one(
            e,
            args,
            shard.unwrap_or((1, 1)),
            &out,
            command_start,
            &mut references_counted,
        )?;
        outcome.failed += failed;
        outcome.times.push(time);
        outcome.dirs.push(out);
    }
    if outcome.times.len() > 1 {
        eprintln!("\n{}", time_table(&outcome.times));
    }
    Ok(outcome)
}

/// Runs made from uncommitted code into a folder git would commit are refused unless
/// asked for (`--allow-dirty`).
fn refuse_dirty_into_committed(out: &Path, allow_dirty: bool) -> Result<()> {
    if allow_dirty || !crate::machine::is_committed_path(out) {
        return Ok(());
    }
    let build = crate::machine::build();
    if build.dirty {
        bail!(
            "{}: a committed results folder, but the source tree has uncommitted changes outside results/ (see `git status`): its runs would name commit {} without being made from it. Commit first, write elsewhere (--out target/...), or pass --allow-dirty (the files then record dirty and the diff's hash)",
            out.display(),
            build.commit
        );
    }
    Ok(())
}

fn reproduce_one(
    e: &Experiment,
    args: &ReproduceArgs,
    (k, n): (usize, usize),
    out: &Path,
    command_start: Instant,
    references_counted: &mut BTreeSet<PathBuf>,
) -> Result<(usize, ExperimentTime)> {
    let runs = e.shard(k, n);
    let start = Instant::now();
    eprintln!(
        "{}: {} of {} runs{} -> {}",
        e.def.name,
        runs.len(),
        e.runs.len(),
        if n > 1 {
            format!(" (shard {k}/{n})")
        } else {
            String::new()
        },
        out.display()
    );
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let _lock = DirLock::take(out)?;
    if args.fresh {
        crate::resume::clear_outputs(out)?;
    }
    // Holding the lock, every temporary in the folder is a killed writer's.
    let stale = crate::resume::remove_temp_files(out, true)?;
    if !stale.is_empty() {
        eprintln!(
            "removed {} temporary files of an interrupted run in {}",
            stale.len(),
            out.display()
        );
    }
    let references_started = Instant::now();
    let (rendered, missing, cached_references_s) =
        ensure_references(e, &runs, args, references_counted)?;
    let references_s = references_started.elapsed().as_secs_f64();
    crate::resume::mark_unfinished(out)?;
    let build = crate::machine::build();
    let cpu = crate::machine::cpu_model();
    let adapter = args
        .adapter
        .clone()
        .filter(|a| !a.is_empty())
        .or_else(|| std::env::var(caustics_gpu::ADAPTER_ENV).ok())
        .filter(|a| !a.is_empty());
    let exe = crate::resume::ExeStamp::current();
    let progress = bar(runs.len() as u64, "runs");
    // A steady tick redraws the bar below the lines each run prints to stderr.
    progress.enable_steady_tick(std::time::Duration::from_millis(500));
    let mut statuses = Vec::new();
    let mut kept = 0;
    let mut kept_runs_s = 0.0;
    let mut not_run = 0;
    let (mut timed_frames_s, mut scoring_frames_s) = (0.0, 0.0);
    for spec in crate::experiment::scene_major(&runs) {
        progress.set_message(spec.key());
        let rel = run_rel(spec);
        let dir = out.join(&rel);
        let expected = Expected {
            spec,
            exposure: e.def.exposure,
            references: reference_scenes(spec)?
                .iter()
                .map(|scene| {
                    crate::references::find(&args.references, scene)
                        .ok()
                        .flatten()
                        .map(|c| c.caustic_key())
                })
                .collect(),
            build: &build,
            cpu: &cpu,
            adapter: adapter.as_deref(),
            keep_exr: args.keep_exr,
            exe: exe.as_ref(),
        };
        let status = match crate::resume::completeness(&dir, &expected) {
            Completeness::Complete(result) => {
                kept_runs_s += match &result {
                    Some(r) => r.wall.as_ref().map_or(0.0, |w| w.total_s),
                    None => crate::animate::load(&dir.join(crate::animate::ANIMATION_FILE))
                        .map_or(0.0, |a| a.wall_s),
                };
                if let Some(result) = result.filter(|_| !args.keep_exr) {
                    crate::resume::drop_exrs(&dir, &result.images);
                }
                kept += 1;
                RunStatus {
                    index: spec.index,
                    key: spec.key(),
                    status: "done".into(),
                    dir: Some(rel.display().to_string()),
                    reason: None,
                }
            }
            _ if args
                .time_budget_s
                .is_some_and(|b| command_start.elapsed().as_secs_f64() >= b) =>
            {
                // Left as it is: a stale folder is only replaced by the run that redoes it.
                not_run += 1;
                RunStatus {
                    index: spec.index,
                    key: spec.key(),
                    status: NOT_RUN.into(),
                    dir: None,
                    reason: Some(format!(
                        "the time budget (--time-budget-s {}) was spent before it started; the same command again does it",
                        args.time_budget_s.unwrap_or_default()
                    )),
                }
            }
            c => {
                if let Completeness::Stale(why) = c {
                    // suspend, not println: println prints nothing without a terminal.
                    progress.suspend(|| eprintln!("redoing {}: {why}", spec.key()));
                }
                // Nothing of an earlier attempt stays beside the new files.
                if dir.exists() {
                    std::fs::remove_dir_all(&dir)
                        .with_context(|| format!("removing {}", dir.display()))?;
                }
                let (status, wall) = run_one(e, spec, args, out);
                if let Some(w) = wall {
                    timed_frames_s += w.frames_s;
                    scoring_frames_s += w.scoring_frame_s;
                }
                // After result.json: the run is complete once this is written.
                if let Some(stamp) = exe.as_ref().filter(|_| status.status == "done") {
                    stamp.write(&dir)?;
                }
                status
            }
        };
        if status.status == "failed" {
            progress.suspend(|| {
                eprintln!(
                    "failed: {}: {}",
                    spec.key(),
                    status.reason.as_deref().unwrap_or("")
                )
            });
        }
        statuses.push(status);
        progress.inc(1);
    }
    progress.finish_and_clear();
    if kept > 0 {
        eprintln!(
            "{}: kept {kept} complete runs of an earlier reproduction (--fresh redoes them)",
            e.def.name
        );
    }
    if not_run > 0 {
        eprintln!(
            "{}: time budget spent: {not_run} runs not started (the same command again does them)",
            e.def.name
        );
    }
    // The manifest lists the runs in the experiment's order, not the order made.
    statuses.sort_by_key(|s| s.index);
    let failed = statuses.iter().filter(|s| s.status == "failed").count();
    let manifest = Manifest {
        schema_version: MANIFEST_VERSION,
        experiment: e.def.name.clone(),
        experiment_hash: e.hash.clone(),
        runs_hash: Some(e.runs_hash.clone()),
        scale: args.scale,
        shard: [k, n],
        merged_from: Vec::new(),
        runs: statuses,
        missing_references: missing,
        rendered_references: rendered,
    };
    // The manifest last: a folder with one is finished.
    let summary = crate::summary::write_all(out, e, &manifest, &args.references)?;
    write_manifest(out, &manifest)?;
    eprintln!(
        "{}: {} done, {} skipped, {} failed in {:.1} s; summary in {}",
        e.def.name,
        summary.done,
        summary.skipped,
        failed,
        start.elapsed().as_secs_f64(),
        out.join("summary.md").display()
    );
    Ok((
        failed,
        ExperimentTime {
            experiment: e.def.name.clone(),
            runs: runs.len(),
            kept,
            references_s,
            timed_frames_s,
            scoring_frames_s,
            total_s: start.elapsed().as_secs_f64(),
            kept_runs_s,
            cached_references_s,
        },
    ))
}

fn write_manifest(out: &Path, m: &Manifest) -> Result<()> {
    caustics_metrics::atomic_write(&out.join("manifest.json"), &serde_json::to_vec_pretty(m)?)?;
    Ok(())
}

/// Reads `<dir>/manifest.json`.
pub fn read_manifest(dir: &Path) -> Result<Manifest> {
    let p = dir.join("manifest.json");
    let text = std::fs::read_to_string(&p).with_context(|| {
        format!(
            "reading {}: not a finished `caustics reproduce` output folder (an interrupted reproduction has none until it is resumed: run the same command again)",
            p.display()
        )
    })?;
    let m: Manifest = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a manifest.json", p.display()))?;
    check_manifest(&m).map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))?;
    Ok(m)
}

/// What serde cannot check in a manifest from elsewhere: the version, the shard, the
/// statuses, and that every run folder lies inside the experiment folder (`merge` copies
/// them, `compare` reads them).
fn check_manifest(m: &Manifest) -> std::result::Result<(), String> {
    if m.schema_version != MANIFEST_VERSION {
        return Err(format!(
            "schema_version: expected {MANIFEST_VERSION}, got {} (written by another version of caustics)",
            m.schema_version
        ));
    }
    if !(m.scale.is_finite() && m.scale > 0.0) {
        return Err(format!(
            "scale: expected a positive number, got {}",
            m.scale
        ));
    }
    let [k, n] = m.shard;
    if k == 0 || k > n {
        return Err(format!(
            "shard: expected [k, n] with 1 <= k <= n, got [{k}, {n}]"
        ));
    }
    for (i, r) in m.runs.iter().enumerate() {
        if !["done", "skipped", "failed", NOT_RUN].contains(&r.status.as_str()) {
            return Err(format!(
                "runs[{i}].status: expected \"done\", \"skipped\", \"failed\" or \"{NOT_RUN}\", got {:?}",
                r.status
            ));
        }
        match (&r.dir, r.status == "done") {
            (None, true) => {
                return Err(format!(
                    "runs[{i}].dir: expected the run folder of a done run"
                ));
            }
            (Some(_), false) => {
                return Err(format!(
                    "runs[{i}].dir: expected none for a {} run",
                    r.status
                ));
            }
            _ => {}
        }
        if let Some(d) = &r.dir {
            let p = Path::new(d);
            let inside = p.starts_with("runs")
                && p.components()
                    .all(|c| matches!(c, std::path::Component::Normal(_)));
            if !inside {
                return Err(format!(
                    "runs[{i}].dir: expected a folder under runs/ of the experiment folder, got {d:?}"
                ));
            }
        }
    }
    Ok(())
}

/// The scenes a run is scored against: its scene, or a sequence's scene posed at each
/// scored instant.
fn reference_scenes(spec: &RunSpec) -> Result<Vec<caustics_scene::Scene>> {
    match &spec.animate {
        None => Ok(vec![spec.scene.clone()]),
        Some(sequence) => sequence
            .scored_instants()
            .into_iter()
            .map(|t| {
                spec.scene
                    .at_time(t)
                    .with_context(|| format!("{}: posing the scene at {t} s", spec.key()))
            })
            .collect(),
    }
}

/// Renders the references the shard's runs need and the cache lacks, when the experiment
/// states a photon budget; returns (rendered, still missing). A sequence needs one per
/// scored instant.
fn ensure_references(
    e: &Experiment,
    runs: &[&RunSpec],
    args: &ReproduceArgs,
    counted: &mut BTreeSet<PathBuf>,
) -> Result<(Vec<String>, Vec<String>, f64)> {
    let mut seen = BTreeSet::new();
    let (mut rendered, mut missing) = (Vec::new(), Vec::new());
    // Render seconds of the cached references used that this command has not counted yet
    // (`counted`).
    let mut cached_s = 0.0;
    for (spec, scene) in runs
        .iter()
        .map(|spec| Ok((spec, reference_scenes(spec)?)))
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .flat_map(|(spec, scenes)| scenes.into_iter().map(move |s| (spec, s)))
    {
        let scene = &scene;
        let label = match spec.animate {
            Some(_) => format!(
                "{} {}x{} at {} s",
                scene.name, scene.camera.width, scene.camera.height, scene.time
            ),
            None => format!(
                "{} {}x{}",
                scene.name, scene.camera.width, scene.camera.height
            ),
        };
        // Only for runs that will happen: a method that skips the scene needs none.
        let params = serde_json::Value::Object(spec.params.clone());
        let info = crate::registry::find(&spec.method)?;
        let runnable = (info.parse)(&params).is_ok_and(|p| info.supports(scene, &p).is_ok());
        if !runnable || seen.contains(&label) {
            continue;
        }
        // A cached reference serves if it has at least the experiment's photons (any
        // seed is as good a reference); one with fewer would score the runs against
        // more noise than the experiment states, so it is rendered again when allowed.
        let budget = e.def.reference.filter(|_| !args.no_render_references);
        if let Some(cached) = crate::references::find(&args.references, scene)? {
            match budget {
                Some(b) if cached.meta.photons < b.photons => {
                    eprintln!(
                        "reference {label}: the cached one has {} photons, the experiment asks {}: rendering it again",
                        cached.meta.photons, b.photons
                    );
                    // meta.json first: until the new one is written the folder is
                    // incomplete, never a mix of two renders that passes for one.
                    let meta = cached.dir.join("meta.json");
                    std::fs::remove_file(&meta)
                        .with_context(|| format!("removing {}", meta.display()))?;
                }
                _ => {
                    seen.insert(label);
                    if counted.insert(cached.dir.clone()) {
                        cached_s += cached.meta.seconds;
                    }
                    continue;
                }
            }
        }
        seen.insert(label.clone());
        // A killed render's temporaries (the cache is shared: only dead writers' go).
        crate::resume::remove_temp_files(
            &crate::references::cache_dir(&args.references, scene),
            false,
        )?;
        match budget {
            Some(budget) => {
                let dir = crate::references::cache_dir(&args.references, scene);
                counted.insert(dir.clone());
                let progress = bar(budget.photons, &format!("photons, reference {label}"));
                let tick = |done: u64| progress.set_position(done);
                let started = Instant::now();
                let rel = crate::reference_cmd::render_into(
                    &dir,
                    scene,
                    budget.photons,
                    budget.seed,
                    budget.batches,
                    &tick,
                )
                .with_context(|| format!("rendering the reference of {label}"))?;
                progress.finish_and_clear();
                let wall_s = started.elapsed().as_secs_f64();
                eprintln!(
                    "reference {label}: {} photons in {wall_s:.1} s, mean relative standard error {:.1}% -> {}",
                    budget.photons,
                    100.0 * rel,
                    dir.display()
                );
                rendered.push(format!(
                    "{label} ({} photons, {wall_s:.1} s)",
                    budget.photons
                ));
            }
            None => missing.push(label),
        }
    }
    if !missing.is_empty() {
        eprintln!(
            "no reference for {} (the experiment gives no photon budget{}): those runs have no errors",
            missing.join(", "),
            if args.no_render_references {
                ", or --no-render-references"
            } else {
                ""
            }
        );
    }
    Ok((rendered, missing, cached_s))
}

/// The manifest of a reproduction killed before it wrote one: a run whose folder holds
/// its `result.json` (a sequence's `animation.json`: written last of a run's files) is
/// done, every other is not run.
/// The experiment is taken as the one the folder was made from; its runs' own
/// `result.json` name their scene, method and parameters.
///
/// No manifest records the `--scale` the runs were made at, so each complete run's
/// resolution must be the one `scale` gives its scene: a summary under another scale
/// would label the runs with a resolution they do not have.
fn interrupted_manifest(e: &Experiment, out: &Path, scale: f64) -> Result<Manifest> {
    let mut runs = Vec::new();
    for spec in &e.runs {
        let rel = run_rel(spec);
        let file = out.join(&rel).join(run_file(spec));
        let complete = file.is_file();
        if complete {
            let made_at = match spec.animate {
                Some(_) => {
                    let a = crate::summary::read_sequence(&out.join(&rel))?;
                    (a.scene.width, a.scene.height)
                }
                None => {
                    let r = crate::summary::read_result(&out.join(&rel))?;
                    (r.scene.width, r.scene.height)
                }
            };
            let (w, h) = (spec.scene.camera.width, spec.scene.camera.height);
            if made_at != (w, h) {
                bail!(
                    "{}: made at {}x{}, but --scale {scale} gives {}'s run {w}x{h}: pass the --scale the reproduction was made with",
                    file.display(),
                    made_at.0,
                    made_at.1,
                    spec.key()
                );
            }
        }
        runs.push(RunStatus {
            index: spec.index,
            key: spec.key(),
            status: if complete { "done" } else { NOT_RUN }.into(),
            dir: complete.then(|| rel.display().to_string()),
            reason: (!complete)
                .then(|| "the reproduction was interrupted before this run completed".to_owned()),
        });
    }
    Ok(Manifest {
        schema_version: MANIFEST_VERSION,
        experiment: e.def.name.clone(),
        experiment_hash: e.hash.clone(),
        runs_hash: Some(e.runs_hash.clone()),
        scale,
        shard: [1, 1],
        merged_from: Vec::new(),
        runs,
        missing_references: Vec::new(),
        rendered_references: Vec::new(),
    })
}

/// `runs/<params>/<scene>/<method>`, and its `animation/` for a sequence: the folder of
/// the run's `result.json` (or `animation.json`), relative to the experiment folder.
fn run_rel(spec: &RunSpec) -> PathBuf {
    let dir = Path::new("runs")
        .join(&spec.slug)
        .join(&spec.scene.name)
        .join(&spec.method);
    if spec.animate.is_some() {
        dir.join("animation")
    } else {
        dir
    }
}

/// The file written last of a run: its `result.json`, or a sequence's `animation.json`.
fn run_file(spec: &RunSpec) -> &'static str {
    if spec.animate.is_some() {
        crate::animate::ANIMATION_FILE
    } else {
        "result.json"
    }
}

/// Makes one run; with its status, a still run's wall time by phase (for the time table).
fn run_one(
    e: &Experiment,
    spec: &RunSpec,
    args: &ReproduceArgs,
    out: &Path,
) -> (RunStatus, Option<crate::result::RunWall>) {
    let rel = Path::new("runs").join(&spec.slug);
    let o = RunOptions {
        scene: spec.scene.source.display().to_string(),
        method: spec.method.clone(),
        params: Vec::new(),
        param_values: spec.params.clone(),
        limits: Default::default(),
        frames: spec.frames,
        warmup: spec.warmup,
        reference: None,
        out: out.join(&rel),
        adapter: args.adapter.clone(),
        exposure: e.def.exposure,
        score_grid: spec.score_grid,
        references: args.references.clone(),
        // The experiment's budget decides its references (`ensure_references`).
        quick_reference_photons: 0,
        ceilings: args.ceilings.clone(),
        instrumentation_overhead: false,
        resolution: None,
        time: None,
        animate: None,
        reference_every: spec.animate.map(|a| a.reference_every()),
        representative_lights: spec.representative_lights.unwrap_or(0),
    };
    let status = |status: &str, dir: Option<String>, reason: Option<String>| RunStatus {
        index: spec.index,
        key: spec.key(),
        status: status.into(),
        dir,
        reason,
    };
    let outcome = match &spec.animate {
        Some(a) => crate::animate::run_animated(&o, &a.spec(), spec.scene.clone()),
        None => run_scene(&o, spec.scene.clone()),
    };
    match outcome {
        Ok(RunOutcome::Done { dir, result }) => {
            if !args.keep_exr {
                crate::resume::drop_exrs(&dir, &result.images);
            }
            let rel = run_rel(spec);
            (
                status("done", Some(rel.display().to_string()), None),
                result.wall.clone(),
            )
        }
        Ok(RunOutcome::Skipped { reason }) => (status("skipped", None, Some(reason)), None),
        Ok(RunOutcome::Animated { .. }) => (
            status("done", Some(run_rel(spec).display().to_string()), None),
            None,
        ),
        Err(err) => (status("failed", None, Some(crate::error_text(&err))), None),
    }
}

/// Flags of `caustics merge`.
#[derive(Clone, Debug, clap::Args)]
pub struct MergeArgs {
    /// Shard folders (each `<out>/<experiment>/` of a `reproduce --shard k/n`).
    #[arg(required = true, num_args = 1..)]
    pub shards: Vec<PathBuf>,
    /// Folder of the merged experiment (must not exist or be empty).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Folder of experiment files.
    #[arg(long, value_name = "DIR")]
    pub experiments: Option<PathBuf>,
}

/// Merges shard folders into one, as if the experiment had run unsharded: checks that
/// they come from the same experiment file, scale and shard count, that every shard is
/// there exactly once, then copies the runs and writes the summary.
pub fn merge(args: &MergeArgs) -> Result<PathBuf> {
    let manifests = args
        .shards
        .iter()
        .map(|d| read_manifest(d))
        .collect::<Result<Vec<_>>>()?;
    let first = &manifests[0];
    for (m, d) in manifests.iter().zip(&args.shards) {
        if (&m.experiment, &m.experiment_hash, m.scale, m.shard[1])
            != (
                &first.experiment,
                &first.experiment_hash,
                first.scale,
                first.shard[1],
            )
        {
            bail!(
                "{}: shard of {} (file hash {}, scale {}, {} shards), but {} is of {} (file hash {}, scale {}, {} shards)",
                d.display(),
                m.experiment,
                m.experiment_hash,
                m.scale,
                m.shard[1],
                args.shards[0].display(),
                first.experiment,
                first.experiment_hash,
                first.scale,
                first.shard[1]
            );
        }
    }
    let n = first.shard[1];
    let ks: BTreeSet<usize> = manifests.iter().map(|m| m.shard[0]).collect();
    if ks.len() != manifests.len() || ks.len() != n {
        let have: Vec<String> = manifests
            .iter()
            .map(|m| format!("{}/{}", m.shard[0], n))
            .collect();
        bail!(
            "merge needs each of the {n} shards exactly once, got {}",
            have.join(", ")
        );
    }
    let dir = args
        .experiments
        .clone()
        .unwrap_or_else(crate::experiment::builtin_dir);
    let files = crate::experiment::resolve(&first.experiment, &dir)?;
    let e = Experiment::load(&files[0], first.scale)?;
    if e.hash != first.experiment_hash {
        bail!(
            "{}: changed since the shards ran (hash {} now, {} then)",
            e.file.display(),
            e.hash,
            first.experiment_hash
        );
    }
    if args.out.exists() {
        let entries: Vec<String> = std::fs::read_dir(&args.out)
            .with_context(|| format!("reading {}", args.out.display()))?
            .map(|e| e.map(|e| e.file_name().to_string_lossy().into_owned()))
            .collect::<std::io::Result<_>>()
            .with_context(|| format!("reading {}", args.out.display()))?;
        // An interrupted merge (no manifest.json, written last, and only what merge
        // writes) is redone; anything else is not merge's to replace.
        let interrupted = !entries.iter().any(|n| n == "manifest.json")
            && entries.iter().all(|n| {
                ["runs", "plots", "figures"].contains(&n.as_str())
                    || crate::resume::SUMMARY_FILES.contains(&n.as_str())
                    || crate::resume::temp_file_pid(n).is_some()
            });
        if !entries.is_empty() && !interrupted {
            bail!(
                "--out {}: exists and is not empty; merge writes a fresh folder",
                args.out.display()
            );
        }
        if !entries.is_empty() {
            eprintln!(
                "--out {}: an interrupted merge; merging again",
                args.out.display()
            );
            crate::resume::clear_outputs(&args.out)?;
            crate::resume::remove_temp_files(&args.out, true)?;
        }
    }
    let mut runs: Vec<RunStatus> = Vec::new();
    for (m, d) in manifests.iter().zip(&args.shards) {
        for r in &m.runs {
            if let Some(rel) = &r.dir {
                let from = d.join(rel);
                if !(from.join("result.json").is_file() || crate::summary::is_sequence_dir(&from)) {
                    bail!("{}: missing (listed in its manifest)", from.display());
                }
            }
            runs.push(r.clone());
        }
    }
    runs.sort_by_key(|r| r.index);
    let expected: Vec<usize> = (0..e.runs.len()).collect();
    if runs.iter().map(|r| r.index).collect::<Vec<_>>() != expected {
        bail!(
            "the shards hold {} runs, the experiment has {}: some shard is incomplete",
            runs.len(),
            e.runs.len()
        );
    }
    for (m, d) in manifests.iter().zip(&args.shards) {
        for r in &m.runs {
            if let Some(rel) = &r.dir {
                copy_dir(&d.join(rel), &args.out.join(rel))?;
            }
        }
    }
    let union = |f: fn(&Manifest) -> &Vec<String>| -> Vec<String> {
        let s: BTreeSet<String> = manifests.iter().flat_map(|m| f(m).clone()).collect();
        s.into_iter().collect()
    };
    let manifest = Manifest {
        schema_version: MANIFEST_VERSION,
        experiment: first.experiment.clone(),
        experiment_hash: first.experiment_hash.clone(),
        runs_hash: Some(e.runs_hash.clone()),
        scale: first.scale,
        shard: [1, 1],
        merged_from: ks.into_iter().collect(),
        runs,
        missing_references: union(|m| &m.missing_references),
        rendered_references: union(|m| &m.rendered_references),
    };
    // The manifest last: a folder with one is a finished merge.
    crate::summary::write_all(
        &args.out,
        &e,
        &manifest,
        Path::new(crate::references::DEFAULT_ROOT),
    )?;
    write_manifest(&args.out, &manifest)?;
    Ok(args.out.clone())
}

fn copy_dir(from: &Path, to: &Path) -> Result<()> {
    std::fs::create_dir_all(to).with_context(|| format!("creating {}", to.display()))?;
    for entry in std::fs::read_dir(from).with_context(|| format!("reading {}", from.display()))? {
        let entry = entry?;
        let path = entry.path();
        if path.is_file() {
            let bytes =
                std::fs::read(&path).with_context(|| format!("reading {}", path.display()))?;
            caustics_metrics::atomic_write(&to.join(entry.file_name()), &bytes)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_time_table_lists_experiments_slowest_first_with_their_share() {
        let t = |experiment: &str, references_s: f64, total_s: f64| ExperimentTime {
            experiment: experiment.into(),
            runs: 3,
            kept: 1,
            references_s,
            timed_frames_s: 0.25 * (total_s - references_s),
            scoring_frames_s: 0.5 * (total_s - references_s),
            total_s,
            kept_runs_s: 0.0,
            cached_references_s: 0.0,
        };
        let table = time_table(&[t("quick", 0.0, 100.0), t("slow", 60.0, 300.0)]);
        assert!(
            table.starts_with(
                "2 experiments in 400 s (6.7 min; references 60 s, timed frames 85 s, scoring frames 170 s):"
            ),
            "nothing made earlier, no whole to add up:\n{table}"
        );
        let slow = table
            .find("| slow | 3 | 1 | 60 | 60 | 120 | 240 | 300 | 75% | 0 | 0 |")
            .expect(&table);
        let quick = table
            .find("| quick | 3 | 1 | 0 | 25 | 50 | 100 | 100 | 25% | 0 | 0 |")
            .expect(&table);
        assert!(slow < quick, "slowest first:\n{table}");

        // A pass that resumed an earlier one: the kept runs and the cached references
        // count at what they took when made, so the whole is not the pass's share.
        let resumed = ExperimentTime {
            kept_runs_s: 2400.0,
            cached_references_s: 500.0,
            ..t("resumed", 0.0, 20.0)
        };
        let table = time_table(&[resumed, t("quick", 0.0, 100.0)]);
        assert!(
            table.starts_with(
                "2 experiments in 120 s (2.0 min; references 0 s, timed frames 30 s, scoring frames 60 s); made in one go with an empty reference cache about 3020 s (50.3 min), with the kept runs' 2400 s and the cached references' 500 s as long as they took when made:"
            ),
            "{table}"
        );
        assert!(
            table.contains("| resumed | 3 | 1 | 0 | 5 | 10 | 20 | 20 | 17% | 2400 | 500 |"),
            "{table}"
        );
    }
}
