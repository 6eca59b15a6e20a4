//! `caustics run --animate START:END:FPS`: a method on a moving scene, frame by frame.
//!
//! Every frame is a new instant: the scene is posed ([`Scene::at_time`]), uploaded and
//! the method created anew, so no method reuses anything of the previous frame (what a
//! method costs when nothing can be cached). The rebuild (upload, the method's setup:
//! its buffers, bind groups and whatever it derives from the scene) is timed on the CPU
//! apart from the frame. Pipelines are not part of it after the first instant: like a
//! real-time renderer, the device compiles each pipeline once
//! ([`caustics_gpu::pipeline_cache`]), and each frame records how many its rebuild
//! compiled (`pipelines_compiled`: the first instant's, then 0 unless a scene change
//! asks for another variant). Each instant gets one untimed count frame (the counters
//! are read after it), then one timed frame, so the GPU time is the frame's own and not
//! the first use of new pipelines.
//!
//! Every `--reference-every`-th instant is scored like a still run (pixel-averaged
//! scoring frame against a reference posed at that instant, from the cache or rendered
//! quickly), and so is the instant after it: the pair gives the temporal error
//! ([`caustics_metrics::temporal_error`]), the flicker a still error misses.
//! Writes `animation.json` (atomically) and `animation.md` under
//! `<out>/<scene>/<method>/animation/`, with the scored instants' caustic images.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result, bail};
use caustics_gpu::{
    AdapterChoice, FrameMode, GpuContext, GpuScene, PassProfiler, Renderer, RendererOptions,
};
use caustics_metrics::{Errors, HdrImage, TemporalError, ToneMap};
use caustics_scene::{MAX_TIME_S, Scene};
use serde::{Deserialize, Serialize};

use crate::machine::{self, Build, Machine};
use crate::registry;
use crate::result::{MethodRun, SceneInfo, Timing};
use crate::run::{RunOptions, RunOutcome};
use crate::stats::{Summary, summarize};

/// Most frames of one sequence.
pub const MAX_ANIMATION_FRAMES: usize = 10_000;

/// Name of a sequence's result file in its folder.
pub const ANIMATION_FILE: &str = "animation.json";

/// Version of `animation.json`.
pub const ANIMATION_SCHEMA_VERSION: u32 = 1;

/// `START:END:FPS`: instants START, START + 1/FPS, … before END.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct AnimateSpec {
    /// First instant (s).
    pub start_s: f32,
    /// End of the sequence (s), not included.
    pub end_s: f32,
    /// Frames per second.
    pub fps: f32,
}

impl AnimateSpec {
    /// Parses `START:END:FPS` (e.g. `0:2:30`, 60 frames).
    pub fn parse(text: &str) -> Result<AnimateSpec> {
        let bad = |why: String| anyhow::anyhow!("--animate {text:?}: {why}");
        let parts: Vec<&str> = text.split(':').collect();
        let [start, end, fps] = parts.as_slice() else {
            return Err(bad("expected START:END:FPS, e.g. 0:2:30".into()));
        };
        let num = |name: &str, s: &str| -> Result<f32> {
            s.trim()
                .parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(format!("{name}: expected a finite number, got {s:?}")))
        };
        let spec = AnimateSpec {
            start_s: num("START", start)?,
            end_s: num("END", end)?,
            fps: num("FPS", fps)?,
        };
        spec.check().map_err(|(field, why)| {
            let name = match field {
                "start_s" => "START",
                "end_s" => "END",
                _ => "FPS",
            };
            bad(format!("{name}: {why}"))
        })?;
        Ok(spec)
    }

    /// What makes a sequence valid: START and END within ±[`MAX_TIME_S`], END after
    /// START, FPS in (0, 1000], 1..=[`MAX_ANIMATION_FRAMES`] frames. On failure: the
    /// field at fault (`start_s`, `end_s`, `fps`) and what was expected.
    pub fn check(&self) -> std::result::Result<(), (&'static str, String)> {
        for (field, v) in [
            ("start_s", self.start_s),
            ("end_s", self.end_s),
            ("fps", self.fps),
        ] {
            if !v.is_finite() {
                return Err((field, format!("expected a finite number, got {v}")));
            }
        }
        for (field, v) in [("start_s", self.start_s), ("end_s", self.end_s)] {
            if v.abs() > MAX_TIME_S {
                return Err((
                    field,
                    format!("expected START and END within ±{MAX_TIME_S:e} s, got {v}"),
                ));
            }
        }
        if self.end_s <= self.start_s {
            return Err((
                "end_s",
                format!(
                    "expected END after START ({}), got {}",
                    self.start_s, self.end_s
                ),
            ));
        }
        if !(self.fps > 0.0 && self.fps <= 1000.0) {
            return Err((
                "fps",
                format!("expected a rate in (0, 1000], got {}", self.fps),
            ));
        }
        let n = self.frame_count();
        if n == 0 || n > MAX_ANIMATION_FRAMES {
            return Err((
                "end_s",
                format!("expected 1..={MAX_ANIMATION_FRAMES} frames, got {n} ((END − START)·FPS)"),
            ));
        }
        Ok(())
    }

    /// Frames between scored instants when none is given: a quarter of the sequence, so
    /// 4 scored instants (and their partners).
    pub fn default_reference_every(&self) -> u32 {
        u32::try_from((self.frame_count() / 4).max(1)).unwrap_or(u32::MAX)
    }

    /// The instants scored with `reference_every` (> 0): every `reference_every`-th frame
    /// and the frame after each, in time order; the instants whose references a
    /// sequence needs.
    pub fn scored_instants(&self, reference_every: u32) -> Vec<f32> {
        let instants = self.instants();
        self.scored_frames(reference_every)
            .into_iter()
            .map(|i| instants[i])
            .collect()
    }

    /// The frame indices of [`AnimateSpec::scored_instants`].
    pub fn scored_frames(&self, reference_every: u32) -> Vec<usize> {
        scored_indices(self.frame_count(), reference_every.max(1) as usize)
            .into_iter()
            .filter(|&(_, scored)| scored)
            .map(|(i, _)| i)
            .collect()
    }

    /// Number of frames: ⌈(END − START)·FPS⌉ (rounded to the nearest first when within
    /// 1e-4 of a whole number, so `0:2:30` is 60 frames).
    pub fn frame_count(&self) -> usize {
        let exact = f64::from(self.end_s - self.start_s) * f64::from(self.fps);
        let near = exact.round();
        let n = if (exact - near).abs() < 1e-4 {
            near
        } else {
            exact.ceil()
        };
        n.max(0.0) as usize
    }

    /// The instants of the frames (s).
    pub fn instants(&self) -> Vec<f32> {
        (0..self.frame_count())
            .map(|i| (f64::from(self.start_s) + i as f64 / f64::from(self.fps)) as f32)
            .collect()
    }
}

