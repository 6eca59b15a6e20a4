//! `caustics reference`: render the CPU reference of a scene (surface caustic image,
//! its standard error, volume image for scenes with a medium, optionally the direct
//! image) into the reference cache, or `--out DIR`, with a progress bar.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use caustics_metrics::{HdrImage, luminance};
use caustics_reference::{
    Reference, ReferenceImage, ReferenceOptions, ReferenceResult, memory_budget_from_env,
};
use caustics_scene::Scene;
use indicatif::{ProgressBar, ProgressStyle};

use crate::references::{ReferenceMeta, cache_dir};

/// Flags of `caustics reference`.
#[derive(Clone, Debug, clap::Args)]
pub struct ReferenceArgs {
    /// Built-in scene name or path to a scene JSON file.
    #[arg(long, required_unless_present = "bench")]
    pub scene: Option<String>,
    /// Photons to trace (rounded up to whole work units).
    #[arg(long, conflicts_with = "seconds")]
    pub photons: Option<u64>,
    /// Trace for this many seconds instead (the photon count is recorded, so the image
    /// can be reproduced bit for bit with --photons).
    #[arg(long, value_name = "SECONDS")]
    pub seconds: Option<f64>,
    /// The instant of an animated scene to render (seconds; default: the file's
    /// `"time"`); the cache keys the instant, so `caustics run --time` finds it.
    #[arg(long, value_name = "SECONDS")]
    pub time: Option<f32>,
    /// Render at this camera resolution instead of the scene file's (`WIDTHxHEIGHT`);
    /// the cache keys the resolution, so `caustics run --resolution` finds it.
    #[arg(long, value_name = "WxH")]
    pub resolution: Option<String>,
    /// Output folder (default: the reference cache, where `caustics run` finds it).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Reference cache root.
    #[arg(long, value_name = "DIR", default_value = crate::references::DEFAULT_ROOT)]
    pub references: PathBuf,
    /// RNG seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Independent batches for the standard-error image (at least 2).
    #[arg(long, default_value_t = 16)]
    pub batches: u32,
    /// Also render the direct image (L D E), to cross-check the GPU direct image.
    #[arg(long)]
    pub direct: bool,
    /// Measure photons/s on sphere_on_plane, ring and water_pool instead.
    #[arg(long)]
    pub bench: bool,
    /// Limits on the scene's meshes (`--max-scene-triangles` etc.).
    #[command(flatten)]
    pub limits: crate::limits_args::LimitArgs,
}

fn to_hdr(img: &ReferenceImage) -> HdrImage {
    HdrImage {
        width: img.width,
        height: img.height,
        pixels: img.pixels.clone(),
    }
}

/// Mean standard error over caustic pixels relative to the mean caustic there
/// (luminance), the figure that says whether a reference is converged.
pub fn relative_stderr(caustic: &ReferenceImage, stderr: &ReferenceImage) -> f64 {
    let (mut sum_c, mut sum_e, mut n) = (0.0f64, 0.0f64, 0u64);
    for (c, e) in caustic.pixels.iter().zip(&stderr.pixels) {
        let lc = luminance(*c) as f64;
        if lc > 0.0 {
            sum_c += lc;
            sum_e += luminance(*e) as f64;
            n += 1;
        }
    }
    if n == 0 || sum_c == 0.0 {
        f64::INFINITY
    } else {
        sum_e / sum_c
    }
}

/// A photon progress bar (of `total` photons, or of unknown length).
pub(crate) fn progress_bar(total: Option<u64>) -> ProgressBar {
    let bar = match total {
        Some(t) => ProgressBar::new(t),
        None => ProgressBar::no_length(),
    };
    let style = ProgressStyle::with_template(
        "{elapsed_precise} [{bar:40}] {human_pos}/{human_len} photons ({per_sec}, ETA {eta})",
    )
    .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style.progress_chars("=> "));
    bar
}

fn options(args: &ReferenceArgs, photons: u64) -> ReferenceOptions {
    ReferenceOptions {
        photons,
        batches: args.batches,
        seed: args.seed,
        direct: args.direct,
    }
}

fn validate(args: &ReferenceArgs) -> Result<()> {
    match (args.photons, args.seconds) {
        (None, None) if !args.bench => bail!("give --photons N or --seconds SECONDS"),
        (Some(0), _) => bail!("--photons: expected a positive integer, got 0"),
        (_, Some(t)) if !(t.is_finite() && t > 0.0) => {
            bail!("--seconds: expected a positive number of seconds, got {t}")
        }
        _ => {}
    }
    if args.batches < 2 {
        bail!(
            "--batches: expected at least 2 (the standard error needs independent batches), got {}",
            args.batches
        );
    }
    Ok(())
}

