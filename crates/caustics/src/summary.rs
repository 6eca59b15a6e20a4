//! The summary of a reproduced experiment: `summary.json` (one row per run),
//! `summary.md` (tables shaped like the paper's, with the paper's own numbers beside the
//! measured ones), `bmf.json` (Bencher Metric Format) and the plots. Written from the
//! manifest and the result files only, so `reproduce` and `merge` give the same summary.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

use crate::experiment::{Experiment, figure_matches};
use crate::reproduce::Manifest;
use crate::result::RunResult;

/// `summary.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Summary {
    /// [`crate::reproduce::MANIFEST_VERSION`].
    pub schema_version: u32,
    /// Experiment name.
    pub experiment: String,
    /// Its description.
    pub description: String,
    /// `--scale`.
    pub scale: f64,
    /// Adapter, CPU and commits of the runs (distinct values, sorted).
    pub adapters: Vec<String>,
    /// Commits the runs were made from (distinct, sorted; `+dirty` marks a dirty tree).
    pub commits: Vec<String>,
    /// Build profiles (distinct).
    pub profiles: Vec<String>,
    /// The paper and its hardware, when the experiment gives its figures.
    pub paper: Option<PaperInfo>,
    /// Runs done.
    pub done: usize,
    /// Runs skipped (the method cannot render the scene).
    pub skipped: usize,
    /// Runs failed.
    pub failed: usize,
    /// References that were missing: those runs have no errors.
    pub missing_references: Vec<String>,
    /// One row per run, in experiment order.
    pub runs: Vec<Row>,
}

/// The paper a table compares with.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PaperInfo {
    /// The paper.
    pub source: String,
    /// Its hardware.
    pub hardware: String,
}

/// Median with the 10th and 90th percentiles.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Spread {
    /// Median.
    pub median: f64,
    /// 10th percentile.
    pub p10: f64,
    /// 90th percentile.
    pub p90: f64,
}

impl From<&crate::stats::Summary> for Spread {
    fn from(s: &crate::stats::Summary) -> Self {
        Spread {
            median: s.median,
            p10: s.p10,
            p90: s.p90,
        }
    }
}

/// One run in the summary.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Row {
    /// Position in the experiment.
    pub index: usize,
    /// `<scene>/<method>/<params>`.
    pub key: String,
    /// Group label.
    pub group: String,
    /// Scene.
    pub scene: String,
    /// Method.
    pub method: String,
    /// Parameters as given.
    pub params: serde_json::Map<String, serde_json::Value>,
    /// Image size.
    pub width: u32,
    /// Image size.
    pub height: u32,
    /// "done", "skipped", "failed".
    pub status: String,
    /// Why skipped or failed.
    pub reason: Option<String>,
    /// Folder of result.json relative to the experiment folder.
    pub dir: Option<String>,
    /// GPU ms of the method's passes.
    pub method_gpu_ms: Option<Spread>,
    /// GPU ms of the whole frame.
    pub frame_gpu_ms: Option<Spread>,
    /// Fragment shader invocations of the method's passes (count frame).
    pub fragments: Option<u64>,
    /// Fill-counted camera-resolution fragments.
    pub fill_total: Option<u64>,
    /// The method's counters.
    pub counters: BTreeMap<String, u64>,
    /// Surface caustic errors against the reference.
    pub errors: Option<caustics_metrics::Errors>,
    /// The reference's own noise (RMS of its standard error).
    pub reference_noise_rms: Option<f64>,
    /// The paper's figures for this run.
    pub paper: Vec<PaperValue>,
}

/// A number from the paper beside a run.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PaperValue {
    /// Measure name.
    pub measure: String,
    /// The paper's value.
    pub value: f64,
    /// Where in the paper.
    pub note: String,
}

impl Row {
    /// The measured value of a paper measure, if this run has it.
    pub fn measure(&self, measure: &str) -> Option<f64> {
        match measure {
            "method_gpu_ms" => self.method_gpu_ms.map(|s| s.median),
            "frame_gpu_ms" => self.frame_gpu_ms.map(|s| s.median),
            "fps" => self.frame_gpu_ms.map(|s| 1000.0 / s.median),
            "fragments" => self.fragments.map(|f| f as f64),
            m => m
                .strip_prefix("counter:")
                .and_then(|c| self.counters.get(c))
                .map(|&v| v as f64),
        }
    }
}

