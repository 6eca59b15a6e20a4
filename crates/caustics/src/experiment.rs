//! Experiments as data: `bench/experiments/<name>.json` names scenes × methods ×
//! parameter sweeps × resolution × frames, and [`Experiment::load`] validates it
//! against the scenes on disk and the method registry before anything runs.
//!
//! ```json
//! {
//!   "name": "wand-fig4",
//!   "description": "one line",
//!   "resolution": {"scale": 0.125},
//!   "frames": 3, "warmup": 1,
//!   "reference": {"photons": 20000000},
//!   "runs": [
//!     {"label": "strategies", "scenes": ["ring"], "methods": ["pinhole"],
//!      "params": {"sampling": ["random", "grid"], "samples": [100, 1000]}}
//!   ],
//!   "paper": {"source": "wand-strasser-2003-real-time-caustics.txt",
//!             "hardware": "ATI Radeon 9700 Pro, 512x512",
//!             "figures": [{"scene": "ring", "method": "pinhole", "params": {"samples": 100},
//!                          "measure": "method_gpu_ms", "value": 135}]}
//! }
//! ```
//!
//! A parameter given as an array is swept (the cartesian product over all swept
//! parameters of a group); `params` may also be an array of such objects (their union).
//! `"scenes": "*"` is every built-in scene and `"methods": "*"` every registered method.
//! An optional `figures` list declares what to draw from the runs (image grids, lines,
//! ratios, tables; [`crate::figure_spec`]). An optional `animate` (top level or per
//! group) makes the runs animated sequences ([`Sequence`], `caustics run --animate`).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use caustics_scene::Scene;
use serde::{Deserialize, Serialize};

use crate::registry;

/// A bad experiment file: names the file, the field and what was expected.
#[derive(Debug, thiserror::Error)]
pub enum ExperimentError {
    /// The file could not be read.
    #[error("{file}: {source}")]
    Io {
        /// The experiment file.
        file: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The JSON does not parse or has the wrong shape.
    #[error("{file}: {field}: {message}")]
    Invalid {
        /// The experiment file.
        file: PathBuf,
        /// JSON path of the bad value, e.g. `runs[1].methods[0]`.
        field: String,
        /// What was expected.
        message: String,
    },
    /// No experiment of that name.
    #[error("no experiment {name:?} in {dir}; known: {known}")]
    Unknown {
        /// The name asked for.
        name: String,
        /// Where experiments are looked for.
        dir: PathBuf,
        /// The known names.
        known: String,
    },
    /// `--shard` is not `k/n` with 1 ≤ k ≤ n.
    #[error("--shard {0:?}: expected k/n with 1 <= k <= n, e.g. 2/4")]
    Shard(String),
}

type Result<T> = std::result::Result<T, ExperimentError>;

/// The experiment file as written (before expansion).
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(
    title = "caustics-bench experiment",
    description = "An experiment file of caustics-bench (bench/experiments/README.md): scenes × methods × parameter sweeps at a resolution, frames, a reference budget, the paper's numbers and the figures to draw."
)]
pub struct ExperimentFile {
    /// Must equal the file stem.
    pub name: String,
    /// One line on what it reproduces.
    #[serde(default)]
    pub description: String,
    /// Image size of every run, unless a group overrides it.
    #[serde(default)]
    pub resolution: Resolution,
    /// Measured frames per run.
    #[serde(default = "default_frames")]
    pub frames: u32,
    /// Warm-up frames per run.
    #[serde(default = "default_warmup")]
    pub warmup: u32,
    /// Exposure of the tone-mapped images and of LDR FLIP. Absent: each scene's
    /// reference sets it (its 99th-percentile luminance maps to white).
    #[serde(default)]
    pub exposure: Option<f32>,
    /// N of the N×N sub-pixel offsets of each run's scoring frame (`caustics run
    /// --score-grid`).
    #[serde(default = "default_score_grid")]
    pub score_grid: u32,
    /// `score_grid` per scene name, for the scenes whose foci are narrower than
    /// 1/`score_grid` of a pixel at the experiment's resolution: fixed offsets that far
    /// apart miss such a focus every time and bias its flux low (README, "Scoring at the
    /// reference's footprint"). Each name must be a scene the experiment renders.
    #[serde(default)]
    pub score_grid_scenes: BTreeMap<String, u32>,
    /// Render every run as an animated sequence (`caustics run --animate`) instead of a
    /// still instant, unless a group overrides it: each frame a new instant, errors and
    /// the temporal error at the scored instants (`frames` and `warmup` do not apply).
    #[serde(default)]
    pub animate: Option<Sequence>,
    /// Photon budget of references that `reproduce` renders when the cache has none for
    /// a scene at the experiment's resolution. Absent: such runs are made without errors
    /// and the summary says so.
    #[serde(default)]
    pub reference: Option<ReferenceBudget>,
    /// The run groups.
    pub runs: Vec<RunGroup>,
    /// The paper's own figures, shown beside the measured ones.
    #[serde(default)]
    pub paper: Option<Paper>,
    /// Figures to draw from the runs (image grids, lines, ratios, tables), checked at load
    /// ([`crate::figure_spec`]) and drawn into `figures/` beside the summary.
    #[serde(default)]
    pub figures: Vec<crate::figure_spec::FigureDecl>,
}