/// `animation.json`: one method on one animated scene over a sequence of instants.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AnimationResult {
    /// [`ANIMATION_SCHEMA_VERSION`].
    pub schema_version: u32,
    /// Source and profile of the binary.
    pub build: Build,
    /// Adapter and CPU.
    pub machine: Machine,
    /// The scene (its hash and time at the first instant).
    pub scene: SceneInfo,
    /// The method and its parameters.
    pub method: MethodRun,
    /// The sequence.
    pub sequence: AnimateSpec,
    /// Frames between scored instants.
    pub reference_every: u32,
    /// N of the N×N sub-pixel grid of the scored instants' scoring frames.
    pub score_grid: u32,
    /// The one exposure of the scored instants' PNGs and LDR FLIP: `--exposure`, else the
    /// first scored reference's 99th percentile (absent without a scored instant, and in
    /// files before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tone_map: Option<crate::result::ToneMapInfo>,
    /// Every frame, in time order.
    pub frames: Vec<AnimationFrame>,
    /// Per-pass GPU times over the sequence's timed frames (one per instant).
    pub timing: Timing,
    /// CPU wall time (ms) of each instant's rebuild (upload, the method's setup;
    /// pipelines only where compiled, see [`AnimationFrame::pipelines_compiled`]).
    pub rebuild_ms: Option<Summary>,
    /// The temporal error of each scored pair of consecutive instants.
    pub temporal: Vec<TemporalPair>,
    /// Root mean square of the pairs' `temporal_rel_rmse`.
    pub temporal_rel_rmse: Option<f64>,
    /// Root mean square of the pairs' `still_rel_rmse` (the same frames, still).
    pub still_rel_rmse: Option<f64>,
    /// Wall time of the whole sequence (s).
    pub wall_s: f64,
}

/// A sequence in one line: what `caustics animations`, `reproduce`'s summary and its
/// Bencher file show of it. Errors are means over the scored instants.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SequenceFigures {
    /// First instant (s).
    pub start_s: f32,
    /// End (s), not included.
    pub end_s: f32,
    /// Frames per second.
    pub fps: f32,
    /// Frames (instants) rendered.
    pub frames: usize,
    /// Frames between scored instants.
    pub reference_every: u32,
    /// Instants scored against a reference.
    pub scored: usize,
    /// Mean flux ratio of the scored instants.
    pub flux_ratio: Option<f64>,
    /// Mean relMSE of the scored instants.
    pub rel_mse: Option<f64>,
    /// Mean HDR-FLIP of the scored instants.
    pub hdr_flip: Option<f64>,
    /// RMS over the scored pairs of the temporal relRMSE.
    pub temporal_rel_rmse: Option<f64>,
    /// RMS over the scored pairs of the still relRMSE of the same frames.
    pub still_rel_rmse: Option<f64>,
    /// Mean change ratio Σ Δm² / Σ Δr² over the scored pairs.
    pub change_ratio: Option<f64>,
    /// CPU ms of each instant's rebuild: median (p10, p90).
    pub rebuild_ms: Option<crate::summary::Spread>,
    /// Wall time of the whole sequence (s).
    pub wall_s: f64,
}