/// Reads `<dir>/<rel>/result.json`.
pub fn read_result(dir: &Path) -> Result<RunResult> {
    let p = dir.join("result.json");
    let text = std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
    RunResult::from_json(&text).with_context(|| format!("{}: not a result.json", p.display()))
}

/// Builds the summary of `out` from its manifest and result files.
pub fn build(out: &Path, e: &Experiment, m: &Manifest) -> Result<Summary> {
    let mut rows = Vec::new();
    let (mut adapters, mut commits, mut profiles) = (vec![], vec![], vec![]);
    for st in &m.runs {
        let spec = e
            .runs
            .get(st.index)
            .filter(|s| s.key() == st.key)
            .with_context(|| {
                format!(
                    "{}: run {} ({}) is not in {} as it is now",
                    out.join("manifest.json").display(),
                    st.index,
                    st.key,
                    e.file.display()
                )
            })?;
        let result = match &st.dir {
            Some(rel) => Some(read_result(&out.join(rel))?),
            None => None,
        };
        if let Some(r) = &result {
            adapters.push(format!(
                "{} ({}), CPU {}",
                r.machine.adapter, r.machine.backend, r.machine.cpu
            ));
            commits.push(format!(
                "{}{}",
                r.build.commit,
                if r.build.dirty { "+dirty" } else { "" }
            ));
            profiles.push(r.build.profile.clone());
        }
        let paper = e
            .def
            .paper
            .iter()
            .flat_map(|p| &p.figures)
            .filter(|f| figure_matches(f, spec))
            .map(|f| PaperValue {
                measure: f.measure.clone(),
                value: f.value,
                note: f.note.clone(),
            })
            .collect();
        rows.push(Row {
            index: st.index,
            key: st.key.clone(),
            group: spec.group.clone(),
            scene: spec.scene.name.clone(),
            method: spec.method.clone(),
            params: spec.params.clone(),
            width: spec.scene.camera.width,
            height: spec.scene.camera.height,
            status: st.status.clone(),
            reason: st.reason.clone(),
            dir: st.dir.clone(),
            method_gpu_ms: result
                .as_ref()
                .and_then(|r| r.timing.method_gpu_ms.as_ref().map(Spread::from)),
            frame_gpu_ms: result
                .as_ref()
                .and_then(|r| r.timing.frame_gpu_ms.as_ref().map(Spread::from)),
            fragments: result
                .as_ref()
                .and_then(|r| r.fragments.as_ref().map(|f| f.method_total)),
            fill_total: result
                .as_ref()
                .and_then(|r| r.fragments.as_ref().map(|f| f.fill_total)),
            counters: result
                .as_ref()
                .map(|r| r.counters.clone())
                .unwrap_or_default(),
            errors: result
                .as_ref()
                .and_then(|r| r.errors.as_ref().map(|e| e.surface)),
            reference_noise_rms: result
                .as_ref()
                .and_then(|r| r.errors.as_ref().and_then(|e| e.reference_noise_rms)),
            paper,
        });
    }
    let distinct = |mut v: Vec<String>| {
        v.sort();
        v.dedup();
        v
    };
    let count = |s: &str| rows.iter().filter(|r| r.status == s).count();
    Ok(Summary {
        schema_version: crate::reproduce::MANIFEST_VERSION,
        experiment: e.def.name.clone(),
        description: e.def.description.clone(),
        scale: m.scale,
        adapters: distinct(adapters),
        commits: distinct(commits),
        profiles: distinct(profiles),
        paper: e.def.paper.as_ref().map(|p| PaperInfo {
            source: p.source.clone(),
            hardware: p.hardware.clone(),
        }),
        done: count("done"),
        skipped: count("skipped"),
        failed: count("failed"),
        missing_references: m.missing_references.clone(),
        runs: rows,
    })
}

