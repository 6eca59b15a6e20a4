//! The adapter's own ceilings: what the device in use can do at most for each kind of
//! work a caustics pass does, measured the way the passes are.
//!
//! A pass's milliseconds say little on their own: 40 ms of hull rasterization is slow
//! on a GPU and fast on lavapipe. Read against the adapter's ceiling for the same
//! work (fragments blended per second, bytes per second, atomics per second) they say
//! how close the pass runs to what this adapter can do, and which bound it is nearest.
//! Each probe here is a synthetic pass of one kind of work, timed by the harness's
//! [`PassProfiler`] through [`BareFrame`] (the same timestamp scopes as every method
//! pass), with its work counted in closed form and checked against pipeline
//! statistics where the adapter has them:
//!
//! | probe | work | unit |
//! |---|---|---|
//! | `fill_blend_rgba32f_fullscreen`, `fill_blend_rgba16f_fullscreen` | full-screen triangles, additive blend | Gfragments/s |
//! | `fill_blend_rgba32f_small`, `fill_blend_rgba16f_small` | 8-pixel triangles tiling the target, additive blend | Gfragments/s |
//! | `fill_unblended_rgba32f_fullscreen` | full-screen triangles, no blending | Gfragments/s |
//! | `compute_fp32` | independent FMA chains | GFLOP/s |
//! | `bandwidth_copy` | sequential vec4 copy (bytes read + written) | GB/s |
//! | `bandwidth_clear` | render passes that clear an RGBA32F target, no draws (bytes written) | GB/s |
//! | `bandwidth_strided` | gather with a 528-byte stride, sequential writes | GB/s |
//! | `atomics_storage` | `atomicAdd` on 65,536 hashed u32 counters | Gatomics/s |
//! | `overhead_pass` | 64 empty compute passes | µs per pass |
//! | `overhead_draw` | draws of a zero-area triangle in one render pass | µs per draw |
//!
//! Every probe is first scaled (layers, loop trips or repeated dispatches) until one
//! trial takes at least [`ProbeOptions::target_ms`], so that timestamp resolution and
//! submission jitter are small against it on a fast GPU as on lavapipe; then one
//! warm-up and [`ProbeOptions::trials`] timed trials follow, each a frame of its own.
//! The caller summarizes the trial times (median and spread).

use caustics_gpu::{BareFrame, FrameMode, GpuContext, GpuError, PassProfiler};

mod probes;
pub mod roofline;

pub use probes::{ProbeKind, ProbeResult, measure};

/// The fill probes' WGSL.
pub const FILL_WGSL: &str = include_str!("fill.wgsl");
/// The compute probes' WGSL.
pub const COMPUTE_WGSL: &str = include_str!("compute.wgsl");

/// Side of the square cells the small-triangle fill probe halves (pixels): each
/// triangle covers 8 pixels, the size of a caustic triangle or a small beam hull.
pub const SMALL_CELL_PX: u32 = 4;
/// Passes of the per-pass overhead probe (one profiled frame of them; the profiler's
/// capacity was 64 when the committed ceilings were measured, and it stays the probe's
/// size so records stay comparable).
pub const OVERHEAD_PASSES: u32 = 64;

/// How the probes run.
#[derive(Clone, Debug, PartialEq)]
pub struct ProbeOptions {
    /// Fill target size (pixels); multiples of [`SMALL_CELL_PX`].
    pub width: u32,
    /// Fill target height (pixels).
    pub height: u32,
    /// Timed trials per probe (after one warm-up).
    pub trials: u32,
    /// A trial is scaled up until it takes at least this long (ms).
    pub target_ms: f64,
    /// Bytes of each bandwidth buffer (at most; lowered to the device's largest
    /// storage binding and to a power of two of 16-byte elements).
    pub bandwidth_bytes: u64,
    /// Run only the probes whose names contain one of these (all when empty).
    pub only: Vec<String>,
}

impl Default for ProbeOptions {
    fn default() -> Self {
        Self {
            width: 1024,
            height: 768,
            trials: 9,
            target_ms: 20.0,
            bandwidth_bytes: 64 << 20,
            only: Vec::new(),
        }
    }
}

