//! Wand & Straßer 2003, Fig. 4 style: the `ring` scene with 100 / 1000 / 10000 samples
//! for each sampling strategy, filtering on vs off at 1000 samples, and the gather time
//! against samples × receiver pixels. Drives `caustics run` programmatically and writes
//! `results/pinhole-fig4/`: `README.md` (tables), `grid.png` (rows: strategies,
//! columns: sample counts, then the reference), `filtering.png` and one
//! `runs/<config>/ring/pinhole/result.json` per run.
//!
//! ```text
//! cargo run --release -p caustics -- reference --scene results/pinhole-fig4/ring_128x96.json --time 150
//! cargo run --release -p pinhole --example fig4 [-- SCENE.json [SAMPLES,...]]
//! ```
//!
//! The same runs as data are the `wand-fig4` experiment (`caustics reproduce wand-fig4`,
//! with the paper's timings beside ours, plots, Bencher output, shards, `compare`); this
//! example stays for what only it draws: the strategies × samples grid composite and the
//! least-squares fit of gather time against sample-pixel pairs.
//!
//! The scene is `ring` at a reduced resolution (the reference must be cached for the
//! same file, or the error columns stay empty); the default is 128×96 so that the
//! sweep finishes in minutes on a software adapter.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use caustics::result::RunResult;
use caustics::run::{RunOptions, RunOutcome, run};
use caustics_metrics::{HdrImage, Rgb8Image, ToneMap, read_exr, write_png};

const OUT: &str = "results/pinhole-fig4";
const STRATEGIES: [&str; 4] = ["random", "grid", "quantized", "neighbor_removal"];
const EXPOSURE: f32 = 2.0;

struct Row {
    config: String,
    samples: u64,
    result: RunResult,
    surface: HdrImage,
}

fn run_one(scene: &str, config: &str, params: &[String]) -> Result<Row> {
    let out = PathBuf::from(OUT).join("runs").join(config);
    let o = RunOptions {
        scene: scene.into(),
        method: "pinhole".into(),
        params: params.to_vec(),
        param_values: Default::default(),
        frames: 3,
        warmup: 1,
        reference: None,
        out,
        adapter: None,
        exposure: Some(EXPOSURE),
        score_grid: caustics::run::DEFAULT_SCORE_GRID,
        references: caustics::references::DEFAULT_ROOT.into(),
    };
    eprintln!("== {config}: {}", params.join(" "));
    match run(&o)? {
        RunOutcome::Done { dir, result } => {
            let surface = read_exr(&dir.join("surface.exr"))?;
            // The EXRs stay out of the repository (size); result.json and PNGs are kept.
            for f in ["surface.exr", "direct.exr"] {
                let _ = std::fs::remove_file(dir.join(f));
            }
            Ok(Row {
                config: config.into(),
                samples: result.counters.get("samples").copied().unwrap_or(0),
                result: *result,
                surface,
            })
        }
        RunOutcome::Skipped { reason } => bail!("{config}: skipped: {reason}"),
    }
}

fn gather_ms(r: &RunResult) -> f64 {
    r.timing
        .passes
        .iter()
        .filter(|p| p.name.starts_with("pinhole/"))
        .filter_map(|p| p.gpu_ms.as_ref().map(|s| s.median))
        .sum()
}

fn err_cells(r: &RunResult) -> String {
    match &r.errors {
        Some(e) => format!(
            "{:.4} | {:.3} | {:.2} | {:.4}",
            e.surface.rmse, e.surface.rel_mse, e.surface.psnr_db, e.surface.flip
        ),
        None => "– | – | – | –".into(),
    }
}

