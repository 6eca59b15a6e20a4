//! `caustics compare BASE NEW`: a regression gate over two result folders, run by run.
//!
//! Runs are matched by the path of their `result.json` relative to the folder (so two
//! `reproduce` outputs, two `caustics run --out` folders or a baseline and a new run all
//! compare). For each pair:
//!
//! - **inputs**: scene (name and content hash), resolution, method, parameters and adapter
//!   (name and driver) must be equal, else the pair is *not comparable*: nothing else of
//!   it is compared, the line says which inputs differ, and `compare` exits with
//!   [`EXIT_NOT_COMPARABLE`] (unless a comparable pair regressed). `--across-adapters`
//!   compares runs of different adapters anyway (counts and errors gated, timings shown);
//! - **deterministic figures** (fragment-shader invocations and primitives per pass, the
//!   fill counts, the method's counters): equal, or within `--count-tolerance` (relative);
//! - **errors** against the reference, of the surface and, the same way, of the volume
//!   caustic (measures `error <figure>` and `error volume <figure>`): relMSE, relMSE
//!   after flux normalization, HDR-FLIP, LDR-FLIP, RMSE and RMSE after the best scale are
//!   worse when `new − base > max(--error-tolerance · base, --noise-k · σ_ref)`, the noise
//!   term only for the RMSE-like figures (σ_ref the larger of the two surface references'
//!   noise RMS; the volume reference states none, so volume RMSE has the relative
//!   tolerance alone): a change inside the reference's own noise means nothing. The flux
//!   ratios (caustic region, whole image), whose ideal is 1, changed when
//!   `|new − base| > --error-tolerance` (absolute), worse when they moved away from 1;
//! - **like with like**: the pixel-averaged errors (`errors`) are compared only with
//!   pixel-averaged errors of as many samples per pixel; the timed frame's 1-spp errors
//!   (`errors_1spp`, measures `error 1spp <figure>`) with each other. A schema-1 file has
//!   1-spp errors only: against it only the 1-spp errors are compared, and an Info line
//!   says so. A figure the older file predates (e.g. HDR-FLIP) is shown, not gated;
////! - **timings** (method and frame GPU ms): slower when the two-sided Mann-Whitney U test
//!   over the per-frame samples gives p < `--alpha` *and* the median grew by more than
//!   `--time-threshold`; files without per-frame samples fall back to "new p10 above base
//!   p90 and median grew by more than the threshold". Timings on different adapters are
//!   shown, never gated; `--no-timings` shows them without gating (CI on shared CPUs).
//!
//! A run of BASE missing from NEW is a regression; a run only in NEW is listed as new.
//! The table shows what changed, run by run (`--verbose`: every comparison); `--wide`
//! gives one flat row per comparison with the test behind each verdict (tolerances,
//! p-values).
//!
//! Exit codes: 0 nothing regressed, [`EXIT_REGRESSION`] a regression, [`EXIT_NOT_COMPARABLE`]
//! no regression but some pair not comparable, 1 an error (a bad folder or flag).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use crate::result::RunResult;
use crate::stats::{Summary, mann_whitney};

/// Flags of `caustics compare`.
#[derive(Clone, Debug, clap::Args)]
pub struct CompareArgs {
    /// Baseline folder.
    pub base: PathBuf,
    /// New folder.
    pub new: PathBuf,
    /// Minimum relative growth of a median GPU time that counts as slower (0.05 = 5%).
    #[arg(long, default_value_t = 0.05)]
    pub time_threshold: f64,
    /// Significance level of the Mann-Whitney test on per-frame GPU times.
    #[arg(long, default_value_t = 0.01)]
    pub alpha: f64,
    /// Relative tolerance of deterministic counts (0 = exact).
    #[arg(long, default_value_t = 0.0)]
    pub count_tolerance: f64,
    /// Relative growth of an error that counts as worse.
    #[arg(long, default_value_t = 0.02)]
    pub error_tolerance: f64,
    /// Growth of RMSE-like errors below this many reference-noise RMS is not a change.
    #[arg(long, default_value_t = 0.5)]
    pub noise_k: f64,
    /// Show timings without gating them (CI on shared or software adapters).
    #[arg(long)]
    pub no_timings: bool,
    /// Print every comparison, not only the changed ones.
    #[arg(long, short)]
    pub verbose: bool,
    /// One flat row per comparison, with the test behind each verdict (tolerances,
    /// p-values); the default groups rows by run and leaves the tests out.
    #[arg(long)]
    pub wide: bool,
    /// Compare runs made on different adapters (counts and errors gated, timings shown
    /// only); by default such pairs are not comparable.
    #[arg(long)]
    pub across_adapters: bool,
    /// Also write the comparison as a static HTML page to this file (the only file
    /// compare writes; never inside BASE or NEW).
    #[arg(long, value_name = "FILE.html")]
    pub html: Option<PathBuf>,
}