/// What can go wrong measuring the ceilings.
#[derive(Debug, thiserror::Error)]
pub enum CeilingsError {
    /// The adapter gives no timestamps: nothing can be timed on the device.
    #[error(
        "adapter {adapter:?} has no timestamp queries: the ceilings are GPU times and cannot be measured on it"
    )]
    NoTimestamps {
        /// Adapter name.
        adapter: String,
    },
    /// An option is out of range.
    #[error("{option}: {message}")]
    InvalidOption {
        /// The option's name.
        option: &'static str,
        /// What was expected.
        message: String,
    },
    /// A probe's timestamps were rejected (zero or going backwards) in every trial.
    #[error("probe {probe}: the adapter returned no valid timestamps")]
    NoTimings {
        /// The probe.
        probe: String,
    },
    /// The device failed.
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

impl ProbeOptions {
    /// Checks the options before anything is allocated.
    pub fn validate(&self) -> Result<(), CeilingsError> {
        let bad = |option, message: String| Err(CeilingsError::InvalidOption { option, message });
        for (option, v) in [("width", self.width), ("height", self.height)] {
            if v == 0 || v % SMALL_CELL_PX != 0 || v > 16384 {
                return bad(
                    option,
                    format!("expected a multiple of {SMALL_CELL_PX} in 4..=16384, got {v}"),
                );
            }
        }
        if !(1..=1000).contains(&self.trials) {
            return bad("trials", format!("expected 1..=1000, got {}", self.trials));
        }
        if !(self.target_ms.is_finite() && self.target_ms > 0.0 && self.target_ms <= 10_000.0) {
            return bad(
                "target_ms",
                format!("expected a time in (0, 10000] ms, got {}", self.target_ms),
            );
        }
        if !(1 << 16..=1 << 32).contains(&self.bandwidth_bytes) {
            return bad(
                "bandwidth_bytes",
                format!(
                    "expected 64 KiB..=4 GiB, got {} bytes",
                    self.bandwidth_bytes
                ),
            );
        }
        Ok(())
    }

    /// Whether the probe `name` is selected.
    pub fn selects(&self, name: &str) -> bool {
        self.only.is_empty() || self.only.iter().any(|o| name.contains(o.as_str()))
    }
}

/// Times one frame of `record` (its passes' span from the first pass's start to the
/// last pass's end, ms), or counts it (`FrameMode::Count`: the summed pipeline
/// statistics of its passes).
fn run_frame(
    ctx: &GpuContext,
    profiler: &mut PassProfiler,
    mode: FrameMode,
    record: &dyn Fn(&mut BareFrame<'_>) -> Result<(), GpuError>,
) -> Result<caustics_gpu::FrameSample, GpuError> {
    let mut frame = BareFrame::begin(ctx, profiler, mode)?;
    record(&mut frame)?;
    frame.submit(ctx)?;
    let mut samples = profiler.collect(ctx)?;
    samples
        .pop()
        .ok_or_else(|| GpuError::ProfilerCapacity("a frame was submitted but not recorded".into()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn probe_shaders_validate() {
        caustics_gpu::shader::validate_wgsl("ceilings fill.wgsl", FILL_WGSL)
            .unwrap_or_else(|e| panic!("{e}"));
        caustics_gpu::shader::validate_wgsl("ceilings compute.wgsl", COMPUTE_WGSL)
            .unwrap_or_else(|e| panic!("{e}"));
    }

    #[test]
    fn options_out_of_range_name_the_option() {
        let cases: [(ProbeOptions, &str); 5] = [
            (
                ProbeOptions {
                    width: 1023,
                    ..Default::default()
                },
                "width",
            ),
            (
                ProbeOptions {
                    height: 0,
                    ..Default::default()
                },
                "height",
            ),
            (
                ProbeOptions {
                    trials: 0,
                    ..Default::default()
                },
                "trials",
            ),
            (
                ProbeOptions {
                    target_ms: f64::NAN,
                    ..Default::default()
                },
                "target_ms",
            ),
            (
                ProbeOptions {
                    bandwidth_bytes: 10,
                    ..Default::default()
                },
                "bandwidth_bytes",
            ),
        ];
        for (options, name) in cases {
            let e = options.validate().expect_err(name).to_string();
            assert!(e.starts_with(name), "{e}");
        }
        ProbeOptions::default()
            .validate()
            .expect("defaults are valid");
    }
}
