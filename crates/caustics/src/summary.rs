//! The summary of a reproduced experiment: `summary.json` (one row per run),
//! `summary.md` (tables shaped like the paper's, with the paper's own numbers beside the
//! measured ones), `bmf.json` (Bencher Metric Format) and the plots. Written from the
//! manifest and the result files only, so `reproduce` and `merge` give the same summary.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result, bail};
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
    /// Runs not started (the time budget ran out, or the reproduction was interrupted).
    #[serde(default)]
    pub not_run: usize,
    /// References that were missing: those runs have no errors.
    pub missing_references: Vec<String>,
    /// References this reproduction rendered, with their photons and wall seconds.
    #[serde(default)]
    pub rendered_references: Vec<String>,
    /// One row per run, in experiment order.
    pub runs: Vec<Row>,
    /// The figures the experiment declares, as drawn (`figures/`).
    #[serde(default)]
    pub figures: Vec<crate::figures::DrawnFigure>,
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
    /// "done", "skipped", "failed" or "not_run".
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
    /// Samples per pixel of the scoring frame that `errors` and `volume_errors` were
    /// computed on; absent when the run has no pixel-averaged errors (a schema-1 result,
    /// whose only errors are the timed frame's, `errors_1spp`).
    #[serde(default)]
    pub score_spp: Option<u32>,
    /// Surface caustic errors of the pixel-averaged scoring frame against the reference.
    pub errors: Option<caustics_metrics::Errors>,
    /// Surface caustic errors of the timed frame (one sample at each pixel centre).
    #[serde(default)]
    pub errors_1spp: Option<caustics_metrics::Errors>,
    /// Volume caustic errors of the pixel-averaged scoring frame.
    #[serde(default)]
    pub volume_errors: Option<caustics_metrics::Errors>,
    /// Volume caustic errors of the timed frame.
    #[serde(default)]
    pub volume_errors_1spp: Option<caustics_metrics::Errors>,
    /// Exposure of the surface LDR-FLIP (`tone_map.exposure_scale`).
    #[serde(default)]
    pub exposure_scale: Option<f32>,
    /// Exposure of the volume LDR-FLIP (`tone_map.volume_exposure_scale`).
    #[serde(default)]
    pub volume_exposure_scale: Option<f32>,
    /// Largest per-pixel fill count (the top of the run's own `fill_heatmap.png`).
    #[serde(default)]
    pub fill_max: Option<u32>,
    /// The reference's own noise (RMS of its standard error).
    pub reference_noise_rms: Option<f64>,
    /// The paper's figures for this run.
    pub paper: Vec<PaperValue>,
    /// GPU ms of every timed pass (`<owner>/<pass>`), for figures' `pass:` measures.
    #[serde(default)]
    pub pass_gpu_ms: BTreeMap<String, Spread>,
    /// Fragment-shader invocations of every pass in the count frame.
    #[serde(default)]
    pub pass_fragments: BTreeMap<String, u64>,
    /// Every pass against the adapter's ceilings (result.json's `roofline`).
    #[serde(default)]
    pub roofline: Option<crate::roofline::RooflineReport>,
    /// The run's CPU wall time by phase (result.json's `wall`).
    #[serde(default)]
    pub wall: Option<crate::result::RunWall>,
    /// An animated run's sequence (its `animation.json`): GPU times above are over its
    /// instants, one timed frame each; errors and the temporal error are here.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sequence: Option<crate::animate::SequenceFigures>,
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

/// The names of [`error_figures`], in its order.
pub const ERROR_FIGURES: [&str; 12] = [
    "flux_ratio",
    "flux_ratio_image",
    "rel_mse",
    "rel_mse_after_flux",
    "hdr_flip",
    "hdr_flip_after_flux",
    "flip",
    "rmse",
    "best_scale",
    "rmse_after_best_scale",
    "rel_mse_after_best_scale",
    "flip_after_best_scale",
];