/// Exit code of `compare` when a comparable pair regressed (1 is an error).
pub const EXIT_REGRESSION: u8 = 2;
/// Exit code of `compare` when no pair regressed but some pair is not comparable (its
/// scene, resolution, method, parameters or adapter differ).
pub const EXIT_NOT_COMPARABLE: u8 = 3;

/// What a comparison found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Verdict {
    /// Equal, or a change inside the noise/tolerance.
    Same,
    /// Better (faster, smaller error).
    Better,
    /// Changed, reported but not gated (timings with --no-timings or across adapters).
    Info,
    /// Only in NEW.
    New,
    /// The two runs were made from different inputs: nothing of them is compared.
    NotComparable,
    /// A regression: slower, worse, a changed count, missing.
    Regression,
}

impl Verdict {
    fn word(&self) -> &'static str {
        match self {
            Verdict::Same => "same",
            Verdict::Better => "better",
            Verdict::Info => "changed (not gated)",
            Verdict::New => "new",
            Verdict::NotComparable => "NOT COMPARABLE",
            Verdict::Regression => "REGRESSION",
        }
    }
}

/// One comparison.
#[derive(Clone, Debug)]
pub struct Line {
    /// Run (relative folder).
    pub run: String,
    /// What was compared.
    pub measure: String,
    /// Baseline value, formatted.
    pub base: String,
    /// New value, formatted.
    pub new: String,
    /// Change, formatted.
    pub change: String,
    /// The test behind the verdict (tolerance, p-value), shown with `--wide`.
    pub detail: String,
    /// What the HTML page draws: the two values and the change allowed around the base.
    pub band: Option<Band>,
    /// The verdict.
    pub verdict: Verdict,
}

/// The numbers behind a verdict, for the HTML page.
#[derive(Clone, Debug)]
pub enum Band {
    /// A count or an error: worse/changed beyond `allowed` (absolute) from `base`.
    Value {
        /// Baseline value.
        base: f64,
        /// New value.
        new: f64,
        /// Change allowed either way.
        allowed: f64,
    },
    /// Per-frame GPU times of both runs, and the relative threshold on the median.
    Samples {
        /// Baseline samples (ms).
        base: Vec<f64>,
        /// New samples (ms).
        new: Vec<f64>,
        /// `--time-threshold`.
        threshold: f64,
    },
}

/// The result of a comparison.
#[derive(Clone, Debug, Default)]
pub struct Report {
    /// Every comparison made.
    pub lines: Vec<Line>,
    /// Runs compared.
    pub runs: usize,
}

impl Report {
    /// Number of regressions.
    pub fn regressions(&self) -> usize {
        self.lines
            .iter()
            .filter(|l| l.verdict == Verdict::Regression)
            .count()
    }

    /// Number of pairs that are not comparable.
    pub fn not_comparable(&self) -> usize {
        self.lines
            .iter()
            .filter(|l| l.verdict == Verdict::NotComparable)
            .count()
    }

    /// The process exit code (see the module docs).
    pub fn exit_code(&self) -> u8 {
        if self.regressions() > 0 {
            EXIT_REGRESSION
        } else if self.not_comparable() > 0 {
            EXIT_NOT_COMPARABLE
        } else {
            0
        }
    }

    /// The compact table (changed lines only unless `all`), grouped by run, then a
    /// one-line verdict.
    pub fn table(&self, all: bool) -> String {
        self.render(all, false)
    }

    /// A static HTML page of the comparison (`--html FILE`), in the manner of criterion's
    /// reports: per run, each measure's base and new value with the band inside which a
    /// change is not one, drawn as a strip (counts and errors: the base's band and the new
    /// value; timings: both runs' per-frame samples, their medians and the threshold).
    /// Changed lines only unless `all`.
    pub fn html(&self, base: &str, new: &str, all: bool) -> String {
        let esc = |s: &str| {
            s.replace('&', "&amp;")
                .replace('<', "&lt;")
                .replace('>', "&gt;")
                .replace('"', "&quot;")
        };
        let mut h = String::new();
        h.push_str("<!DOCTYPE html>\n<html lang=en><head><meta charset=utf-8><title>caustics compare</title><style>body{font-family:sans-serif;margin:2em;color:#222}table{border-collapse:collapse;font-size:13px;margin:.5em 0 1.5em}td,th{border:1px solid #ccc;padding:3px 6px;text-align:right}td:first-child,th{text-align:left}th{background:#f0f0f0}tr.REGRESSION td{background:#fde4e4}tr.better td{background:#e4f5e4}tr.NOT td{background:#fff1d6}.meta{color:#555;font-size:13px}</style></head><body>\n");
        h += &format!(
            "<h1>caustics compare</h1><p class=meta>BASE {}<br>NEW {}</p><p><b>{}</b></p>\n",
            esc(base),
            esc(new),
            esc(self.table(false).lines().last().unwrap_or_default())
        );
        h.push_str("<p class=meta>Bands: a count or error is unchanged inside the grey band around BASE (the tolerance, or the reference's noise for RMSE); timings show every frame of BASE (blue) and NEW (orange), their medians (ticks) and the threshold around BASE's median (grey).</p>\n");
        let rows: Vec<&Line> = self
            .lines
            .iter()
            .filter(|l| all || l.verdict != Verdict::Same)
            .collect();
        let mut run: Option<&str> = None;
        for l in &rows {
            if run != Some(l.run.as_str()) {
                if run.is_some() {
                    h.push_str("</table>\n");
                }
                h += &format!(
                    "<h3>{}</h3><table><tr><th>measure</th><th>base</th><th>new</th><th>change</th><th>band</th><th>verdict</th><th>test</th></tr>\n",
                    esc(&l.run)
                );
                run = Some(&l.run);
            }
            let class = l.verdict.word().split(' ').next().unwrap_or_default();
            h += &format!(
                "<tr class={class}><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
                esc(&l.measure),
                esc(&l.base),
                esc(&l.new),
                esc(&l.change),
                l.band.as_ref().map(band_svg).unwrap_or_default(),
                esc(l.verdict.word()),
                esc(&l.detail)
            );
        }
        if run.is_some() {
            h.push_str("</table>\n");
        } else {
            h.push_str("<p>Nothing changed.</p>\n");
        }
        h.push_str("</body></html>\n");
        h
    }

