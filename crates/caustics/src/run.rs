//! `caustics run`: render one scene with one method, measure it the same way as every
//! other method, score it against a reference, and write the results atomically.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result, bail};
use caustics_gpu::{
    AdapterChoice, FrameMode, GpuContext, GpuScene, PassProfiler, Renderer, RendererOptions,
};
use caustics_metrics::{HdrImage, ToneMap};
use caustics_scene::Scene;

use crate::result::{
    ErrorReport, Fragments, FrameCounts, Memory, MethodRun, PassFragments, PassTiming, RunResult,
    SCHEMA_VERSION, SceneInfo, Timing, ToneMapInfo,
};
use crate::stats::summarize;
use crate::{machine, registry};

/// Exit code of a run skipped because the method cannot render the scene.
pub const EXIT_SKIPPED: i32 = 3;

/// Everything `caustics run` takes (also its command-line flags).
#[derive(Clone, Debug, clap::Args)]
pub struct RunOptions {
    /// Built-in scene name (see `caustics list`) or path to a scene JSON file.
    #[arg(long)]
    pub scene: String,
    /// Method name (see `caustics list`).
    #[arg(long)]
    pub method: String,
    /// Method parameter, `key=value` (repeatable).
    #[arg(long = "param", value_name = "KEY=VALUE")]
    pub params: Vec<String>,
    /// Measured frames (timings are medians over these).
    #[arg(long, default_value_t = 20)]
    pub frames: u32,
    /// Warm-up frames before measuring.
    #[arg(long, default_value_t = 3)]
    pub warmup: u32,
    /// Reference surface caustic image (EXR) to score against.
    #[arg(long, value_name = "FILE.exr")]
    pub reference: Option<PathBuf>,
    /// Output root; results go under DIR/<scene>/<method>/.
    #[arg(long, value_name = "DIR", default_value = "results/runs")]
    pub out: PathBuf,
    /// Substring of the adapter name to use (default: CAUSTICS_ADAPTER, else the
    /// first hardware adapter, else lavapipe).
    #[arg(long)]
    pub adapter: Option<String>,
    /// Exposure scale of the tone-mapped PNGs and of FLIP: linear × scale, clamp, sRGB.
    #[arg(long, default_value_t = 2.0)]
    pub exposure: f32,
    /// Reference cache root; without --reference, a cached reference of this scene
    /// (same content hash and resolution) is used for errors.
    #[arg(long, value_name = "DIR", default_value = crate::references::DEFAULT_ROOT)]
    pub references: PathBuf,
}

/// How a run ended.
#[derive(Debug)]
pub enum RunOutcome {
    /// Results written to this folder.
    Done {
        /// `<out>/<scene>/<method>/`.
        dir: PathBuf,
        /// The result document.
        result: Box<RunResult>,
    },
    /// The method declared the scene out of reach; nothing was written.
    Skipped {
        /// Why.
        reason: String,
    },
}

/// Turns `key=value` flags into a JSON object. Values parse as JSON when they can
/// (numbers, booleans, quoted strings), else they are taken as strings.
pub fn parse_param_flags(flags: &[String]) -> Result<serde_json::Value> {
    let mut map = serde_json::Map::new();
    for flag in flags {
        let Some((key, value)) = flag.split_once('=') else {
            bail!("--param {flag:?}: expected key=value");
        };
        let key = key.trim();
        if key.is_empty() {
            bail!("--param {flag:?}: empty parameter name");
        }
        let value = serde_json::from_str(value.trim())
            .unwrap_or_else(|_| serde_json::Value::String(value.to_owned()));
        if map.insert(key.to_owned(), value).is_some() {
            bail!("--param {key} given twice");
        }
    }
    Ok(serde_json::Value::Object(map))
}

fn validate_options(o: &RunOptions) -> Result<()> {
    if o.frames == 0 || o.frames > 10_000 {
        bail!(
            "--frames: expected an integer in 1..=10000, got {}",
            o.frames
        );
    }
    if o.warmup > 10_000 {
        bail!(
            "--warmup: expected an integer in 0..=10000, got {}",
            o.warmup
        );
    }
    if !(o.exposure.is_finite() && o.exposure > 0.0) {
        bail!("--exposure: expected a positive number, got {}", o.exposure);
    }
    if let Some(r) = o.reference.as_ref().filter(|r| !r.is_file()) {
        bail!("--reference {}: no such file", r.display());
    }
    Ok(())
}