fn default_frames() -> u32 {
    10
}
fn default_warmup() -> u32 {
    2
}
fn default_score_grid() -> u32 {
    crate::run::DEFAULT_SCORE_GRID
}

/// Image size: a scale of each scene's camera, or an absolute size.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(untagged, try_from = "RawResolution")]
pub enum Resolution {
    /// Width and height in pixels.
    Absolute {
        /// Pixels.
        width: u32,
        /// Pixels.
        height: u32,
    },
    /// Scale of the scene camera's width and height.
    Scale {
        /// In (0, 4].
        scale: f64,
    },
}

/// What a `resolution` object may hold; exactly one of the two forms.
#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
struct RawResolution {
    width: Option<u32>,
    height: Option<u32>,
    scale: Option<f64>,
}

impl TryFrom<RawResolution> for Resolution {
    type Error = String;
    fn try_from(r: RawResolution) -> std::result::Result<Self, String> {
        match (r.width, r.height, r.scale) {
            (Some(width), Some(height), None) => Ok(Resolution::Absolute { width, height }),
            (None, None, Some(scale)) => Ok(Resolution::Scale { scale }),
            _ => Err("expected {\"scale\": S} or {\"width\": W, \"height\": H}".to_owned()),
        }
    }
}

impl Default for Resolution {
    fn default() -> Self {
        Resolution::Scale { scale: 1.0 }
    }
}

impl Resolution {
    /// The size for a camera of `w`×`h`, times the command line's `extra` scale.
    pub fn apply(&self, w: u32, h: u32, extra: f64) -> (u32, u32) {
        let (fw, fh) = match *self {
            Resolution::Absolute { width, height } => (width as f64, height as f64),
            Resolution::Scale { scale } => (w as f64 * scale, h as f64 * scale),
        };
        (
            ((fw * extra).round() as u32).max(1),
            ((fh * extra).round() as u32).max(1),
        )
    }
}

/// Photons for references rendered on demand.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ReferenceBudget {
    /// Photons per reference.
    pub photons: u64,
    /// RNG seed.
    #[serde(default = "one")]
    pub seed: u64,
    /// Batches for the standard-error image.
    #[serde(default = "sixteen")]
    pub batches: u32,
}

fn one() -> u64 {
    1
}
fn sixteen() -> u32 {
    16
}

/// Scenes × methods × parameter sweep.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RunGroup {
    /// Names the group in tables (default: `group<i>`).
    #[serde(default)]
    pub label: Option<String>,
    /// Built-in scene names, scene files relative to the experiment file, or `"*"`.
    pub scenes: Selection,
    /// Method names or `"*"`.
    pub methods: Selection,
    /// Parameters: an object whose array values are swept, or an array of such objects.
    #[serde(default)]
    pub params: serde_json::Value,
    /// Overrides the experiment's resolution.
    #[serde(default)]
    pub resolution: Option<Resolution>,
    /// Overrides the experiment's frames.
    #[serde(default)]
    pub frames: Option<u32>,
    /// Overrides the experiment's warm-up.
    #[serde(default)]
    pub warmup: Option<u32>,
    /// Overrides the experiment's `animate`: a sequence, or `false` for still runs.
    #[serde(default)]
    pub animate: Option<SequenceOrStill>,
    /// Renders each extended light a method does not take as this many representative
    /// lights (`caustics run --representative-lights`, 1..=64), or each of a list of
    /// counts (swept like a parameter); absent: such a method declines.
    #[serde(default)]
    pub representative_lights: Option<Counts>,
}