    /// The wide table: one row per comparison with its test (`--wide`).
    pub fn wide_table(&self, all: bool) -> String {
        self.render(all, true)
    }

    fn render(&self, all: bool, wide: bool) -> String {
        let rows: Vec<&Line> = self
            .lines
            .iter()
            .filter(|l| all || l.verdict != Verdict::Same)
            .collect();
        let mut out = String::new();
        if !rows.is_empty() {
            let w = |f: fn(&Line) -> &str, h: &str| {
                rows.iter()
                    .map(|l| f(l).chars().count())
                    .max()
                    .unwrap_or(0)
                    .max(h.chars().count())
            };
            let (a, b, c, d, e) = (
                w(|l| &l.run, "run"),
                w(|l| &l.measure, "measure"),
                w(|l| &l.base, "base"),
                w(|l| &l.new, "new"),
                w(|l| &l.change, "change"),
            );
            if wide {
                out += &format!(
                    "{:a$}  {:b$}  {:>c$}  {:>d$}  {:e$}  {:14}  test\n",
                    "run", "measure", "base", "new", "change", "verdict"
                );
                for l in &rows {
                    out += &format!(
                        "{:a$}  {:b$}  {:>c$}  {:>d$}  {:e$}  {:14}  {}\n",
                        l.run,
                        l.measure,
                        l.base,
                        l.new,
                        l.change,
                        l.verdict.word(),
                        l.detail
                    );
                }
            } else {
                out += &format!(
                    "  {:b$}  {:>c$}  {:>d$}  {:e$}  verdict\n",
                    "measure", "base", "new", "change"
                );
                let mut run = None;
                for l in &rows {
                    if run != Some(&l.run) {
                        out += &format!("{}\n", l.run);
                        run = Some(&l.run);
                    }
                    out += &format!(
                        "  {:b$}  {:>c$}  {:>d$}  {:e$}  {}\n",
                        l.measure,
                        l.base,
                        l.new,
                        l.change,
                        l.verdict.word()
                    );
                }
            }
        }
        let count = |v: Verdict| self.lines.iter().filter(|l| l.verdict == v).count();
        out += &format!(
            "{} runs paired ({} not comparable): {} regressions, {} better, {} changed but not gated, {} new, {} unchanged\n",
            self.runs,
            count(Verdict::NotComparable),
            count(Verdict::Regression),
            count(Verdict::Better),
            count(Verdict::Info),
            count(Verdict::New),
            count(Verdict::Same)
        );
        out
    }
}

/// A horizontal value axis of a band's strip: `lo..hi` (padded) onto 240 px.
struct Strip {
    lo: f64,
    hi: f64,
}

impl Strip {
    const W: f64 = 240.0;

    fn new(lo: f64, hi: f64) -> Strip {
        let (lo, hi) = if hi > lo {
            (lo, hi)
        } else {
            (lo - 1.0, hi + 1.0)
        };
        let pad = 0.08 * (hi - lo);
        Strip {
            lo: lo - pad,
            hi: hi + pad,
        }
    }

    fn x(&self, v: f64) -> f64 {
        4.0 + (Self::W - 8.0) * (v - self.lo) / (self.hi - self.lo)
    }

    fn svg(body: &str) -> String {
        format!(
            "<svg width={0} height=18 viewBox=\"0 0 {0} 18\">{body}</svg>",
            Self::W
        )
    }
}