impl SequenceFigures {
    /// The figures of a sequence.
    pub fn of(r: &AnimationResult) -> SequenceFigures {
        let scored: Vec<&Errors> = r.frames.iter().filter_map(|f| f.errors.as_ref()).collect();
        let mean = |v: Vec<f64>| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
        SequenceFigures {
            start_s: r.sequence.start_s,
            end_s: r.sequence.end_s,
            fps: r.sequence.fps,
            frames: r.frames.len(),
            reference_every: r.reference_every,
            scored: scored.len(),
            flux_ratio: mean(scored.iter().filter_map(|e| e.flux_ratio).collect()),
            rel_mse: mean(scored.iter().map(|e| e.rel_mse).collect()),
            hdr_flip: mean(scored.iter().filter_map(|e| e.hdr_flip).collect()),
            temporal_rel_rmse: r.temporal_rel_rmse,
            still_rel_rmse: r.still_rel_rmse,
            change_ratio: mean(
                r.temporal
                    .iter()
                    .filter_map(|p| p.error.change_ratio)
                    .collect(),
            ),
            rebuild_ms: r.rebuild_ms.as_ref().map(crate::summary::Spread::from),
            wall_s: r.wall_s,
        }
    }

    /// Table cells of the sequence and its errors, as every sequence table shows them:
    /// frames (span, rate), flux, relMSE, HDR-FLIP, temporal relRMSE, still relRMSE,
    /// change ratio.
    pub fn cells(&self) -> [String; 7] {
        [
            format!(
                "{} ({}–{} s, {} FPS)",
                self.frames, self.start_s, self.end_s, self.fps
            ),
            opt(self.flux_ratio, 3),
            self.rel_mse.map_or("–".into(), |v| format!("{v:.3e}")),
            opt(self.hdr_flip, 3),
            opt(self.temporal_rel_rmse, 4),
            opt(self.still_rel_rmse, 4),
            opt(self.change_ratio, 3),
        ]
    }

    /// The figures by their `bmf.json` measure names (finite ones only).
    pub fn measures(&self) -> Vec<(&'static str, f64)> {
        [
            ("sequence_flux_ratio", self.flux_ratio),
            ("sequence_rel_mse", self.rel_mse),
            ("sequence_hdr_flip", self.hdr_flip),
            ("temporal_rel_rmse", self.temporal_rel_rmse),
            ("still_rel_rmse", self.still_rel_rmse),
            ("change_ratio", self.change_ratio),
            ("rebuild_ms", self.rebuild_ms.map(|s| s.median)),
        ]
        .into_iter()
        .filter_map(|(k, v)| Some((k, v.filter(|v| v.is_finite())?)))
        .collect()
    }
}

/// One frame of a sequence.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AnimationFrame {
    /// Index in the sequence.
    pub index: usize,
    /// Instant (s).
    pub time_s: f32,
    /// Content hash of the scene posed at this instant.
    pub scene_hash: String,
    /// GPU time of the method's passes in the timed frame (ms).
    pub method_gpu_ms: Option<f64>,
    /// GPU time of the whole timed frame (ms).
    pub frame_gpu_ms: Option<f64>,
    /// CPU wall time of this instant's rebuild (ms).
    pub rebuild_ms: f64,
    /// Pipelines the rebuild compiled (the others were compiled at an earlier instant
    /// and reused; files before this field read 0).
    #[serde(default)]
    pub pipelines_compiled: u64,
    /// The method's counters at this instant (of its untimed count frame).
    pub counters: std::collections::BTreeMap<String, u64>,
    /// Surface-caustic errors of the pixel-averaged scoring frame against the reference
    /// at this instant (scored instants only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub errors: Option<Errors>,
    /// The reference it was scored against (cache folder).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<String>,
    /// `caustic_t<time>.png` written for this instant.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image: Option<String>,
}

/// The temporal error of two consecutive instants.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TemporalPair {
    /// First instant (s).
    pub from_s: f32,
    /// Second instant (s).
    pub to_s: f32,
    /// The errors.
    pub error: TemporalError,
}

/// The instants that are scored: every `every`-th, and the one after each (for the
/// temporal pair) when there is one.
fn scored_indices(n: usize, every: usize) -> Vec<(usize, bool)> {
    (0..n)
        .map(|i| {
            let first = i % every == 0;
            let second = i > 0 && (i - 1) % every == 0;
            (i, first || second)
        })
        .collect()
}

