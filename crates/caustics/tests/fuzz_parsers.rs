//! Seeded fuzzing of the harness's parsers (issue 18, point 5): experiment files
//! (`bench/experiments/*.json`), `result.json` (the schema-1 fixture and a schema-2 file
//! made here), `manifest.json` and `summary.json`, a few hundred mutations each, read
//! through the functions `reproduce`, `merge`, `compare` and `report` use, under
//! `catch_unwind`. Every read must return (no panic) within a bounded time, and every
//! error must name the file. Then every parameter of every method, from the registry's
//! `ParamSpec`s, with hostile `--param` values through `parse_param_flags` and the
//! method's `parse`: no panic, and the values that should be refused but are
//! accepted are listed.
//!
//! The generator is SplitMix64, the one copy in `crates/scene/tests/common/split_mix.rs`
//! (no new dev-dependency). `cargo test -p caustics --test fuzz_parsers -- --nocapture` prints
//! the counts; `FUZZ_SEED=<n>` picks another seed (default 18), `FUZZ_N=<n>` the
//! mutations per family (default 300).

#[path = "../../scene/tests/common/split_mix.rs"]
mod split_mix;

use std::collections::BTreeMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use caustics::experiment::Experiment;
use caustics::reproduce::{ReproduceArgs, read_manifest, reproduce};
use serde_json::{Value, json};
use split_mix::{SplitMix, env_or};

/// The longest one read may take (debug build, 2 busy cores; reads take milliseconds,
/// an experiment load with every scene a few hundred).
const MAX_READ: Duration = Duration::from_secs(10);

/// Number texts that break parsers: NaN-ish strings, overflow, negatives, huge ints.
const NUMBERS: &[&str] = &[
    "\"NaN\"",
    "\"nan\"",
    "\"inf\"",
    "\"-Infinity\"",
    "NaN",
    "1e308",
    "-1e308",
    "1e999",
    "-1",
    "-0",
    "0",
    "0.5",
    "4294967295",
    "4294967296",
    "18446744073709551615",
    "18446744073709551616",
    "99999999999999999999999",
    "-9223372036854775809",
    "1e-320",
];

/// Values of the wrong type for any field.
fn wrong_type(rng: &mut SplitMix) -> Value {
    rng.pick(&[
        json!(null),
        json!(true),
        json!("x"),
        json!(""),
        json!([]),
        json!([1, 2]),
        json!({}),
        json!({"a": 1}),
        json!(-1),
        json!(1e308),
        json!(u64::MAX),
        json!(0),
    ])
    .clone()
}

/// Byte ranges of the numbers in `d`.
fn number_spans(d: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < d.len() {
        let starts =
            d[i].is_ascii_digit() || (d[i] == b'-' && d.get(i + 1).is_some_and(u8::is_ascii_digit));
        let after_word =
            i > 0 && (d[i - 1].is_ascii_alphanumeric() || matches!(d[i - 1], b'.' | b'_'));
        if starts && !after_word {
            let a = i;
            i += 1;
            while i < d.len()
                && (d[i].is_ascii_digit() || matches!(d[i], b'.' | b'e' | b'E' | b'+' | b'-'))
            {
                i += 1;
            }
            out.push((a, i));
        } else {
            i += 1;
        }
    }
    out
}

/// Every object or array in `v`, as JSON pointers.
fn containers(v: &Value, at: String, out: &mut Vec<String>) {
    match v {
        Value::Object(o) => {
            out.push(at.clone());
            for (k, x) in o {
                containers(
                    x,
                    format!("{at}/{}", k.replace('~', "~0").replace('/', "~1")),
                    out,
                );
            }
        }
        Value::Array(a) => {
            out.push(at.clone());
            for (i, x) in a.iter().enumerate() {
                containers(x, format!("{at}/{i}"), out);
            }
        }
        _ => {}
    }
}