/// Writes `summary.json`, `summary.md`, `bmf.json` and `plots/` into `out`.
pub fn write_all(out: &Path, e: &Experiment, m: &Manifest) -> Result<Summary> {
    let s = build(out, e, m)?;
    let plots = crate::plots::write_plots(&out.join("plots"), &s)?;
    caustics_metrics::atomic_write(&out.join("summary.json"), &serde_json::to_vec_pretty(&s)?)?;
    caustics_metrics::atomic_write(&out.join("bmf.json"), &serde_json::to_vec_pretty(&bmf(&s))?)?;
    caustics_metrics::atomic_write(&out.join("summary.md"), markdown(&s, &plots).as_bytes())?;
    Ok(s)
}

/// Reads `summary.json` of an experiment folder.
pub fn read_summary(dir: &Path) -> Result<Summary> {
    let p = dir.join("summary.json");
    let text = std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{}: not a summary.json", p.display()))
}

/// Bencher Metric Format: `{ "<experiment>/<run key>": { "<measure>": {"value": v,
/// "lower_value": lo, "upper_value": hi} } }`. Timings carry their p10/p90 as bounds;
/// counts and errors are single values.
pub fn bmf(s: &Summary) -> serde_json::Value {
    use serde_json::{Map, Value, json};
    let mut out = Map::new();
    for r in s.runs.iter().filter(|r| r.status == "done") {
        let mut m = Map::new();
        let spread =
            |v: &Spread| json!({"value": v.median, "lower_value": v.p10, "upper_value": v.p90});
        if let Some(v) = &r.method_gpu_ms {
            m.insert("method_gpu_ms".into(), spread(v));
        }
        if let Some(v) = &r.frame_gpu_ms {
            m.insert("frame_gpu_ms".into(), spread(v));
        }
        let mut single = |name: String, v: f64| {
            if v.is_finite() {
                m.insert(name, json!({"value": v}));
            }
        };
        if let Some(f) = r.fragments {
            single("fragments".into(), f as f64);
        }
        if let Some(f) = r.fill_total {
            single("fill_fragments".into(), f as f64);
        }
        for (k, v) in &r.counters {
            single(format!("counter_{k}"), *v as f64);
        }
        if let Some(e) = &r.errors {
            single("rmse".into(), e.rmse);
            single("rel_mse".into(), e.rel_mse);
            single("flip".into(), e.flip);
            single("best_scale".into(), e.best_scale);
            single("rmse_after_best_scale".into(), e.rmse_after_best_scale);
            if let Some(v) = e.rel_mse_after_best_scale {
                single("rel_mse_after_best_scale".into(), v);
            }
            if let Some(v) = e.flip_after_best_scale {
                single("flip_after_best_scale".into(), v);
            }
        }
        out.insert(format!("{}/{}", s.experiment, r.key), Value::Object(m));
    }
    Value::Object(out)
}

fn params_cell(p: &serde_json::Map<String, serde_json::Value>) -> String {
    if p.is_empty() {
        return "defaults".into();
    }
    p.iter()
        .map(|(k, v)| match v {
            serde_json::Value::String(s) => format!("{k}={s}"),
            v => format!("{k}={v}"),
        })
        .collect::<Vec<_>>()
        .join(" ")
}

fn ms(s: &Option<Spread>) -> String {
    match s {
        Some(s) => format!("{:.2} ({:.2}–{:.2})", s.median, s.p10, s.p90),
        None => "–".into(),
    }
}

/// Short form of a number for tables.
pub fn num(v: f64) -> String {
    if !v.is_finite() {
        format!("{v}")
    } else if v == 0.0 {
        "0".into()
    } else if v.abs() >= 1e4 || v.abs() < 1e-3 {
        format!("{v:.3e}")
    } else {
        format!("{v:.4}")
    }
}