/// A scored instant's images, kept for the temporal pairs.
struct Scored {
    surface: HdrImage,
    reference: HdrImage,
    stderr: Option<HdrImage>,
}

/// Runs the sequence (see the module doc).
pub fn run_animated(o: &RunOptions, spec: &AnimateSpec, scene: Scene) -> Result<RunOutcome> {
    let started = std::time::Instant::now();
    crate::run::validate_options(o)?;
    let instants = spec.instants();
    let n = instants.len();
    let every = match o.reference_every {
        Some(0) => bail!("--reference-every: expected a positive number of frames, got 0"),
        Some(k) => k as usize,
        None => spec.default_reference_every() as usize,
    };
    if !scene.is_animated() {
        eprintln!(
            "note: {} does not move (no motion, no travelling waves): every frame is the same instant",
            scene.name
        );
    }
    let info = registry::find(&o.method)?;
    let params = crate::run::given_params(o)?;
    let parsed = (info.parse)(&params)?;
    // Every instant is posed before any GPU work, so a motion that leaves the coordinate
    // range fails before anything is written.
    let posed: Vec<Scene> = instants
        .iter()
        .map(|&t| {
            scene
                .at_time(t)
                .with_context(|| format!("--animate: posing {} at {t} s", scene.name))
        })
        .collect::<Result<_>>()?;
    // The method may see representative lights; the references are of the posed scene.
    let mut representative_lights = None;
    for s in &posed {
        let method_scene;
        (method_scene, representative_lights) =
            crate::run::scene_for_method(&info, s, o.representative_lights);
        if let Err(reason) = info.supports(&method_scene, &parsed) {
            return Ok(RunOutcome::Skipped {
                reason: format!("at {} s: {}", s.time, reason.0),
            });
        }
    }
    let ctx = GpuContext::new(&AdapterChoice::from_flag_or_env(o.adapter.as_deref()))?;
    eprintln!(
        "adapter: {} ({}, {}); {n} instants from {} s at {} FPS, scored every {every}",
        ctx.summary.name, ctx.summary.backend, ctx.summary.device_type, spec.start_s, spec.fps
    );
    let dir = o.out.join(&scene.name).join(&o.method).join("animation");
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let (w, h) = (scene.camera.width, scene.camera.height);

    let mut frames = Vec::with_capacity(n);
    let mut samples = Vec::with_capacity(n);
    let mut scored: Vec<Option<Scored>> = Vec::with_capacity(n);
    let mut tone: Option<ToneMap> = None;
    let bar = indicatif::ProgressBar::new(n as u64);
    for ((i, is_scored), posed_scene) in scored_indices(n, every).into_iter().zip(posed) {
        let t = posed_scene.time;
        let scene_hash = posed_scene.hash_hex();
        let reference = if is_scored {
            crate::run::load_reference(o, &posed_scene, false)?
        } else {
            None
        };
        let rebuild_started = std::time::Instant::now();
        let pipelines_before = ctx.pipeline_stats();
        // Part of the rebuild: a moving sphere light moves its representative lights.
        let (method_scene, _) =
            crate::run::scene_for_method(&info, &posed_scene, o.representative_lights);
        let gpu_scene = GpuScene::upload(&ctx, Arc::new(method_scene), Default::default())?;
        let renderer = Renderer::new(&ctx, gpu_scene, RendererOptions::default())?;
        let mut method = (info.create)(&ctx, &renderer, &parsed)?;
        let rebuild_ms = rebuild_started.elapsed().as_secs_f64() * 1e3;
        let pipelines_compiled = ctx.pipeline_stats().since(pipelines_before).compiled;
        // The untimed frame is a count frame: it takes the first use of the new
        // pipelines, and the counters are read after it (some methods count only in
        // count frames, e.g. pinhole's gather); then the timed frame.
        let mut profiler = PassProfiler::new(&ctx, 2);
        let mut frame = renderer.begin_frame(&mut profiler, FrameMode::Count)?;
        method.record(&mut frame)?;
        frame.submit(&ctx)?;
        let counters = method.counters(&ctx)?;
        let mut frame = renderer.begin_frame(&mut profiler, FrameMode::Timed)?;
        method.record(&mut frame)?;
        frame.submit(&ctx)?;
        let sample = profiler
            .collect(&ctx)?
            .pop()
            .context("the timed frame left no sample")?;
        let one = crate::run::timing(
            std::slice::from_ref(&sample),
            profiler.has_timestamps(),
            &o.method,
        );
        samples.push(sample);
        let mut frame = AnimationFrame {
            index: i,
            time_s: t,
            scene_hash,
            method_gpu_ms: one.method_gpu_ms.map(|s| s.median),
            frame_gpu_ms: one.frame_gpu_ms.map(|s| s.median),
            rebuild_ms,
            pipelines_compiled,
            counters,
            errors: None,
            reference: None,
            image: None,
        };
        match reference {
            Some(r) if is_scored => {
                let mut accumulator = caustics_gpu::ScoreAccumulator::new(&ctx, &renderer)?;
                let images = caustics_method::render_scoring_frame(
                    &ctx,
                    &renderer,
                    method.as_mut(),
                    &mut accumulator,
                    o.score_grid,
                    caustics_method::LightSide::Reuse,
                )?;
                let surface = HdrImage::from_rgba_f32(w, h, &images.surface)?;
                surface.check_finite("surface caustic image (scoring frame)")?;
                // One exposure for the whole sequence: the first scored reference's.
                let tone = *tone.get_or_insert_with(|| {
                    o.exposure.map(ToneMap::new).unwrap_or_else(|| {
                        ToneMap::fit_percentile(&r.surface, crate::run::EXPOSURE_PERCENTILE)
                    })
                });
                frame.errors = Some(caustics_metrics::all_errors(&surface, &r.surface, &tone)?);
                frame.reference = Some(machine::portable_path(&r.path));
                let name = format!("caustic_t{t:.3}.png");
                caustics_metrics::write_png(&dir.join(&name), &tone.apply(&surface))?;
                frame.image = Some(name);
                let stderr_path = r.path.with_file_name("stderr.exr");
                let stderr = stderr_path
                    .is_file()
                    .then(|| caustics_metrics::read_exr(&stderr_path))
                    .transpose()
                    .with_context(|| format!("reading {}", stderr_path.display()))?;
                scored.push(Some(Scored {
                    surface,
                    reference: r.surface,
                    stderr,
                }));
            }
            _ => scored.push(None),
        }
        frames.push(frame);
        bar.inc(1);
    }
    bar.finish_and_clear();

    let mut temporal = Vec::new();
    for i in 0..n.saturating_sub(1) {
        if i % every != 0 {
            continue;
        }
        if let (Some(a), Some(b)) = (&scored[i], &scored[i + 1]) {
            let stderr = a.stderr.as_ref().zip(b.stderr.as_ref());
            temporal.push(TemporalPair {
                from_s: instants[i],
                to_s: instants[i + 1],
                error: caustics_metrics::temporal_error(
                    &a.surface,
                    &b.surface,
                    &a.reference,
                    &b.reference,
                    stderr,
                )?,
            });
        }
    }
    let rms = |f: &dyn Fn(&TemporalPair) -> f64| -> Option<f64> {
        (!temporal.is_empty()).then(|| {
            (temporal.iter().map(|p| f(p).powi(2)).sum::<f64>() / temporal.len() as f64).sqrt()
        })
    };
    let rebuild: Vec<f64> = frames.iter().map(|f| f.rebuild_ms).collect();
    let has_timestamps = samples
        .iter()
        .any(|s| s.passes.iter().any(|p| p.gpu_ms.is_some()));
    let result = AnimationResult {
        schema_version: ANIMATION_SCHEMA_VERSION,
        build: machine::build(),
        machine: machine::machine(&ctx.summary),
        scene: SceneInfo {
            name: scene.name.clone(),
            file: machine::portable_path(&scene.source),
            hash: frames
                .first()
                .map(|f| f.scene_hash.clone())
                .unwrap_or_default(),
            width: w,
            height: h,
            time_s: Some(spec.start_s),
            representative_lights,
        },
        method: MethodRun {
            name: o.method.clone(),
            params,
        },
        sequence: *spec,
        reference_every: every as u32,
        score_grid: o.score_grid,
        tone_map: tone.map(|t| crate::result::ToneMapInfo {
            exposure_scale: t.exposure_scale,
            source: Some(
                if o.exposure.is_some() {
                    "--exposure"
                } else {
                    "reference p99"
                }
                .into(),
            ),
            volume_exposure_scale: None,
        }),
        timing: crate::run::timing(&samples, has_timestamps, &o.method),
        rebuild_ms: summarize(&rebuild),
        temporal_rel_rmse: rms(&|p| p.error.temporal_rel_rmse),
        still_rel_rmse: rms(&|p| p.error.still_rel_rmse),
        temporal,
        frames,
        wall_s: started.elapsed().as_secs_f64(),
    };
    caustics_metrics::atomic_write(
        &dir.join("animation.json"),
        &serde_json::to_vec_pretty(&result)?,
    )?;
    caustics_metrics::atomic_write(&dir.join("animation.md"), markdown(&result).as_bytes())?;
    Ok(RunOutcome::Animated {
        dir,
        result: Box::new(result),
    })
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("–".into(), |v| format!("{v:.digits$}"))
}

