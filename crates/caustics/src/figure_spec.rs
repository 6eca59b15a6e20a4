//! Figures declared in an experiment file (`"figures": [...]`): what a paper's figure
//! draws from the experiment's runs, beside the plots every summary gets. [`parse`]
//! checks each declaration against the expanded runs when the experiment loads, so a
//! figure that names an unknown parameter or matches no run fails before any run;
//! [`crate::figures`] draws them into `<experiment>/figures/`.
//!
//! Four kinds, each generic over runs (picked by `where`, grouped by keys `scene`,
//! `method`, `group` or `param:<name>`):
//!
//! - `image_grid`: one image of each run (`image`: `caustic` by default) in a grid whose
//!   rows and columns are keys, with the reference's caustic as a last column when
//!   `reference` is true;
//! - `line`: measure `y` against measure `x`, one line per `series`, optionally divided
//!   by the smallest `y` of `relative_to`'s runs on the same scene, optionally with a
//!   least-squares `fit`;
//! - `ratio`: `measures` of the runs whose key `of` is `numerator` divided by those of
//!   their partners (everything else equal) whose key is `denominator`;
//! - `table`: chosen `columns` (keys and measures) of the selected runs.
//!
//! Parameters are compared as each run has them: those the experiment gives, the
//! method's defaults for the rest.

use std::collections::BTreeMap;
use std::fmt;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::experiment::{ExperimentError, RunSpec};

type Params = serde_json::Map<String, Value>;
type Result<T> = std::result::Result<T, ExperimentError>;

/// A figure as written in the experiment file. Which fields apply depends on `kind`
/// (see the module documentation); a field of another kind is an error.
#[derive(Clone, Debug, Default, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FigureDecl {
    /// File stem of the figure (`figures/<name>.png`): letters, digits, `_`, `-`.
    pub name: String,
    /// `image_grid`, `line`, `ratio` or `table`.
    pub kind: String,
    /// Heading in the summary and title in the image (default: made from the fields).
    #[serde(default)]
    pub title: Option<String>,
    /// A sentence under the figure: what to read in it.
    #[serde(default)]
    pub caption: Option<String>,
    /// Runs the figure draws: a selector `{"group", "scene", "method", "params"}` or an
    /// array of them (their union); absent, every run.
    #[serde(default, rename = "where")]
    pub select: Option<Value>,
    /// `image_grid`: key(s) of the rows (absent: one row).
    #[serde(default)]
    pub rows: Option<Value>,
    /// `image_grid`: key(s) of the columns (absent: each row's runs in experiment order).
    #[serde(default)]
    pub cols: Option<Value>,
    /// `image_grid`: which image of each run ([`IMAGES`], default `caustic`).
    #[serde(default)]
    pub image: Option<String>,
    /// `image_grid`: add the reference's caustic (surface + volume) as a last column,
    /// tone-mapped at the row's exposure; needs `image` `caustic` and one scene a row.
    #[serde(default)]
    pub reference: Option<bool>,
    /// `line`: the x axis, a measure or `param:<name>` (numeric).
    #[serde(default)]
    pub x: Option<String>,
    /// `line`: the y axis, a measure.
    #[serde(default)]
    pub y: Option<String>,
    /// `line`: key(s) of the lines (default `method`).
    #[serde(default)]
    pub series: Option<Value>,
    /// `line`: divide each `y` by the smallest `y` of these runs on the same scene.
    #[serde(default)]
    pub relative_to: Option<Value>,
    /// `line`: `"linear"`: least squares y = a + b·x over every point, drawn and stated.
    #[serde(default)]
    pub fit: Option<String>,
    /// `ratio`: the key the two sides differ in.
    #[serde(default)]
    pub of: Option<String>,
    /// `ratio`: the key's value on the numerator side.
    #[serde(default)]
    pub numerator: Option<Value>,
    /// `ratio`: the key's value on the denominator side.
    #[serde(default)]
    pub denominator: Option<Value>,
    /// `ratio`: the measures divided.
    #[serde(default)]
    pub measures: Option<Vec<String>>,
    /// `table`: the columns, keys or measures, after scene, method and parameters.
    #[serde(default)]
    pub columns: Option<Vec<String>>,
}

/// The figure kinds.
pub const KINDS: [&str; 4] = ["image_grid", "line", "ratio", "table"];

/// Images of a run an `image_grid` can show (`<name>.png` in the run folder).
pub const IMAGES: [&str; 7] = [
    "caustic",
    "composite",
    "error",
    "error_relative",
    "fill_heatmap",
    "volume_error",
    "volume_error_relative",
];

/// Measures by name besides the error measures ([`error_measure_names`]) and the
/// prefixed forms `counter:<name>`, `pass:<pass>[+<pass>...]` (GPU ms, median, summed),
/// `pass_fragments:<pass>[+...]` (fragment-shader invocations) and `param:<name>`.
pub const MEASURES: [&str; 6] = [
    "method_gpu_ms",
    "frame_gpu_ms",
    "fps",
    "fragments",
    "fill_fragments",
    "fill_max",
];