/// An animated sequence of an experiment's runs: `caustics run --animate
/// START:END:FPS --reference-every K`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Sequence {
    /// First instant (s).
    pub start_s: f32,
    /// End of the sequence (s), not included.
    pub end_s: f32,
    /// Frames per second.
    pub fps: f32,
    /// Frames between scored instants (each scored with the frame after it, for the
    /// temporal error); absent: a quarter of the sequence.
    #[serde(default)]
    pub reference_every: Option<u32>,
}

impl Sequence {
    /// The sequence's instants.
    pub fn spec(&self) -> crate::animate::AnimateSpec {
        crate::animate::AnimateSpec {
            start_s: self.start_s,
            end_s: self.end_s,
            fps: self.fps,
        }
    }

    /// Frames between scored instants, the default filled in.
    pub fn reference_every(&self) -> u32 {
        self.reference_every
            .unwrap_or_else(|| self.spec().default_reference_every())
    }

    /// The instants whose references the sequence is scored against.
    pub fn scored_instants(&self) -> Vec<f32> {
        self.spec().scored_instants(self.reference_every())
    }

    fn check(&self, at: &str, invalid: &dyn Fn(&str, String) -> ExperimentError) -> Result<()> {
        self.spec()
            .check()
            .map_err(|(field, why)| invalid(&format!("{at}.{field}"), why))?;
        if self.reference_every == Some(0) {
            return Err(invalid(
                &format!("{at}.reference_every"),
                "expected a positive number of frames, got 0".into(),
            ));
        }
        Ok(())
    }
}

/// A group's `animate`: its own sequence, or `false` (still runs in an animated
/// experiment).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum SequenceOrStill {
    /// `false`: still runs.
    Still(bool),
    /// A sequence.
    Sequence(Sequence),
}

/// One count or a list of counts to sweep.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum Counts {
    /// One count.
    One(u32),
    /// Each of these.
    Sweep(Vec<u32>),
}

impl Counts {
    fn values(&self) -> Vec<u32> {
        match self {
            Counts::One(n) => vec![*n],
            Counts::Sweep(v) => v.clone(),
        }
    }
}

/// A list of names, or `"*"` for all.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum Selection {
    /// `"*"`.
    All(String),
    /// Explicit names.
    List(Vec<String>),
}

/// The paper's own numbers.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Paper {
    /// The paper (file in the papers folder or a citation).
    pub source: String,
    /// The hardware and resolution the paper measured on.
    pub hardware: String,
    /// Its figures.
    #[serde(default)]
    pub figures: Vec<PaperFigure>,
}

/// One number from the paper, matched to runs by scene, method and a subset of params.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PaperFigure {
    /// Scene name.
    pub scene: String,
    /// Method name.
    pub method: String,
    /// Parameters the run must have (others are free).
    #[serde(default)]
    pub params: serde_json::Map<String, serde_json::Value>,
    /// One of [`MEASURES`].
    pub measure: String,
    /// The paper's value.
    pub value: f64,
    /// Where in the paper.
    #[serde(default)]
    pub note: String,
}

/// Measures a paper figure can give: GPU ms of the method's passes, of the frame, the
/// frame rate, the method's fragments, or any counter as `counter:<name>`.
pub const MEASURES: [&str; 4] = ["method_gpu_ms", "frame_gpu_ms", "fps", "fragments"];

/// One (scene, method, parameter set) to run.
#[derive(Clone, Debug)]
pub struct RunSpec {
    /// Position in the expanded list (sharding is by this).
    pub index: usize,
    /// The group's label.
    pub group: String,
    /// The scene, loaded, at the run's resolution.
    pub scene: Scene,
    /// Method name.
    pub method: String,
    /// Parameters (a JSON object; the method's defaults fill in the rest).
    pub params: serde_json::Map<String, serde_json::Value>,
    /// `key=value` pairs, sorted, or `default`: the run's folder name (with
    /// `representative_lights=N` when the group sets it).
    pub slug: String,
    /// The group's `representative_lights` (`caustics run --representative-lights`).
    pub representative_lights: Option<u32>,
    /// Measured frames.
    pub frames: u32,
    /// Warm-up frames.
    pub warmup: u32,
    /// N of the scoring frame's N×N sub-pixel offsets: `score_grid`, or the scene's
    /// entry in `score_grid_scenes`.
    pub score_grid: u32,
    /// The sequence, for an animated run (`frames` and `warmup` then do not apply).
    pub animate: Option<Sequence>,
}