/// An inline SVG strip of a [`Band`] (see [`Report::html`]).
fn band_svg(b: &Band) -> String {
    match b {
        Band::Value { base, new, allowed } => {
            let (lo, hi) = ((base - allowed).min(*new), (base + allowed).max(*new));
            if !(lo.is_finite() && hi.is_finite()) {
                return String::new();
            }
            let s = Strip::new(lo, hi);
            Strip::svg(&format!(
                "<rect x={:.1} y=3 width={:.1} height=12 fill=\"#ddd\"/><line x1={2:.1} x2={2:.1} y1=1 y2=17 stroke=\"#1f77b4\" stroke-width=2/><circle cx={3:.1} cy=9 r=4 fill=\"#ff7f0e\"/>",
                s.x(base - allowed),
                (s.x(base + allowed) - s.x(base - allowed)).max(0.5),
                s.x(*base),
                s.x(*new)
            ))
        }
        Band::Samples {
            base,
            new,
            threshold,
        } => {
            let median = |v: &[f64]| crate::stats::summarize(v).map_or(f64::NAN, |s| s.median);
            let (mb, mn) = (median(base), median(new));
            let (band_lo, band_hi) = (mb / (1.0 + threshold), mb * (1.0 + threshold));
            let (lo, hi) = base
                .iter()
                .chain(new.iter())
                .copied()
                .filter(|v| v.is_finite())
                .fold((band_lo, band_hi), |(a, b), v| (a.min(v), b.max(v)));
            if !(lo.is_finite() && hi.is_finite() && mn.is_finite()) {
                return String::new();
            }
            let s = Strip::new(lo, hi);
            let mut body = format!(
                "<rect x={:.1} y=0 width={:.1} height=18 fill=\"#eee\"/>",
                s.x(band_lo),
                s.x(band_hi) - s.x(band_lo)
            );
            let dots = base
                .iter()
                .map(|v| (v, 5.0, "#1f77b4"))
                .chain(new.iter().map(|v| (v, 13.0, "#ff7f0e")));
            for (v, y, c) in dots {
                body += &format!("<circle cx={:.1} cy={y} r=1.8 fill=\"{c}\"/>", s.x(*v));
            }
            body += &format!(
                "<line x1={0:.1} x2={0:.1} y1=0 y2=9 stroke=\"#1f77b4\" stroke-width=2/><line x1={1:.1} x2={1:.1} y1=9 y2=18 stroke=\"#ff7f0e\" stroke-width=2/>",
                s.x(mb),
                s.x(mn)
            );
            Strip::svg(&body)
        }
    }
}

/// Every `result.json` under `root`, by its folder relative to `root`. In a
/// `reproduce` output folder (one with a `manifest.json`) only the runs its manifest
/// lists as done count, so stale runs of an earlier reproduction into the same folder
/// are not compared.
pub fn collect_results(root: &Path) -> Result<BTreeMap<String, RunResult>> {
    let out = collect_results_maybe_none(root)?;
    if out.is_empty() {
        bail!(
            "{}: holds no result.json (expected a `caustics reproduce` or `caustics run` output folder)",
            root.display()
        );
    }
    Ok(out)
}

/// [`collect_results`], empty when a folder without a manifest holds no result.json.
fn collect_results_maybe_none(root: &Path) -> Result<BTreeMap<String, RunResult>> {
    if !root.is_dir() {
        bail!("{}: no such folder", root.display());
    }
    if root.join("manifest.json").is_file() {
        let m = crate::reproduce::read_manifest(root)?;
        let mut out = BTreeMap::new();
        // A sequence's folder holds an animation.json, which `compare_sequences` pairs.
        let mut sequences = 0;
        for rel in m.runs.iter().filter_map(|r| r.dir.as_ref()) {
            if crate::summary::is_sequence_dir(&root.join(rel)) {
                sequences += 1;
                continue;
            }
            out.insert(rel.clone(), crate::summary::read_result(&root.join(rel))?);
        }
        if out.is_empty() && sequences == 0 {
            bail!(
                "{}: its manifest lists no run that was done",
                root.display()
            );
        }
        return Ok(out);
    }
    let mut out = BTreeMap::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in
            std::fs::read_dir(&dir).with_context(|| format!("reading {}", dir.display()))?
        {
            let path = entry?.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.file_name().is_some_and(|n| n == "result.json") {
                let text = std::fs::read_to_string(&path)
                    .with_context(|| format!("reading {}", path.display()))?;
                let r = RunResult::from_json(&text)
                    .with_context(|| format!("{}: not a result.json", path.display()))?;
                let rel = path
                    .parent()
                    .and_then(|p| p.strip_prefix(root).ok())
                    .map(|p| p.display().to_string())
                    .unwrap_or_default();
                out.insert(if rel.is_empty() { ".".into() } else { rel }, r);
            }
        }
    }
    Ok(out)
}