/// Every error measure name a summary row has ([`crate::summary::Row::error_measures`]):
/// `[volume_]<figure>[_1spp]` and `[volume_](rel_mse|hdr_flip)_aliasing`.
pub fn error_measure_names() -> Vec<String> {
    let mut out = Vec::new();
    for prefix in ["", "volume_"] {
        for suffix in ["", "_1spp"] {
            for f in crate::summary::ERROR_FIGURES {
                out.push(format!("{prefix}{f}{suffix}"));
            }
        }
        out.push(format!("{prefix}rel_mse_aliasing"));
        out.push(format!("{prefix}hdr_flip_aliasing"));
    }
    out
}

/// What groups runs: their scene, method, group label or a parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum Key {
    /// The scene's name.
    Scene,
    /// The method's name.
    Method,
    /// The run group's label.
    Group,
    /// A parameter's value (given, or the method's default).
    Param(String),
}

impl Key {
    fn parse(s: &str) -> std::result::Result<Key, String> {
        match s {
            "scene" => Ok(Key::Scene),
            "method" => Ok(Key::Method),
            "group" => Ok(Key::Group),
            _ => match s.strip_prefix("param:") {
                Some(p) if !p.is_empty() => Ok(Key::Param(p.to_owned())),
                _ => Err(format!(
                    "expected \"scene\", \"method\", \"group\" or \"param:<name>\", got {s:?}"
                )),
            },
        }
    }

    /// The run's value of this key (`None`: its method has no such parameter).
    pub fn value(&self, r: &RunInfo) -> Option<Value> {
        match self {
            Key::Scene => Some(Value::String(r.scene.clone())),
            Key::Method => Some(Value::String(r.method.clone())),
            Key::Group => Some(Value::String(r.group.clone())),
            Key::Param(p) => r.params.get(p).cloned(),
        }
    }

    /// The value as shown: `name=value` for a parameter, the name otherwise.
    pub fn label(&self, r: &RunInfo) -> Option<String> {
        let v = self.value(r)?;
        Some(match self {
            Key::Param(p) => format!("{p}={}", value_text(&v)),
            _ => value_text(&v),
        })
    }
}

impl fmt::Display for Key {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Key::Scene => f.write_str("scene"),
            Key::Method => f.write_str("method"),
            Key::Group => f.write_str("group"),
            Key::Param(p) => write!(f, "param:{p}"),
        }
    }
}

/// A JSON value as text: strings without quotes.
pub fn value_text(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        v => v.to_string(),
    }
}

/// Whether two parameter values are the same (numbers by value: `4` is `4.0`).
pub fn same(a: &Value, b: &Value) -> bool {
    match (a.as_f64(), b.as_f64()) {
        (Some(x), Some(y)) => x == y,
        _ => a == b,
    }
}

/// A number of a run: a named measure, a counter, pass times or fragments, a parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum Measure {
    /// [`MEASURES`] or an error measure ([`error_measure_names`]).
    Named(String),
    /// `counter:<name>`: a method counter.
    Counter(String),
    /// `pass:<a>+<b>`: the summed median GPU ms of those passes of the run's method.
    Pass(Vec<String>),
    /// `pass_fragments:<a>+<b>`: their summed fragment-shader invocations (count frame).
    PassFragments(Vec<String>),
    /// `param:<name>`: a numeric parameter.
    Param(String),
}

impl Measure {
    fn parse(s: &str) -> std::result::Result<Measure, String> {
        let passes = |rest: &str| -> Option<Vec<String>> {
            let v: Vec<String> = rest.split('+').map(|p| p.trim().to_owned()).collect();
            (!v.iter().any(String::is_empty)).then_some(v)
        };
        let parsed = if let Some(c) = s.strip_prefix("counter:") {
            (!c.is_empty()).then(|| Measure::Counter(c.to_owned()))
        } else if let Some(p) = s.strip_prefix("pass:") {
            passes(p).map(Measure::Pass)
        } else if let Some(p) = s.strip_prefix("pass_fragments:") {
            passes(p).map(Measure::PassFragments)
        } else if let Some(p) = s.strip_prefix("param:") {
            (!p.is_empty()).then(|| Measure::Param(p.to_owned()))
        } else if MEASURES.contains(&s) || error_measure_names().iter().any(|n| n == s) {
            Some(Measure::Named(s.to_owned()))
        } else {
            None
        };
        parsed.ok_or_else(|| {
            format!(
                "expected a measure: {}, an error measure ([volume_]flux_ratio, rel_mse, \
                 rel_mse_after_flux, hdr_flip, flip, rmse, ...[_1spp], rel_mse_aliasing), \
                 counter:<name>, pass:<pass>[+<pass>...], pass_fragments:<pass>[+...] or \
                 param:<name>; got {s:?}",
                MEASURES.join(", ")
            )
        })
    }
}