fn paper_cell(r: &Row) -> String {
    r.paper
        .iter()
        .map(|p| {
            let ours = r
                .measure(&p.measure)
                .map(|v| format!(" (ours {})", num(v)))
                .unwrap_or_default();
            format!("{} {}{ours}", p.measure, p.value)
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// The markdown summary: one table per group, skipped and failed runs listed.
pub fn markdown(s: &Summary, plots: &[String]) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# {}\n", s.experiment);
    if !s.description.is_empty() {
        let _ = writeln!(md, "{}\n", s.description);
    }
    let _ = writeln!(
        md,
        "Adapter: {}. Commit: {}. Build: {}. Scale {}. {} runs done, {} skipped, {} failed.\n",
        s.adapters.join("; "),
        s.commits.join(", "),
        s.profiles.join(", "),
        s.scale,
        s.done,
        s.skipped,
        s.failed
    );
    let _ = writeln!(
        md,
        "GPU ms: median (p10–p90) over the measured frames. Errors of the surface caustic \
         image against the CPU reference: RMSE and FLIP as measured, and after the best \
         single brightness factor `s` (a normalization error vanishes there, a shape error \
         does not); σ_ref is the reference's own noise RMS.\n"
    );
    if !s.missing_references.is_empty() {
        let _ = writeln!(
            md,
            "No reference for {}: those runs have no errors (`caustics reference` renders one).\n",
            s.missing_references.join(", ")
        );
    }
    let paper_col = s
        .paper
        .as_ref()
        .filter(|_| s.runs.iter().any(|r| !r.paper.is_empty()));
    let mut groups: Vec<&str> = Vec::new();
    for r in &s.runs {
        if !groups.contains(&r.group.as_str()) {
            groups.push(&r.group);
        }
    }
    for g in groups {
        let rows: Vec<&Row> = s
            .runs
            .iter()
            .filter(|r| r.group == g && r.status == "done")
            .collect();
        if rows.is_empty() {
            continue;
        }
        let _ = writeln!(md, "## {g}\n");
        let mut head = "| scene | method | params | size | method GPU ms | frame GPU ms | fragments | counters | RMSE | FLIP | s | RMSE·s | FLIP·s | σ_ref |".to_string();
        if let Some(p) = paper_col {
            let _ = write!(head, " paper ({}) |", p.hardware);
        }
        let _ = writeln!(md, "{head}");
        let cols = head.matches('|').count() - 1;
        let _ = writeln!(md, "|{}", "---|".repeat(cols));
        for r in rows {
            let counters = r
                .counters
                .iter()
                .map(|(k, v)| format!("{k} {v}"))
                .collect::<Vec<_>>()
                .join(", ");
            let errs = match &r.errors {
                Some(e) => format!(
                    "{} | {} | {} | {} | {}",
                    num(e.rmse),
                    num(e.flip),
                    num(e.best_scale),
                    num(e.rmse_after_best_scale),
                    e.flip_after_best_scale.map(num).unwrap_or("–".into())
                ),
                None => "– | – | – | – | –".into(),
            };
            let _ = write!(
                md,
                "| {} | {} | {} | {}×{} | {} | {} | {} | {} | {} | {} |",
                r.scene,
                r.method,
                params_cell(&r.params),
                r.width,
                r.height,
                ms(&r.method_gpu_ms),
                ms(&r.frame_gpu_ms),
                r.fragments.map(|f| f.to_string()).unwrap_or("–".into()),
                counters,
                errs,
                r.reference_noise_rms.map(num).unwrap_or("–".into())
            );
            if paper_col.is_some() {
                let _ = write!(md, " {} |", paper_cell(r));
            }
            let _ = writeln!(md);
        }
        let _ = writeln!(md);
    }
    if let Some(p) = &s.paper {
        let _ = writeln!(
            md,
            "Paper figures from {}, measured on {} (not comparable in absolute terms: \
             compare ratios between runs).\n",
            p.source, p.hardware
        );
    }
    let others: Vec<&Row> = s.runs.iter().filter(|r| r.status != "done").collect();
    if !others.is_empty() {
        let _ = writeln!(md, "## Not run\n\n| run | status | reason |\n|---|---|---|");
        for r in others {
            let _ = writeln!(
                md,
                "| {} | {} | {} |",
                r.key,
                r.status,
                r.reason.as_deref().unwrap_or("").replace('|', "/")
            );
        }
        let _ = writeln!(md);
    }
    if !plots.is_empty() {
        let _ = writeln!(md, "## Plots\n");
        for p in plots {
            let _ = writeln!(md, "![{p}]({p})\n");
        }
    }
    md
}