/// `animation.md`: the sequence's timings, the scored instants and the temporal pairs.
pub fn markdown(r: &AnimationResult) -> String {
    let mut s = String::new();
    let ms = |x: &Option<Summary>| {
        x.as_ref().map_or("–".into(), |s| {
            format!("{:.3} (p10 {:.3}, p90 {:.3})", s.median, s.p10, s.p90)
        })
    };
    let _ = writeln!(
        s,
        "# {} / {}: {} frames, {}–{} s at {} FPS\n",
        r.scene.name,
        r.method.name,
        r.frames.len(),
        r.sequence.start_s,
        r.sequence.end_s,
        r.sequence.fps
    );
    let _ = writeln!(
        s,
        "{} ({}), {} build {}{}. Every frame is a new instant: the scene posed, uploaded and the method created anew (its rebuild timed on the CPU; pipelines compiled once, at the first instant that needs them), one untimed frame, then the timed one. Scored every {} frames and the frame after (scoring grid {}×{}).\n",
        r.machine.adapter,
        r.machine.backend,
        r.build.profile,
        r.build.commit,
        if r.build.dirty { "+dirty" } else { "" },
        r.reference_every,
        r.score_grid,
        r.score_grid
    );
    let _ = writeln!(s, "| | median (p10, p90) |\n|---|---|");
    let _ = writeln!(s, "| method GPU ms | {} |", ms(&r.timing.method_gpu_ms));
    let _ = writeln!(s, "| frame GPU ms | {} |", ms(&r.timing.frame_gpu_ms));
    let _ = writeln!(s, "| rebuild CPU ms | {} |", ms(&r.rebuild_ms));
    let _ = writeln!(
        s,
        "| temporal relRMSE (RMS over pairs) | {} |",
        opt(r.temporal_rel_rmse, 4)
    );
    let _ = writeln!(
        s,
        "| still relRMSE of the same frames | {} |\n",
        opt(r.still_rel_rmse, 4)
    );
    if !r.temporal.is_empty() {
        let _ = writeln!(
            s,
            "## Temporal pairs\n\n| from s | to s | temporal relRMSE | still relRMSE | change ratio |\n|---|---|---|---|---|"
        );
        for p in &r.temporal {
            let _ = writeln!(
                s,
                "| {:.4} | {:.4} | {:.4} | {:.4} | {} |",
                p.from_s,
                p.to_s,
                p.error.temporal_rel_rmse,
                p.error.still_rel_rmse,
                opt(p.error.change_ratio, 3)
            );
        }
        let _ = writeln!(s);
    }
    let _ = writeln!(
        s,
        "## Frames\n\n| # | t s | method GPU ms | frame GPU ms | rebuild ms | pipelines compiled | flux | relMSE | HDR-FLIP |\n|---|---|---|---|---|---|---|---|---|"
    );
    for f in &r.frames {
        let e = f.errors.as_ref();
        let _ = writeln!(
            s,
            "| {} | {:.4} | {} | {} | {:.1} | {} | {} | {} | {} |",
            f.index,
            f.time_s,
            opt(f.method_gpu_ms, 3),
            opt(f.frame_gpu_ms, 3),
            f.rebuild_ms,
            f.pipelines_compiled,
            opt(e.and_then(|e| e.flux_ratio), 3),
            e.map_or("–".into(), |e| format!("{:.3e}", e.rel_mse)),
            opt(e.and_then(|e| e.hdr_flip), 3),
        );
    }
    s
}