impl fmt::Display for Measure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Measure::Named(n) => f.write_str(n),
            Measure::Counter(c) => write!(f, "counter:{c}"),
            Measure::Pass(p) => write!(f, "pass:{}", p.join("+")),
            Measure::PassFragments(p) => write!(f, "pass_fragments:{}", p.join("+")),
            Measure::Param(p) => write!(f, "param:{p}"),
        }
    }
}

/// A table column: a key (its value) or a measure.
#[derive(Clone, Debug, PartialEq)]
pub enum Column {
    /// `scene`, `method`, `group`, `param:<name>`.
    Key(Key),
    /// Any measure.
    Measure(Measure),
}

impl fmt::Display for Column {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Column::Key(k) => k.fmt(f),
            Column::Measure(m) => m.fmt(f),
        }
    }
}

/// Which runs: every field given must hold (a list: any of its values).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Selector {
    /// Group labels.
    pub group: Option<Vec<String>>,
    /// Scene names.
    pub scene: Option<Vec<String>>,
    /// Method names.
    pub method: Option<Vec<String>>,
    /// Parameters the run has (an array: any of its values).
    pub params: Params,
}

impl Selector {
    /// Whether the run is one of these.
    pub fn matches(&self, r: &RunInfo) -> bool {
        let any = |list: &Option<Vec<String>>, v: &str| {
            list.as_ref().is_none_or(|l| l.iter().any(|x| x == v))
        };
        any(&self.group, &r.group)
            && any(&self.scene, &r.scene)
            && any(&self.method, &r.method)
            && self.params.iter().all(|(k, want)| {
                let Some(have) = r.params.get(k) else {
                    return false;
                };
                match want {
                    Value::Array(a) => same(have, want) || a.iter().any(|w| same(have, w)),
                    w => same(have, w),
                }
            })
    }
}

/// What a figure needs of a run: its names and its parameters as it runs them.
#[derive(Clone, Debug, PartialEq)]
pub struct RunInfo {
    /// Position in the experiment.
    pub index: usize,
    /// Scene name.
    pub scene: String,
    /// Method name.
    pub method: String,
    /// Group label.
    pub group: String,
    /// The given parameters over the method's defaults (and the group's
    /// `representative_lights`, [`RunSpec::shown_params`]).
    pub params: Params,
}

/// The methods' parameter defaults, looked up once per method.
#[derive(Default)]
pub struct Defaults(BTreeMap<String, Params>);

impl Defaults {
    fn of(&mut self, method: &str) -> &Params {
        self.0.entry(method.to_owned()).or_insert_with(|| {
            crate::registry::find(method)
                .map(|m| {
                    (m.params)()
                        .into_iter()
                        .map(|p| (p.name, p.default))
                        .collect()
                })
                .unwrap_or_default()
        })
    }

    /// The run as a figure sees it.
    pub fn run(&mut self, spec: &RunSpec) -> RunInfo {
        let mut params = self.of(&spec.method).clone();
        for (k, v) in &spec.shown_params() {
            params.insert(k.clone(), v.clone());
        }
        RunInfo {
            index: spec.index,
            scene: spec.scene.name.clone(),
            method: spec.method.clone(),
            group: spec.group.clone(),
            params,
        }
    }
}

/// A checked figure.
#[derive(Clone, Debug)]
pub struct Figure {
    /// File stem.
    pub name: String,
    /// Heading and image title.
    pub title: String,
    /// The declaration's caption (may be empty).
    pub caption: String,
    /// Its runs (empty: all).
    pub select: Vec<Selector>,
    /// What it draws.
    pub kind: Kind,
}

/// What a figure draws.
#[derive(Clone, Debug)]
pub enum Kind {
    /// Images in a grid.
    ImageGrid {
        /// Row keys (empty: one row).
        rows: Vec<Key>,
        /// Column keys (empty: each row's runs in order).
        cols: Vec<Key>,
        /// One of [`IMAGES`].
        image: String,
        /// Add the reference as a last column.
        reference: bool,
    },
    /// A measure against another.
    Line {
        /// x axis.
        x: Measure,
        /// y axis.
        y: Measure,
        /// One line per value of these keys.
        series: Vec<Key>,
        /// y ÷ the smallest y of these runs on the same scene.
        relative_to: Option<Vec<Selector>>,
        /// A least-squares line over all points.
        fit: bool,
    },
    /// Measures of one side over the other's.
    Ratio {
        /// The key the sides differ in.
        of: Key,
        /// Its value on the numerator side.
        numerator: Value,
        /// Its value on the denominator side.
        denominator: Value,
        /// The measures divided.
        measures: Vec<Measure>,
    },
    /// Chosen columns of the runs.
    Table {
        /// The columns.
        columns: Vec<Column>,
    },
}

impl Kind {
    /// The kind's name in the file.
    pub fn name(&self) -> &'static str {
        match self {
            Kind::ImageGrid { .. } => "image_grid",
            Kind::Line { .. } => "line",
            Kind::Ratio { .. } => "ratio",
            Kind::Table { .. } => "table",
        }
    }
}