/// The figures of one [`caustics_metrics::Errors`] by measure name ([`ERROR_FIGURES`]),
/// headline first (energy, then shape), the RMSE and best-scale diagnostics last.
pub fn error_figures(e: &caustics_metrics::Errors) -> [(&'static str, Option<f64>); 12] {
    let values = [
        e.flux_ratio,
        e.flux_ratio_image,
        Some(e.rel_mse),
        e.rel_mse_after_flux,
        e.hdr_flip,
        e.hdr_flip_after_flux,
        Some(e.flip),
        Some(e.rmse),
        Some(e.best_scale),
        Some(e.rmse_after_best_scale),
        e.rel_mse_after_best_scale,
        e.flip_after_best_scale,
    ];
    std::array::from_fn(|i| (ERROR_FIGURES[i], values[i]))
}

impl Row {
    /// The measured value of a paper measure, if this run has it: the timing and count
    /// measures (`fill_fragments`, `fill_max`: the fill counts), `counter:<name>`, or any
    /// error measure of [`Row::error_measures`].
    pub fn measure(&self, measure: &str) -> Option<f64> {
        match measure {
            "method_gpu_ms" => self.method_gpu_ms.map(|s| s.median),
            "frame_gpu_ms" => self.frame_gpu_ms.map(|s| s.median),
            "fps" => self.frame_gpu_ms.map(|s| 1000.0 / s.median),
            "fragments" => self.fragments.map(|f| f as f64),
            "fill_fragments" => self.fill_total.map(|f| f as f64),
            "fill_max" => self.fill_max.map(f64::from),
            m => match m.strip_prefix("counter:") {
                Some(c) => self.counters.get(c).map(|&v| v as f64),
                None => self
                    .error_measures()
                    .into_iter()
                    .find(|(k, _)| k == m)
                    .map(|(_, v)| v)
                    .or_else(|| {
                        let s = self.sequence.as_ref()?;
                        s.measures()
                            .into_iter()
                            .find(|(k, _)| *k == m)
                            .map(|(_, v)| v)
                    }),
            },
        }
    }

    /// Every error figure of the run by its `bmf.json` measure name:
    /// `[volume_]<figure>` of the pixel-averaged scoring frame ([`error_figures`] names),
    /// `[volume_]<figure>_1spp` of the timed frame, and the camera-aliasing share
    /// `[volume_]rel_mse_aliasing` = `rel_mse_1spp − rel_mse` (likewise
    /// `hdr_flip_aliasing`) where both exist. A schema-1 run has only the `_1spp` ones.
    pub fn error_measures(&self) -> Vec<(String, f64)> {
        let mut out = Vec::new();
        for (prefix, avg, one) in [
            ("", &self.errors, &self.errors_1spp),
            ("volume_", &self.volume_errors, &self.volume_errors_1spp),
        ] {
            for (suffix, e) in [("", avg), ("_1spp", one)] {
                let Some(e) = e else { continue };
                for (name, v) in error_figures(e) {
                    if let Some(v) = v.filter(|v| v.is_finite()) {
                        out.push((format!("{prefix}{name}{suffix}"), v));
                    }
                }
            }
            if let (Some(a), Some(o)) = (avg, one) {
                out.push((format!("{prefix}rel_mse_aliasing"), o.rel_mse - a.rel_mse));
                if let (Some(x), Some(y)) = (a.hdr_flip, o.hdr_flip) {
                    out.push((format!("{prefix}hdr_flip_aliasing"), y - x));
                }
            }
        }
        out.retain(|(_, v)| v.is_finite());
        out
    }
}

/// Whether a run folder holds an animated sequence (`animation.json`, `caustics run
/// --animate`) rather than a still run (`result.json`).
pub fn is_sequence_dir(dir: &Path) -> bool {
    dir.join(crate::animate::ANIMATION_FILE).is_file() && !dir.join("result.json").is_file()
}

/// Reads `<dir>/animation.json`.
pub fn read_sequence(dir: &Path) -> Result<crate::animate::AnimationResult> {
    crate::animate::load(&dir.join(crate::animate::ANIMATION_FILE))
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
        let (result, sequence) = match &st.dir {
            Some(rel) if is_sequence_dir(&out.join(rel)) => {
                (None, Some(read_sequence(&out.join(rel))?))
            }
            Some(rel) => (Some(read_result(&out.join(rel))?), None),
            None => (None, None),
        };
        let made = result
            .as_ref()
            .map(|r| (&r.machine, &r.build))
            .or(sequence.as_ref().map(|a| (&a.machine, &a.build)));
        if let Some((machine, b)) = made {
            adapters.push(format!(
                "{} ({}), CPU {}",
                machine.adapter, machine.backend, machine.cpu
            ));
            commits.push(format!(
                "{}{}",
                b.commit,
                if b.dirty { "+dirty" } else { "" }
            ));
            profiles.push(b.profile.clone());
        }
        // A sequence's timings are over its instants (one timed frame each).
        let timing = result
            .as_ref()
            .map(|r| &r.timing)
            .or(sequence.as_ref().map(|a| &a.timing));
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
            params: spec.shown_params(),
            width: spec.scene.camera.width,
            height: spec.scene.camera.height,
            status: st.status.clone(),
            reason: st.reason.clone(),
            dir: st.dir.clone(),
            method_gpu_ms: timing.and_then(|t| t.method_gpu_ms.as_ref().map(Spread::from)),
            frame_gpu_ms: timing.and_then(|t| t.frame_gpu_ms.as_ref().map(Spread::from)),
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
            score_spp: result.as_ref().and_then(|r| {
                r.errors.as_ref()?;
                // A schema-2 file always states its scoring frame; without it the
                // errors were scored like the timed frame.
                Some(r.scoring.as_ref().map_or(1, |s| s.samples_per_pixel))
            }),
            errors: result
                .as_ref()
                .and_then(|r| r.errors.as_ref().map(|e| e.surface)),
            errors_1spp: result
                .as_ref()
                .and_then(|r| r.errors_1spp.as_ref().map(|e| e.surface)),
            volume_errors: result
                .as_ref()
                .and_then(|r| r.errors.as_ref().and_then(|e| e.volume)),
            volume_errors_1spp: result
                .as_ref()
                .and_then(|r| r.errors_1spp.as_ref().and_then(|e| e.volume)),
            exposure_scale: result.as_ref().map(|r| r.tone_map.exposure_scale),
            volume_exposure_scale: result
                .as_ref()
                .and_then(|r| r.tone_map.volume_exposure_scale),
            fill_max: result
                .as_ref()
                .and_then(|r| r.fragments.as_ref().map(|f| f.fill_max)),
            reference_noise_rms: result.as_ref().and_then(|r| {
                r.errors
                    .as_ref()
                    .or(r.errors_1spp.as_ref())
                    .and_then(|e| e.reference_noise_rms)
            }),
            paper,
            pass_gpu_ms: timing
                .map(|t| {
                    t.passes
                        .iter()
                        .filter_map(|p| Some((p.name.clone(), Spread::from(p.gpu_ms.as_ref()?))))
                        .collect()
                })
                .unwrap_or_default(),
            pass_fragments: result
                .as_ref()
                .and_then(|r| r.fragments.as_ref())
                .map(|f| {
                    f.passes
                        .iter()
                        .map(|p| (p.name.clone(), p.fragment_shader_invocations))
                        .collect()
                })
                .unwrap_or_default(),
            roofline: result.as_ref().and_then(|r| r.roofline.clone()),
            wall: result.as_ref().and_then(|r| r.wall.clone()),
            sequence: sequence.as_ref().map(crate::animate::SequenceFigures::of),
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
        not_run: count(crate::reproduce::NOT_RUN),
        missing_references: m.missing_references.clone(),
        rendered_references: m.rendered_references.clone(),
        runs: rows,
        figures: Vec::new(),
    })
}