/// Reads an `animation.json`.
pub fn load(path: &Path) -> Result<AnimationResult> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let de = &mut serde_json::Deserializer::from_str(&text);
    serde_path_to_error::deserialize(de)
        .map_err(|e| anyhow::anyhow!("{}: {}: {}", path.display(), e.path(), e.inner()))
}

/// Every `animation.json` under `dir` (any depth), sorted by scene, method, parameters.
pub fn find_all(dir: &Path) -> Result<Vec<AnimationResult>> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
        let entries =
            std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))?;
        for entry in entries {
            let path = entry?.path();
            if path.is_dir() {
                walk(&path, out)?;
            } else if path.file_name().is_some_and(|n| n == "animation.json") {
                out.push(path);
            }
        }
        Ok(())
    }
    let mut files = Vec::new();
    walk(dir, &mut files)?;
    let mut all = files.iter().map(|f| load(f)).collect::<Result<Vec<_>>>()?;
    all.sort_by_key(|r| {
        (
            r.scene.name.clone(),
            r.method.name.clone(),
            r.method.params.to_string(),
        )
    });
    Ok(all)
}

/// Sequences side by side: one row per sequence.
pub fn side_by_side(all: &[AnimationResult]) -> String {
    let mut s = String::new();
    let median = |x: &Option<Summary>| {
        x.as_ref().map_or("–".into(), |s| {
            format!("{:.2} ({:.2}–{:.2})", s.median, s.p10, s.p90)
        })
    };
    let _ = writeln!(
        s,
        "# Animated sequences side by side\n\nEvery frame a new instant (scene posed, uploaded, method created anew; its rebuild on the CPU apart, pipelines compiled once per sequence); GPU times are medians (p10–p90) of the timed frames, one per instant. Errors: means over the scored instants (pixel-averaged scoring frames against references at those instants). Temporal relRMSE: the method's frame-to-frame change against the reference's, RMS over the scored pairs, beside the same frames' still relRMSE; change ratio: Σ Δm² / Σ Δr² (1 = the method's image changes as much as the caustic's).\n"
    );
    let _ = writeln!(
        s,
        "| scene | method | parameters | frames | adapter | method GPU ms | frame GPU ms | rebuild CPU ms | flux | relMSE | HDR-FLIP | temporal relRMSE | still relRMSE | change ratio |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for r in all {
        let f = SequenceFigures::of(r);
        let params = match &r.method.params {
            serde_json::Value::Object(m) if m.is_empty() => "defaults".to_owned(),
            p => p.to_string(),
        };
        let [frames, errors @ ..] = f.cells();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {frames} | {} | {} | {} | {} | {} |",
            r.scene.name,
            r.method.name,
            params,
            r.machine.adapter,
            median(&r.timing.method_gpu_ms),
            median(&r.timing.frame_gpu_ms),
            median(&r.rebuild_ms),
            errors.join(" | "),
        );
    }
    s
}