impl Figure {
    /// Whether the figure draws this run.
    pub fn selects(&self, r: &RunInfo) -> bool {
        self.select.is_empty() || self.select.iter().any(|s| s.matches(r))
    }
}

/// The labels of `keys` for a run, joined by spaces (missing parameters left out).
pub fn labels(keys: &[Key], r: &RunInfo) -> String {
    keys.iter()
        .filter_map(|k| k.label(r))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The values a selector lists for a key, in its order (the first selector that lists
/// two or more).
fn listed(key: &Key, select: &[Selector]) -> Option<Vec<Value>> {
    let names = |l: &Option<Vec<String>>| -> Option<Vec<Value>> {
        let l = l.as_ref()?;
        Some(l.iter().map(|n| Value::String(n.clone())).collect())
    };
    select
        .iter()
        .filter_map(|s| match key {
            Key::Scene => names(&s.scene),
            Key::Method => names(&s.method),
            Key::Group => names(&s.group),
            Key::Param(p) => s.params.get(p).and_then(Value::as_array).cloned(),
        })
        .find(|l| l.len() > 1)
}

/// The distinct labels of `keys` over `runs`. Where one key decides: in the order the
/// figure's `where` lists its values, else by value if they are numbers; otherwise in
/// order of first appearance.
pub fn ordered(keys: &[Key], runs: &[&RunInfo], select: &[Selector]) -> Vec<String> {
    let hint = match keys {
        [k] => listed(k, select),
        _ => None,
    };
    let mut seen: Vec<(String, Option<f64>)> = Vec::new();
    for r in runs {
        let label = labels(keys, r);
        if !seen.iter().any(|s| s.0 == label) {
            let number = match (keys, &hint) {
                ([k], Some(h)) => k
                    .value(r)
                    .and_then(|v| h.iter().position(|x| same(x, &v)))
                    .map(|i| i as f64),
                ([k], None) => k.value(r).and_then(|v| v.as_f64()),
                _ => None,
            };
            seen.push((label, number));
        }
    }
    if seen.iter().all(|s| s.1.is_some()) {
        seen.sort_by(|a, b| a.1.unwrap_or(0.0).total_cmp(&b.1.unwrap_or(0.0)));
    }
    seen.into_iter().map(|s| s.0).collect()
}

/// The keys whose values differ among the `runs` that have them (method, scene, then
/// parameters), less `except`: what tells the runs apart (a parameter only some methods
/// have, at one value, does not).
pub fn distinguishing(runs: &[&RunInfo], except: &[Key]) -> Vec<Key> {
    let mut keys = vec![Key::Method, Key::Scene];
    let mut names: Vec<&String> = runs.iter().flat_map(|r| r.params.keys()).collect();
    names.sort();
    names.dedup();
    keys.extend(names.into_iter().map(|n| Key::Param(n.clone())));
    keys.retain(|k| {
        let values: Vec<Value> = runs.iter().filter_map(|r| k.value(r)).collect();
        !except.contains(k) && values.iter().any(|v| !same(v, &values[0]))
    });
    keys
}

/// The cells of an image grid: row and column labels and, per run, its (row, column).
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Row labels (one empty label without row keys).
    pub rows: Vec<String>,
    /// Column labels, or `None` when each row lists its runs in order.
    pub cols: Option<Vec<String>>,
    /// (row, column, position of the run in the given runs, the cell's label).
    pub cells: Vec<(usize, usize, usize, String)>,
}

/// Lays `runs` out by `rows` and `cols` (ordered as [`ordered`] says, by the figure's
/// selectors `select`); two runs in one cell is an error.
pub fn grid(
    rows: &[Key],
    cols: &[Key],
    runs: &[&RunInfo],
    select: &[Selector],
) -> std::result::Result<Grid, String> {
    let row_labels = ordered(rows, runs, select);
    let mut cells = Vec::new();
    if cols.is_empty() {
        // Each cell labelled by what tells it from the other runs of its row.
        let row_of = |r: &RunInfo| {
            row_labels
                .iter()
                .position(|l| *l == labels(rows, r))
                .unwrap_or(0)
        };
        let dist: Vec<Vec<Key>> = (0..row_labels.len())
            .map(|row| {
                let mine: Vec<&RunInfo> =
                    runs.iter().copied().filter(|r| row_of(r) == row).collect();
                distinguishing(&mine, rows)
            })
            .collect();
        let mut next = vec![0usize; row_labels.len()];
        for (i, r) in runs.iter().enumerate() {
            let row = row_of(r);
            cells.push((row, next[row], i, labels(&dist[row], r)));
            next[row] += 1;
        }
        return Ok(Grid {
            rows: row_labels,
            cols: None,
            cells,
        });
    }
    let col_labels = ordered(cols, runs, select);
    let mut taken: BTreeMap<(usize, usize), usize> = BTreeMap::new();
    for (i, r) in runs.iter().enumerate() {
        let row = row_labels
            .iter()
            .position(|l| *l == labels(rows, r))
            .unwrap_or(0);
        let col = col_labels
            .iter()
            .position(|l| *l == labels(cols, r))
            .unwrap_or(0);
        if let Some(&j) = taken.get(&(row, col)) {
            return Err(format!(
                "runs {} and {} fall in one cell (row {:?}, column {:?}): add a key to rows or cols, or narrow `where`",
                runs[j].index, r.index, row_labels[row], col_labels[col]
            ));
        }
        taken.insert((row, col), i);
        cells.push((row, col, i, col_labels[col].clone()));
    }
    Ok(Grid {
        rows: row_labels,
        cols: Some(col_labels),
        cells,
    })
}

/// The (numerator, denominator) pairs of a ratio among `runs` (positions in `runs`):
/// runs whose `of` is `numerator`, each with the one run whose `of` is `denominator` and
/// that agrees with it on everything else (scene, method and every other parameter; for
/// `of` = method, the scene only).
pub fn pairs(
    of: &Key,
    numerator: &Value,
    denominator: &Value,
    runs: &[&RunInfo],
) -> std::result::Result<Vec<(usize, usize)>, String> {
    let rest = |r: &RunInfo, skip: Option<&str>| -> String {
        let p: Params = r
            .params
            .iter()
            .filter(|(k, _)| Some(k.as_str()) != skip)
            .map(|(k, v)| (k.clone(), v.as_f64().map(Value::from).unwrap_or(v.clone())))
            .collect();
        Value::Object(p).to_string()
    };
    let signature = |r: &RunInfo| -> String {
        match of {
            Key::Param(p) => format!("{}|{}|{}", r.scene, r.method, rest(r, Some(p))),
            Key::Method => r.scene.clone(),
            Key::Scene => format!("{}|{}", r.method, rest(r, None)),
            Key::Group => format!("{}|{}", r.scene, r.method),
        }
    };
    let side = |r: &RunInfo, v: &Value| of.value(r).is_some_and(|x| same(&x, v));
    let mut out = Vec::new();
    for (i, n) in runs.iter().enumerate().filter(|(_, r)| side(r, numerator)) {
        let partners: Vec<usize> = runs
            .iter()
            .enumerate()
            .filter(|(_, d)| side(d, denominator) && signature(d) == signature(n))
            .map(|(j, _)| j)
            .collect();
        match partners.as_slice() {
            [] => {}
            [j] => out.push((i, *j)),
            many => {
                return Err(format!(
                    "run {} has {} partners (runs {}): narrow `where` so that one run is left",
                    n.index,
                    many.len(),
                    many.iter()
                        .map(|&j| runs[j].index.to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                ));
            }
        }
    }
    Ok(out)
}

/// Parses and checks the `figures` of an experiment against its expanded runs.
pub fn parse(
    decls: &[FigureDecl],
    specs: &[RunSpec],
    invalid: &dyn Fn(&str, String) -> ExperimentError,
) -> Result<Vec<Figure>> {
    let mut defaults = Defaults::default();
    let runs: Vec<RunInfo> = specs.iter().map(|s| defaults.run(s)).collect();
    let mut out: Vec<Figure> = Vec::new();
    for (i, d) in decls.iter().enumerate() {
        let at = |f: &str| {
            if f.is_empty() {
                format!("figures[{i}]")
            } else {
                format!("figures[{i}].{f}")
            }
        };
        let err = |f: &str, m: String| invalid(&at(f), m);
        let name_ok = !d.name.is_empty()
            && d.name.len() <= 64
            && d.name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
        if !name_ok {
            return Err(err(
                "name",
                format!(
                    "expected 1 to 64 letters, digits, '_' or '-' (the file stem), got {:?}",
                    d.name
                ),
            ));
        }
        if let Some(j) = out.iter().position(|f| f.name == d.name) {
            return Err(err(
                "name",
                format!("{:?} is already the name of figures[{j}]", d.name),
            ));
        }
        let Some(kind) = KINDS.iter().find(|k| **k == d.kind) else {
            return Err(err(
                "kind",
                format!("expected one of {}, got {:?}", KINDS.join(", "), d.kind),
            ));
        };
        check_fields(d, kind, &err)?;
        let select = selectors(
            d.select.as_ref(),
            &runs,
            &at("where"),
            invalid,
            &mut defaults,
        )?;
        let mine: Vec<&RunInfo> = runs
            .iter()
            .filter(|r| select.is_empty() || select.iter().any(|s| s.matches(r)))
            .collect();
        let param_known = |f: &str, p: &str| -> Result<()> {
            if mine.iter().any(|r| r.params.contains_key(p)) {
                return Ok(());
            }
            let mut methods: Vec<&str> = mine.iter().map(|r| r.method.as_str()).collect();
            methods.dedup();
            Err(err(
                f,
                format!(
                    "{p:?} is not a parameter of {} (the figure's runs)",
                    methods.join(", ")
                ),
            ))
        };
        let keys = |f: &str, v: Option<&Value>| -> Result<Vec<Key>> {
            let list: Vec<&Value> = match v {
                None | Some(Value::Null) => vec![],
                Some(Value::Array(a)) => a.iter().collect(),
                Some(v) => vec![v],
            };
            list.into_iter()
                .map(|v| {
                    let s = v.as_str().ok_or_else(|| {
                        err(
                            f,
                            format!("expected a key (\"scene\", \"method\", \"group\", \"param:<name>\") or an array of keys, got {v}"),
                        )
                    })?;
                    let k = Key::parse(s).map_err(|m| err(f, m))?;
                    if let Key::Param(p) = &k {
                        param_known(f, p)?;
                    }
                    Ok(k)
                })
                .collect()
        };
        let measure = |f: &str, s: &str| -> Result<Measure> {
            let m = Measure::parse(s).map_err(|m| err(f, m))?;
            if let Measure::Param(p) = &m {
                param_known(f, p)?;
                if let Some(r) = mine
                    .iter()
                    .find(|r| r.params.get(p).is_none_or(|v| v.as_f64().is_none()))
                {
                    return Err(err(
                        f,
                        format!(
                            "param:{p} is not a number for run {} ({}/{}: {}); narrow `where`",
                            r.index,
                            r.scene,
                            r.method,
                            r.params
                                .get(p)
                                .map_or("no such parameter".into(), value_text)
                        ),
                    ));
                }
            }
            Ok(m)
        };
        let kind = match *kind {
            "image_grid" => {
                let rows = keys("rows", d.rows.as_ref())?;
                let cols = keys("cols", d.cols.as_ref())?;
                let image = d.image.clone().unwrap_or_else(|| "caustic".into());
                if !IMAGES.contains(&image.as_str()) {
                    return Err(err(
                        "image",
                        format!("expected one of {}, got {image:?}", IMAGES.join(", ")),
                    ));
                }
                let reference = d.reference.unwrap_or(false);
                if reference && image != "caustic" {
                    return Err(err(
                        "reference",
                        format!(
                            "the reference is a caustic image: it needs \"image\": \"caustic\", not {image:?}"
                        ),
                    ));
                }
                let g = grid(&rows, &cols, &mine, &select).map_err(|m| err("", m))?;
                if reference {
                    for (row, label) in g.rows.iter().enumerate() {
                        let mut scenes: Vec<&str> = g
                            .cells
                            .iter()
                            .filter(|c| c.0 == row)
                            .map(|c| mine[c.2].scene.as_str())
                            .collect();
                        scenes.sort();
                        scenes.dedup();
                        if scenes.len() > 1 {
                            return Err(err(
                                "reference",
                                format!(
                                    "row {label:?} holds scenes {}: a reference column needs one scene a row (rows by \"scene\", or `where` one scene)",
                                    scenes.join(", ")
                                ),
                            ));
                        }
                    }
                }
                let n_cols = g.cells.iter().map(|c| c.1 + 1).max().unwrap_or(0);
                if g.rows.len() * n_cols > MAX_CELLS {
                    return Err(err(
                        "",
                        format!(
                            "{} rows x {n_cols} columns: at most {MAX_CELLS} images a figure; split it",
                            g.rows.len()
                        ),
                    ));
                }
                Kind::ImageGrid {
                    rows,
                    cols,
                    image,
                    reference,
                }
            }
            "line" => {
                let x = measure(
                    "x",
                    need(d.x.as_deref(), "x", "a measure or param:<name>", &err)?,
                )?;
                let y = measure("y", need(d.y.as_deref(), "y", "a measure", &err)?)?;
                let mut series = keys("series", d.series.as_ref())?;
                if d.series.is_none() {
                    series = vec![Key::Method];
                }
                let relative_to = match &d.relative_to {
                    None => None,
                    Some(v) => {
                        let sel =
                            selectors(Some(v), &runs, &at("relative_to"), invalid, &mut defaults)?;
                        let mut scenes: Vec<&str> = mine.iter().map(|r| r.scene.as_str()).collect();
                        scenes.dedup();
                        for s in scenes {
                            if !runs
                                .iter()
                                .any(|r| r.scene == s && sel.iter().any(|x| x.matches(r)))
                            {
                                return Err(err(
                                    "relative_to",
                                    format!(
                                        "selects no run of scene {s:?}, which the figure draws: each point is divided by a run of its own scene"
                                    ),
                                ));
                            }
                        }
                        Some(sel)
                    }
                };
                let fit = match d.fit.as_deref() {
                    None => false,
                    Some("linear") => true,
                    Some(f) => {
                        return Err(err("fit", format!("expected \"linear\", got {f:?}")));
                    }
                };
                Kind::Line {
                    x,
                    y,
                    series,
                    relative_to,
                    fit,
                }
            }
            "ratio" => {
                let of = Key::parse(need(d.of.as_deref(), "of", "a key", &err)?)
                    .map_err(|m| err("of", m))?;
                if let Key::Param(p) = &of {
                    param_known("of", p)?;
                }
                let mut sides = Vec::new();
                for (f, v) in [("numerator", &d.numerator), ("denominator", &d.denominator)] {
                    let v = v.clone().ok_or_else(|| {
                        err(f, format!("expected the value of {of} on the {f} side"))
                    })?;
                    let mut values: Vec<String> = mine
                        .iter()
                        .filter_map(|r| of.value(r))
                        .map(|v| value_text(&v))
                        .collect();
                    values.sort();
                    values.dedup();
                    if !mine
                        .iter()
                        .any(|r| of.value(r).is_some_and(|x| same(&x, &v)))
                    {
                        return Err(err(
                            f,
                            format!(
                                "no run of the figure has {of} = {v} (values: {})",
                                values.join(", ")
                            ),
                        ));
                    }
                    sides.push(v);
                }
                let measures = d.measures.as_deref().unwrap_or_default();
                if measures.is_empty() {
                    return Err(err(
                        "measures",
                        "expected a non-empty array of measures".into(),
                    ));
                }
                let measures = measures
                    .iter()
                    .enumerate()
                    .map(|(j, m)| measure(&format!("measures[{j}]"), m))
                    .collect::<Result<Vec<_>>>()?;
                let (numerator, denominator) = (sides.remove(0), sides.remove(0));
                let p = pairs(&of, &numerator, &denominator, &mine).map_err(|m| err("", m))?;
                if p.is_empty() {
                    return Err(err(
                        "",
                        format!(
                            "no pair of runs with {of} = {numerator} and {of} = {denominator} agrees on everything else (scene, method, other parameters)"
                        ),
                    ));
                }
                Kind::Ratio {
                    of,
                    numerator,
                    denominator,
                    measures,
                }
            }
            _ => {
                let cols = d.columns.as_deref().unwrap_or_default();
                if cols.is_empty() {
                    return Err(err(
                        "columns",
                        "expected a non-empty array of keys or measures".into(),
                    ));
                }
                let columns = cols
                    .iter()
                    .enumerate()
                    .map(|(j, c)| {
                        let f = format!("columns[{j}]");
                        match Key::parse(c) {
                            Ok(k) => {
                                if let Key::Param(p) = &k {
                                    param_known(&f, p)?;
                                }
                                Ok(Column::Key(k))
                            }
                            Err(_) => measure(&f, c).map(Column::Measure),
                        }
                    })
                    .collect::<Result<Vec<_>>>()?;
                Kind::Table { columns }
            }
        };
        let title = d.title.clone().unwrap_or_else(|| default_title(&kind));
        out.push(Figure {
            name: d.name.clone(),
            title,
            caption: d.caption.clone().unwrap_or_default(),
            select,
            kind,
        });
    }
    Ok(out)
}

/// Most images an image grid may hold.
pub const MAX_CELLS: usize = 400;

fn need<'a>(
    v: Option<&'a str>,
    field: &str,
    what: &str,
    err: &dyn Fn(&str, String) -> ExperimentError,
) -> Result<&'a str> {
    v.ok_or_else(|| err(field, format!("expected {what} (required by this kind)")))
}