impl RunSpec {
    /// `<scene>/<method>/<slug>`: unique within an experiment, stable across shards.
    pub fn key(&self) -> String {
        format!("{}/{}/{}", self.scene.name, self.method, self.slug)
    }

    /// The parameters as summaries and figures show them: the method's, and
    /// `representative_lights` when the group sets it (so a figure can sweep it).
    pub fn shown_params(&self) -> serde_json::Map<String, serde_json::Value> {
        shown_params(&self.params, self.representative_lights)
    }
}

fn shown_params(
    params: &serde_json::Map<String, serde_json::Value>,
    representative_lights: Option<u32>,
) -> serde_json::Map<String, serde_json::Value> {
    let mut shown = params.clone();
    if let Some(n) = representative_lights {
        shown.insert("representative_lights".into(), n.into());
    }
    shown
}

/// A loaded, validated experiment.
#[derive(Clone, Debug)]
pub struct Experiment {
    /// Its file.
    pub file: PathBuf,
    /// As written.
    pub def: ExperimentFile,
    /// FNV-1a of the file bytes, so shards of different versions are not merged.
    pub hash: String,
    /// FNV-1a of what the runs are made from: the file's JSON without `description`,
    /// `paper` and `figures`, which only change what the summary shows. `reproduce
    /// --summary-only` redraws a folder whose file changed only there.
    pub runs_hash: String,
    /// Every run, in file order (groups, then scenes, methods, parameter sets).
    pub runs: Vec<RunSpec>,
    /// The declared figures, checked against `runs`.
    pub figures: Vec<crate::figure_spec::Figure>,
}

/// `bench/experiments` of the workspace ([`caustics_scene::workspace_root`]).
pub fn builtin_dir() -> PathBuf {
    caustics_scene::workspace_root()
        .join("bench")
        .join("experiments")
}

/// Names of the experiment files in `dir`, sorted.
pub fn names_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    names.sort();
    names
}

/// The files `name` stands for: a path to a `.json` file, `all` (every file in `dir`),
/// or a name in `dir`.
pub fn resolve(name: &str, dir: &Path) -> Result<Vec<PathBuf>> {
    let p = Path::new(name);
    if p.extension().is_some_and(|e| e == "json") || p.is_file() {
        return Ok(vec![p.to_path_buf()]);
    }
    let known = names_in(dir);
    if name == "all" {
        if known.is_empty() {
            return Err(ExperimentError::Unknown {
                name: name.into(),
                dir: dir.into(),
                known: "(none)".into(),
            });
        }
        return Ok(known
            .iter()
            .map(|n| dir.join(format!("{n}.json")))
            .collect());
    }
    if known.iter().any(|k| k == name) {
        return Ok(vec![dir.join(format!("{name}.json"))]);
    }
    Err(ExperimentError::Unknown {
        name: name.into(),
        dir: dir.into(),
        known: known.join(", "),
    })
}

/// Parses `k/n`.
pub fn parse_shard(s: &str) -> Result<(usize, usize)> {
    let bad = || ExperimentError::Shard(s.to_owned());
    let (k, n) = s.split_once('/').ok_or_else(bad)?;
    let k: usize = k.trim().parse().map_err(|_| bad())?;
    let n: usize = n.trim().parse().map_err(|_| bad())?;
    if k == 0 || n == 0 || k > n {
        return Err(bad());
    }
    Ok((k, n))
}