/// JSON text of `v` in which the `dup`-th object (pre-order) holds its first key twice,
/// the second time with `with` (serde_json's `Value` cannot hold a duplicate key).
fn write_dup(v: &Value, dup: usize, with: &Value, n: &mut usize, out: &mut String) {
    match v {
        Value::Object(o) => {
            let me = *n;
            *n += 1;
            out.push('{');
            let mut first = true;
            for (k, x) in o {
                if !first {
                    out.push(',');
                }
                first = false;
                out.push_str(&Value::String(k.clone()).to_string());
                out.push(':');
                write_dup(x, dup, with, n, out);
            }
            if me == dup
                && let Some((k, _)) = o.iter().next()
            {
                out.push(',');
                out.push_str(&Value::String(k.clone()).to_string());
                out.push(':');
                out.push_str(&with.to_string());
            }
            out.push('}');
        }
        Value::Array(a) => {
            out.push('[');
            for (i, x) in a.iter().enumerate() {
                if i > 0 {
                    out.push(',');
                }
                write_dup(x, dup, with, n, out);
            }
            out.push(']');
        }
        other => out.push_str(&other.to_string()),
    }
}

/// One mutation of a JSON document: text-level (bit flips, truncation, numbers replaced)
/// or structural (a key removed, duplicated or renamed, a value of the wrong type).
fn mutate(rng: &mut SplitMix, text: &[u8]) -> (Vec<u8>, &'static str) {
    let Ok(doc) = serde_json::from_slice::<Value>(text) else {
        return (text.to_vec(), "unparsable seed");
    };
    let mut ptrs = Vec::new();
    containers(&doc, String::new(), &mut ptrs);
    let pick_ptr = |rng: &mut SplitMix| rng.pick(&ptrs).clone();
    match rng.below(9) {
        0 => {
            let mut d = text.to_vec();
            for _ in 0..1 + rng.below(4) {
                if !d.is_empty() {
                    let i = rng.below(d.len());
                    d[i] ^= 1 << rng.below(8);
                }
            }
            (d, "bit flips")
        }
        1 => {
            let mut d = text.to_vec();
            d.truncate(rng.below(d.len() + 1));
            (d, "truncation")
        }
        2 | 3 => {
            let mut d = text.to_vec();
            for _ in 0..1 + rng.below(3) {
                let spans = number_spans(&d);
                if spans.is_empty() {
                    break;
                }
                let (a, b) = *rng.pick(&spans);
                d.splice(a..b, rng.pick(NUMBERS).bytes());
            }
            (d, "numbers replaced")
        }
        k => {
            let mut doc = doc;
            let p = pick_ptr(rng);
            let what = match (k, doc.pointer_mut(&p)) {
                (4, Some(Value::Object(o))) if !o.is_empty() => {
                    let key = o
                        .keys()
                        .nth(rng.below(o.len()))
                        .cloned()
                        .unwrap_or_default();
                    o.remove(&key);
                    "key removed"
                }
                (5, Some(Value::Object(o))) if !o.is_empty() => {
                    let key = o
                        .keys()
                        .nth(rng.below(o.len()))
                        .cloned()
                        .unwrap_or_default();
                    if let Some(v) = o.remove(&key) {
                        let new = rng.pick(&["", "x", "Name", "schema-version", "runs "]);
                        o.insert(format!("{key}{new}"), v);
                    }
                    "key renamed"
                }
                (6, _) => {
                    let mut n = 0;
                    let mut c = 0;
                    count_objects(&doc, &mut c);
                    let dup = rng.below(c);
                    let with = wrong_type(rng);
                    let mut out = String::new();
                    write_dup(&doc, dup, &with, &mut n, &mut out);
                    return (out.into_bytes(), "key duplicated");
                }
                (_, Some(Value::Object(o))) if !o.is_empty() => {
                    let key = o
                        .keys()
                        .nth(rng.below(o.len()))
                        .cloned()
                        .unwrap_or_default();
                    o.insert(key, wrong_type(rng));
                    "wrong type"
                }
                (_, Some(Value::Array(a))) if !a.is_empty() => {
                    let i = rng.below(a.len());
                    a[i] = wrong_type(rng);
                    "wrong type in array"
                }
                (_, Some(v)) => {
                    *v = wrong_type(rng);
                    "container replaced"
                }
                (_, None) => "no-op",
            };
            (serde_json::to_vec_pretty(&doc).unwrap_or_default(), what)
        }
    }
}