/// Compares two folders.
pub fn compare(args: &CompareArgs) -> Result<Report> {
    for (v, name, ok) in [
        (
            args.time_threshold,
            "--time-threshold",
            args.time_threshold >= 0.0,
        ),
        (args.alpha, "--alpha", args.alpha > 0.0 && args.alpha < 1.0),
        (
            args.count_tolerance,
            "--count-tolerance",
            args.count_tolerance >= 0.0,
        ),
        (
            args.error_tolerance,
            "--error-tolerance",
            args.error_tolerance >= 0.0,
        ),
        (args.noise_k, "--noise-k", args.noise_k >= 0.0),
    ] {
        if !(v.is_finite() && ok) {
            bail!("{name}: expected a non-negative number (alpha: in (0, 1)), got {v}");
        }
    }
    if let Some(page) = &args.html {
        for (folder, what) in [(&args.base, "BASE"), (&args.new, "NEW")] {
            if is_inside(page, folder) {
                bail!(
                    "--html {}: inside {what} ({}); compare never writes into the folders it reads",
                    page.display(),
                    folder.display()
                );
            }
        }
    }
    let base = collect_results_maybe_none(&args.base).context("BASE")?;
    let new = collect_results_maybe_none(&args.new).context("NEW")?;
    let base_sequences = crate::animate::find_keyed(&args.base).context("BASE")?;
    let new_sequences = crate::animate::find_keyed(&args.new).context("NEW")?;
    for (folder, runs, sequences) in [
        (&args.base, &base, &base_sequences),
        (&args.new, &new, &new_sequences),
    ] {
        if runs.is_empty() && sequences.is_empty() {
            bail!(
                "{}: holds no result.json and no animation.json (expected a `caustics reproduce`, `caustics run` or `caustics run --animate` output folder)",
                folder.display()
            );
        }
    }
    let mut report = Report::default();
    crate::animate::compare_sequences(&base_sequences, &new_sequences, args, &mut report);
    for (key, b) in &base {
        let Some(n) = new.get(key) else {
            report.lines.push(line(
                key,
                "run",
                "present",
                "missing",
                "",
                Verdict::Regression,
            ));
            continue;
        };
        report.runs += 1;
        compare_run(key, b, n, args, &mut report.lines);
    }
    for key in new.keys().filter(|k| !base.contains_key(*k)) {
        report.lines.push(line(
            key,
            "run",
            "–",
            "present",
            "not in BASE",
            Verdict::New,
        ));
    }
    Ok(report)
}

/// Whether `file` (which may not exist yet) would lie inside `folder`.
fn is_inside(file: &Path, folder: &Path) -> bool {
    let abs = |p: &Path| {
        let p = if p.is_absolute() {
            p.to_path_buf()
        } else {
            std::env::current_dir().map_or_else(|_| p.to_path_buf(), |c| c.join(p))
        };
        // Resolve what exists (symlinks, `..`), keep the rest as written.
        let existing = p
            .ancestors()
            .find(|a| a.exists())
            .unwrap_or(&p)
            .to_path_buf();
        let rest = p
            .strip_prefix(&existing)
            .map(Path::to_path_buf)
            .unwrap_or_default();
        existing.canonicalize().unwrap_or(existing).join(rest)
    };
    abs(file).starts_with(abs(folder))
}

/// Writes [`Report::html`] to `path` (atomically).
pub fn write_html(path: &Path, args: &CompareArgs, report: &Report) -> Result<()> {
    let page = report.html(
        &args.base.display().to_string(),
        &args.new.display().to_string(),
        args.verbose,
    );
    caustics_metrics::atomic_write(path, page.as_bytes())
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

pub(crate) fn line(
    run: &str,
    measure: &str,
    base: &str,
    new: &str,
    change: &str,
    verdict: Verdict,
) -> Line {
    Line {
        run: run.into(),
        measure: measure.into(),
        base: base.into(),
        new: new.into(),
        change: change.into(),
        detail: String::new(),
        band: None,
        verdict,
    }
}

/// The inputs of two runs that differ, as (what, base, new); empty when comparable.
fn differing_inputs(
    b: &RunResult,
    n: &RunResult,
    across_adapters: bool,
) -> Vec<(&'static str, String, String)> {
    let mut out = Vec::new();
    let mut check = |what: &'static str, x: String, y: String| {
        if x != y {
            out.push((what, x, y));
        }
    };
    check("scene", b.scene.name.clone(), n.scene.name.clone());
    check(
        "resolution",
        format!("{}x{}", b.scene.width, b.scene.height),
        format!("{}x{}", n.scene.width, n.scene.height),
    );
    // The hash covers the camera too, so another resolution changes it as well.
    check(
        "scene content hash",
        b.scene.hash.clone(),
        n.scene.hash.clone(),
    );
    check(
        "representative lights",
        format!("{:?}", b.scene.representative_lights),
        format!("{:?}", n.scene.representative_lights),
    );
    check("method", b.method.name.clone(), n.method.name.clone());
    check(
        "parameters",
        b.method.params.to_string(),
        n.method.params.to_string(),
    );
    if !across_adapters {
        let adapter = |r: &RunResult| format!("{} ({})", r.machine.adapter, r.machine.driver_info);
        check("adapter", adapter(b), adapter(n));
    }
    out
}

