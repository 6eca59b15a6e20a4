//! `result.json`: one document per (scene, method, parameter set), DESIGN "Results".

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::machine::{Build, Machine};
use crate::stats::Summary;

/// Bumped whenever a field changes meaning or is removed.
///
/// - 1: `errors` were scored on the timed frame, one sample at each pixel centre.
/// - 2: `errors` are scored on the pixel-averaged scoring frame ([`ScoringInfo`]); the
///   timed frame's own errors moved to `errors_1spp`. [`RunResult::from_json`] reads a
///   version-1 file by moving its `errors` there, so old and new are never compared as
///   if they meant the same.
pub const SCHEMA_VERSION: u32 = 2;

/// The whole result of one run.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(
    title = "caustics-bench run result",
    description = "The result.json of one `caustics run`: build, machine, scene, method and parameters, timings per pass, fragments, counters, memory, images, tone mapping, scoring and errors against the reference (README, \"What caustics run writes\")."
)]
pub struct RunResult {
    /// [`SCHEMA_VERSION`] of the writer.
    pub schema_version: u32,
    /// Source and profile of the binary.
    pub build: Build,
    /// Adapter and CPU.
    pub machine: Machine,
    /// What was rendered.
    pub scene: SceneInfo,
    /// With what.
    pub method: MethodRun,
    /// How many frames of each kind.
    pub frames: FrameCounts,
    /// Per-pass GPU times over the measured frames.
    pub timing: Timing,
    /// Pipeline statistics and fill counts of the count frame; `None` when the
    /// adapter has no pipeline-statistics queries.
    pub fragments: Option<Fragments>,
    /// The method's counters (beams, triangles, overflow, ...).
    pub counters: BTreeMap<String, u64>,
    /// GPU memory in bytes.
    pub gpu_memory_bytes: Memory,
    /// File names of the images written beside this file.
    pub images: BTreeMap<String, String>,
    /// The tone mapping of `composite.png` and of FLIP.
    pub tone_map: ToneMapInfo,
    /// How the scored images were made (absent in version-1 files: scored at 1 spp).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scoring: Option<ScoringInfo>,
    /// Errors of the pixel-averaged scoring frame against the reference (the reference
    /// is a pixel-area average too), when a reference was given.
    pub errors: Option<ErrorReport>,
    /// Errors of the timed frame itself (one sample at each pixel centre, what the
    /// method shows in real time). `errors_1spp − errors` is the camera-aliasing share.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub errors_1spp: Option<ErrorReport>,
    /// Each pass against the adapter's measured ceilings (`caustics ceilings`): the
    /// fraction of each ceiling it reaches and the bound it is nearest. Absent when no
    /// ceilings record of the adapter exists (or in files before it existed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub roofline: Option<crate::roofline::RooflineReport>,
    /// What the harness's own measuring costs (`caustics run
    /// --instrumentation-overhead`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub instrumentation: Option<Instrumentation>,
    /// Where the run's wall-clock time went on this machine (absent in files before it
    /// existed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wall: Option<RunWall>,
}

/// A run's CPU wall-clock time by phase, in seconds: what a reproduction's time is made
/// of (the GPU's own time is in [`Timing`]). The phases add up to `total_s`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RunWall {
    /// From the scene handed to the run until `result.json` is written.
    pub total_s: f64,
    /// Parameters, the reference read from the cache, adapter and device, scene upload,
    /// the method's pipelines and buffers: everything before the first frame.
    pub setup_s: f64,
    /// Warm-up, timed and count frames (each recorded, submitted and waited for), the
    /// queries' and counters' readback and the timed frame's images.
    pub frames_s: f64,
    /// The scoring frame's N² camera sub-frames ([`ScoringInfo::wall_ms`]).
    pub scoring_frame_s: f64,
    /// Errors against the reference (FLIP, HDR-FLIP, SSIM, relMSE...) and error maps.
    pub errors_s: f64,
    /// Rooflines, images (EXR, PNG, heatmaps) and `result.json` written.
    pub writing_s: f64,
}

/// The cost of measuring: CPU wall time per frame (record, submit, wait for the GPU)
/// of the timed frames (timestamps around every pass) against bare frames (the same
/// frame with no queries), each bare frame right after a timed one.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Instrumentation {
    /// `timed_wall_ms.median / bare_wall_ms.median − 1` (issue 17's goal: ≤ 0.02).
    pub overhead: f64,
    /// The count frame (pipeline statistics and fill counting on) against the bare
    /// median, `count_wall_ms / bare_wall_ms.median − 1`: one frame, so noisier.
    pub count_frame_overhead: f64,
    /// Timed frames.
    pub timed_wall_ms: Summary,
    /// Bare frames.
    pub bare_wall_ms: Summary,
    /// The count frame.
    pub count_wall_ms: f64,
}

impl RunResult {
    /// Parses a `result.json` of any schema version this build knows, upgraded to the
    /// current meaning of every field (see [`SCHEMA_VERSION`]).
    pub fn from_json(text: &str) -> Result<Self, serde_json::Error> {
        let mut r: Self = serde_json::from_str(text)?;
        if r.schema_version < 2 && r.errors_1spp.is_none() {
            r.errors_1spp = r.errors.take();
        }
        Ok(r)
    }
}