/// Writes `summary.json`, `summary.md`, `bmf.json`, `plots/` and the experiment's
/// declared `figures/` into `out`; `references` is the reference cache the figures'
/// reference columns come from.
pub fn write_all(out: &Path, e: &Experiment, m: &Manifest, references: &Path) -> Result<Summary> {
    let mut s = build(out, e, m)?;
    s.figures = crate::figures::draw(out, e, &s, references)?;
    let plots = crate::plots::write_plots(&out.join("plots"), &s)?;
    caustics_metrics::atomic_write(&out.join("summary.json"), &serde_json::to_vec_pretty(&s)?)?;
    caustics_metrics::atomic_write(&out.join("bmf.json"), &serde_json::to_vec_pretty(&bmf(&s))?)?;
    caustics_metrics::atomic_write(&out.join("summary.md"), markdown(&s, &plots).as_bytes())?;
    Ok(s)
}

/// Reads `summary.json` of an experiment folder. A summary written before rows had
/// `score_spp` held the timed frame's errors under `errors` (schema-1 runs): they are
/// moved to `errors_1spp` (and `volume_errors_1spp`), as [`RunResult::from_json`] does.
pub fn read_summary(dir: &Path) -> Result<Summary> {
    let p = dir.join("summary.json");
    let text = std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
    let mut s: Summary = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a summary.json", p.display()))?;
    // A done run's folder is read by the report and figures: it must be a folder of
    // this experiment that holds a result.json (a summary from elsewhere, or edited,
    // may name one that is not there, or one outside the experiment).
    for (i, r) in s.runs.iter().enumerate() {
        let Some(rel) = r.dir.as_deref().filter(|_| r.status == "done") else {
            continue;
        };
        let inside = Path::new(rel)
            .components()
            .all(|c| matches!(c, std::path::Component::Normal(_)));
        let run = dir.join(rel);
        if !inside || !(run.join("result.json").is_file() || is_sequence_dir(&run)) {
            bail!(
                "{}: runs[{i}].dir: {rel:?} is not a run folder of this experiment (expected a relative path below {} holding a result.json or an animation.json)",
                p.display(),
                dir.display()
            );
        }
    }
    for r in &mut s.runs {
        if r.score_spp.is_none() && r.errors_1spp.is_none() && r.errors.is_some() {
            r.errors_1spp = r.errors.take();
            r.volume_errors_1spp = r.volume_errors.take();
        }
    }
    Ok(s)
}