fn compare_run(key: &str, b: &RunResult, n: &RunResult, args: &CompareArgs, out: &mut Vec<Line>) {
    let differ = differing_inputs(b, n, args.across_adapters);
    if !differ.is_empty() {
        let what: Vec<&str> = differ.iter().map(|d| d.0).collect();
        let side = |base: bool| {
            differ
                .iter()
                .map(|d| if base { d.1.as_str() } else { d.2.as_str() })
                .collect::<Vec<_>>()
                .join("; ")
        };
        let mut l = line(
            key,
            "inputs",
            &side(true),
            &side(false),
            &format!("{} differ", what.join(", ")),
            Verdict::NotComparable,
        );
        l.detail = if what.contains(&"adapter") {
            "made from different inputs: nothing of the pair is compared (--across-adapters compares runs of two adapters)".into()
        } else {
            "made from different inputs: nothing of the pair is compared".into()
        };
        out.push(l);
        return;
    }
    // Deterministic counts.
    let counts = |r: &RunResult| -> BTreeMap<String, u64> {
        let mut m = BTreeMap::new();
        if let Some(f) = &r.fragments {
            m.insert("fragments (method)".into(), f.method_total);
            m.insert("fill total".into(), f.fill_total);
            m.insert("fill max".into(), f.fill_max as u64);
            m.insert("fill covered pixels".into(), f.fill_covered_pixels);
            for p in &f.passes {
                m.insert(
                    format!("{} fragments", p.name),
                    p.fragment_shader_invocations,
                );
                m.insert(format!("{} primitives", p.name), p.primitives);
                if p.compute_shader_invocations > 0 {
                    m.insert(format!("{} compute", p.name), p.compute_shader_invocations);
                }
            }
        }
        for (k, v) in &r.counters {
            m.insert(format!("counter {k}"), *v);
        }
        m
    };
    let (cb, cn) = (counts(b), counts(n));
    let keys: std::collections::BTreeSet<&String> = cb.keys().chain(cn.keys()).collect();
    for k in keys {
        match (cb.get(k), cn.get(k)) {
            (Some(&x), Some(&y)) => {
                let rel = (y as f64 - x as f64).abs() / (x as f64).max(1.0);
                let verdict = if x == y || rel <= args.count_tolerance {
                    Verdict::Same
                } else {
                    Verdict::Regression
                };
                let change = if x == y {
                    String::new()
                } else {
                    format!(
                        "{:+} ({:+.2}%)",
                        y as i128 - x as i128,
                        100.0 * (y as f64 - x as f64) / (x as f64).max(1.0)
                    )
                };
                let mut l = line(key, k, &x.to_string(), &y.to_string(), &change, verdict);
                l.band = Some(Band::Value {
                    base: x as f64,
                    new: y as f64,
                    allowed: args.count_tolerance * x as f64,
                });
                l.detail = format!(
                    "deterministic: allowed ±{}% (--count-tolerance)",
                    crate::summary::num(100.0 * args.count_tolerance)
                );
                out.push(l);
            }
            (x, y) => out.push(line(
                key,
                k,
                &x.map(|v| v.to_string()).unwrap_or("absent".into()),
                &y.map(|v| v.to_string()).unwrap_or("absent".into()),
                "present in one run only",
                Verdict::Regression,
            )),
        }
    }
    compare_errors(key, b, n, args, out);
    // Only with --across-adapters do runs of two adapters get this far.
    let adapters_differ =
        b.machine.adapter != n.machine.adapter || b.machine.driver_info != n.machine.driver_info;
    let timing = |r: &RunResult, which: &str| -> Option<Summary> {
        match which {
            "method GPU ms" => r.timing.method_gpu_ms.clone(),
            _ => r.timing.frame_gpu_ms.clone(),
        }
    };
    for which in ["method GPU ms", "frame GPU ms"] {
        if let (Some(x), Some(y)) = (timing(b, which), timing(n, which)) {
            let mut l = compare_timing(key, which, &x, &y, args);
            if l.verdict != Verdict::Same && (args.no_timings || adapters_differ) {
                l.change += if adapters_differ {
                    " [different adapters]"
                } else {
                    " [--no-timings]"
                };
                l.verdict = Verdict::Info;
            }
            out.push(l);
        }
    }
}

/// The samples per pixel of a run's pixel-averaged errors (1 for a schema-2 file that
/// states no scoring frame, which no writer makes).
fn score_spp(r: &RunResult) -> u32 {
    r.scoring.as_ref().map_or(1, |s| s.samples_per_pixel)
}

