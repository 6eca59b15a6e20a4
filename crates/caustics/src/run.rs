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
    ErrorReport, Fragments, FrameCounts, Instrumentation, Memory, MethodRun, PassFragments,
    PassTiming, RunResult, RunWall, SCHEMA_VERSION, SceneInfo, ScoringInfo, Timing, ToneMapInfo,
};
use crate::stats::summarize;
use crate::{machine, registry};

/// Exit code of a run skipped because the method cannot render the scene.
pub const EXIT_SKIPPED: i32 = 3;

/// Default N of the N×N scoring grid (16 samples per pixel, DESIGN "Measuring honestly").
pub const DEFAULT_SCORE_GRID: u32 = 4;

/// Everything `caustics run` takes (also its command-line flags).
#[derive(Clone, Debug, clap::Args)]
pub struct RunOptions {
    /// Built-in scene name (see `caustics list`) or path to a scene JSON file.
    #[arg(long)]
    pub scene: String,
    /// Method name (see `caustics list`).
    #[arg(long)]
    pub method: String,
    /// Method parameter, `key=value` (repeatable); the value is read as JSON
    /// (`grid=64`, `hull="tight"` or `hull=tight`).
    #[arg(long = "param", value_name = "KEY=VALUE")]
    pub params: Vec<String>,
    /// Parameters given as typed JSON values (experiments); merged with `params`.
    #[arg(skip)]
    pub param_values: serde_json::Map<String, serde_json::Value>,
    /// Limits on the scene's meshes (`--max-scene-triangles` etc.).
    #[command(flatten)]
    pub limits: crate::limits_args::LimitArgs,
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
    /// Exposure scale of the tone-mapped PNGs and of LDR FLIP: linear × scale, clamp,
    /// sRGB. Default: the reference surface caustic's 99th-percentile luminance maps to
    /// white (the same for every method on a scene), else the run's own composite's.
    #[arg(long)]
    pub exposure: Option<f32>,
    /// N of the N×N sub-pixel camera offsets averaged in the scoring frame, after the
    /// timed frames (the reference is a pixel-area average; 1 scores the pixel centre,
    /// as the timed frames sample it). Timed frames stay one sample per pixel.
    #[arg(long, default_value_t = DEFAULT_SCORE_GRID, value_name = "N")]
    pub score_grid: u32,
    /// Reference cache root; without --reference, a cached reference of this scene
    /// (same content hash and resolution) is used for errors.
    #[arg(long, value_name = "DIR", default_value = crate::references::DEFAULT_ROOT)]
    pub references: PathBuf,
    /// Without --reference and with no cached reference of the scene at this resolution,
    /// first render a quick one of N photons (seed 1; rounded up to whole work units) into
    /// the cache, so that the run is
    /// scored (its noise is in the errors' σ_ref; `caustics reference --photons` renders
    /// a converged one over it). 0: render none, the run then has no errors.
    #[arg(long, value_name = "N", default_value_t = QUICK_REFERENCE_PHOTONS)]
    pub quick_reference_photons: u64,
    /// Ceilings records (`caustics ceilings`); the adapter's record there, when one
    /// exists, gives every pass its roofline in result.json.
    #[arg(long, value_name = "DIR", default_value = crate::ceilings_cmd::DEFAULT_ROOT)]
    pub ceilings: PathBuf,
    /// Render at this camera resolution instead of the scene file's (`WIDTHxHEIGHT`,
    /// e.g. `256x192`; the reference cache keys the resolution).
    #[arg(long, value_name = "WxH")]
    pub resolution: Option<String>,
    /// Render the scene at this instant (seconds; default: the file's `"time"`, else 0).
    /// Only an animated scene (moving objects or lights, travelling waves) changes.
    #[arg(long, value_name = "SECONDS", conflicts_with = "animate")]
    pub time: Option<f32>,
    /// Render a sequence instead: instants START, START + 1/FPS, … before END, each a
    /// new scene and a new method (nothing carried from the previous frame), one timed
    /// frame each after an untimed one; errors against references at every
    /// `--reference-every`-th instant and the temporal error at the instant after each
    /// (`animation.json`, `animation.md`).
    #[arg(long, value_name = "START:END:FPS")]
    pub animate: Option<String>,
    /// With `--animate`: frames between scored instants (default: a quarter of the
    /// sequence, so 4 scored instants).
    #[arg(long, value_name = "K", requires = "animate")]
    pub reference_every: Option<u32>,
    /// Render each extended light the method does not take (a sphere or environment
    /// light, outside pinhole) as at most N lights without extent: a sphere light as N
    /// point lights inside its ball, an environment by median cut as N directional
    /// lights (`Light::representative`). Errors stay against the reference of the true
    /// light. 0: such a method declines the scene.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub representative_lights: u32,
    /// Also time the frame without instrumentation: after each timed frame, the same
    /// frame again with no timestamp or statistics queries, and result.json's
    /// `instrumentation` compares their CPU wall times (record, submit, wait).
    #[arg(long)]
    pub instrumentation_overhead: bool,
}