/// Writes `<dir>/animations.md` from every sequence under `dir`; returns its path.
pub fn side_by_side_file(dir: &Path) -> Result<PathBuf> {
    let all = find_all(dir)?;
    if all.is_empty() {
        bail!(
            "{}: no animation.json below (run `caustics run --animate START:END:FPS --out {}` first)",
            dir.display(),
            dir.display()
        );
    }
    let path = dir.join("animations.md");
    caustics_metrics::atomic_write(&path, side_by_side(&all).as_bytes())?;
    Ok(path)
}

/// Every `animation.json` under `root`, keyed by its folder relative to `root`.
pub fn find_keyed(root: &Path) -> Result<std::collections::BTreeMap<String, AnimationResult>> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<(String, PathBuf)>) -> Result<()> {
        let entries =
            std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))?;
        for entry in entries {
            let path = entry?.path();
            if path.is_dir() {
                walk(root, &path, out)?;
            } else if path.file_name().is_some_and(|n| n == "animation.json") {
                let rel = path
                    .parent()
                    .and_then(|p| p.strip_prefix(root).ok())
                    .map(|p| p.display().to_string())
                    .unwrap_or_default();
                out.push((rel, path));
            }
        }
        Ok(())
    }
    let mut files = Vec::new();
    if root.is_dir() {
        walk(root, root, &mut files)?;
    }
    files
        .into_iter()
        .map(|(key, path)| Ok((key, load(&path)?)))
        .collect()
}