/// FNV-1a 64 of `bytes`, 16 hex digits.
pub(crate) fn fnv_hex(bytes: &[u8]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// The folder-name form of a parameter set: sorted `key=value`, `,`-joined.
pub fn slug(params: &serde_json::Map<String, serde_json::Value>) -> String {
    if params.is_empty() {
        return "default".into();
    }
    let s = params
        .iter()
        .map(|(k, v)| {
            let v = match v {
                serde_json::Value::String(s) => s.clone(),
                other => other.to_string(),
            };
            format!("{k}={v}")
        })
        .collect::<Vec<_>>()
        .join(",");
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "._=,-".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

impl Experiment {
    /// Reads and validates an experiment file; `scale` multiplies its resolution
    /// (`reproduce --scale`). Every scene is loaded, every method looked up and every
    /// parameter set validated by its method, so a bad file fails here, before any run.
    pub fn load(file: &Path, scale: f64) -> Result<Experiment> {
        let bytes = std::fs::read(file).map_err(|source| ExperimentError::Io {
            file: file.into(),
            source,
        })?;
        let invalid = |field: &str, message: String| ExperimentError::Invalid {
            file: file.into(),
            field: field.into(),
            message,
        };
        let de = &mut serde_json::Deserializer::from_slice(&bytes);
        let def: ExperimentFile = serde_path_to_error::deserialize(de).map_err(|e| {
            let path = e.path().to_string();
            invalid(
                if path == "." { "(root)" } else { &path },
                e.into_inner().to_string(),
            )
        })?;
        if !(scale.is_finite() && scale > 0.0 && scale <= 4.0) {
            return Err(invalid(
                "--scale",
                format!("expected a number in (0, 4], got {scale}"),
            ));
        }
        let stem = file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        if def.name != stem {
            return Err(invalid(
                "name",
                format!(
                    "expected {stem:?} (the file name), got {:?}: results are filed by it",
                    def.name
                ),
            ));
        }
        check_frames(&def.frames, def.warmup, "", &invalid)?;
        if let Some(e) = def.exposure.filter(|e| !(e.is_finite() && *e > 0.0)) {
            return Err(invalid(
                "exposure",
                format!("expected a positive number, got {e}"),
            ));
        }
        let max_grid = caustics_gpu::scoring::MAX_SCORE_GRID;
        let grids = std::iter::once(("score_grid".to_owned(), def.score_grid)).chain(
            def.score_grid_scenes
                .iter()
                .map(|(scene, g)| (format!("score_grid_scenes.{scene}"), *g)),
        );
        for (field, grid) in grids {
            if grid == 0 || grid > max_grid {
                return Err(invalid(
                    &field,
                    format!("expected an integer in 1..={max_grid}, got {grid}"),
                ));
            }
        }
        check_resolution(&def.resolution, "resolution", &invalid)?;
        if let Some(a) = &def.animate {
            a.check("animate", &invalid)?;
        }
        if let Some(r) = &def.reference {
            if r.photons == 0 {
                return Err(invalid(
                    "reference.photons",
                    "expected a positive integer".into(),
                ));
            }
            let max = caustics_reference::MAX_BATCHES;
            if !(2..=max).contains(&r.batches) {
                return Err(invalid(
                    "reference.batches",
                    format!("expected an integer in 2..={max}, got {}", r.batches),
                ));
            }
        }
        if def.runs.is_empty() {
            return Err(invalid("runs", "expected at least one run group".into()));
        }
        let base = file.parent().unwrap_or(Path::new("."));
        let mut runs: Vec<RunSpec> = Vec::new();
        let mut seen: BTreeMap<String, usize> = BTreeMap::new();
        for (g, group) in def.runs.iter().enumerate() {
            let at = |f: &str| format!("runs[{g}].{f}");
            let resolution = group.resolution.unwrap_or(def.resolution);
            check_resolution(&resolution, &at("resolution"), &invalid)?;
            let frames = group.frames.unwrap_or(def.frames);
            let warmup = group.warmup.unwrap_or(def.warmup);
            check_frames(&frames, warmup, &at(""), &invalid)?;
            let max_lights = caustics_scene::MAX_REPRESENTATIVE_LIGHTS;
            let light_counts: Vec<Option<u32>> = match &group.representative_lights {
                None => vec![None],
                Some(counts) => {
                    let values = counts.values();
                    if let Some(n) = values.iter().find(|n| !(1..=max_lights).contains(*n)) {
                        return Err(invalid(
                            &at("representative_lights"),
                            format!("expected integers in 1..={max_lights}, got {n}"),
                        ));
                    }
                    if values.is_empty() {
                        return Err(invalid(
                            &at("representative_lights"),
                            "expected a count or a non-empty list of counts".into(),
                        ));
                    }
                    values.into_iter().map(Some).collect()
                }
            };
            let animate = match group.animate {
                None => def.animate,
                Some(SequenceOrStill::Still(false)) => None,
                Some(SequenceOrStill::Still(true)) => {
                    return Err(invalid(
                        &at("animate"),
                        "expected a sequence {\"start_s\", \"end_s\", \"fps\"} or false, got true"
                            .into(),
                    ));
                }
                Some(SequenceOrStill::Sequence(s)) => {
                    s.check(&at("animate"), &invalid)?;
                    Some(s)
                }
            };
            let label = group.label.clone().unwrap_or_else(|| format!("group{g}"));
            let scenes = select_scenes(&group.scenes, base, &at("scenes"), &invalid)?;
            let methods = select_methods(&group.methods, &at("methods"), &invalid)?;
            let param_sets = expand_params(&group.params, &at("params"), &invalid)?;
            for (scene_field, mut scene) in scenes {
                let (w, h) = resolution.apply(scene.camera.width, scene.camera.height, scale);
                if w > 8192 || h > 8192 {
                    return Err(invalid(
                        &scene_field,
                        format!("resolution {w}x{h} is over 8192 pixels a side"),
                    ));
                }
                scene.camera.width = w;
                scene.camera.height = h;
                let score_grid = def
                    .score_grid_scenes
                    .get(&scene.name)
                    .copied()
                    .unwrap_or(def.score_grid);
                if runs.len() + methods.len() * param_sets.len() * light_counts.len() > MAX_RUNS {
                    return Err(invalid(
                        &at("params"),
                        format!("the experiment makes more than {MAX_RUNS} runs; split it"),
                    ));
                }
                for method in &methods {
                    let info = registry::find(method)
                        .map_err(|e| invalid(&at("methods"), crate::error_text(&e)))?;
                    for (params, lights) in param_sets
                        .iter()
                        .flat_map(|p| light_counts.iter().map(move |n| (p, *n)))
                    {
                        let value = serde_json::Value::Object(params.clone());
                        registry::parse_params(&info, &value).map_err(|e| {
                            invalid(
                                &at("params"),
                                format!("{} (in the parameter set {value})", crate::error_text(&e)),
                            )
                        })?;
                        let spec = RunSpec {
                            index: runs.len(),
                            group: label.clone(),
                            scene: scene.clone(),
                            method: method.clone(),
                            slug: slug(&shown_params(params, lights)),
                            params: params.clone(),
                            representative_lights: lights,
                            frames,
                            warmup,
                            score_grid,
                            animate,
                        };
                        if let Some(first) = seen.insert(spec.key(), g) {
                            return Err(invalid(
                                &at("params"),
                                format!(
                                    "run {} is already made by runs[{first}]: each (scene, method, parameters) once",
                                    spec.key()
                                ),
                            ));
                        }
                        runs.push(spec);
                    }
                }
            }
        }
        if let Some(scene) = def
            .score_grid_scenes
            .keys()
            .find(|name| !runs.iter().any(|r| &r.scene.name == *name))
        {
            return Err(invalid(
                &format!("score_grid_scenes.{scene}"),
                "no run of the experiment renders this scene".into(),
            ));
        }
        if let Some(paper) = &def.paper {
            for (i, f) in paper.figures.iter().enumerate() {
                let at = format!("paper.figures[{i}]");
                if !(MEASURES.contains(&f.measure.as_str()) || f.measure.starts_with("counter:")) {
                    return Err(invalid(
                        &format!("{at}.measure"),
                        format!(
                            "expected one of {} or counter:<name>, got {:?}",
                            MEASURES.join(", "),
                            f.measure
                        ),
                    ));
                }
                if !runs.iter().any(|r| figure_matches(f, r)) {
                    return Err(invalid(
                        &at,
                        format!(
                            "matches no run (scene {:?}, method {:?}, params {})",
                            f.scene,
                            f.method,
                            serde_json::Value::Object(f.params.clone())
                        ),
                    ));
                }
            }
        }
        let grid = def.figures.iter().position(|f| f.kind == "image_grid");
        if let Some(i) = grid.filter(|_| runs.iter().any(|r| r.animate.is_some())) {
            return Err(invalid(
                &format!("figures[{i}].kind"),
                "an image grid draws still runs' images, and this experiment's runs include animated sequences (their scored instants' images are in each sequence's folder); use a line, ratio or table".into(),
            ));
        }
        let figures = crate::figure_spec::parse(&def.figures, &runs, &invalid)?;
        let mut what_runs: serde_json::Value =
            serde_json::from_slice(&bytes).map_err(|e| invalid("(root)", e.to_string()))?;
        if let Some(o) = what_runs.as_object_mut() {
            for presentation in ["description", "paper", "figures"] {
                o.remove(presentation);
            }
        }
        Ok(Experiment {
            file: file.into(),
            hash: fnv_hex(&bytes),
            runs_hash: fnv_hex(what_runs.to_string().as_bytes()),
            def,
            runs,
            figures,
        })
    }

    /// The runs of shard `k` of `n` (1-based): every n-th run starting at the k-th, so
    /// that each shard gets a share of every group.
    pub fn shard(&self, k: usize, n: usize) -> Vec<&RunSpec> {
        self.runs.iter().filter(|r| r.index % n == k - 1).collect()
    }
}

/// The order in which to make `runs`: scene by scene, in the order the list first
/// names each scene, and each scene's runs in the list's (the experiment's) order. Ratio and
/// table figures set runs of different groups on the same scene side by side, and a
/// software adapter's times drift by tens of percent over minutes on a shared host:
/// run group by group, liktor-table1's two water_pool runs were made about seven
/// minutes apart, and the passes both methods share (light G-buffer, impostors,
/// surface filter) took 1.37-1.54x as long in the later one. Back to back, both see
/// the same machine. Indices, folders and the manifest's order stay the experiment's.
pub fn scene_major<'a>(runs: &[&'a RunSpec]) -> Vec<&'a RunSpec> {
    let mut first_seen: Vec<&str> = Vec::new();
    for r in runs {
        if !first_seen.contains(&r.scene.name.as_str()) {
            first_seen.push(&r.scene.name);
        }
    }
    let mut ordered = runs.to_vec();
    // Stable: within a scene the experiment's order stays.
    ordered.sort_by_key(|r| first_seen.iter().position(|s| *s == r.scene.name));
    ordered
}