/// Bencher Metric Format: `{ "<experiment>/<run key>": { "<measure>": {"value": v,
/// "lower_value": lo, "upper_value": hi} } }`. Timings carry their p10/p90 as bounds;
/// counts and errors are single values, the errors named as in [`Row::error_measures`]
/// (the old names `rmse`, `rel_mse`, `flip`, `best_scale`, ... are the pixel-averaged
/// figures of a schema-2 run; a schema-1 run has only their `_1spp` forms).
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
        for (name, v) in r.error_measures() {
            single(name, v);
        }
        for (name, v) in r.sequence.iter().flat_map(|q| q.measures()) {
            single(name.to_owned(), v);
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

/// What a summary's sequence table means.
const SEQUENCE_NOTE: &str = "Each frame a new instant: the scene posed, uploaded and the method created anew (its rebuild timed on the CPU apart; pipelines compiled once per sequence), one untimed frame, then the timed one. GPU ms: median (p10–p90) over the instants. Errors: means over the scored instants (every `reference_every`-th and the one after, pixel-averaged scoring frames against references posed at those instants). **Temporal relRMSE**: the method's frame-to-frame change against the reference's, RMS over the scored pairs (flicker that a still error misses), beside the same frames' still relRMSE; **change ratio** Σ Δm² / Σ Δr² (1: the image changes as much as the caustic). Per frame: `animation.md` in the run's folder.\n\n";

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

/// Seconds of wall time, to a tenth.
fn secs(v: f64) -> String {
    format!("{v:.1}")
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

/// The error columns of a summary table, headline first: energy (flux ratios), shape
/// (relMSE, HDR-FLIP, before and after flux normalization), LDR-FLIP at its stated
/// exposure; then the timed frame's 1-spp figures and the aliasing share; RMSE and the
/// best scale last, as diagnostics.
pub const ERROR_COLUMNS: [&str; 16] = [
    "spp",
    "flux",
    "flux (image)",
    "relMSE",
    "relMSE after flux",
    "HDR-FLIP",
    "HDR-FLIP after flux",
    "LDR-FLIP @exposure",
    "relMSE 1spp",
    "HDR-FLIP 1spp",
    "LDR-FLIP 1spp",
    "aliasing: relMSE 1spp − relMSE",
    "RMSE",
    "RMSE 1spp",
    "s",
    "RMSE·s",
];

/// The cells under [`ERROR_COLUMNS`] of one run's surface or volume errors: `avg` of the
/// scoring frame at `spp` samples per pixel, `one` of the timed frame. A run without
/// pixel-averaged errors (schema 1) shows "–" in every pixel-averaged column and its
/// errors in the 1-spp ones.
pub fn error_cells(
    spp: Option<u32>,
    avg: Option<&caustics_metrics::Errors>,
    one: Option<&caustics_metrics::Errors>,
    exposure: Option<f32>,
) -> [String; 16] {
    let dash = || "–".to_owned();
    let opt = |v: Option<f64>| v.map(num).unwrap_or_else(dash);
    let spp = match (spp, avg, one) {
        (Some(n), Some(_), _) => n.to_string(),
        (_, None, Some(_)) => "1 only (schema 1)".into(),
        _ => dash(),
    };
    let flip = |e: Option<&caustics_metrics::Errors>| match (e, exposure) {
        (Some(e), Some(x)) => {
            let x = format!("{x:.3}");
            format!(
                "{} @{}",
                num(e.flip),
                x.trim_end_matches('0').trim_end_matches('.')
            )
        }
        (Some(e), None) => num(e.flip),
        (None, _) => dash(),
    };
    let aliasing = match (avg, one) {
        (Some(a), Some(o)) => {
            let d = o.rel_mse - a.rel_mse;
            if o.rel_mse > 0.0 {
                format!("{} ({:.0}%)", num(d), 100.0 * d / o.rel_mse)
            } else {
                num(d)
            }
        }
        _ => dash(),
    };
    [
        spp,
        opt(avg.and_then(|e| e.flux_ratio)),
        opt(avg.and_then(|e| e.flux_ratio_image)),
        opt(avg.map(|e| e.rel_mse)),
        opt(avg.and_then(|e| e.rel_mse_after_flux)),
        opt(avg.and_then(|e| e.hdr_flip)),
        opt(avg.and_then(|e| e.hdr_flip_after_flux)),
        flip(avg),
        opt(one.map(|e| e.rel_mse)),
        opt(one.and_then(|e| e.hdr_flip)),
        flip(one),
        aliasing,
        opt(avg.map(|e| e.rmse)),
        opt(one.map(|e| e.rmse)),
        opt(avg.map(|e| e.best_scale)),
        opt(avg.map(|e| e.rmse_after_best_scale)),
    ]
}

/// The method passes of every run against the adapter's ceilings (result.json's
/// `roofline`), one row per run; nothing when no run has one.
fn roofline_section(md: &mut String, s: &Summary) {
    let Some(table) = roofline_rows(s) else {
        return;
    };
    let _ = writeln!(
        md,
        "## Roofline\n\n{}\n\n| scene | method | params | method passes: GPU ms, bound, share of its ceiling |\n|---|---|---|---|",
        table
            .caption
            .replace("caustics ceilings", "`caustics ceilings`")
    );
    for (r, cells) in &table.rows {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} |",
            r.scene,
            r.method,
            params_cell(&r.params),
            cells.join("; ")
        );
    }
    let _ = writeln!(md);
}

/// The roofline of an experiment's runs, for the summary and the HTML report.
pub(crate) struct RooflineRows<'s> {
    /// What the numbers mean, and the ceilings records they were read against.
    pub(crate) caption: String,
    /// Each done run with a roofline and its method passes, each as
    /// `<pass> <ms> ms <bound> <share>%`.
    pub(crate) rows: Vec<(&'s Row, Vec<String>)>,
}

