//! `caustics ceilings`: the adapter's own ceilings (fill, compute, bandwidth, atomics,
//! overhead), measured by `caustics-ceilings` and kept as one record per adapter under
//! `results/ceilings/`, where the passes of later runs are read against them.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use caustics_ceilings::{ProbeKind, ProbeOptions};
use caustics_gpu::{AdapterChoice, GpuContext};
use serde::{Deserialize, Serialize};

use crate::machine::{Build, Machine};
use crate::stats::Summary;

/// Where `caustics ceilings` writes and `caustics run` reads the records.
pub const DEFAULT_ROOT: &str = "results/ceilings";

/// Version of the ceilings record's layout.
pub const CEILINGS_SCHEMA_VERSION: u32 = 1;

/// `caustics ceilings` flags.
#[derive(clap::Args, Debug, Clone)]
pub struct CeilingsArgs {
    /// Substring of the adapter name (see `caustics run --adapter`).
    #[arg(long)]
    pub adapter: Option<String>,
    /// Fill target width (pixels; a multiple of 4).
    #[arg(long, default_value_t = 1024)]
    pub width: u32,
    /// Fill target height (pixels; a multiple of 4).
    #[arg(long, default_value_t = 768)]
    pub height: u32,
    /// Timed trials per probe and round, after one warm-up.
    #[arg(long, default_value_t = 9)]
    pub trials: u32,
    /// Rounds: every probe is measured this many times, each round on a freshly opened
    /// device, and the ceiling is the median of all rounds' trials. On a shared machine
    /// one round's probes can all land in a slow spell; rounds spread them out, and the
    /// spread of the rounds' medians says how repeatable each ceiling is.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=20))]
    pub rounds: u32,
    /// Each probe is scaled up until one trial takes at least this long (ms).
    #[arg(long, default_value_t = 20.0)]
    pub target_ms: f64,
    /// Size of each bandwidth buffer (MiB; lowered to the device's largest storage binding).
    #[arg(long, default_value_t = 64)]
    pub bandwidth_mib: u64,
    /// Run only the probes whose names contain this (repeatable); the record then holds
    /// only those.
    #[arg(long)]
    pub only: Vec<String>,
    /// Folder of the per-adapter records.
    #[arg(long, default_value = DEFAULT_ROOT)]
    pub out: PathBuf,
}

/// One probe in the record.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CeilingEntry {
    /// Stable probe name, e.g. `fill_blend_rgba32f_fullscreen`.
    pub name: String,
    /// What it measures.
    pub what: String,
    /// Unit of `figure`: a throughput (e.g. `Gfragments/s`, `GB/s`; higher is better)
    /// or a time per item (`us/pass`, `us/draw`; lower is better).
    pub unit: String,
    /// Whether `figure` is a throughput (`throughput`) or a time per item (`per_item`).
    pub kind: String,
    /// The ceiling: the figure of each trial, summarized (the median is the ceiling).
    pub figure: Summary,
    /// `(p90 − p10) / median` of the figure over every trial of every round.
    pub spread: f64,
    /// The median figure of each round (records before rounds existed: none).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub round_medians: Vec<f64>,
    /// `(max − min) / median` of `round_medians`: how repeatable the ceiling is from one
    /// measurement to the next (issue 17 asks for 5 % on a quiet machine).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub round_spread: Option<f64>,
    /// Work of one trial (closed form), in `work_unit`.
    pub work: f64,
    /// Unit of `work`.
    pub work_unit: String,
    /// The same work from pipeline statistics, where the adapter counts it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub counted_work: Option<f64>,
    /// Scale the probe was calibrated to (layers, loop trips, dispatches or draws).
    pub scale: u32,
    /// GPU time of one trial (ms).
    pub trial_ms: Summary,
}

/// The ceilings of one adapter.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CeilingsRecord {
    /// Layout version ([`CEILINGS_SCHEMA_VERSION`]).
    pub schema_version: u32,
    /// The binary that measured them.
    pub build: Build,
    /// The adapter and machine.
    pub machine: Machine,
    /// Fill target size (pixels).
    pub width: u32,
    /// Fill target height (pixels).
    pub height: u32,
    /// Timed trials per probe and round.
    pub trials: u32,
    /// Rounds, each on a freshly opened device (1 in records before rounds existed).
    #[serde(default = "one_round")]
    pub rounds: u32,
    /// Calibration target per trial (ms).
    pub target_ms: f64,
    /// The probes.
    pub ceilings: Vec<CeilingEntry>,
}

impl CeilingsRecord {
    /// The entry named `name`.
    pub fn get(&self, name: &str) -> Option<&CeilingEntry> {
        self.ceilings.iter().find(|c| c.name == name)
    }
}