/// Whether a paper figure refers to this run.
pub fn figure_matches(f: &PaperFigure, r: &RunSpec) -> bool {
    f.scene == r.scene.name
        && f.method == r.method
        && f.params.iter().all(|(k, v)| r.params.get(k) == Some(v))
}

fn check_frames(
    frames: &u32,
    warmup: u32,
    at: &str,
    invalid: &dyn Fn(&str, String) -> ExperimentError,
) -> Result<()> {
    if *frames == 0 || *frames > 10_000 {
        return Err(invalid(
            &format!("{at}frames"),
            format!("expected an integer in 1..=10000, got {frames}"),
        ));
    }
    if warmup > 10_000 {
        return Err(invalid(
            &format!("{at}warmup"),
            format!("expected an integer in 0..=10000, got {warmup}"),
        ));
    }
    Ok(())
}

fn check_resolution(
    r: &Resolution,
    at: &str,
    invalid: &dyn Fn(&str, String) -> ExperimentError,
) -> Result<()> {
    match *r {
        Resolution::Scale { scale } if !(scale.is_finite() && scale > 0.0 && scale <= 4.0) => {
            Err(invalid(
                at,
                format!("scale: expected a number in (0, 4], got {scale}"),
            ))
        }
        Resolution::Absolute { width, height }
            if !(1..=8192).contains(&width) || !(1..=8192).contains(&height) =>
        {
            Err(invalid(
                at,
                format!("expected width and height in 1..=8192, got {width}x{height}"),
            ))
        }
        _ => Ok(()),
    }
}