/// The scoring frame (DESIGN "Measuring honestly": scoring is at the reference's
/// footprint).
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ScoringInfo {
    /// N of the N×N sub-pixel camera offsets (stratum centres) averaged per pixel.
    pub grid: u32,
    /// N², the samples per pixel of the scored images.
    pub samples_per_pixel: u32,
    /// CPU wall time of the scoring frame (ms): its whole frame at the pixel centre (the
    /// light side, rendered once) and the N² camera-side sub-frames, each recorded,
    /// submitted, waited for and accumulated, outside the timed frames.
    pub wall_ms: f64,
}

/// The scene as run.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SceneInfo {
    /// Scene name.
    pub name: String,
    /// Scene file: relative to the checkout (`scenes/ring.json`) when inside it, else
    /// as given ([`crate::machine::portable_path`]).
    pub file: String,
    /// Content hash of the scene file and its meshes.
    pub hash: String,
    /// Image width (pixels).
    pub width: u32,
    /// Image height (pixels).
    pub height: u32,
    /// The instant (s) an animated scene was posed at (`caustics run --time`); absent
    /// for a still scene, which is the same at every instant.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_s: Option<f32>,
    /// N when the method rendered each extended light it does not take as N
    /// representative lights (`--representative-lights`); absent when it rendered the
    /// scene's own lights. The hash and the reference are the scene's own.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub representative_lights: Option<u32>,
}

/// The method as run.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MethodRun {
    /// Registry name.
    pub name: String,
    /// Parameters given on the command line (the method's defaults fill in the rest).
    pub params: serde_json::Value,
}

/// Frame counts.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FrameCounts {
    /// Warm-up frames, not measured.
    pub warmup: u32,
    /// Timed frames.
    pub measured: u32,
    /// Count frames (statistics and fill counting on; not timed).
    pub count: u32,
}

/// GPU times.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Timing {
    /// Whether the adapter gives timestamps; without them every `gpu_ms` is absent.
    pub timestamps_available: bool,
    /// Per pass name (summed over the pass's instances within a frame, e.g. 6 cube
    /// faces), over the measured frames, in recording order of first appearance.
    pub passes: Vec<PassTiming>,
    /// Sum of the method's passes per frame.
    pub method_gpu_ms: Option<Summary>,
    /// Sum of the base passes (G-buffers, direct light) per frame.
    pub base_gpu_ms: Option<Summary>,
    /// Sum of all passes per frame.
    pub frame_gpu_ms: Option<Summary>,
    /// CPU wall time per frame: record, submit and wait for the GPU.
    pub frame_wall_ms: Option<Summary>,
    /// Timestamp pairs rejected as zero or non-monotonic over all measured frames.
    pub rejected_timestamps: u32,
}

/// GPU time of one named pass.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PassTiming {
    /// "<owner>/<pass>".
    pub name: String,
    /// Times over the measured frames (absent without timestamps).
    pub gpu_ms: Option<Summary>,
}

/// Pipeline statistics of one named pass in the count frame.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PassFragments {
    /// "<owner>/<pass>".
    pub name: String,
    /// Fragment shader invocations.
    pub fragment_shader_invocations: u64,
    /// Primitives out of the clipper.
    pub primitives: u64,
    /// Vertex shader invocations.
    pub vertex_shader_invocations: u64,
    /// Compute shader invocations.
    pub compute_shader_invocations: u64,
}

/// Fragments shaded.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Fragments {
    /// Per pass.
    pub passes: Vec<PassFragments>,
    /// Fragment shader invocations of the method's passes.
    pub method_total: u64,
    /// Sum of the per-pixel fill counts (the method's camera-resolution fragments).
    pub fill_total: u64,
    /// Largest per-pixel count.
    pub fill_max: u32,
    /// Pixels with at least one fragment.
    pub fill_covered_pixels: u64,
    /// Histogram of per-pixel counts.
    pub fill_histogram: caustics_metrics::Histogram,
}

/// GPU memory.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Memory {
    /// Owned by the method.
    pub method: u64,
    /// Owned by the base renderer (scene upload, G-buffers, targets, fill counter).
    pub base: u64,
}

/// Tone mapping used for PNGs and LDR FLIP.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ToneMapInfo {
    /// Linear radiance is multiplied by this, clamped to [0, 1], then sRGB-encoded.
    pub exposure_scale: f32,
    /// Where the exposure came from: "--exposure", "scene camera.exposure", "reference p99" (the reference
    /// surface caustic's 99th-percentile luminance maps to 1), or "image p99" (no
    /// reference: the run's own composite). Absent in files before it existed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// Exposure of the volume caustic's LDR FLIP (its reference's 99th percentile).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub volume_exposure_scale: Option<f32>,
}

/// Errors of the caustic images against a reference.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ErrorReport {
    /// The reference surface caustic image: from the cache, its path inside the cache
    /// (`<scene>/<hash>-<width>x<height>-t<version>/caustic.exr`); from `--reference`,
    /// relative to the checkout when inside it, else as given.
    pub reference: String,
    /// Where it came from: "--reference" or "cache".
    pub reference_source: String,
    /// Errors of the surface caustic image.
    pub surface: caustics_metrics::Errors,
    /// Errors of the volume caustic image, when the method renders volume caustics
    /// and the reference has a volume image.
    pub volume: Option<caustics_metrics::Errors>,
    /// RMS of the reference's own per-pixel standard error (from `stderr.exr` beside
    /// it), the noise floor below which RMSE differences mean nothing.
    pub reference_noise_rms: Option<f64>,
}