fn default_title(k: &Kind) -> String {
    let join = |keys: &[Key]| {
        keys.iter()
            .map(Key::to_string)
            .collect::<Vec<_>>()
            .join(" ")
    };
    match k {
        Kind::ImageGrid {
            rows, cols, image, ..
        } => format!(
            "{image} images{}{}",
            if rows.is_empty() {
                String::new()
            } else {
                format!(", rows {}", join(rows))
            },
            if cols.is_empty() {
                String::new()
            } else {
                format!(", columns {}", join(cols))
            }
        ),
        Kind::Line {
            x, y, relative_to, ..
        } => format!(
            "{y}{} against {x}",
            if relative_to.is_some() {
                " (relative)"
            } else {
                ""
            }
        ),
        Kind::Ratio {
            of,
            numerator,
            denominator,
            ..
        } => format!(
            "{of}: {} / {}",
            value_text(numerator),
            value_text(denominator)
        ),
        Kind::Table { .. } => "table".into(),
    }
}

/// A field of another kind is an error (it would be silently ignored).
fn check_fields(
    d: &FigureDecl,
    kind: &str,
    err: &dyn Fn(&str, String) -> ExperimentError,
) -> Result<()> {
    let fields: [(&str, bool, &str); 13] = [
        ("rows", d.rows.is_some(), "image_grid"),
        ("cols", d.cols.is_some(), "image_grid"),
        ("image", d.image.is_some(), "image_grid"),
        ("reference", d.reference.is_some(), "image_grid"),
        ("x", d.x.is_some(), "line"),
        ("y", d.y.is_some(), "line"),
        ("series", d.series.is_some(), "line"),
        ("relative_to", d.relative_to.is_some(), "line"),
        ("fit", d.fit.is_some(), "line"),
        ("of", d.of.is_some(), "ratio"),
        ("numerator", d.numerator.is_some(), "ratio"),
        ("denominator", d.denominator.is_some(), "ratio"),
        ("measures", d.measures.is_some(), "ratio"),
    ];
    let columns = ("columns", d.columns.is_some(), "table");
    for (f, present, owner) in fields.into_iter().chain([columns]) {
        if present && owner != kind {
            let mine: Vec<&str> = fields
                .iter()
                .chain([&columns])
                .filter(|x| x.2 == kind)
                .map(|x| x.0)
                .collect();
            return Err(err(
                f,
                format!(
                    "not a field of kind {kind:?} (a field of {owner:?}); {kind:?} takes name, kind, title, caption, where, {}",
                    mine.join(", ")
                ),
            ));
        }
    }
    Ok(())
}