fn count_objects(v: &Value, n: &mut usize) {
    match v {
        Value::Object(o) => {
            *n += 1;
            o.values().for_each(|x| count_objects(x, n));
        }
        Value::Array(a) => a.iter().for_each(|x| count_objects(x, n)),
        _ => {}
    }
}

#[derive(Default, Debug)]
struct Counts {
    mutations: usize,
    ok: usize,
    err: usize,
    panics: Vec<String>,
    slow: Vec<String>,
    unnamed: Vec<String>,
    by_kind: BTreeMap<&'static str, usize>,
}

impl Counts {
    /// Runs `read` under catch_unwind; its error must contain `needle` (the file).
    fn check(
        &mut self,
        what: &str,
        kind: &'static str,
        needle: &str,
        read: impl FnOnce() -> anyhow::Result<()>,
    ) {
        self.mutations += 1;
        *self.by_kind.entry(kind).or_default() += 1;
        let start = Instant::now();
        let r = catch_unwind(AssertUnwindSafe(read));
        let took = start.elapsed();
        if took > MAX_READ {
            self.slow.push(format!("{what} ({kind}): {took:?}"));
        }
        match r {
            Err(p) => {
                let msg = p
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                self.panics.push(format!("{what} ({kind}): {msg}"));
            }
            Ok(Ok(())) => self.ok += 1,
            Ok(Err(e)) => {
                self.err += 1;
                let e = format!("{e:#}");
                if !e.contains(needle) || e.trim().is_empty() {
                    self.unnamed.push(format!("{what} ({kind}): {e}"));
                }
            }
        }
    }

    fn report(&self, family: &str) {
        eprintln!(
            "{family}: {} mutations, {} Ok, {} Err, {} panics, {} slow, {} errors not naming the file; by kind {:?}",
            self.mutations,
            self.ok,
            self.err,
            self.panics.len(),
            self.slow.len(),
            self.unnamed.len(),
            self.by_kind
        );
        assert!(
            self.panics.is_empty(),
            "{family}: panics: {:#?}",
            self.panics
        );
        assert!(self.slow.is_empty(), "{family}: slow: {:#?}", self.slow);
        assert!(
            self.unnamed.is_empty(),
            "{family}: errors not naming the file: {:#?}",
            &self.unnamed[..self.unnamed.len().min(10)]
        );
    }
}

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .expect("workspace")
}

const TINY: &str = r#"{
  "name": "fuzzseed",
  "description": "one tiny run, to fuzz the files it writes",
  "resolution": {"width": 24, "height": 18},
  "frames": 2, "warmup": 0, "score_grid": 1,
  "reference": {"photons": 100000, "seed": 1, "batches": 4},
  "runs": [{"scenes": ["sphere_on_plane"], "methods": ["wavefront"], "params": {"grid": [32, 48]}},
           {"scenes": ["two_lenses"], "methods": ["pinhole"]}],
  "paper": {"source": "none", "hardware": "none",
            "figures": [{"scene": "sphere_on_plane", "method": "wavefront", "params": {"grid": 32},
                         "measure": "method_gpu_ms", "value": 1}]}
}"#;