/// The runs of `s` that have a roofline; `None` when none has.
pub(crate) fn roofline_rows(s: &Summary) -> Option<RooflineRows<'_>> {
    let with: Vec<(&Row, &crate::roofline::RooflineReport)> = s
        .runs
        .iter()
        .filter(|r| r.status == "done")
        .filter_map(|r| Some((r, r.roofline.as_ref()?)))
        .collect();
    let (_, first) = with.first()?;
    let mut records: Vec<String> = with
        .iter()
        .map(|(_, rl)| format!("{} (measured by {})", rl.ceilings, rl.ceilings_build))
        .collect();
    records.sort();
    records.dedup();
    let caption = format!(
        "Each method pass against the adapter's own ceilings ({}; caustics ceilings \
         measures them): the pass's counted work at each ceiling, over its median GPU time. \
         Fill: its fragments and triangles at the fill rate of its target (full-screen and \
         small-triangle probes); bandwidth: the attachments it clears; overhead: a pass's \
         fixed cost. The bound is the ceiling that explains the largest share of the time, \
         or shader when none explains half of it (the pass's own instructions, memory \
         accesses and atomics, which pipeline statistics cannot split); the percentage is \
         that largest share.{}",
        records.join(", "),
        first.fill_roof.as_ref().map_or(String::new(), |f| format!(
            " The fill roof of the methods' targets (additive RGBA32F): {:.3} Gfragments/s \
             full-screen, plus {:.1} ns per triangle.",
            f.fragments_per_s / 1e9,
            f.triangle_s * 1e9
        ))
    );
    let rows = with
        .into_iter()
        .map(|(r, rl)| {
            let cells = rl
                .passes
                .iter()
                .filter(|p| crate::run::is_method_pass(&p.name, &r.method))
                .map(|p| {
                    format!(
                        "{} {:.3} ms {} {:.1}%",
                        p.name.split_once('/').map_or(p.name.as_str(), |n| n.1),
                        p.gpu_ms,
                        p.bound.as_str(),
                        100.0 * p.fraction
                    )
                })
                .collect();
            (r, cells)
        })
        .collect();
    Some(RooflineRows { caption, rows })
}

/// The markdown summary: one table per group (cost and surface errors), a volume table
/// beside it when a run of the group has volume errors, skipped and failed runs listed.
pub fn markdown(s: &Summary, plots: &[String]) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# {}\n", s.experiment);
    if !s.description.is_empty() {
        let _ = writeln!(md, "{}\n", s.description);
    }
    let _ = writeln!(
        md,
        "Adapter: {}. Commit: {}. Build: {}. Scale {}. {} runs done, {} skipped, {} failed{}.\n",
        s.adapters.join("; "),
        s.commits.join(", "),
        s.profiles.join(", "),
        s.scale,
        s.done,
        s.skipped,
        s.failed,
        if s.not_run > 0 {
            format!(", {} not run (listed under Not run)", s.not_run)
        } else {
            String::new()
        }
    );
    let _ = writeln!(
        md,
        "GPU ms: median (p10–p90) over the measured frames (one sample per pixel). Errors \
         against the CPU reference, energy before shape: **flux** = method ÷ reference \
         luminance over the reference's caustic region (and over the whole image), 1 = all \
         the light is there; **relMSE** and **HDR-FLIP** (exposure-bracketed, Andersson et \
         al. 2021) as measured and after dividing the image by its whole-image flux ratio \
         (a brightness error vanishes there, a shape error does not); **LDR-FLIP** at the \
         exposure after `@`. These are scored on a frame averaging `spp` stratified \
         sub-pixel camera offsets, the reference's pixel-area footprint; the `1spp` columns \
         are the timed frame's own errors (one sample at each pixel centre), and \
         **aliasing** = relMSE 1spp − relMSE (in % of relMSE 1spp) is the share of the \
         real-time error due to camera aliasing. Runs of schema-1 result files were scored \
         at 1 spp only: their pixel-averaged columns are empty. Diagnostics last: RMSE \
         (linear HDR, set by the brightest pixel), the least-squares brightness factor `s` \
         and RMSE after it (set by the focus); σ_ref is the reference's own noise RMS.\n"
    );
    if !s.missing_references.is_empty() {
        let _ = writeln!(
            md,
            "No reference for {}: those runs have no errors (`caustics reference` renders one).\n",
            s.missing_references.join(", ")
        );
    }
    md.push_str(&crate::figures::markdown(&s.figures));
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
    let head_rule = |md: &mut String, head: &str| {
        let _ = writeln!(md, "{head}");
        let cols = head.matches('|').count() - 1;
        let _ = writeln!(md, "|{}", "---|".repeat(cols));
    };
    for g in groups {
        let done = s.runs.iter().filter(|r| r.group == g && r.status == "done");
        let sequences: Vec<&Row> = done.clone().filter(|r| r.sequence.is_some()).collect();
        let rows: Vec<&Row> = done.filter(|r| r.sequence.is_none()).collect();
        if !sequences.is_empty() {
            let _ = writeln!(md, "## {g}: animated sequences\n");
            md.push_str(SEQUENCE_NOTE);
            head_rule(
                &mut md,
                "| scene | method | params | size | frames | method GPU ms | frame GPU ms | rebuild CPU ms | scored | flux | relMSE | HDR-FLIP | temporal relRMSE | still relRMSE | change ratio |",
            );
            for r in &sequences {
                let Some(q) = &r.sequence else { continue };
                let [frames, errors @ ..] = q.cells();
                let [flux, rest @ ..] = errors;
                let _ = writeln!(
                    md,
                    "| {} | {} | {} | {}×{} | {frames} | {} | {} | {} | {} | {flux} | {} |",
                    r.scene,
                    r.method,
                    params_cell(&r.params),
                    r.width,
                    r.height,
                    ms(&r.method_gpu_ms),
                    ms(&r.frame_gpu_ms),
                    ms(&q.rebuild_ms),
                    q.scored,
                    rest.join(" | "),
                );
            }
            let _ = writeln!(md);
        }
        if rows.is_empty() {
            continue;
        }
        let _ = writeln!(md, "## {g}\n");
        let mut head = format!(
            "| scene | method | params | size | method GPU ms | frame GPU ms | fragments | counters | {} | σ_ref |",
            ERROR_COLUMNS.join(" | ")
        );
        if let Some(p) = paper_col {
            let _ = write!(head, " paper ({}) |", p.hardware);
        }
        head_rule(&mut md, &head);
        for r in &rows {
            let counters = r
                .counters
                .iter()
                .map(|(k, v)| format!("{k} {v}"))
                .collect::<Vec<_>>()
                .join(", ");
            let errs = error_cells(
                r.score_spp,
                r.errors.as_ref(),
                r.errors_1spp.as_ref(),
                r.exposure_scale,
            );
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
                errs.join(" | "),
                r.reference_noise_rms.map(num).unwrap_or("–".into())
            );
            if paper_col.is_some() {
                let _ = write!(md, " {} |", paper_cell(r));
            }
            let _ = writeln!(md);
        }
        let _ = writeln!(md);
        let volume: Vec<&&Row> = rows
            .iter()
            .filter(|r| r.volume_errors.is_some() || r.volume_errors_1spp.is_some())
            .collect();
        if !volume.is_empty() {
            let _ = writeln!(md, "### {g}: volume caustic\n");
            head_rule(
                &mut md,
                &format!(
                    "| scene | method | params | {} |",
                    ERROR_COLUMNS.join(" | ")
                ),
            );
            for r in volume {
                let errs = error_cells(
                    r.score_spp,
                    r.volume_errors.as_ref(),
                    r.volume_errors_1spp.as_ref(),
                    r.volume_exposure_scale,
                );
                let _ = writeln!(
                    md,
                    "| {} | {} | {} | {} |",
                    r.scene,
                    r.method,
                    params_cell(&r.params),
                    errs.join(" | ")
                );
            }
            let _ = writeln!(md);
        }
    }
    if let Some(p) = &s.paper {
        let _ = writeln!(
            md,
            "Paper figures from {}, measured on {} (not comparable in absolute terms: \
             compare ratios between runs).\n",
            p.source, p.hardware
        );
    }
    roofline_section(&mut md, s);
    wall_section(&mut md, s);
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