fn one_round() -> u32 {
    1
}

/// The record file of an adapter: its name and driver version, as a file name; for a
/// software adapter (lavapipe: `device_type` `Cpu`) also the CPU model and threads, since
/// its ceilings are the CPU's.
pub fn record_path(dir: &Path, machine: &Machine) -> PathBuf {
    let mut name = format!("{} {}", machine.adapter, machine.driver_info);
    if is_cpu(machine) {
        name = format!("{name} {} {} threads", machine.cpu, machine.cpu_threads);
    }
    dir.join(format!("{}.json", slug(&name)))
}

/// The record file of an adapter as named before software adapters were keyed by CPU
/// (adapter and driver only), read when it was measured on this CPU.
fn legacy_record_path(dir: &Path, machine: &Machine) -> PathBuf {
    dir.join(format!(
        "{}.json",
        slug(&format!("{} {}", machine.adapter, machine.driver_info))
    ))
}

fn slug(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '-'
            }
        })
        .collect::<String>()
        .split('-')
        .filter(|s| !s.is_empty())
        .collect::<Vec<_>>()
        .join("-")
}

fn is_cpu(machine: &Machine) -> bool {
    machine.device_type == "Cpu"
}

/// Why a record measured on `measured` does not give `machine`'s ceilings, if it does
/// not: another adapter or driver, or for a software adapter another CPU or thread count.
pub fn mismatch(measured: &Machine, machine: &Machine) -> Option<String> {
    if (measured.adapter.as_str(), measured.driver_info.as_str())
        != (machine.adapter.as_str(), machine.driver_info.as_str())
    {
        return Some(format!(
            "measured on {} ({}), this run is on {} ({})",
            measured.adapter, measured.driver_info, machine.adapter, machine.driver_info
        ));
    }
    if is_cpu(machine)
        && (measured.cpu.as_str(), measured.cpu_threads)
            != (machine.cpu.as_str(), machine.cpu_threads)
    {
        return Some(format!(
            "a software adapter's ceilings are its CPU's: measured on {} ({} threads), this run is on {} ({} threads)",
            measured.cpu, measured.cpu_threads, machine.cpu, machine.cpu_threads
        ));
    }
    None
}

/// Reads and checks a ceilings record: it must parse, have this layout version, and
/// every figure must be positive and finite.
pub fn load(path: &Path) -> Result<CeilingsRecord> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("reading ceilings record {}", path.display()))?;
    let de = &mut serde_json::Deserializer::from_str(&text);
    let record: CeilingsRecord = serde_path_to_error::deserialize(de).map_err(|e| {
        anyhow::anyhow!(
            "ceilings record {}: field `{}`: {}",
            path.display(),
            e.path(),
            e.inner()
        )
    })?;
    if record.schema_version != CEILINGS_SCHEMA_VERSION {
        bail!(
            "ceilings record {}: field `schema_version`: expected {CEILINGS_SCHEMA_VERSION}, got {} (re-run `caustics ceilings`)",
            path.display(),
            record.schema_version
        );
    }
    for (i, c) in record.ceilings.iter().enumerate() {
        if !(c.figure.median.is_finite() && c.figure.median > 0.0) {
            bail!(
                "ceilings record {}: field `ceilings[{i}].figure.median` ({}): expected a positive number, got {}",
                path.display(),
                c.name,
                c.figure.median
            );
        }
    }
    Ok(record)
}

/// The cached record of `machine`'s adapter under `dir` and its path, if one was
/// measured for it: `None` when there is none (or only one of another CPU, for a software
/// adapter: said on stderr), an error when there is one that cannot be read.
pub fn cached(dir: &Path, machine: &Machine) -> Result<Option<(CeilingsRecord, PathBuf)>> {
    let path = [record_path(dir, machine), legacy_record_path(dir, machine)]
        .into_iter()
        .find(|p| p.exists());
    let Some(path) = path else {
        return Ok(None);
    };
    let record = load(&path)?;
    if let Some(why) = mismatch(&record.machine, machine) {
        eprintln!(
            "note: ceilings record {} not used ({why}); `caustics ceilings` measures this machine's",
            path.display()
        );
        return Ok(None);
    }
    Ok(Some((record, path)))
}