fn star(s: &str, at: &str, invalid: &dyn Fn(&str, String) -> ExperimentError) -> Result<()> {
    if s == "*" {
        Ok(())
    } else {
        Err(invalid(
            at,
            format!("expected \"*\" or a list of names, got {s:?}"),
        ))
    }
}

fn select_scenes(
    sel: &Selection,
    base: &Path,
    at: &str,
    invalid: &dyn Fn(&str, String) -> ExperimentError,
) -> Result<Vec<(String, Scene)>> {
    let names: Vec<(String, String)> = match sel {
        Selection::All(s) => {
            star(s, at, invalid)?;
            caustics_scene::builtin_names()
                .into_iter()
                .map(|n| (at.to_owned(), n))
                .collect()
        }
        Selection::List(l) if l.is_empty() => {
            return Err(invalid(at, "expected at least one scene".into()));
        }
        Selection::List(l) => l
            .iter()
            .enumerate()
            .map(|(i, n)| (format!("{at}[{i}]"), n.clone()))
            .collect(),
    };
    let mut out = Vec::new();
    let mut seen = BTreeSet::new();
    for (field, name) in names {
        let path = if name.ends_with(".json") {
            base.join(&name)
        } else {
            caustics_scene::resolve(&name).map_err(|e| invalid(&field, e.to_string()))?
        };
        let scene = Scene::load(&path).map_err(|e| invalid(&field, e.to_string()))?;
        if !seen.insert(scene.name.clone()) {
            return Err(invalid(
                &field,
                format!("scene {:?} is listed twice", scene.name),
            ));
        }
        out.push((field, scene));
    }
    Ok(out)
}