#[test]
fn mutated_experiment_result_manifest_and_summary_files_never_panic_and_name_the_file() {
    let seed = env_or("FUZZ_SEED", 18);
    let n = env_or("FUZZ_N", 300) as usize;
    let mut rng = SplitMix(seed);
    let tmp = tempfile::tempdir().expect("tempdir");
    let t = tmp.path();
    let started = Instant::now();

    // Real files to mutate: one reproduction (schema-2 results, manifest, summary).
    let exp = t.join("experiments");
    std::fs::create_dir_all(&exp).expect("mkdir");
    std::fs::write(exp.join("fuzzseed.json"), TINY).expect("write");
    let out = reproduce(&ReproduceArgs {
        name: "fuzzseed".into(),
        scale: 1.0,
        out: t.join("out"),
        shard: None,
        references: t.join("refs"),
        ceilings: t.join("ceilings"),
        no_render_references: false,
        experiments: Some(exp.clone()),
        adapter: None,
        keep_exr: false,
        summary_only: false,
        fresh: false,
        allow_dirty: false,
        time_budget_s: None,
    })
    .expect("seed reproduction");
    assert_eq!(out.failed, 0);
    let folder = t.join("out/fuzzseed");
    let manifest = std::fs::read(folder.join("manifest.json")).expect("manifest");
    let summary = std::fs::read(folder.join("summary.json")).expect("summary");
    let run_rel = read_manifest(&folder).expect("manifest").runs[0]
        .dir
        .clone()
        .expect("done run");
    let result_v2 = std::fs::read(folder.join(&run_rel).join("result.json")).expect("result");
    let result_v1 = std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/result_v1_fog_sphere_static_grid.json"),
    )
    .expect("v1 fixture");
    let e = Experiment::load(&exp.join("fuzzseed.json"), 1.0).expect("experiment");

    // 1. Experiment files: every file of bench/experiments, mutated, loaded as
    //    `reproduce` loads them (the name must stay the file stem to get past it).
    let mut seeds: Vec<(String, Vec<u8>)> =
        std::fs::read_dir(workspace().join("bench/experiments"))
            .expect("bench/experiments")
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|x| x == "json"))
            .map(|p| {
                let stem = p.file_stem().expect("stem").to_string_lossy().into_owned();
                (stem, std::fs::read(&p).expect("read"))
            })
            .collect();
    seeds.sort();
    seeds.push(("fuzzseed".into(), TINY.as_bytes().to_vec()));
    let mut c = Counts::default();
    let edir = t.join("mutated-experiments");
    std::fs::create_dir_all(&edir).expect("mkdir");
    for i in 0..n {
        let (stem, bytes) = rng.pick(&seeds).clone();
        let (m, kind) = mutate(&mut rng, &bytes);
        let f = edir.join(format!("{stem}.json"));
        std::fs::write(&f, &m).expect("write");
        let needle = f.display().to_string();
        c.check(&format!("experiment #{i} {stem}"), kind, &needle, || {
            Experiment::load(&f, 1.0).map(|_| ()).map_err(Into::into)
        });
    }
    c.report("experiment files");
    // Resources a file asks for are bounded before anything is expanded or run.
    let sweep: Vec<u32> = (1..=200).collect();
    for (label, body, needle) in [
        (
            "a sweep of 200^3 parameter sets",
            json!({"name": "big", "runs": [{"scenes": ["ring"], "methods": ["pinhole"],
                   "params": {"samples": sweep, "seed": sweep, "cube_size": sweep}}]}),
            "runs[0].params",
        ),
        (
            "2000 reference batches",
            json!({"name": "big", "reference": {"photons": 1000, "batches": 2000},
                   "runs": [{"scenes": ["ring"], "methods": ["pinhole"]}]}),
            "reference.batches",
        ),
    ] {
        let f = edir.join("big.json");
        std::fs::write(&f, body.to_string()).expect("write");
        let start = Instant::now();
        let e = Experiment::load(&f, 1.0).expect_err(label);
        let e = format!("{e:#}");
        assert!(e.contains("big.json") && e.contains(needle), "{label}: {e}");
        assert!(
            start.elapsed() < Duration::from_secs(2),
            "{label}: {:?}",
            start.elapsed()
        );
    }

    // 2. result.json (schema 1 and 2): as summaries and merge read them, and as
    //    `compare` collects a folder of them.
    let mut c = Counts::default();
    let rdir = t.join("mutated-result/run");
    std::fs::create_dir_all(&rdir).expect("mkdir");
    for i in 0..n {
        let (label, bytes) = if rng.below(2) == 0 {
            ("v1", &result_v1)
        } else {
            ("v2", &result_v2)
        };
        let (m, kind) = mutate(&mut rng, bytes);
        let f = rdir.join("result.json");
        std::fs::write(&f, &m).expect("write");
        let needle = f.display().to_string();
        c.check(&format!("result #{i} {label}"), kind, &needle, || {
            caustics::summary::read_result(&rdir).map(|_| ())
        });
        c.check(
            &format!("result #{i} {label} (compare)"),
            kind,
            &needle,
            || {
                // Compared with itself: no panic on any figure it parsed.
                let root = rdir.parent().expect("parent").to_path_buf();
                caustics::compare::compare(&caustics::compare::CompareArgs {
                    base: root.clone(),
                    new: root,
                    time_threshold: 0.05,
                    alpha: 0.01,
                    count_tolerance: 0.0,
                    error_tolerance: 0.02,
                    noise_k: 0.5,
                    no_timings: false,
                    verbose: true,
                    wide: false,
                    across_adapters: false,
                    html: None,
                })
                .map(|r| {
                    let _ = r.table(true);
                })
            },
        );
    }
    c.report("result.json");

    // 3. manifest.json: read as `merge`, `compare` and `--summary-only` read it, then
    //    the summary built from it (every run it lists must exist in the experiment).
    let mut c = Counts::default();
    let mdir = t.join("mutated-manifest");
    copy_tree(&folder, &mdir);
    for i in 0..n {
        let (m, kind) = mutate(&mut rng, &manifest);
        let f = mdir.join("manifest.json");
        std::fs::write(&f, &m).expect("write");
        let needle = mdir.display().to_string();
        c.check(&format!("manifest #{i}"), kind, &needle, || {
            let man = read_manifest(&mdir)?;
            caustics::summary::build(&mdir, &e, &man)?;
            caustics::compare::collect_results(&mdir)?;
            Ok(())
        });
    }
    c.report("manifest.json");

    // 4. summary.json: read as `report` reads it, and the report written from it.
    let mut c = Counts::default();
    let sdir = t.join("mutated-summary/fuzzseed");
    copy_tree(&folder, &sdir);
    for i in 0..n {
        let (m, kind) = mutate(&mut rng, &summary);
        let f = sdir.join("summary.json");
        std::fs::write(&f, &m).expect("write");
        let needle = f.display().to_string();
        let report = i % 5 == 0;
        c.check(&format!("summary #{i}"), kind, &needle, || {
            caustics::summary::read_summary(&sdir)?;
            if report {
                caustics::report::report(&caustics::report::ReportArgs {
                    dir: sdir.clone(),
                    out: Some(t.join("report")),
                    references: t.join("references"),
                })?;
            }
            Ok(())
        });
    }
    c.report("summary.json");
    eprintln!(
        "seed {seed}, {n} mutations per family, {:.1} s",
        started.elapsed().as_secs_f64()
    );
}

fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("mkdir");
    for e in std::fs::read_dir(from).expect("read").flatten() {
        let p = e.path();
        if p.is_dir() {
            copy_tree(&p, &to.join(e.file_name()));
        } else {
            std::fs::copy(&p, to.join(e.file_name())).expect("copy");
        }
    }
}

/// `--param` values a careful user would not give, by what they are.
const HOSTILE: &[(&str, &str)] = &[
    ("NaN", "NaN"),
    ("nan", "nan"),
    ("inf", "inf"),
    ("-inf", "-inf"),
    ("Infinity", "Infinity"),
    ("negative", "-1"),
    ("negative", "-1000000"),
    ("negative zero", "-0"),
    ("zero", "0"),
    ("zero", "0.0"),
    ("huge", "1e308"),
    ("huge", "1e39"),
    ("huge", "4294967296"),
    ("huge", "18446744073709551615"),
    ("huge", "99999999999999999999999"),
    ("tiny", "1e-300"),
    ("fraction", "0.5"),
    ("wrong type", "true"),
    ("wrong type", "\"x\""),
    ("wrong type", "[1]"),
    ("wrong type", "{}"),
    ("wrong type", "null"),
    ("empty", ""),
];

#[test]
fn hostile_param_values_of_every_method_never_panic() {
    let mut total = 0;
    let mut refused = 0;
    let mut accepted: Vec<String> = Vec::new();
    let mut zeros: Vec<String> = Vec::new();
    let mut unnamed: Vec<String> = Vec::new();
    let mut panics: Vec<String> = Vec::new();
    for m in caustics::registry::methods() {
        let specs = (m.params)();
        // Every numeric parameter states its range (issue 18: refused by name, not
        // accepted and clamped or overflowed later).
        for p in &specs {
            if p.default.is_number() {
                assert!(
                    p.range.is_some(),
                    "{} {}: a numeric parameter without a stated range",
                    m.name,
                    p.name
                );
            }
        }
        // The defaults themselves are accepted.
        let defaults: serde_json::Map<String, Value> = specs
            .iter()
            .map(|p| (p.name.clone(), p.default.clone()))
            .collect();
        (m.parse)(&Value::Object(defaults)).unwrap_or_else(|e| {
            panic!("{}: its own defaults are refused: {e}", m.name);
        });
        // An unknown parameter is refused by name.
        let unknown = caustics::run::parse_param_flags(&["no_such_param=1".into()]).expect("flags");
        let e = (m.parse)(&Value::Object(unknown)).expect_err("unknown parameter accepted");
        assert!(e.to_string().contains("no_such_param"), "{}: {e}", m.name);
        for p in &specs {
            for (kind, v) in HOSTILE {
                total += 1;
                let flag = format!("{}={v}", p.name);
                let r = catch_unwind(AssertUnwindSafe(|| {
                    let params = caustics::run::parse_param_flags(std::slice::from_ref(&flag))?;
                    caustics::registry::parse_params(&m, &Value::Object(params.clone()))?;
                    Ok::<_, anyhow::Error>(params)
                }));
                match r {
                    Err(_) => panics.push(format!("{} --param {flag}", m.name)),
                    Ok(Err(e)) => {
                        refused += 1;
                        let e = format!("{e:#}");
                        assert!(
                            e.contains(&p.name),
                            "{} --param {flag}: {e} does not name it",
                            m.name
                        );
                        // The method's own message (what `caustics run --param` shows).
                        let params = caustics::run::parse_param_flags(std::slice::from_ref(&flag))
                            .expect("flags parsed above");
                        if let Err(raw) = (m.parse)(&Value::Object(params))
                            && !raw.to_string().contains(&p.name)
                        {
                            unnamed.push(format!("{} --param {flag}: {raw}", m.name));
                        }
                    }
                    Ok(Ok(params)) => {
                        if kind.contains("zero") && p.default.as_f64().is_some_and(|d| d != 0.0) {
                            zeros.push(format!("{} {}={v}", m.name, p.name));
                        }
                        if should_refuse(&p.name, &p.default, kind, &params[&p.name]) {
                            accepted.push(format!(
                                "{} --param {flag} ({kind}; default {}) -> {}",
                                m.name, p.default, params[&p.name]
                            ));
                        }
                    }
                }
            }
        }
    }
    eprintln!(
        "params: {total} hostile values, {refused} refused, {} accepted that should not be, {} panics",
        accepted.len(),
        panics.len()
    );
    for a in &accepted {
        eprintln!("  accepted: {a}");
    }
    assert!(
        unnamed.is_empty(),
        "refused by the method without naming the parameter: {unnamed:#?}"
    );
    assert!(
        accepted.is_empty(),
        "values no parameter of that kind should take were accepted: {accepted:#?}"
    );
    // Zero is a valid setting of some parameters (0 = off); listed for review.
    eprintln!("zero accepted (default non-zero): {}", zeros.join(", "));
    assert!(panics.is_empty(), "panics: {panics:#?}");
}

/// Whether a value accepted for a parameter with this default is one no parameter of
/// that kind should take: NaN, infinities, values of another type, and for counts
/// (integer defaults) fractions; negatives; and huge values (but for a u64 seed).
fn should_refuse(name: &str, default: &Value, kind: &str, got: &Value) -> bool {
    let same_type = matches!(
        (default, got),
        (Value::Number(_), Value::Number(_))
            | (Value::Bool(_), Value::Bool(_))
            | (Value::String(_), Value::String(_))
    );
    if !same_type {
        return true;
    }
    match kind {
        "NaN" | "nan" | "inf" | "-inf" | "Infinity" => true,
        // A seed is any u64.
        "huge" => !(name == "seed" && got.is_u64()),
        "negative" => true,
        "fraction" | "tiny" => default.is_u64(),
        _ => false,
    }
}