/// Runs the method on the scene. Everything the user gave is validated before any
/// GPU work or any write, so a bad input leaves earlier results untouched.
pub fn run(o: &RunOptions) -> Result<RunOutcome> {
    validate_options(o)?;
    let scene_path = caustics_scene::resolve(&o.scene)?;
    let scene = Scene::load(&scene_path)?;
    run_scene(o, scene)
}

/// [`run`] on a scene already loaded (and possibly changed, e.g. its camera's
/// resolution by `caustics reproduce`); `o.scene` is not read.
pub fn run_scene(o: &RunOptions, scene: Scene) -> Result<RunOutcome> {
    validate_options(o)?;
    let info = registry::find(&o.method)?;
    let params = parse_param_flags(&o.params)?;
    (info.validate_params)(&params)?;
    if let Err(reason) = info.supports(&scene, &params) {
        return Ok(RunOutcome::Skipped { reason: reason.0 });
    }
    let reference = load_reference(o, &scene, info.capabilities.volume)?;
    let ctx = GpuContext::new(&AdapterChoice::from_flag_or_env(o.adapter.as_deref()))?;
    eprintln!(
        "adapter: {} ({}, {}, driver {} {})",
        ctx.summary.name,
        ctx.summary.backend,
        ctx.summary.device_type,
        ctx.summary.driver,
        ctx.summary.driver_info
    );
    if ctx.summary.device_type == "Cpu" {
        eprintln!(
            "note: software adapter: absolute times are CPU times; compare ratios measured in one run"
        );
    }
    let scene = Arc::new(scene);
    let gpu_scene = GpuScene::upload(&ctx, scene.clone(), Default::default())?;
    let renderer = Renderer::new(&ctx, gpu_scene, RendererOptions::default())?;
    let mut method = (info.create)(&ctx, &renderer, &params)?;

    // Warm-up and timed frames with counting off, then one count frame.
    let mut profiler = PassProfiler::new(&ctx, o.warmup + o.frames + 1);
    for i in 0..o.warmup + o.frames + 1 {
        let mode = if i < o.warmup + o.frames {
            FrameMode::Timed
        } else {
            FrameMode::Count
        };
        let mut frame = renderer.begin_frame(&mut profiler, mode)?;
        method.record(&mut frame)?;
        frame.submit(&ctx)?;
    }
    let samples = profiler.collect(&ctx)?;
    let counters = method.counters(&ctx)?;
    // Methods report buffer overflow as counters named overflow_*; it is never silent.
    for (name, value) in counters
        .iter()
        .filter(|(n, v)| n.starts_with("overflow") && **v > 0)
    {
        eprintln!(
            "warning: {} overflowed its buffers ({name} = {value}); the image misses that work, raise the method's capacity parameter",
            info.name
        );
    }
    let fill = renderer.read_fill_counts(&ctx)?;
    let read = |t: &caustics_gpu::textures::Target, what: &str| -> Result<HdrImage> {
        let rgba = caustics_gpu::readback::read_rgba32f(&ctx, &t.texture, what)?;
        Ok(HdrImage::from_rgba_f32(
            t.texture.width(),
            t.texture.height(),
            &rgba,
        )?)
    };
    let targets = renderer.targets();
    let direct = read(&targets.direct, "direct image")?;
    let surface = read(&targets.surface, "surface caustic image")?;
    let volume = read(&targets.volume, "volume caustic image")?;
    surface.check_finite("surface caustic image")?;
    volume.check_finite("volume caustic image")?;

    let measured = &samples[o.warmup as usize..(o.warmup + o.frames) as usize];
    let count_frame = samples.last().context("no count frame recorded")?;
    let timing = timing(measured, profiler.has_timestamps(), &o.method);
    let fragments = fragments(count_frame, &fill, &o.method);

    let dir = o.out.join(&scene.name).join(&o.method);
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let tone = ToneMap {
        exposure_scale: o.exposure,
    };
    let mut images = BTreeMap::new();
    let mut write_exr = |name: &str, img: &HdrImage| -> Result<()> {
        caustics_metrics::write_exr(&dir.join(name), img)?;
        images.insert(name.trim_end_matches(".exr").to_owned(), name.to_owned());
        Ok(())
    };
    write_exr("surface.exr", &surface)?;
    if info.capabilities.volume {
        write_exr("volume.exr", &volume)?;
    }
    write_exr("direct.exr", &direct)?;
    let composite = direct.add(&surface)?.add(&volume)?;
    caustics_metrics::write_png(&dir.join("composite.png"), &tone.apply(&composite))?;
    images.insert("composite".into(), "composite.png".into());
    let (w, h) = (scene.camera.width, scene.camera.height);
    if fragments.is_some() || fill.iter().any(|&c| c > 0) {
        let heat = caustics_metrics::heatmap(&fill, w, h, &format!("{} fragments/px", o.method))?;
        caustics_metrics::write_png(&dir.join("fill_heatmap.png"), &heat)?;
        images.insert("fill_heatmap".into(), "fill_heatmap.png".into());
    }
    let errors = match &reference {
        Some(r) => {
            let surface_errors = caustics_metrics::all_errors(&surface, &r.surface, &tone)?;
            // Scale topped at the 99th percentile: cusps would otherwise black out the rest.
            let top = caustics_metrics::error_quantile(&surface, &r.surface, 0.99)?;
            let map = caustics_metrics::error_map_with_max(
                &surface,
                &r.surface,
                (top > 0.0).then_some(top),
            )?;
            caustics_metrics::write_png(&dir.join("error.png"), &map)?;
            images.insert("error".into(), "error.png".into());
            let volume_errors = match &r.volume {
                Some(v) => Some(caustics_metrics::all_errors(&volume, v, &tone)?),
                None => None,
            };
            Some(ErrorReport {
                reference: r.path.display().to_string(),
                reference_source: r.source.to_owned(),
                surface: surface_errors,
                volume: volume_errors,
                reference_noise_rms: reference_noise(&r.path)?,
            })
        }
        None => None,
    };

    let result = RunResult {
        schema_version: SCHEMA_VERSION,
        build: machine::build(),
        machine: machine::machine(&ctx.summary),
        scene: SceneInfo {
            name: scene.name.clone(),
            file: scene.source.display().to_string(),
            hash: scene.hash_hex(),
            width: w,
            height: h,
        },
        method: MethodRun {
            name: o.method.clone(),
            params,
        },
        frames: FrameCounts {
            warmup: o.warmup,
            measured: o.frames,
            count: 1,
        },
        timing,
        fragments,
        counters,
        gpu_memory_bytes: Memory {
            method: method.gpu_memory_bytes(),
            base: renderer.bytes(),
        },
        images,
        tone_map: ToneMapInfo {
            exposure_scale: o.exposure,
        },
        errors,
    };
    let json = serde_json::to_vec_pretty(&result)?;
    caustics_metrics::atomic_write(&dir.join("result.json"), &json)?;
    Ok(RunOutcome::Done {
        dir,
        result: Box::new(result),
    })
}