fn grid(images: &[Vec<&HdrImage>], path: &Path) -> Result<()> {
    let tone = ToneMap {
        exposure_scale: EXPOSURE,
    };
    let (w, h) = (images[0][0].width, images[0][0].height);
    let cols = images.iter().map(Vec::len).max().unwrap_or(1) as u32;
    let gap = 2;
    let mut out = Rgb8Image::filled(cols * (w + gap), images.len() as u32 * (h + gap), [255; 3]);
    for (r, row) in images.iter().enumerate() {
        for (c, img) in row.iter().enumerate() {
            let t = tone.apply(img);
            for y in 0..h {
                for x in 0..w {
                    let (ox, oy) = (c as u32 * (w + gap) + x, r as u32 * (h + gap) + y);
                    out.pixels[(oy * out.width + ox) as usize] = t.pixels[(y * w + x) as usize];
                }
            }
        }
    }
    write_png(path, &out)?;
    Ok(())
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene = args
        .first()
        .cloned()
        .unwrap_or_else(|| format!("{OUT}/ring_128x96.json"));
    let counts: Vec<u32> = match args.get(1) {
        Some(list) => list
            .split(',')
            .map(|s| s.parse().with_context(|| format!("sample count {s:?}")))
            .collect::<Result<_>>()?,
        None => vec![100, 1000, 10000],
    };
    std::fs::create_dir_all(OUT)?;
    let mut md = String::new();
    writeln!(md, "# pinhole: Wand & Straßer 2003, Fig. 4 style\n")?;
    writeln!(
        md,
        "Scene `{scene}`, written by `cargo run --release -p pinhole --example fig4`. \
         GPU ms: median of 3 frames of the pinhole passes (prepare + gather). Errors of the \
         surface caustic image against the cached CPU reference (single- and multi-bounce \
         light; pinhole renders one bounce). Filtering `full` (the paper's footprint) unless stated.\n"
    )?;

    // Strategies × sample counts.
    let mut rows: Vec<Vec<Row>> = Vec::new();
    for s in STRATEGIES {
        let mut r = Vec::new();
        for &n in &counts {
            r.push(run_one(
                &scene,
                &format!("{s}-{n}"),
                &[format!("sampling=\"{s}\""), format!("samples={n}")],
            )?);
        }
        rows.push(r);
    }
    let adapter = rows[0][0].result.machine.adapter.clone();
    writeln!(md, "Adapter: {adapter}.\n")?;
    writeln!(md, "## Strategies × samples\n")?;
    writeln!(
        md,
        "| strategy | samples | GPU ms | RMSE | relMSE | PSNR dB | FLIP |\n|---|---|---|---|---|---|---|"
    )?;
    for r in rows.iter().flatten() {
        writeln!(
            md,
            "| {} | {} | {:.1} | {} |",
            r.config.rsplit_once('-').map(|x| x.0).unwrap_or(""),
            r.samples,
            gather_ms(&r.result),
            err_cells(&r.result)
        )?;
    }
    let reference = caustics::references::find(
        Path::new(caustics::references::DEFAULT_ROOT),
        &caustics_scene::Scene::load(&caustics_scene::resolve(&scene)?)?,
    )?
    .map(|c| read_exr(&c.caustic()))
    .transpose()?;
    let mut images: Vec<Vec<&HdrImage>> = rows
        .iter()
        .map(|r| r.iter().map(|x| &x.surface).collect())
        .collect();
    if let Some(reference) = &reference {
        for row in &mut images {
            row.push(reference);
        }
    }
    grid(&images, &PathBuf::from(OUT).join("grid.png"))?;
    writeln!(
        md,
        "\n![grid](grid.png)\n\nRows: {}; columns: {:?} samples{}.\n",
        STRATEGIES.join(", "),
        counts,
        if reference.is_some() {
            ", reference"
        } else {
            ""
        }
    )?;

    // Filtering on vs off at 1000 samples.
    let mut filt = Vec::new();
    for f in ["off", "curvature", "full"] {
        filt.push(run_one(
            &scene,
            &format!("filtering-{f}"),
            &["samples=1000".into(), format!("filtering=\"{f}\"")],
        )?);
    }
    writeln!(md, "## Filtering at 1000 samples (neighbor_removal)\n")?;
    writeln!(
        md,
        "| filtering | GPU ms | texture fetches | RMSE | relMSE | PSNR dB | FLIP |\n|---|---|---|---|---|---|---|"
    )?;
    for r in &filt {
        writeln!(
            md,
            "| {} | {:.1} | {} | {} |",
            r.config.trim_start_matches("filtering-"),
            gather_ms(&r.result),
            r.result
                .counters
                .get("texture_fetches")
                .copied()
                .unwrap_or(0),
            err_cells(&r.result)
        )?;
    }
    grid(
        &[filt.iter().map(|r| &r.surface).collect()],
        &PathBuf::from(OUT).join("filtering.png"),
    )?;
    writeln!(
        md,
        "\n![filtering](filtering.png)\n\nLeft to right: off, curvature, full.\n"
    )?;

    // Time against samples × receiver pixels (every run above).
    writeln!(md, "## Gather time against samples × receiver pixels\n")?;
    writeln!(
        md,
        "| config | pairs | GPU ms | ns / pair |\n|---|---|---|---|"
    )?;
    let mut pts = Vec::new();
    for r in rows.iter().flatten().chain(&filt) {
        let pairs = r
            .result
            .counters
            .get("sample_pixel_pairs")
            .copied()
            .unwrap_or(0) as f64;
        let ms = gather_ms(&r.result);
        pts.push((pairs, ms));
        writeln!(
            md,
            "| {} | {pairs:.0} | {ms:.1} | {:.1} |",
            r.config,
            ms * 1e6 / pairs
        )?;
    }
    // Least-squares line ms = a + b · pairs over the unfiltered-or-full strategy runs.
    let n = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (mx, my) = (sx / n, sy / n);
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let syy: f64 = pts.iter().map(|p| (p.1 - my) * (p.1 - my)).sum();
    let b = sxy / sxx;
    let r2 = sxy * sxy / (sxx * syy);
    writeln!(
        md,
        "\nLeast squares over all runs: ms = {:.2} + {:.2} ns × pairs, R² = {r2:.4}.",
        my - b * mx,
        b * 1e6
    )?;
    caustics_metrics::atomic_write(&PathBuf::from(OUT).join("README.md"), md.as_bytes())?;
    println!("{md}");
    Ok(())
}
