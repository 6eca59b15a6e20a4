//! Times renders of a built-in scene without writing images (for profiling):
//!
//! `cargo run --release -p caustics-reference --example profile_reference -- SCENE PHOTONS [REPEAT]`

use caustics_reference::{Reference, ReferenceOptions};
use caustics_scene::{Scene, resolve};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [name, photons, rest @ ..] = args.as_slice() else {
        return Err("usage: profile_reference SCENE PHOTONS [REPEAT]".into());
    };
    let repeat: u32 = rest.first().map_or(Ok(1), |r| r.parse())?;
    let scene = Scene::load(&resolve(name)?)?;
    let reference = Reference::new(&scene)?;
    let opts = ReferenceOptions {
        photons: photons.parse()?,
        ..Default::default()
    };
    let mut best = 0f64;
    let mut checksum = 0f64;
    for _ in 0..repeat {
        let r = reference.render(&opts, &|_| {})?;
        let rate = r.photons as f64 / r.seconds / 1e6;
        best = best.max(rate);
        checksum = r
            .caustic
            .pixels
            .iter()
            .chain(&r.caustic_stderr.pixels)
            .flatten()
            .map(|&v| v as f64)
            .sum();
        println!(
            "{}: {} photons in {:.3} s = {:.2} M photons/s",
            scene.name, r.photons, r.seconds, rate
        );
    }
    println!("best {best:.2} M photons/s, checksum {checksum:e}");
    Ok(())
}