/// Measures the ceilings and writes the record (atomically, over an earlier one of the
/// same adapter); returns it and its path.
pub fn ceilings(args: &CeilingsArgs) -> Result<(CeilingsRecord, PathBuf)> {
    let options = ProbeOptions {
        width: args.width,
        height: args.height,
        trials: args.trials,
        target_ms: args.target_ms,
        bandwidth_bytes: args.bandwidth_mib.saturating_mul(1 << 20),
        only: args.only.clone(),
    };
    options
        .validate()
        .map_err(|e| anyhow::anyhow!("caustics ceilings --{}", e.to_string().replace('_', "-")))?;
    let choice = AdapterChoice::from_flag_or_env(args.adapter.as_deref());
    let ctx = GpuContext::new(&choice)?;
    let machine = crate::machine::machine(&ctx.summary);
    let build = crate::machine::build();
    if build.profile != "release" {
        eprintln!(
            "warning: a {} build: the ceilings of an unoptimized harness are still the device's, but report release builds",
            build.profile
        );
    }
    // Round 1 on the device opened above, later rounds each on a fresh one (the FP32
    // probe must run before any render pass on its device, see `measure`).
    let mut rounds: Vec<Vec<caustics_ceilings::ProbeResult>> = Vec::new();
    let mut device = Some(ctx);
    for round in 1..=args.rounds {
        let ctx = match device.take() {
            Some(ctx) => ctx,
            None => GpuContext::new(&choice)?,
        };
        eprintln!("round {round} of {}:", args.rounds);
        let probes = caustics_ceilings::measure(&ctx, &options, &mut |name| {
            eprintln!("  {name}");
        })
        .with_context(|| format!("measuring the ceilings of {}", ctx.summary.name))?;
        rounds.push(probes);
    }
    let probes = rounds.first().cloned().unwrap_or_default();
    if probes.is_empty() {
        bail!(
            "caustics ceilings --only {:?}: no probe name contains it",
            args.only
        );
    }
    let mut entries = Vec::with_capacity(probes.len());
    for p in &probes {
        // Every round's run of this probe (each figure with its own round's work).
        let runs: Vec<&caustics_ceilings::ProbeResult> = rounds
            .iter()
            .filter_map(|r| r.iter().find(|q| q.name == p.name))
            .collect();
        let figures_of = |q: &caustics_ceilings::ProbeResult| -> Vec<f64> {
            q.trial_ms.iter().map(|&ms| q.figure(ms)).collect()
        };
        let figures: Vec<f64> = runs.iter().flat_map(|q| figures_of(q)).collect();
        let all_ms: Vec<f64> = runs
            .iter()
            .flat_map(|q| q.trial_ms.iter().copied())
            .collect();
        let figure = crate::stats::summarize(&figures)
            .with_context(|| format!("probe {}: no trials", p.name))?;
        let trial_ms = crate::stats::summarize(&all_ms)
            .with_context(|| format!("probe {}: no trials", p.name))?;
        let round_medians: Vec<f64> = runs
            .iter()
            .filter_map(|q| crate::stats::summarize(&figures_of(q)).map(|s| s.median))
            .collect();
        let round_spread = (round_medians.len() > 1).then(|| {
            let lo = round_medians.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = round_medians.iter().copied().fold(0.0, f64::max);
            (hi - lo) / figure.median
        });
        entries.push(CeilingEntry {
            name: p.name.to_owned(),
            what: p.what.to_owned(),
            unit: p.unit.to_owned(),
            kind: match p.kind {
                ProbeKind::Throughput => "throughput",
                ProbeKind::PerItem => "per_item",
            }
            .to_owned(),
            spread: (figure.p90 - figure.p10) / figure.median,
            round_medians,
            round_spread,
            figure,
            work: p.work,
            work_unit: p.work_unit.to_owned(),
            counted_work: p.counted_work,
            scale: p.scale,
            trial_ms,
        });
    }
    let record = CeilingsRecord {
        schema_version: CEILINGS_SCHEMA_VERSION,
        build,
        machine,
        width: args.width,
        height: args.height,
        trials: args.trials,
        rounds: args.rounds,
        target_ms: args.target_ms,
        ceilings: entries,
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let path = record_path(&args.out, &record.machine);
    let mut json = serde_json::to_vec_pretty(&record)?;
    json.push(b'\n');
    caustics_metrics::atomic_write(&path, &json)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok((record, path))
}

/// The record as a table.
pub fn table(record: &CeilingsRecord) -> String {
    let mut s = format!(
        "Ceilings of {} ({}, {}), {} rounds of {} trials each:\n\n| probe | ceiling (median) | p10–p90 | spread | rounds' medians spread | trial ms | work per trial |\n|---|---|---|---|---|---|---|\n",
        record.machine.adapter,
        record.machine.backend,
        record.machine.driver_info,
        record.rounds,
        record.trials
    );
    for c in &record.ceilings {
        s.push_str(&format!(
            "| {} | {:.4} {} | {:.4}–{:.4} | {:.1} % | {} | {:.2} | {:.4e} {} |\n",
            c.name,
            c.figure.median,
            c.unit,
            c.figure.p10,
            c.figure.p90,
            100.0 * c.spread,
            c.round_spread
                .map_or("–".to_owned(), |r| format!("{:.1} %", 100.0 * r)),
            c.trial_ms.median,
            c.work,
            c.work_unit
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn machine() -> Machine {
        Machine {
            adapter: "llvmpipe (LLVM 15.0.6, 256 bits)".into(),
            backend: "Vulkan".into(),
            device_type: "Cpu".into(),
            driver: "llvmpipe".into(),
            driver_info: "Mesa 22.3.6 (LLVM 15.0.6)".into(),
            cpu: "x".into(),
            cpu_threads: 2,
            os: "linux".into(),
        }
    }

    #[test]
    fn the_record_file_is_named_after_adapter_and_driver_and_a_software_adapters_cpu() {
        let p = record_path(Path::new("c"), &machine());
        assert_eq!(
            p,
            Path::new("c/llvmpipe-llvm-15-0-6-256-bits-mesa-22-3-6-llvm-15-0-6-x-2-threads.json")
        );
        let gpu = Machine {
            adapter: "NVIDIA H100 80GB HBM3".into(),
            device_type: "DiscreteGpu".into(),
            driver_info: "580.159.04".into(),
            ..machine()
        };
        assert_eq!(
            record_path(Path::new("c"), &gpu),
            Path::new("c/nvidia-h100-80gb-hbm3-580-159-04.json")
        );
    }

    #[test]
    fn a_software_adapters_record_of_another_cpu_is_not_used() {
        let here = machine();
        let other_cpu = Machine {
            cpu: "AMD EPYC".into(),
            ..machine()
        };
        let more_threads = Machine {
            cpu_threads: 16,
            ..machine()
        };
        assert!(mismatch(&here, &here).is_none());
        let why = mismatch(&other_cpu, &here).expect("another CPU");
        assert!(why.contains("AMD EPYC") && why.contains("CPU"), "{why}");
        assert!(mismatch(&more_threads, &here).is_some());
        // A GPU's ceilings do not depend on the host CPU.
        let gpu = |cpu: &str| Machine {
            device_type: "DiscreteGpu".into(),
            cpu: cpu.into(),
            ..machine()
        };
        assert!(mismatch(&gpu("a"), &gpu("b")).is_none());
        let driver = Machine {
            driver_info: "Mesa 24".into(),
            ..machine()
        };
        assert!(mismatch(&driver, &here).is_some());

        // On disk: a record under the old name (adapter and driver only) is read on the
        // CPU that measured it, not on another; one under the new name likewise.
        let dir = tempfile::tempdir().expect("temp dir");
        let record = |m: Machine| CeilingsRecord {
            schema_version: CEILINGS_SCHEMA_VERSION,
            build: Build {
                commit: "c".into(),
                dirty: false,
                diff_hash: None,
                version: "0".into(),
                profile: "release".into(),
            },
            machine: m,
            width: 64,
            height: 64,
            trials: 1,
            rounds: 1,
            target_ms: 1.0,
            ceilings: Vec::new(),
        };
        let legacy = legacy_record_path(dir.path(), &here);
        let json = serde_json::to_vec(&record(other_cpu.clone())).expect("json");
        std::fs::write(&legacy, json).expect("write");
        assert!(cached(dir.path(), &here).expect("readable").is_none());
        let (_, path) = cached(dir.path(), &other_cpu)
            .expect("readable")
            .expect("its own CPU's record");
        assert_eq!(path, legacy);
        let json = serde_json::to_vec(&record(here.clone())).expect("json");
        std::fs::write(record_path(dir.path(), &here), json).expect("write");
        let (_, path) = cached(dir.path(), &here)
            .expect("readable")
            .expect("this CPU's record");
        assert_eq!(path, record_path(dir.path(), &here));
    }

    #[test]
    fn a_bad_record_names_the_file_and_field() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("r.json");
        std::fs::write(&path, r#"{"schema_version": 1, "build": 3}"#).expect("write");
        let e = format!("{:#}", load(&path).expect_err("bad build"));
        assert!(e.contains("r.json") && e.contains("field `build`"), "{e}");
        std::fs::write(&path, "not json").expect("write");
        let e = format!("{:#}", load(&path).expect_err("not json"));
        assert!(e.contains("r.json"), "{e}");
        assert!(
            cached(dir.path(), &machine()).expect("no record").is_none(),
            "no record of this adapter is None, not an error"
        );
    }
}