fn compare_errors(
    key: &str,
    b: &RunResult,
    n: &RunResult,
    args: &CompareArgs,
    out: &mut Vec<Line>,
) {
    let any = |r: &RunResult| r.errors.is_some() || r.errors_1spp.is_some();
    match (any(b), any(n)) {
        (false, false) => return,
        (true, false) => {
            out.push(line(
                key,
                "errors",
                "present",
                "absent",
                "no reference in NEW",
                Verdict::Regression,
            ));
            return;
        }
        (false, true) => {
            out.push(line(key, "errors", "absent", "present", "", Verdict::Info));
            return;
        }
        (true, true) => {}
    }
    // Pixel-averaged errors only against pixel-averaged errors of as many samples.
    match (&b.errors, &n.errors) {
        (Some(x), Some(y)) if score_spp(b) == score_spp(n) => {
            compare_report(key, "error", x, y, predates(b, n), args, out);
        }
        (Some(_), Some(_)) => out.push(line(
            key,
            "errors (pixel-averaged)",
            &format!("{} spp", score_spp(b)),
            &format!("{} spp", score_spp(n)),
            "scored at other sample counts: not compared, the 1-spp errors are",
            Verdict::Info,
        )),
        (x, y) if x.is_some() != y.is_some() => {
            let side = |e: &Option<crate::result::ErrorReport>, r: &RunResult| {
                if e.is_some() {
                    format!("{} spp", score_spp(r))
                } else {
                    format!("1 spp only (schema {})", r.schema_version)
                }
            };
            out.push(line(
                key,
                "errors (pixel-averaged)",
                &side(x, b),
                &side(y, n),
                "one side has no pixel-averaged errors: comparing the 1-spp errors only",
                Verdict::Info,
            ));
        }
        _ => {}
    }
    match (&b.errors_1spp, &n.errors_1spp) {
        (Some(x), Some(y)) => compare_report(key, "error 1spp", x, y, predates(b, n), args, out),
        (Some(_), None) => out.push(line(
            key,
            "errors 1spp",
            "present",
            "absent",
            "",
            Verdict::Regression,
        )),
        (None, Some(_)) => out.push(line(
            key,
            "errors 1spp",
            "absent",
            "present",
            "",
            Verdict::Info,
        )),
        (None, None) => {}
    }
}

/// Whether NEW's schema predates BASE's: figures BASE has and NEW lacks are then not lost,
/// only never computed.
fn predates(b: &RunResult, n: &RunResult) -> bool {
    n.schema_version < b.schema_version
}