/// Parses `where` (or `relative_to`): a selector object or a non-empty array of them,
/// each checked against the runs: known scenes, methods, groups and parameters, and at
/// least one run matched.
fn selectors(
    v: Option<&Value>,
    runs: &[RunInfo],
    at: &str,
    invalid: &dyn Fn(&str, String) -> ExperimentError,
    defaults: &mut Defaults,
) -> Result<Vec<Selector>> {
    let list: Vec<(String, &Value)> = match v {
        None | Some(Value::Null) => return Ok(vec![]),
        Some(o @ Value::Object(_)) => vec![(at.to_owned(), o)],
        Some(Value::Array(a)) if !a.is_empty() => a
            .iter()
            .enumerate()
            .map(|(i, x)| (format!("{at}[{i}]"), x))
            .collect(),
        Some(other) => {
            return Err(invalid(
                at,
                format!(
                    "expected a selector {{\"group\", \"scene\", \"method\", \"params\"}} or a non-empty array of selectors, got {other}"
                ),
            ));
        }
    };
    let mut out = Vec::new();
    for (field, v) in list {
        let Value::Object(o) = v else {
            return Err(invalid(
                &field,
                format!("expected a selector object, got {v}"),
            ));
        };
        let mut s = Selector::default();
        for (k, v) in o {
            let here = format!("{field}.{k}");
            let names = |v: &Value| -> Result<Vec<String>> {
                let list: Vec<&Value> = match v {
                    Value::Array(a) if !a.is_empty() => a.iter().collect(),
                    Value::String(_) => vec![v],
                    _ => vec![],
                };
                if list.is_empty() || list.iter().any(|x| !x.is_string()) {
                    return Err(invalid(
                        &here,
                        format!("expected a name or a non-empty array of names, got {v}"),
                    ));
                }
                Ok(list
                    .iter()
                    .filter_map(|x| x.as_str().map(str::to_owned))
                    .collect())
            };
            let known = |list: &[String], of: fn(&RunInfo) -> &str, what: &str| -> Result<()> {
                let mut have: Vec<&str> = runs.iter().map(of).collect();
                have.sort();
                have.dedup();
                match list.iter().find(|n| !have.contains(&n.as_str())) {
                    Some(n) => Err(invalid(
                        &here,
                        format!(
                            "no run of {what} {n:?}; the experiment's: {}",
                            have.join(", ")
                        ),
                    )),
                    None => Ok(()),
                }
            };
            match k.as_str() {
                "group" => {
                    let l = names(v)?;
                    known(&l, |r| &r.group, "group")?;
                    s.group = Some(l);
                }
                "scene" => {
                    let l = names(v)?;
                    known(&l, |r| &r.scene, "scene")?;
                    s.scene = Some(l);
                }
                "method" => {
                    let l = names(v)?;
                    known(&l, |r| &r.method, "method")?;
                    s.method = Some(l);
                }
                "params" => {
                    let Value::Object(p) = v else {
                        return Err(invalid(
                            &here,
                            format!("expected an object of parameter values, got {v}"),
                        ));
                    };
                    s.params = p.clone();
                }
                _ => {
                    return Err(invalid(
                        &here,
                        "unknown field; a selector takes group, scene, method and params".into(),
                    ));
                }
            }
        }
        // Parameters: each a parameter of a method the selector can pick.
        let mut methods: Vec<String> = match &s.method {
            Some(m) => m.clone(),
            None => runs.iter().map(|r| r.method.clone()).collect(),
        };
        methods.sort();
        methods.dedup();
        for k in s.params.keys() {
            // A method's parameter, or the harness's `representative_lights` of a group.
            let ok = methods.iter().any(|m| defaults.of(m).contains_key(k))
                || runs.iter().any(|r| r.params.contains_key(k));
            if !ok {
                let listed: Vec<String> = methods
                    .iter()
                    .map(|m| {
                        format!(
                            "{m}: {}",
                            defaults
                                .of(m)
                                .keys()
                                .cloned()
                                .collect::<Vec<_>>()
                                .join(", ")
                        )
                    })
                    .collect();
                return Err(invalid(
                    &format!("{field}.params.{k}"),
                    format!(
                        "not a parameter of the selected methods ({})",
                        listed.join("; ")
                    ),
                ));
            }
        }
        if !runs.iter().any(|r| s.matches(r)) {
            return Err(invalid(&field, "matches no run of the experiment".into()));
        }
        out.push(s);
    }
    Ok(out)
}