/// Mean relative standard error per caustic pixel above which `run` says its reference
/// is noisy (a quick reference at 1024×768 has ~30%).
const NOISY_REFERENCE: f64 = 0.1;

/// Photons of the quick reference `caustics run` renders when the cache has none: about
/// 3 s on 2 cores for water_pool at 1024×768 (mean relative standard error 30% per
/// caustic pixel: a first look, which the run says is noisy), ~25 s for the
/// 20k-triangle bumpy_glass.
pub const QUICK_REFERENCE_PHOTONS: u64 = 20_000_000;

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
    /// An animated sequence (`--animate`) written to this folder.
    Animated {
        /// `<out>/<scene>/<method>/animation/`.
        dir: PathBuf,
        /// The sequence's document.
        result: Box<crate::animate::AnimationResult>,
    },
    /// The method declared the scene out of reach; nothing was written.
    Skipped {
        /// Why.
        reason: String,
    },
}

/// `WIDTHxHEIGHT` of `--resolution`, each side in 1..=16384.
pub fn parse_resolution(text: &str) -> Result<(u32, u32)> {
    let parsed = text
        .split_once(['x', 'X'])
        .and_then(|(w, h)| Some((w.trim().parse::<u32>().ok()?, h.trim().parse::<u32>().ok()?)));
    match parsed {
        Some((w, h)) if (1..=16384).contains(&w) && (1..=16384).contains(&h) => Ok((w, h)),
        _ => {
            bail!("--resolution {text:?}: expected WIDTHxHEIGHT, each in 1..=16384 (e.g. 256x192)")
        }
    }
}

/// Turns `key=value` flags into a JSON object. Values parse as JSON when they can
/// (numbers, booleans, quoted strings), else they are taken as strings.
pub fn parse_param_flags(flags: &[String]) -> Result<serde_json::Map<String, serde_json::Value>> {
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
    Ok(map)
}

/// The parameters a run was given: the typed values, then the `--param` flags (a key
/// given both ways is an error).
pub(crate) fn given_params(o: &RunOptions) -> Result<serde_json::Value> {
    let mut map = o.param_values.clone();
    for (k, v) in parse_param_flags(&o.params)? {
        if map.insert(k.clone(), v).is_some() {
            bail!("--param {k} is also given as a typed value");
        }
    }
    Ok(serde_json::Value::Object(map))
}

