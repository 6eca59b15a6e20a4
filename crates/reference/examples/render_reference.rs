//! Renders a scene's reference and writes `caustic.exr`, `stderr.exr` (and
//! `volume.exr`, `volume_stderr.exr`, `direct.exr` when present) plus tone-mapped PNGs
//! into a folder:
//!
//! `cargo run --release -p caustics-reference --example render_reference -- SCENE PHOTONS OUT_DIR [WIDTH HEIGHT] [--direct]`

use std::path::PathBuf;

use caustics_metrics::{HdrImage, ToneMap, write_exr, write_png};
use caustics_reference::{Reference, ReferenceImage, ReferenceOptions};
use caustics_scene::{Scene, resolve};

fn to_hdr(img: &ReferenceImage) -> HdrImage {
    let mut h = HdrImage::new(img.width, img.height);
    h.pixels.clone_from(&img.pixels);
    h
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let direct = args.iter().any(|a| a == "--direct");
    let args: Vec<&String> = args.iter().filter(|a| !a.starts_with("--")).collect();
    let [name, photons, out, rest @ ..] = args.as_slice() else {
        return Err(
            "usage: render_reference SCENE PHOTONS OUT_DIR [WIDTH HEIGHT] [--direct]".into(),
        );
    };
    let mut scene = Scene::load(&resolve(name)?)?;
    if let [w, h] = rest {
        scene.camera.width = w.parse()?;
        scene.camera.height = h.parse()?;
    }
    let out = PathBuf::from(out);
    std::fs::create_dir_all(&out)?;
    let t = std::time::Instant::now();
    let reference = Reference::new(&scene)?;
    println!("setup {:.3} s", t.elapsed().as_secs_f64());
    let opts = ReferenceOptions {
        photons: photons.parse()?,
        direct,
        ..Default::default()
    };
    let r = reference.render(&opts, &|_| {})?;
    println!(
        "{}: {} photons in {:.3} s = {:.2} M photons/s",
        scene.name,
        r.photons,
        r.seconds,
        r.photons as f64 / r.seconds / 1e6
    );
    // Mean over caustic pixels (luminance > 0) of the standard error, relative to
    // the mean caustic luminance there (the harness's `relative_stderr`).
    let lum = |p: &[f32; 3]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    let (mut sum, mut err, mut n) = (0f64, 0f64, 0f64);
    for (p, e) in r.caustic.pixels.iter().zip(&r.caustic_stderr.pixels) {
        if lum(p) > 0.0 {
            sum += lum(p) as f64;
            err += lum(e) as f64;
            n += 1.0;
        }
    }
    println!(
        "relative stderr over {n} caustic pixels: {:.4}",
        err / sum.max(f64::MIN_POSITIVE)
    );
    let mut images = vec![("caustic", &r.caustic), ("stderr", &r.caustic_stderr)];
    if let (Some(v), Some(e)) = (&r.volume, &r.volume_stderr) {
        images.push(("volume", v));
        images.push(("volume_stderr", e));
    }
    if let Some(d) = &r.direct {
        images.push(("direct", d));
    }
    for (what, img) in images {
        let h = to_hdr(img);
        write_exr(&out.join(format!("{what}.exr")), &h)?;
        let tone = ToneMap::fit_percentile(&h, 99.0);
        write_png(&out.join(format!("{what}.png")), &tone.apply(&h))?;
    }
    Ok(())
}