/// `caustics compare` of the sequences in BASE and NEW, paired by folder: their inputs
/// (scene, resolution, sequence, method, parameters, adapter) must match; then the
/// per-frame method GPU times (as every run's), the scored instants' mean relMSE and
/// the temporal and still relRMSE are gated with `--error-tolerance`.
pub(crate) fn compare_sequences(
    base: &std::collections::BTreeMap<String, AnimationResult>,
    new: &std::collections::BTreeMap<String, AnimationResult>,
    args: &crate::compare::CompareArgs,
    report: &mut crate::compare::Report,
) {
    use crate::compare::{Verdict, compare_timing, line};
    for (key, b) in base {
        let Some(n) = new.get(key) else {
            report.lines.push(line(
                key,
                "sequence",
                "present",
                "missing",
                "",
                Verdict::Regression,
            ));
            continue;
        };
        report.runs += 1;
        let inputs = |r: &AnimationResult| {
            let mut v = vec![
                ("scene", r.scene.name.clone()),
                (
                    "resolution",
                    format!("{}x{}", r.scene.width, r.scene.height),
                ),
                ("first instant's hash", r.scene.hash.clone()),
                (
                    "sequence",
                    format!(
                        "{}:{}:{} every {}, grid {}",
                        r.sequence.start_s,
                        r.sequence.end_s,
                        r.sequence.fps,
                        r.reference_every,
                        r.score_grid
                    ),
                ),
                ("method", r.method.name.clone()),
                ("parameters", r.method.params.to_string()),
            ];
            if !args.across_adapters {
                v.push((
                    "adapter",
                    format!("{} ({})", r.machine.adapter, r.machine.driver_info),
                ));
            }
            v
        };
        let differ: Vec<String> = inputs(b)
            .into_iter()
            .zip(inputs(n))
            .filter(|(x, y)| x.1 != y.1)
            .map(|(x, y)| format!("{}: {} → {}", x.0, x.1, y.1))
            .collect();
        if !differ.is_empty() {
            report.lines.push(line(
                key,
                "sequence",
                "",
                "",
                &differ.join("; "),
                Verdict::NotComparable,
            ));
            continue;
        }
        if let (Some(x), Some(y)) = (&b.timing.method_gpu_ms, &n.timing.method_gpu_ms) {
            let mut l = compare_timing(key, "method GPU ms (per instant)", x, y, args);
            if args.no_timings && l.verdict == Verdict::Regression {
                l.verdict = Verdict::Info;
            }
            report.lines.push(l);
        }
        let mean_rel_mse = |r: &AnimationResult| {
            let v: Vec<f64> = r
                .frames
                .iter()
                .filter_map(|f| f.errors.as_ref().map(|e| e.rel_mse))
                .collect();
            (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
        };
        for (measure, x, y) in [
            ("temporal relRMSE", b.temporal_rel_rmse, n.temporal_rel_rmse),
            (
                "still relRMSE (temporal pairs)",
                b.still_rel_rmse,
                n.still_rel_rmse,
            ),
            (
                "relMSE (scored instants, mean)",
                mean_rel_mse(b),
                mean_rel_mse(n),
            ),
        ] {
            let (Some(x), Some(y)) = (x, y) else {
                if x.is_some() {
                    report.lines.push(line(
                        key,
                        measure,
                        "present",
                        "absent",
                        "",
                        Verdict::Regression,
                    ));
                }
                continue;
            };
            let allowed = args.error_tolerance * x.abs();
            let verdict = if y > x + allowed {
                Verdict::Regression
            } else if y < x - allowed {
                Verdict::Better
            } else {
                Verdict::Same
            };
            let mut l = line(
                key,
                measure,
                &format!("{x:.4e}"),
                &format!("{y:.4e}"),
                &format!("{:+.1}%", 100.0 * (y / x.max(1e-300) - 1.0)),
                verdict,
            );
            l.detail = format!("tolerance {:.0}%", 100.0 * args.error_tolerance);
            l.band = Some(crate::compare::Band::Value {
                base: x,
                new: y,
                allowed,
            });
            report.lines.push(l);
        }
    }
    for key in new.keys().filter(|k| !base.contains_key(*k)) {
        report.lines.push(line(
            key,
            "sequence",
            "–",
            "present",
            "not in BASE",
            Verdict::New,
        ));
    }
}

/// The folder a sequence writes to.
pub fn animation_dir(out: &Path, scene: &str, method: &str) -> PathBuf {
    out.join(scene).join(method).join("animation")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_parse_and_count_their_frames() {
        let s = AnimateSpec::parse("0:2:30").expect("valid");
        assert_eq!(s.frame_count(), 60);
        let t = s.instants();
        assert_eq!(t.len(), 60);
        assert!((t[59] - 59.0 / 30.0).abs() < 1e-6);
        assert_eq!(
            AnimateSpec::parse("0.5:0.6:25")
                .expect("valid")
                .frame_count(),
            3
        );
        for (bad, says) in [
            ("0:2", "START:END:FPS"),
            ("0:x:30", "END: expected a finite number"),
            ("2:1:30", "END after START"),
            ("0:1:0", "FPS: expected a rate"),
            ("0:1000:1000", "1..=10000 frames"),
            ("0:1e9:1", "within"),
        ] {
            let err = AnimateSpec::parse(bad).expect_err(bad).to_string();
            assert!(
                err.contains(says) && err.contains("--animate"),
                "{bad}: {err}"
            );
        }
    }

    #[test]
    fn scored_instants_come_in_pairs() {
        let s: Vec<usize> = scored_indices(10, 4)
            .into_iter()
            .filter(|(_, scored)| *scored)
            .map(|(i, _)| i)
            .collect();
        assert_eq!(s, [0, 1, 4, 5, 8, 9]);
        assert!(scored_indices(3, 1).iter().all(|(_, s)| *s));
        // The instants whose references a sequence needs: 0:1:10 scored every 4th.
        let spec = AnimateSpec::parse("0:1:10").expect("valid");
        let t = spec.scored_instants(4);
        assert_eq!(t.len(), 6);
        for (have, want) in t.iter().zip([0.0, 0.1, 0.4, 0.5, 0.8, 0.9]) {
            assert!((have - want).abs() < 1e-6, "{t:?}");
        }
        assert_eq!(spec.default_reference_every(), 2);
    }
}