/// One gated figure: name, base, new, and how it is gated.
type Figure = (&'static str, Option<f64>, Option<f64>, Gate);

/// How a figure is gated.
#[derive(Clone, Copy, PartialEq)]
enum Gate {
    /// Lower is better; worse beyond the relative tolerance or the reference noise.
    RmseLike,
    /// Lower is better; worse beyond the relative tolerance.
    Relative,
    /// A ratio whose ideal is 1: changed when `|Δ| > --error-tolerance`, worse when it
    /// moved away from 1.
    Flux,
}

/// Gates the surface errors of two reports, and their volume errors the same way.
fn compare_report(
    key: &str,
    prefix: &str,
    eb: &crate::result::ErrorReport,
    en: &crate::result::ErrorReport,
    new_predates: bool,
    args: &CompareArgs,
    out: &mut Vec<Line>,
) {
    let noise = eb
        .reference_noise_rms
        .unwrap_or(0.0)
        .max(en.reference_noise_rms.unwrap_or(0.0));
    let figures = |name: &str, x, y, noise, out: &mut Vec<Line>| {
        compare_figures(key, name, (x, y), noise, new_predates, args, out)
    };
    figures(prefix, &eb.surface, &en.surface, noise, out);
    let name = format!("{prefix} volume");
    match (&eb.volume, &en.volume) {
        // The reference noise RMS is the surface image's: volume RMSE is gated on the
        // relative tolerance alone.
        (Some(x), Some(y)) => figures(&name, x, y, 0.0, out),
        (Some(_), None) => out.push(line(
            key,
            &name,
            "present",
            "absent",
            "no volume errors in NEW",
            Verdict::Regression,
        )),
        (None, Some(_)) => out.push(line(key, &name, "absent", "present", "", Verdict::Info)),
        (None, None) => {}
    }
}

fn compare_figures(
    key: &str,
    prefix: &str,
    (b, n): (&caustics_metrics::Errors, &caustics_metrics::Errors),
    noise: f64,
    new_predates: bool,
    args: &CompareArgs,
    out: &mut Vec<Line>,
) {
    let figures: [Figure; 8] = [
        ("flux ratio", b.flux_ratio, n.flux_ratio, Gate::Flux),
        (
            "flux ratio (image)",
            b.flux_ratio_image,
            n.flux_ratio_image,
            Gate::Flux,
        ),
        ("relMSE", Some(b.rel_mse), Some(n.rel_mse), Gate::Relative),
        (
            "relMSE after flux",
            b.rel_mse_after_flux,
            n.rel_mse_after_flux,
            Gate::Relative,
        ),
        ("HDR-FLIP", b.hdr_flip, n.hdr_flip, Gate::Relative),
        ("FLIP", Some(b.flip), Some(n.flip), Gate::Relative),
        ("RMSE", Some(b.rmse), Some(n.rmse), Gate::RmseLike),
        (
            "RMSE after best scale",
            Some(b.rmse_after_best_scale),
            Some(n.rmse_after_best_scale),
            Gate::RmseLike,
        ),
    ];
    for (name, x, y, gate) in figures {
        let measure = format!("{prefix} {name}");
        let (x, y) = match (x, y) {
            (Some(x), Some(y)) => (x, y),
            (None, None) => continue,
            // A figure the older file predates is not a change.
            (None, Some(_)) => {
                out.push(line(key, &measure, "absent", "present", "", Verdict::Info));
                continue;
            }
            (Some(x), None) if new_predates => {
                out.push(line(
                    key,
                    &measure,
                    &crate::summary::num(x),
                    "absent",
                    "NEW's schema predates it",
                    Verdict::Info,
                ));
                continue;
            }
            (Some(x), None) => {
                out.push(line(
                    key,
                    &measure,
                    &crate::summary::num(x),
                    "absent",
                    "figure lost",
                    Verdict::Regression,
                ));
                continue;
            }
        };
        let mut allowed_abs = args.error_tolerance;
        let (verdict, change, detail) = match gate {
            Gate::Flux => {
                let d = y - x;
                let verdict = if !y.is_finite() && x.is_finite() {
                    Verdict::Regression
                } else if d.abs() <= args.error_tolerance {
                    Verdict::Same
                } else if (y - 1.0).abs() > (x - 1.0).abs() {
                    Verdict::Regression
                } else {
                    Verdict::Better
                };
                let change = if x == y {
                    String::new()
                } else {
                    format!("{d:+.4}")
                };
                let detail = format!(
                    "allowed ±{} (absolute), ideal 1",
                    crate::summary::num(args.error_tolerance)
                );
                (verdict, change, detail)
            }
            Gate::Relative | Gate::RmseLike => {
                let allowed = (args.error_tolerance * x.abs()).max(if gate == Gate::RmseLike {
                    args.noise_k * noise
                } else {
                    0.0
                });
                let verdict = if (!y.is_finite() && x.is_finite()) || y - x > allowed {
                    Verdict::Regression
                } else if x - y > allowed {
                    Verdict::Better
                } else {
                    Verdict::Same
                };
                let change = if x == y {
                    String::new()
                } else {
                    format!("{:+.2}%", 100.0 * (y - x) / x.abs().max(1e-300))
                };
                let detail = format!("allowed ±{}", crate::summary::num(allowed));
                allowed_abs = allowed;
                (verdict, change, detail)
            }
        };
        let mut l = line(
            key,
            &measure,
            &crate::summary::num(x),
            &crate::summary::num(y),
            &change,
            verdict,
        );
        l.detail = detail;
        l.band = Some(Band::Value {
            base: x,
            new: y,
            allowed: allowed_abs,
        });
        out.push(l);
    }
}

/// Compares two timing summaries (see the module docs).
pub fn compare_timing(key: &str, name: &str, b: &Summary, n: &Summary, args: &CompareArgs) -> Line {
    let ratio = n.median / b.median.max(1e-12);
    let grew = ratio > 1.0 + args.time_threshold;
    let shrank = ratio < 1.0 / (1.0 + args.time_threshold);
    let (verdict, test) = if !b.values.is_empty() && !n.values.is_empty() {
        let t = mann_whitney(&b.values, &n.values);
        let significant = t.p_value < args.alpha;
        let v = match (significant, grew, shrank) {
            (true, true, _) if t.prob_b_greater > 0.5 => Verdict::Regression,
            (true, _, true) if t.prob_b_greater < 0.5 => Verdict::Better,
            _ => Verdict::Same,
        };
        (v, format!("Mann-Whitney p={:.2e}", t.p_value))
    } else {
        let v = if grew && n.p10 > b.p90 {
            Verdict::Regression
        } else if shrank && n.p90 < b.p10 {
            Verdict::Better
        } else {
            Verdict::Same
        };
        (v, "p10/p90 ranges (no per-frame samples)".to_owned())
    };
    let mut l = line(
        key,
        name,
        &format!("{:.3}", b.median),
        &format!("{:.3}", n.median),
        &format!("{:+.1}%", 100.0 * (ratio - 1.0)),
        verdict,
    );
    l.detail = format!("{test}, threshold {:.0}%", 100.0 * args.time_threshold);
    let samples = |x: &Summary| {
        if x.values.is_empty() {
            vec![x.p10, x.median, x.p90]
        } else {
            x.values.clone()
        }
    };
    l.band = Some(Band::Samples {
        base: samples(b),
        new: samples(n),
        threshold: args.time_threshold,
    });
    l
}
