//! The roofline of a run: each pass's GPU time and counted work read against the
//! adapter's cached ceilings record (`caustics ceilings`, [`crate::ceilings_cmd`]), as
//! [`caustics_ceilings::roofline`] models it. Written into `result.json` and read by
//! the experiment summaries.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::Result;
use caustics_ceilings::roofline::{Ceilings, PassRoofline, PassWork, ProbeFigure, pass_roofline};
use caustics_gpu::{FrameSample, PassShape, PassStatistics};
use serde::{Deserialize, Serialize};

use crate::ceilings_cmd::{self, CeilingsRecord};
use crate::machine::Machine;
use crate::result::Timing;

/// The passes of one run against the ceilings of its adapter.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RooflineReport {
    /// The ceilings record read (relative to the checkout when inside it).
    pub ceilings: String,
    /// Commit of the build that measured it, `-dirty` when its tree was.
    pub ceilings_build: String,
    /// The fill roof of the methods' targets (additive blending into RGBA32F): the
    /// curve of the roofline plot.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fill_roof: Option<FillRoof>,
    /// Per pass, in recording order (passes without a positive median time are left
    /// out: nothing to read against).
    pub passes: Vec<PassRoofline>,
}

/// A fill roof: at `s` fragments per primitive a pass can shade at most
/// `s / (triangle_s + s / fragments_per_s)` fragments per second.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FillRoof {
    /// The full-screen probe it comes from.
    pub probe: String,
    /// Full-screen fragments per second.
    pub fragments_per_s: f64,
    /// Seconds per triangle beyond its fragments (0 when not measured).
    pub triangle_s: f64,
}

impl FillRoof {
    /// The roof at `fragments_per_primitive`, in fragments per second.
    pub fn at(&self, fragments_per_primitive: f64) -> f64 {
        fragments_per_primitive / (self.triangle_s + fragments_per_primitive / self.fragments_per_s)
    }
}

/// The roofline model's ceilings from a record.
pub fn model_ceilings(record: &CeilingsRecord) -> Ceilings {
    Ceilings::from_probes(|name| {
        record.get(name).map(|c| ProbeFigure {
            figure: c.figure.median,
            work: c.work,
            counted_work: c.counted_work,
        })
    })
}

/// Reads a run's passes against `machine`'s cached record under `ceilings_dir`:
/// `None` when no record was measured for this adapter (or the adapter has no
/// timestamps), an error when the record exists but cannot be read.
pub fn for_run(
    ceilings_dir: &Path,
    machine: &Machine,
    timing: &Timing,
    count_frame: &FrameSample,
) -> Result<Option<RooflineReport>> {
    if !timing.timestamps_available {
        return Ok(None);
    }
    let Some((record, record_path)) = ceilings_cmd::cached(ceilings_dir, machine)? else {
        return Ok(None);
    };
    let ceilings = model_ceilings(&record);
    if ceilings.is_empty() {
        return Ok(None);
    }
    let fill_roof = ceilings.method_target_fill().map(|fill| FillRoof {
        probe: fill.probe.to_owned(),
        fragments_per_s: fill.fragments_per_s,
        triangle_s: ceilings.triangle_s.as_ref().map_or(0.0, |t| t.0),
    });
    let works = pass_works(timing, count_frame);
    let passes = works
        .iter()
        .filter_map(|w| pass_roofline(w, &ceilings))
        .collect();
    Ok(Some(RooflineReport {
        ceilings: crate::machine::portable_path(&record_path),
        ceilings_build: format!(
            "{}{}",
            record
                .build
                .commit
                .get(..12)
                .unwrap_or(&record.build.commit),
            if record.build.dirty { "-dirty" } else { "" }
        ),
        fill_roof,
        passes,
    }))
}

/// Each named pass's median time (from `timing`) and its count-frame work, summed over
/// its instances.
pub fn pass_works(timing: &Timing, count_frame: &FrameSample) -> Vec<PassWork> {
    let mut per_name: BTreeMap<&str, (u32, PassShape, Option<PassStatistics>)> = BTreeMap::new();
    for p in &count_frame.passes {
        let e = per_name
            .entry(&p.name)
            .or_insert((0, p.shape, Some(Default::default())));
        e.0 += 1;
        e.2 = match (e.2, p.statistics) {
            (Some(a), Some(b)) => Some(PassStatistics {
                vertex_invocations: a.vertex_invocations + b.vertex_invocations,
                clipper_invocations: a.clipper_invocations + b.clipper_invocations,
                primitives_out: a.primitives_out + b.primitives_out,
                fragment_invocations: a.fragment_invocations + b.fragment_invocations,
                compute_invocations: a.compute_invocations + b.compute_invocations,
            }),
            _ => None,
        };
    }
    timing
        .passes
        .iter()
        .filter_map(|t| {
            let gpu_ms = t.gpu_ms.as_ref()?.median;
            let (instances, shape, statistics) = per_name.get(t.name.as_str())?;
            Some(PassWork {
                name: t.name.clone(),
                gpu_ms,
                instances: *instances,
                shape: *shape,
                statistics: *statistics,
            })
        })
        .collect()
}

/// One line per pass: `name  ms  bound  fraction  fill% bandwidth% overhead%`.
pub fn table(report: &RooflineReport) -> String {
    let pct = |s: &Option<caustics_ceilings::roofline::CeilingShare>| {
        s.as_ref()
            .map_or("-".to_owned(), |s| format!("{:.1}%", 100.0 * s.fraction))
    };
    let width = report
        .passes
        .iter()
        .map(|p| p.name.len())
        .max()
        .unwrap_or(4)
        .max(4);
    let mut out = format!(
        "{:width$}  {:>10}  {:>9}  {:>7}  {:>7}  {:>9}  {:>8}\n",
        "pass", "gpu ms", "bound", "of ceil", "fill", "bandwidth", "overhead"
    );
    for p in &report.passes {
        out += &format!(
            "{:width$}  {:>10.3}  {:>9}  {:>6.1}%  {:>7}  {:>9}  {:>8}\n",
            p.name,
            p.gpu_ms,
            p.bound.as_str(),
            100.0 * p.fraction,
            pct(&p.fill),
            pct(&p.bandwidth),
            pct(&p.overhead),
        );
    }
    out
}