/// The reference images a run scores against.
struct LoadedReference {
    path: PathBuf,
    source: &'static str,
    surface: HdrImage,
    volume: Option<HdrImage>,
}

fn read_reference_image(p: &Path, scene: &Scene) -> Result<HdrImage> {
    let img = caustics_metrics::read_exr(p)
        .with_context(|| format!("reading reference {}", p.display()))?;
    let (w, h) = (scene.camera.width, scene.camera.height);
    if (img.width, img.height) != (w, h) {
        bail!(
            "--reference {}: expected a {w}x{h} image (the scene's camera), got {}x{}",
            p.display(),
            img.width,
            img.height
        );
    }
    img.check_finite(&p.display().to_string())?;
    Ok(img)
}

/// `--reference`, else the cached reference of the scene (said on stderr), else none.
fn load_reference(o: &RunOptions, scene: &Scene, volume: bool) -> Result<Option<LoadedReference>> {
    if let Some(p) = &o.reference {
        let surface = read_reference_image(p, scene)?;
        return Ok(Some(LoadedReference {
            path: p.clone(),
            source: "--reference",
            surface,
            volume: None,
        }));
    }
    let Some(cached) = crate::references::find(&o.references, scene)? else {
        return Ok(None);
    };
    eprintln!(
        "using cached reference {} ({} photons, mean relative standard error {:.2}%)",
        cached.dir.display(),
        cached.meta.photons,
        100.0 * cached.meta.relative_stderr
    );
    let surface = read_reference_image(&cached.caustic(), scene)?;
    let volume = match cached.volume().filter(|_| volume) {
        Some(p) => Some(read_reference_image(&p, scene)?),
        None => None,
    };
    Ok(Some(LoadedReference {
        path: cached.caustic(),
        source: "cache",
        surface,
        volume,
    }))
}

/// RMS of `stderr.exr` beside the reference, if present.
fn reference_noise(reference: &Path) -> Result<Option<f64>> {
    let Some(p) = reference
        .parent()
        .map(|d| d.join("stderr.exr"))
        .filter(|p| p.is_file())
    else {
        return Ok(None);
    };
    let img = caustics_metrics::read_exr(&p).with_context(|| format!("reading {}", p.display()))?;
    let n = (img.pixels.len() * 3).max(1) as f64;
    let sum: f64 = img
        .pixels
        .iter()
        .flat_map(|p| p.iter())
        .map(|&v| (v as f64) * (v as f64))
        .sum();
    Ok(Some((sum / n).sqrt()))
}