fn select_methods(
    sel: &Selection,
    at: &str,
    invalid: &dyn Fn(&str, String) -> ExperimentError,
) -> Result<Vec<String>> {
    let names: Vec<String> = match sel {
        Selection::All(s) => {
            star(s, at, invalid)?;
            return Ok(registry::methods()
                .iter()
                .map(|m| m.name.to_owned())
                .collect());
        }
        Selection::List(l) if l.is_empty() => {
            return Err(invalid(at, "expected at least one method".into()));
        }
        Selection::List(l) => l.clone(),
    };
    let mut seen = BTreeSet::new();
    for (i, n) in names.iter().enumerate() {
        registry::find(n).map_err(|e| invalid(&format!("{at}[{i}]"), crate::error_text(&e)))?;
        if !seen.insert(n) {
            return Err(invalid(
                &format!("{at}[{i}]"),
                format!("method {n:?} is listed twice"),
            ));
        }
    }
    Ok(names)
}

type Params = serde_json::Map<String, serde_json::Value>;

/// Most runs an experiment may expand to (parameter sets of a group, and runs in all).
pub const MAX_RUNS: usize = 10_000;

/// The parameter sets of a group: the cartesian product of each object's swept values.
fn expand_params(
    v: &serde_json::Value,
    at: &str,
    invalid: &dyn Fn(&str, String) -> ExperimentError,
) -> Result<Vec<Params>> {
    use serde_json::Value;
    let objects: Vec<(String, &Params)> = match v {
        Value::Null => return Ok(vec![Params::new()]),
        Value::Object(o) => vec![(at.to_owned(), o)],
        Value::Array(a) if !a.is_empty() => a
            .iter()
            .enumerate()
            .map(|(i, x)| match x {
                Value::Object(o) => Ok((format!("{at}[{i}]"), o)),
                other => Err(invalid(
                    &format!("{at}[{i}]"),
                    format!("expected an object of parameters, got {other}"),
                )),
            })
            .collect::<Result<_>>()?,
        other => {
            return Err(invalid(
                at,
                format!(
                    "expected an object of parameters (array values are swept) or a non-empty array of such objects, got {other}"
                ),
            ));
        }
    };
    let mut out = Vec::new();
    for (field, obj) in objects {
        // Bounded before expanding: a sweep is a product of its arrays' lengths.
        let size = obj.values().try_fold(1usize, |n, v| match v {
            Value::Array(a) => n.checked_mul(a.len().max(1)),
            _ => Some(n),
        });
        if size.is_none_or(|n| n + out.len() > MAX_RUNS) {
            return Err(invalid(
                &field,
                format!(
                    "the sweep makes more than {MAX_RUNS} parameter sets (the product of its arrays' lengths); split the experiment"
                ),
            ));
        }
        let mut sets = vec![Params::new()];
        for (k, v) in obj {
            let values: Vec<Value> = match v {
                Value::Array(a) if a.is_empty() => {
                    return Err(invalid(
                        &format!("{field}.{k}"),
                        "expected at least one value to sweep".into(),
                    ));
                }
                Value::Array(a) => a.clone(),
                other => vec![other.clone()],
            };
            sets = sets
                .into_iter()
                .flat_map(|s| {
                    values.iter().map(move |v| {
                        let mut s = s.clone();
                        s.insert(k.clone(), v.clone());
                        s
                    })
                })
                .collect();
        }
        out.extend(sets);
    }
    Ok(out)
}