/// Runs `caustics reference`.
pub fn reference(args: &ReferenceArgs) -> Result<()> {
    validate(args)?;
    if args.bench {
        return bench(args);
    }
    let name = args.scene.as_deref().context("--scene is required")?;
    let resolution = args
        .resolution
        .as_deref()
        .map(crate::run::parse_resolution)
        .transpose()?;
    let path = caustics_scene::resolve(name)?;
    let mut scene = Scene::load_with_limits(&path, &args.limits.limits())?;
    if let Some((w, h)) = resolution {
        (scene.camera.width, scene.camera.height) = (w, h);
    }
    let scene = match args.time {
        Some(t) => scene
            .at_time(t)
            .with_context(|| format!("--time {t}: posing {}", path.display()))?,
        None => scene,
    };
    let dir = match &args.out {
        Some(d) => d.clone(),
        None => cache_dir(&args.references, &scene),
    };
    let tracer = Reference::new(&scene)?.with_memory_budget(memory_budget_from_env()?);
    let bar = progress_bar(args.photons);
    let tick = |done: u64| bar.set_position(done);
    let result = match (args.photons, args.seconds) {
        (Some(n), _) => tracer.render(&options(args, n), &tick)?,
        (None, Some(t)) => tracer.render_for(t, &options(args, 0), &tick)?,
        (None, None) => bail!("give --photons N or --seconds SECONDS"),
    };
    bar.finish_and_clear();
    write(&dir, &scene, args.seed, args.batches, &result)?;
    let rel = relative_stderr(&result.caustic, &result.caustic_stderr);
    crate::outln!(
        "{}: {} photons in {:.1} s ({:.2} M photons/s), mean relative standard error {:.2}% -> {}",
        scene.name,
        result.photons,
        result.seconds,
        result.photons as f64 / result.seconds / 1e6,
        100.0 * rel,
        dir.display()
    );
    Ok(())
}

/// Renders the reference of `scene` (as loaded: its camera's resolution is the image's)
/// with a fixed photon budget into `dir`, `meta.json` last; `tick` gets photons done.
/// Returns the mean relative standard error over caustic pixels.
pub fn render_into(
    dir: &std::path::Path,
    scene: &Scene,
    photons: u64,
    seed: u64,
    batches: u32,
    tick: &(dyn Fn(u64) + Sync),
) -> Result<f64> {
    if photons == 0 || batches < 2 {
        bail!("a reference needs photons > 0 and at least 2 batches");
    }
    let tracer = Reference::new(scene)?.with_memory_budget(memory_budget_from_env()?);
    let opts = ReferenceOptions {
        photons,
        batches,
        seed,
        direct: false,
    };
    let result = tracer.render(&opts, tick)?;
    write(dir, scene, seed, batches, &result)?;
    Ok(relative_stderr(&result.caustic, &result.caustic_stderr))
}

fn write(
    dir: &std::path::Path,
    scene: &Scene,
    seed: u64,
    batches: u32,
    r: &ReferenceResult,
) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let exr = |name: &str, img: &ReferenceImage| -> Result<()> {
        caustics_metrics::write_exr(&dir.join(name), &to_hdr(img))?;
        Ok(())
    };
    exr("caustic.exr", &r.caustic)?;
    exr("stderr.exr", &r.caustic_stderr)?;
    // A look at it without an EXR viewer: the caustic with its 99th-percentile
    // luminance at white, as `caustics run` tone-maps against a reference.
    let caustic = to_hdr(&r.caustic);
    let tone = caustics_metrics::ToneMap::fit_percentile(&caustic, crate::run::EXPOSURE_PERCENTILE);
    caustics_metrics::write_png(&dir.join("caustic.png"), &tone.apply(&caustic))?;
    if let (Some(v), Some(e)) = (&r.volume, &r.volume_stderr) {
        exr("volume.exr", v)?;
        exr("volume_stderr.exr", e)?;
    }
    if let Some(d) = &r.direct {
        exr("direct.exr", d)?;
    }
    let meta = ReferenceMeta {
        schema_version: 2,
        transport_version: caustics_reference::TRANSPORT_VERSION,
        scene: scene.name.clone(),
        scene_hash: scene.hash_hex(),
        width: scene.camera.width,
        height: scene.camera.height,
        photons: r.photons,
        seconds: r.seconds,
        photons_per_second: r.photons as f64 / r.seconds.max(1e-9),
        seed,
        batches,
        commit: crate::machine::build().commit,
        relative_stderr: relative_stderr(&r.caustic, &r.caustic_stderr),
        time_s: scene.is_animated().then_some(scene.time),
    };
    // meta.json last: a folder with one is complete.
    caustics_metrics::atomic_write(&dir.join("meta.json"), &serde_json::to_vec_pretty(&meta)?)?;
    Ok(())
}

/// Photons/s of the reference on the scenes the issue names.
fn bench(args: &ReferenceArgs) -> Result<()> {
    let photons = args.photons.unwrap_or(4_000_000);
    crate::outln!(
        "{:<20} {:>12} {:>10} {:>14}",
        "scene",
        "photons",
        "seconds",
        "M photons/s"
    );
    for name in ["sphere_on_plane", "ring", "water_pool"] {
        let scene = Scene::load(&caustics_scene::resolve(name)?)?;
        let tracer = Reference::new(&scene)?.with_memory_budget(memory_budget_from_env()?);
        let start = Instant::now();
        let r = tracer.render(&options(args, photons), &|_| {})?;
        let s = start.elapsed().as_secs_f64();
        crate::outln!(
            "{name:<20} {:>12} {s:>10.2} {:>14.3}",
            r.photons,
            r.photons as f64 / s / 1e6
        );
    }
    Ok(())
}