/// "Where the time went": each method's runs' wall time on this machine by phase, and
/// the slowest runs, so a long reproduction says what to shorten.
fn wall_section(md: &mut String, s: &Summary) {
    let walls: Vec<(&Row, &crate::result::RunWall)> = s
        .runs
        .iter()
        .filter_map(|r| Some((r, r.wall.as_ref()?)))
        .collect();
    let sequences: Vec<(&Row, f64)> = s
        .runs
        .iter()
        .filter_map(|r| Some((r, r.sequence.as_ref()?.wall_s)))
        .collect();
    if walls.is_empty() && sequences.is_empty() && s.rendered_references.is_empty() {
        return;
    }
    let _ = writeln!(md, "## Where the time went\n");
    if !s.rendered_references.is_empty() {
        let _ = writeln!(
            md,
            "References rendered on the CPU first: {}.\n",
            s.rendered_references.join("; ")
        );
    }
    if !sequences.is_empty() {
        let all_s: f64 = sequences.iter().map(|(_, w)| w).sum();
        let _ = writeln!(
            md,
            "CPU wall seconds of the {} sequences ({} s in all; references not included; each \
             instant's rebuild, untimed and timed frames, and the scored instants' scoring \
             frames): {}.\n",
            sequences.len(),
            secs(all_s),
            sequences
                .iter()
                .map(|(r, w)| format!("{} {} {}", r.method, params_cell(&r.params), secs(*w)))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    if walls.is_empty() {
        return;
    }
    let all_s: f64 = walls.iter().map(|(_, w)| w.total_s).sum();
    let _ = writeln!(
        md,
        "CPU wall seconds of the {} runs that recorded it ({} s in all; references not \
         included), by phase: setup (device, upload, pipelines), frames (warm-up, timed, \
         count), the scoring frame's sub-frames, errors (FLIP, HDR-FLIP, SSIM...), \
         writing (images, result).\n\n\
         | method | runs | total s | share | setup | frames | scoring frame | errors | \
         writing | slowest run (s) |\n|---|---|---|---|---|---|---|---|---|---|",
        walls.len(),
        secs(all_s)
    );
    let mut methods: Vec<&str> = walls.iter().map(|(r, _)| r.method.as_str()).collect();
    methods.sort();
    methods.dedup();
    let mut by_total: Vec<(&str, f64)> = methods
        .iter()
        .map(|m| {
            let t = walls
                .iter()
                .filter(|(r, _)| r.method == *m)
                .map(|(_, w)| w.total_s)
                .sum();
            (*m, t)
        })
        .collect();
    by_total.sort_by(|a, b| b.1.total_cmp(&a.1));
    for (m, total) in by_total {
        let mine: Vec<&(&Row, &crate::result::RunWall)> =
            walls.iter().filter(|(r, _)| r.method == m).collect();
        let sum =
            |f: fn(&crate::result::RunWall) -> f64| -> f64 { mine.iter().map(|(_, w)| f(w)).sum() };
        let slowest = mine
            .iter()
            .max_by(|a, b| a.1.total_s.total_cmp(&b.1.total_s))
            .map(|(r, w)| {
                format!(
                    "{} {} ({})",
                    r.scene,
                    params_cell(&r.params),
                    secs(w.total_s)
                )
            })
            .unwrap_or_default();
        let _ = writeln!(
            md,
            "| {m} | {} | {} | {:.0}% | {} | {} | {} | {} | {} | {} |",
            mine.len(),
            secs(total),
            100.0 * total / all_s.max(f64::MIN_POSITIVE),
            secs(sum(|w| w.setup_s)),
            secs(sum(|w| w.frames_s)),
            secs(sum(|w| w.scoring_frame_s)),
            secs(sum(|w| w.errors_s)),
            secs(sum(|w| w.writing_s)),
            slowest
        );
    }
    let _ = writeln!(md);
}

/// A done run with no figures, for tests.
#[cfg(test)]
pub(crate) fn test_row(method: &str) -> Row {
    Row {
        index: 0,
        key: format!("s/{method}/default"),
        group: "g".into(),
        scene: "s".into(),
        method: method.into(),
        params: Default::default(),
        width: 32,
        height: 24,
        status: "done".into(),
        reason: None,
        dir: None,
        method_gpu_ms: None,
        frame_gpu_ms: None,
        fragments: None,
        fill_total: None,
        counters: Default::default(),
        score_spp: None,
        errors: None,
        errors_1spp: None,
        volume_errors: None,
        volume_errors_1spp: None,
        exposure_scale: None,
        volume_exposure_scale: None,
        fill_max: None,
        reference_noise_rms: None,
        paper: vec![],
        pass_gpu_ms: Default::default(),
        pass_fragments: Default::default(),
        roofline: None,
        wall: None,
        sequence: None,
    }
}

/// A summary of `runs`, for tests.
#[cfg(test)]
pub(crate) fn test_summary(runs: Vec<Row>) -> Summary {
    Summary {
        schema_version: 1,
        experiment: "x".into(),
        description: String::new(),
        scale: 1.0,
        adapters: vec![],
        commits: vec![],
        profiles: vec![],
        paper: None,
        done: runs.len(),
        skipped: 0,
        failed: 0,
        not_run: 0,
        missing_references: vec![],
        rendered_references: vec![],
        runs,
        figures: vec![],
    }
}

/// A roofline of one method render pass (`<method>/rasterize`, 100 fragments per
/// primitive, 5% of its fill ceiling) and one base pass, for tests.
#[cfg(test)]
pub(crate) fn test_roofline(method: &str) -> crate::roofline::RooflineReport {
    use caustics_ceilings::roofline::{Bound, CeilingShare, PassRoofline};
    let pass = |name: String, bound, fraction| PassRoofline {
        name,
        gpu_ms: 10.0,
        bound,
        fraction,
        fill: Some(CeilingShare {
            ceiling: "fill_blend_rgba32f_fullscreen".into(),
            work: 1e6,
            model_ms: 10.0 * fraction,
            fraction,
        }),
        bandwidth: None,
        overhead: None,
        fragments_per_s: Some(1e8),
        fragments_per_primitive: Some(100.0),
        invocations_per_s: None,
    };
    crate::roofline::RooflineReport {
        ceilings: "results/ceilings/test.json".into(),
        ceilings_build: "0123456789ab".into(),
        fill_roof: Some(crate::roofline::FillRoof {
            probe: "fill_blend_rgba32f_fullscreen".into(),
            fragments_per_s: 2e9,
            triangle_s: 1e-7,
        }),
        passes: vec![
            pass("base/direct".into(), Bound::Fill, 0.9),
            pass(format!("{method}/rasterize"), Bound::Shader, 0.05),
        ],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_time_section_sums_each_methods_phases_slowest_first() {
        let wall = |total_s: f64| crate::result::RunWall {
            total_s,
            setup_s: 1.0,
            frames_s: 2.0,
            scoring_frame_s: total_s - 5.0,
            errors_s: 1.5,
            writing_s: 0.5,
        };
        let mut a = test_row("beams");
        a.wall = Some(wall(10.0));
        let mut b = test_row("beams");
        b.scene = "t".into();
        b.wall = Some(wall(20.0));
        let mut c = test_row("pinhole");
        c.wall = Some(wall(70.0));
        let older = test_row("splatting");
        let md = markdown(&summary(vec![a, b, c, older]), &[]);
        let section = md
            .split("## Where the time went")
            .nth(1)
            .expect("a time section");
        assert!(
            section.contains("of the 3 runs that recorded it (100.0 s in all"),
            "{section}"
        );
        let pinhole = section
            .find("| pinhole | 1 | 70.0 | 70% |")
            .expect("pinhole row");
        let beams = section
            .find("| beams | 2 | 30.0 | 30% | 2.0 | 4.0 | 20.0 | 3.0 | 1.0 | t defaults (20.0) |")
            .unwrap_or_else(|| panic!("beams row in {section}"));
        assert!(pinhole < beams, "the costliest method first: {section}");
        assert!(!section.contains("splatting"), "{section}");
        // No run with a wall record (older files): no section.
        assert!(!markdown(&summary(vec![test_row("beams")]), &[]).contains("Where the time"));
    }

    #[test]
    fn the_roofline_section_lists_each_runs_method_passes() {
        let mut with = test_row("beams");
        with.roofline = Some(test_roofline("beams"));
        let without = test_row("splatting");
        let mut s = summary(vec![with, without]);
        let md = markdown(&s, &[]);
        let section = md.split("## Roofline").nth(1).expect("a roofline section");
        assert!(section.contains("results/ceilings/test.json (measured by 0123456789ab)"));
        assert!(section.contains("`caustics ceilings`"), "{section}");
        assert!(
            section.contains("| s | beams | defaults | rasterize 10.000 ms shader 5.0% |"),
            "{section}"
        );
        assert!(
            !section.contains("direct"),
            "base passes are not the method's: {section}"
        );
        assert!(
            !section.contains("splatting"),
            "a run without a roofline has no row"
        );
        s.runs.iter_mut().for_each(|r| r.roofline = None);
        assert!(!markdown(&s, &[]).contains("## Roofline"));
    }

    fn errors(rel_mse: f64, hdr_flip: Option<f64>) -> caustics_metrics::Errors {
        caustics_metrics::Errors {
            rmse: 0.1,
            rel_mse,
            psnr_db: 30.0,
            ssim: 0.9,
            flip: 0.02,
            best_scale: 1.5,
            rmse_after_best_scale: 0.08,
            rel_mse_after_best_scale: None,
            flip_after_best_scale: None,
            flux_ratio: hdr_flip.map(|_| 0.97),
            flux_ratio_image: hdr_flip.map(|_| 0.99),
            rel_mse_after_flux: hdr_flip.map(|_| 0.5 * rel_mse),
            hdr_flip,
            hdr_flip_after_flux: hdr_flip.map(|f| 0.9 * f),
            hdr_flip_start_exposure: None,
            hdr_flip_stop_exposure: None,
        }
    }

    fn summary(runs: Vec<Row>) -> Summary {
        test_summary(runs)
    }

    #[test]
    fn schema_2_runs_lead_with_flux_and_shape_and_show_the_aliasing_share() {
        let mut r = test_row("m");
        r.score_spp = Some(16);
        r.errors = Some(errors(0.01, Some(0.05)));
        r.errors_1spp = Some(errors(0.04, Some(0.08)));
        r.volume_errors = Some(errors(0.002, Some(0.03)));
        r.volume_errors_1spp = Some(errors(0.003, Some(0.04)));
        r.exposure_scale = Some(2.0);
        let s = summary(vec![r]);
        let b = bmf(&s);
        let m = &b["x/s/m/default"];
        for (k, v) in [
            ("rel_mse", 0.01),
            ("rel_mse_1spp", 0.04),
            ("hdr_flip", 0.05),
            ("hdr_flip_1spp", 0.08),
            ("flux_ratio", 0.97),
            ("rel_mse_after_flux", 0.005),
            ("volume_rel_mse", 0.002),
            ("volume_hdr_flip", 0.03),
            ("volume_flux_ratio", 0.97),
            ("volume_rel_mse_1spp", 0.003),
            ("rel_mse_aliasing", 0.03),
            ("rmse", 0.1),
            ("best_scale", 1.5),
        ] {
            let got = m[k]["value"].as_f64().unwrap_or(f64::NAN);
            assert!((got - v).abs() < 1e-12, "{k}: {got} != {v} in {m}");
        }
        let md = markdown(&s, &[]);
        let head = md
            .lines()
            .find(|l| l.starts_with("| scene | method | params | size"))
            .expect("head");
        let at = |c: &str| {
            head.find(c)
                .unwrap_or_else(|| panic!("{c} missing: {head}"))
        };
        assert!(
            at("| flux |") < at("| relMSE |") && at("| HDR-FLIP |") < at("| RMSE |"),
            "{head}"
        );
        assert!(md.contains("| 16 | 0.9700 | 0.9900 | 0.0100 | 0.0050 | 0.0500 | 0.0450 | 0.0200 @2 | 0.0400 | 0.0800 | 0.0200 @2 | 0.0300 (75%) |"), "{md}");
        assert!(md.contains("### g: volume caustic"), "{md}");
    }

    #[test]
    fn schema_1_runs_show_1spp_errors_only() {
        let mut r = test_row("m");
        r.errors_1spp = Some(errors(0.04, None));
        let s = summary(vec![r]);
        let b = bmf(&s);
        let m = b["x/s/m/default"].as_object().expect("object");
        assert!(
            m.contains_key("rel_mse_1spp") && m.contains_key("rmse_1spp"),
            "{m:?}"
        );
        assert!(
            !m.contains_key("rel_mse") && !m.contains_key("rmse"),
            "{m:?}"
        );
        let md = markdown(&s, &[]);
        assert!(md.contains("| 1 only (schema 1) | – | – | – |"), "{md}");
        assert!(!md.contains("volume caustic\n"), "{md}");
        assert_eq!(s.runs[0].measure("rel_mse_1spp"), Some(0.04));
        assert_eq!(s.runs[0].measure("rel_mse"), None);
    }
}
