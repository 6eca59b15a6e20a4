//! The command line of the `caustics` binary (here, not in `main.rs`, so that tests can
//! parse the README's commands with the binary's own parser).

use clap::{Parser, Subcommand};

use crate::ceilings_cmd::CeilingsArgs;
use crate::compare::CompareArgs;
use crate::reference_cmd::ReferenceArgs;
use crate::report::ReportArgs;
use crate::reproduce::{MergeArgs, ReproduceArgs};
use crate::run::RunOptions;

/// `caustics`.
#[derive(Parser)]
#[command(
    name = "caustics",
    version,
    about = "Render, measure and score real-time caustics methods"
)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Subcommand)]
pub enum Command {
    /// List the built-in scenes and the methods with their parameters, defaults and counters.
    List,
    /// Render a scene with a method; write images, timings, fragment counts and errors.
    Run(RunOptions),
    /// Render the CPU reference of a scene (surface and volume caustics with standard
    /// errors) into the reference cache that `run` scores against.
    Reference(ReferenceArgs),
    /// Run an experiment of bench/experiments (or `all`): every (scene, method,
    /// parameter set) it names, then a summary (tables, plots, Bencher Metric Format).
    Reproduce(ReproduceArgs),
    /// Put the sequences of `run --animate` under a folder side by side:
    /// `<DIR>/animations.md` (per method: GPU and rebuild time, errors at the scored
    /// instants, temporal error).
    Animations {
        /// Folder holding `<scene>/<method>/animation/animation.json` files.
        dir: std::path::PathBuf,
    },
    /// Merge the output folders of `reproduce --shard k/n` into one.
    Merge(MergeArgs),
    /// Compare two result folders run by run; exit 2 on a regression, 3 when no pair
    /// regressed but some pair is not comparable (other scene, resolution, method,
    /// parameters or adapter).
    Compare(CompareArgs),
    /// Measure the adapter's own ceilings (blended and unblended fill, FP32 compute,
    /// memory bandwidth, storage atomics, pass and draw overhead) through the harness's
    /// pass profiler and keep them as the adapter's record under results/ceilings/.
    Ceilings(CeilingsArgs),
    /// List the adapters wgpu finds, the one `run` would pick, and each one's features
    /// and limits.
    Adapters(crate::adapters_cmd::AdaptersArgs),
    /// Write a static HTML report (index.html + images) of reproduced experiments.
    Report(ReportArgs),
    /// Print the JSON Schema of a scene, experiment or result file (committed under
    /// schemas/).
    Schema {
        /// Which file format.
        #[arg(value_enum)]
        kind: crate::schemas::SchemaKind,
    },
}