pub(crate) fn validate_options(o: &RunOptions) -> Result<()> {
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
    if let Some(e) = o.exposure.filter(|e| !(e.is_finite() && *e > 0.0)) {
        bail!("--exposure: expected a positive number, got {e}");
    }
    let max_grid = caustics_gpu::scoring::MAX_SCORE_GRID;
    if o.score_grid == 0 || o.score_grid > max_grid {
        bail!(
            "--score-grid: expected an integer in 1..={max_grid} (N of N×N sub-pixel offsets), got {}",
            o.score_grid
        );
    }
    let max_lights = caustics_scene::MAX_REPRESENTATIVE_LIGHTS;
    if o.representative_lights > max_lights {
        bail!(
            "--representative-lights: expected an integer in 0..={max_lights} (0: decline extended lights), got {}",
            o.representative_lights
        );
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
    let animate = o
        .animate
        .as_deref()
        .map(crate::animate::AnimateSpec::parse)
        .transpose()?;
    let resolution = o.resolution.as_deref().map(parse_resolution).transpose()?;
    let scene_path = caustics_scene::resolve(&o.scene)?;
    let mut scene = Scene::load_with_limits(&scene_path, &o.limits.limits())?;
    if let Some((w, h)) = resolution {
        (scene.camera.width, scene.camera.height) = (w, h);
    }
    if let Some(spec) = animate {
        return crate::animate::run_animated(o, &spec, scene);
    }
    let scene = match o.time {
        Some(t) => scene
            .at_time(t)
            .with_context(|| format!("--time {t}: posing {}", scene_path.display()))?,
        None => scene,
    };
    run_scene(o, scene)
}

/// The scene the method renders: `scene` with each extended light the method does not
/// take swapped for `count` representative lights ([`Light::representative`]), and
/// `Some(count)` when any was; `scene` itself (and `None`) when `count` is 0 or every
/// light is one the method takes.
///
/// [`Light::representative`]: caustics_scene::Light::representative
pub(crate) fn scene_for_method(
    info: &caustics_method::MethodInfo,
    scene: &Scene,
    count: u32,
) -> (Scene, Option<u32>) {
    use caustics_scene::Light;
    let caps = &info.capabilities;
    let replace = |l: &Light| match l {
        Light::Sphere { .. } => !caps.sphere_light,
        Light::Environment { .. } => !caps.environment_light,
        _ => false,
    };
    if count == 0 || !scene.lights.iter().any(replace) {
        return (scene.clone(), None);
    }
    (
        scene.with_representative_lights(count, replace),
        Some(count),
    )
}

/// [`run`] on a scene already loaded (and possibly changed, e.g. its camera's
/// resolution by `caustics reproduce`); `o.scene` is not read.
pub fn run_scene(o: &RunOptions, scene: Scene) -> Result<RunOutcome> {
    let started = std::time::Instant::now();
    validate_options(o)?;
    let info = registry::find(&o.method)?;
    let params = given_params(o)?;
    // Parsed and checked once; the method receives its own typed struct.
    let parsed = (info.parse)(&params)?;
    // The method may see representative lights; the reference is always of `scene`.
    let (method_scene, representative_lights) =
        scene_for_method(&info, &scene, o.representative_lights);
    if let Err(reason) = info.supports(&method_scene, &parsed) {
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
    let gpu_scene = GpuScene::upload(&ctx, Arc::new(method_scene), Default::default())?;
    let renderer = Renderer::new(&ctx, gpu_scene, RendererOptions::default())?;
    let mut method = (info.create)(&ctx, &renderer, &parsed)?;

    // Warm-up and timed frames with counting off, then one count frame. With
    // --instrumentation-overhead each timed frame is followed by a bare one: the same
    // frame with no queries at all, so the two alternate and share the machine's state.
    let frames_started = std::time::Instant::now();
    let setup_s = (frames_started - started).as_secs_f64();
    let mut profiler = PassProfiler::new(&ctx, o.warmup + o.frames + 1);
    let mut bare_profiler = PassProfiler::unmeasured(o.frames);
    for i in 0..o.warmup + o.frames + 1 {
        let mode = if i < o.warmup + o.frames {
            FrameMode::Timed
        } else {
            FrameMode::Count
        };
        let mut frame = renderer.begin_frame(&mut profiler, mode)?;
        method.record(&mut frame)?;
        frame.submit(&ctx)?;
        if o.instrumentation_overhead && mode == FrameMode::Timed && i >= o.warmup {
            // The timed frame's query resolution (its own small submission after the
            // frame's wall time was taken) finishes first, so neither frame pays for it.
            ctx.wait_idle()?;
            let mut frame = renderer.begin_frame(&mut bare_profiler, FrameMode::Timed)?;
            method.record(&mut frame)?;
            frame.submit(&ctx)?;
            ctx.wait_idle()?;
        }
    }
    let samples = profiler.collect(&ctx)?;
    let bare_wall_ms: Vec<f64> = bare_profiler
        .collect(&ctx)?
        .iter()
        .map(|f| f.wall_ms)
        .collect();
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
    let (w, h) = (scene.camera.width, scene.camera.height);
    let image = |rgba: &[f32], what: &str| -> Result<HdrImage> {
        let img = HdrImage::from_rgba_f32(w, h, rgba)?;
        img.check_finite(what)?;
        Ok(img)
    };
    // The timed frame's image (the count frame renders the same image as every timed
    // frame): one sample at each pixel centre.
    let targets = renderer.targets();
    let read = |t: &caustics_gpu::textures::Target, what: &str| -> Result<HdrImage> {
        image(
            &caustics_gpu::readback::read_rgba32f(&ctx, &t.texture, what)?,
            what,
        )
    };
    let surface_1spp = read(&targets.surface, "surface caustic image (timed frame)")?;
    let volume_1spp = read(&targets.volume, "volume caustic image (timed frame)")?;

    // The scoring frame: N×N sub-pixel offsets averaged, outside the timed frames.
    let score_started = std::time::Instant::now();
    let frames_s = (score_started - frames_started).as_secs_f64();
    let mut accumulator = caustics_gpu::ScoreAccumulator::new(&ctx, &renderer)?;
    let scored = caustics_method::render_scoring_frame(
        &ctx,
        &renderer,
        method.as_mut(),
        &mut accumulator,
        o.score_grid,
        caustics_method::LightSide::Reuse,
    )?;
    let scoring = ScoringInfo {
        grid: o.score_grid,
        samples_per_pixel: scored.frames,
        wall_ms: score_started.elapsed().as_secs_f64() * 1e3,
    };
    let direct = image(&scored.direct, "direct image (scoring frame)")?;
    let surface = image(&scored.surface, "surface caustic image (scoring frame)")?;
    let volume = image(&scored.volume, "volume caustic image (scoring frame)")?;
    drop(accumulator);

    let measured = &samples[o.warmup as usize..(o.warmup + o.frames) as usize];
    let count_frame = samples.last().context("no count frame recorded")?;
    let timing = timing(measured, profiler.has_timestamps(), &o.method);
    let fragments = fragments(count_frame, &fill, &o.method);
    let instrumentation = instrumentation(measured, count_frame, &bare_wall_ms);
    let run_machine = machine::machine(&ctx.summary);
    let roofline = crate::roofline::for_run(&o.ceilings, &run_machine, &timing, count_frame)?;
    if roofline.is_none() && timing.timestamps_available {
        eprintln!(
            "note: no ceilings record of this adapter in {}: passes are not read against its ceilings (`caustics ceilings` measures them, in seconds)",
            o.ceilings.display()
        );
    }

    let dir = o.out.join(&scene.name).join(&o.method);
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let composite = direct.add(&surface)?.add(&volume)?;
    let (tone, tone_source) = match (o.exposure.or(scene.camera.exposure), &reference) {
        (Some(e), _) if o.exposure.is_some() => (ToneMap::new(e), "--exposure"),
        (Some(e), _) => (ToneMap::new(e), "scene camera.exposure"),
        (None, Some(r)) => (
            ToneMap::fit_percentile(&r.surface, EXPOSURE_PERCENTILE),
            "reference p99",
        ),
        (None, None) => (
            ToneMap::fit_percentile(&composite, EXPOSURE_PERCENTILE),
            "image p99",
        ),
    };
    let volume_tone = reference
        .as_ref()
        .and_then(|r| r.volume.as_ref())
        .map(|v| ToneMap::fit_percentile(v, EXPOSURE_PERCENTILE));
    let mut images = BTreeMap::new();
    let mut write_exr = |name: &str, img: &HdrImage| -> Result<()> {
        caustics_metrics::write_exr(&dir.join(name), img)?;
        images.insert(name.trim_end_matches(".exr").to_owned(), name.to_owned());
        Ok(())
    };
    write_exr("surface.exr", &surface)?;
    write_exr("surface_1spp.exr", &surface_1spp)?;
    if info.capabilities.volume {
        write_exr("volume.exr", &volume)?;
        write_exr("volume_1spp.exr", &volume_1spp)?;
    }
    write_exr("direct.exr", &direct)?;
    caustics_metrics::write_png(&dir.join("composite.png"), &tone.apply(&composite))?;
    images.insert("composite".into(), "composite.png".into());
    // The caustic alone (surface + volume) at the composite's exposure: what figures put
    // beside the reference's caustic.
    caustics_metrics::write_png(
        &dir.join("caustic.png"),
        &tone.apply(&surface.add(&volume)?),
    )?;
    images.insert("caustic".into(), "caustic.png".into());
    if fragments.is_some() || fill.iter().any(|&c| c > 0) {
        let heat = caustics_metrics::heatmap(&fill, w, h, &format!("{} fragments/px", o.method))?;
        caustics_metrics::write_png(&dir.join("fill_heatmap.png"), &heat)?;
        images.insert("fill_heatmap".into(), "fill_heatmap.png".into());
        // The exact counts, for figures that put several runs on one colour scale.
        caustics_metrics::write_counts_png(&dir.join("fill_counts.png"), &fill, w, h)?;
        images.insert("fill_counts".into(), "fill_counts.png".into());
    }
    let errors_started = std::time::Instant::now();
    let (errors, errors_1spp) = match &reference {
        Some(r) => {
            let noise = reference_noise(&r.path)?;
            let score = |surface: &HdrImage, volume: &HdrImage| -> Result<ErrorReport> {
                let volume_errors = match (&r.volume, &volume_tone) {
                    (Some(v), Some(vt)) => Some(caustics_metrics::all_errors(volume, v, vt)?),
                    _ => None,
                };
                Ok(ErrorReport {
                    reference: r.name.clone(),
                    reference_source: r.source.to_owned(),
                    surface: caustics_metrics::all_errors(surface, &r.surface, &tone)?,
                    volume: volume_errors,
                    reference_noise_rms: noise,
                })
            };
            write_error_maps(&dir, &surface, &r.surface, "error", &mut images)?;
            if let Some(v) = r.volume.as_ref().filter(|_| info.capabilities.volume) {
                write_error_maps(&dir, &volume, v, "volume_error", &mut images)?;
            }
            // The two scorings are independent (each mostly single-threaded FLIP).
            let (pixel_averaged, one_spp) = rayon::join(
                || score(&surface, &volume),
                || score(&surface_1spp, &volume_1spp),
            );
            (Some(pixel_averaged?), Some(one_spp?))
        }
        None => {
            eprintln!(
                "note: no reference for {} at {w}x{h}: no errors (render one with `caustics reference --scene {}`)",
                scene.name, o.scene
            );
            (None, None)
        }
    };

    let errors_s = errors_started.elapsed().as_secs_f64();
    let total_s = started.elapsed().as_secs_f64();
    let scoring_frame_s = scoring.wall_ms / 1e3;
    let wall = RunWall {
        total_s,
        setup_s,
        frames_s,
        scoring_frame_s,
        errors_s,
        // The rest: images converted and written, rooflines, tone maps.
        writing_s: (total_s - setup_s - frames_s - scoring_frame_s - errors_s).max(0.0),
    };
    let result = RunResult {
        schema_version: SCHEMA_VERSION,
        build: machine::build(),
        machine: run_machine,
        scene: SceneInfo {
            name: scene.name.clone(),
            file: machine::portable_path(&scene.source),
            hash: scene.hash_hex(),
            width: w,
            height: h,
            time_s: scene.is_animated().then_some(scene.time),
            representative_lights,
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
            exposure_scale: tone.exposure_scale,
            source: Some(tone_source.to_owned()),
            volume_exposure_scale: volume_tone.map(|t| t.exposure_scale),
        },
        scoring: Some(scoring),
        errors,
        errors_1spp,
        roofline,
        instrumentation,
        wall: Some(wall),
    };
    let json = serde_json::to_vec_pretty(&result)?;
    caustics_metrics::atomic_write(&dir.join("result.json"), &json)?;
    Ok(RunOutcome::Done {
        dir,
        result: Box::new(result),
    })
}

/// Percentile of the reference's luminance that the default exposure maps to white.
pub(crate) const EXPOSURE_PERCENTILE: f64 = 0.99;

/// The error maps of a scored image against its reference: `<stem>.png`, signed
/// (method − reference luminance, W·m⁻²·sr⁻¹, blue too dark, red too bright) and
/// `<stem>_relative.png` ((t − r)/r, ±100 %). The signed map's range is the reference's
/// 99th-percentile luminance, so every method's map of one scene shares one scale.
fn write_error_maps(
    dir: &Path,
    test: &HdrImage,
    reference: &HdrImage,
    stem: &str,
    images: &mut BTreeMap<String, String>,
) -> Result<()> {
    let scale = 1.0 / ToneMap::fit_percentile(reference, EXPOSURE_PERCENTILE).exposure_scale;
    let maps = [
        (
            stem.to_owned(),
            caustics_metrics::signed_error_map(test, reference, Some(scale))?,
        ),
        (
            format!("{stem}_relative"),
            caustics_metrics::relative_error_map(test, reference, None)?,
        ),
    ];
    for (name, map) in maps {
        let file = format!("{name}.png");
        caustics_metrics::write_png(&dir.join(&file), &map)?;
        images.insert(name, file);
    }
    Ok(())
}

/// The reference images a run scores against.
pub(crate) struct LoadedReference {
    pub(crate) path: PathBuf,
    /// How `result.json` names it (`ErrorReport::reference`).
    pub(crate) name: String,
    pub(crate) source: &'static str,
    pub(crate) surface: HdrImage,
    pub(crate) volume: Option<HdrImage>,
}

pub(crate) fn read_reference_image(p: &Path, scene: &Scene) -> Result<HdrImage> {
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
pub(crate) fn load_reference(
    o: &RunOptions,
    scene: &Scene,
    volume: bool,
) -> Result<Option<LoadedReference>> {
    if let Some(p) = &o.reference {
        let surface = read_reference_image(p, scene)?;
        return Ok(Some(LoadedReference {
            path: p.clone(),
            name: machine::portable_path(p),
            source: "--reference",
            surface,
            volume: None,
        }));
    }
    let cached = match crate::references::find(&o.references, scene)? {
        Some(c) => c,
        None if o.quick_reference_photons > 0 => {
            render_quick_reference(o, scene)?;
            crate::references::find(&o.references, scene)?
                .context("the quick reference just rendered is not in the cache")?
        }
        None => return Ok(None),
    };
    eprintln!(
        "using cached reference {} ({} photons, mean relative standard error {:.2}%)",
        cached.dir.display(),
        cached.meta.photons,
        100.0 * cached.meta.relative_stderr
    );
    if cached.meta.relative_stderr > NOISY_REFERENCE {
        eprintln!(
            "note: that reference is noisy ({:.0}% mean relative standard error per caustic pixel): the errors below include its noise; `caustics reference --scene {} --photons 200000000` renders a converged one over it",
            100.0 * cached.meta.relative_stderr,
            o.scene
        );
    }
    let surface = read_reference_image(&cached.caustic(), scene)?;
    let volume = match cached.volume().filter(|_| volume) {
        Some(p) => Some(read_reference_image(&p, scene)?),
        None => None,
    };
    Ok(Some(LoadedReference {
        path: cached.caustic(),
        name: cached.caustic_key(),
        source: "cache",
        surface,
        volume,
    }))
}

/// Renders the quick reference of `scene` into the cache (see
/// [`RunOptions::quick_reference_photons`]), saying so.
fn render_quick_reference(o: &RunOptions, scene: &Scene) -> Result<()> {
    let dir = crate::references::cache_dir(&o.references, scene);
    let photons = o.quick_reference_photons;
    eprintln!(
        "no reference of {} at {}x{} in {}: rendering a quick one ({photons} photons, seed 1) so that this run is scored (--quick-reference-photons 0 skips it; `caustics reference --scene {} --photons 200000000` renders a converged one over it)",
        scene.name,
        scene.camera.width,
        scene.camera.height,
        o.references.display(),
        o.scene
    );
    // A killed render's temporaries (the cache is shared: only dead writers' go).
    crate::resume::remove_temp_files(&dir, false)?;
    let start = std::time::Instant::now();
    let bar = crate::reference_cmd::progress_bar(Some(photons));
    let tick = |done: u64| bar.set_position(done);
    let rel = crate::reference_cmd::render_into(&dir, scene, photons, 1, 16, &tick)
        .with_context(|| format!("rendering the quick reference of {}", scene.name))?;
    bar.finish_and_clear();
    eprintln!(
        "quick reference rendered in {:.1} s, mean relative standard error {:.1}% -> {}",
        start.elapsed().as_secs_f64(),
        100.0 * rel,
        dir.display()
    );
    Ok(())
}

/// RMS of `stderr.exr` beside the reference, if present.
pub(crate) fn reference_noise(reference: &Path) -> Result<Option<f64>> {
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

pub(crate) fn is_method_pass(name: &str, method: &str) -> bool {
    name.split('/').next() == Some(method)
}

/// Per-pass and per-owner time summaries over the measured frames.
pub(crate) fn timing(
    frames: &[caustics_gpu::FrameSample],
    available: bool,
    method: &str,
) -> Timing {
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

/// The timed and count frames' wall times against the bare frames' (none without
/// `--instrumentation-overhead`).
fn instrumentation(
    measured: &[caustics_gpu::FrameSample],
    count_frame: &caustics_gpu::FrameSample,
    bare_wall_ms: &[f64],
) -> Option<Instrumentation> {
    let bare = summarize(bare_wall_ms)?;
    let timed: Vec<f64> = measured.iter().map(|f| f.wall_ms).collect();
    let timed = summarize(&timed)?;
    Some(Instrumentation {
        overhead: timed.median / bare.median - 1.0,
        count_frame_overhead: count_frame.wall_ms / bare.median - 1.0,
        timed_wall_ms: timed,
        bare_wall_ms: bare,
        count_wall_ms: count_frame.wall_ms,
    })
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
    fn resolutions_parse_or_name_the_flag() {
        assert_eq!(parse_resolution("256x192").ok(), Some((256, 192)));
        assert_eq!(parse_resolution("64X48").ok(), Some((64, 48)));
        for bad in ["256", "0x10", "10x99999", "axb", ""] {
            let err = parse_resolution(bad).expect_err(bad).to_string();
            assert!(err.contains("--resolution"), "{bad}: {err}");
        }
    }

    #[test]
    fn param_flags_parse_json_values_and_reject_junk() {
        let v = parse_param_flags(&["grid=64".into(), "hull=tight".into(), "on=true".into()])
            .expect("valid");
        assert_eq!(
            serde_json::Value::Object(v),
            serde_json::json!({"grid": 64, "hull": "tight", "on": true})
        );
        assert!(parse_param_flags(&["grid".into()]).is_err());
        assert!(parse_param_flags(&["=3".into()]).is_err());
        assert!(parse_param_flags(&["a=1".into(), "a=2".into()]).is_err());
    }
}