fn is_method_pass(name: &str, method: &str) -> bool {
    name.split('/').next() == Some(method)
}

/// Per-pass and per-owner time summaries over the measured frames.
fn timing(frames: &[caustics_gpu::FrameSample], available: bool, method: &str) -> Timing {
    let mut order: Vec<String> = Vec::new();
    let mut per_pass: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let (mut method_ms, mut base_ms, mut frame_ms, mut wall_ms) = (vec![], vec![], vec![], vec![]);
    let mut rejected = 0;
    for f in frames {
        rejected += f.rejected_timestamps;
        wall_ms.push(f.wall_ms);
        let mut sums: BTreeMap<&str, Option<f64>> = BTreeMap::new();
        for p in &f.passes {
            if !order.contains(&p.name) {
                order.push(p.name.clone());
            }
            let e = sums.entry(&p.name).or_insert(Some(0.0));
            *e = match (*e, p.gpu_ms) {
                (Some(a), Some(b)) => Some(a + b),
                _ => None,
            };
        }
        // A frame with a rejected timestamp contributes nothing to the totals it touches.
        let total = |pred: &dyn Fn(&str) -> bool| -> Option<f64> {
            sums.iter()
                .filter(|(n, _)| pred(n))
                .map(|(_, v)| *v)
                .sum::<Option<f64>>()
        };
        if let Some(v) = total(&|n| is_method_pass(n, method)) {
            method_ms.push(v);
        }
        if let Some(v) = total(&|n| !is_method_pass(n, method)) {
            base_ms.push(v);
        }
        if let Some(v) = total(&|_| true) {
            frame_ms.push(v);
        }
        for (n, v) in sums {
            if let Some(v) = v {
                per_pass.entry(n.to_owned()).or_default().push(v);
            }
        }
    }
    let passes = order
        .into_iter()
        .map(|name| PassTiming {
            gpu_ms: per_pass.get(&name).and_then(|s| summarize(s)),
            name,
        })
        .collect();
    let opt = |v: Vec<f64>| if available { summarize(&v) } else { None };
    Timing {
        timestamps_available: available,
        passes,
        method_gpu_ms: opt(method_ms),
        base_gpu_ms: opt(base_ms),
        frame_gpu_ms: opt(frame_ms),
        frame_wall_ms: summarize(&wall_ms),
        rejected_timestamps: rejected,
    }
}

/// Pipeline statistics per pass of the count frame, and the fill counts.
fn fragments(frame: &caustics_gpu::FrameSample, fill: &[u32], method: &str) -> Option<Fragments> {
    let mut passes: Vec<PassFragments> = Vec::new();
    for p in &frame.passes {
        let s = p.statistics?;
        match passes.iter_mut().find(|q| q.name == p.name) {
            Some(q) => {
                q.fragment_shader_invocations += s.fragment_invocations;
                q.primitives += s.primitives_out;
                q.vertex_shader_invocations += s.vertex_invocations;
                q.compute_shader_invocations += s.compute_invocations;
            }
            None => passes.push(PassFragments {
                name: p.name.clone(),
                fragment_shader_invocations: s.fragment_invocations,
                primitives: s.primitives_out,
                vertex_shader_invocations: s.vertex_invocations,
                compute_shader_invocations: s.compute_invocations,
            }),
        }
    }
    let method_total = passes
        .iter()
        .filter(|p| is_method_pass(&p.name, method))
        .map(|p| p.fragment_shader_invocations)
        .sum();
    Some(Fragments {
        passes,
        method_total,
        fill_total: fill.iter().map(|&c| c as u64).sum(),
        fill_max: fill.iter().copied().max().unwrap_or(0),
        fill_covered_pixels: fill.iter().filter(|&&c| c > 0).count() as u64,
        fill_histogram: caustics_metrics::histogram(fill),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn param_flags_parse_json_values_and_reject_junk() {
        let v = parse_param_flags(&["grid=64".into(), "hull=tight".into(), "on=true".into()])
            .expect("valid");
        assert_eq!(
            v,
            serde_json::json!({"grid": 64, "hull": "tight", "on": true})
        );
        assert!(parse_param_flags(&["grid".into()]).is_err());
        assert!(parse_param_flags(&["=3".into()]).is_err());
        assert!(parse_param_flags(&["a=1".into(), "a=2".into()]).is_err());
    }
}
