//! CPU-side costs of the harness, the ones a run pays outside the GPU: loading and
//! validating scenes (mesh parsing included), tessellating them for upload, and
//! scoring a 1024×768 image (every metric, error map, heatmap). GPU time is never
//! measured here: it comes from the harness's timestamp queries (`caustics run`).
//!
//! `cargo bench -p caustics-benches` measures; `cargo test -p caustics-benches
//! --benches` runs each benchmark once as a smoke test (CI does).

use std::hint::black_box;

use caustics_metrics::{HdrImage, ToneMap, all_errors, error_map, heatmap};
use caustics_scene::{Scene, Tessellation, builtin_names, resolve};
use criterion::{Criterion, criterion_group, criterion_main};

fn scenes(c: &mut Criterion) {
    for name in builtin_names() {
        let path = resolve(&name).expect("built-in scene");
        c.bench_function(&format!("scene_load/{name}"), |b| {
            b.iter(|| Scene::load(black_box(&path)).expect("loads"))
        });
        let scene = Scene::load(&path).expect("loads");
        let tess = Tessellation::default();
        c.bench_function(&format!("tessellate/{name}"), |b| {
            b.iter(|| {
                scene
                    .objects
                    .iter()
                    .map(|o| o.shape.triangulate(black_box(&tess)).indices.len())
                    .sum::<usize>()
            })
        });
    }
}

/// A smooth image and a perturbed copy, deterministic.
fn image_pair(width: u32, height: u32) -> (HdrImage, HdrImage) {
    let mut a = HdrImage::new(width, height);
    let mut b = HdrImage::new(width, height);
    for y in 0..height {
        for x in 0..width {
            let i = (y * width + x) as usize;
            let v = ((x as f32 * 0.05).sin() * (y as f32 * 0.03).cos()).abs();
            a.pixels[i] = [v, v * 0.8, v * 0.6];
            let n = ((i as u32).wrapping_mul(2_654_435_761) >> 16) as f32 / 65_536.0 * 0.05;
            b.pixels[i] = [v + n, v * 0.8, v * 0.6 - n * 0.5];
        }
    }
    (a, b)
}

fn metrics(c: &mut Criterion) {
    let (test, reference) = image_pair(1024, 768);
    let tone = ToneMap {
        exposure_scale: 2.0,
    };
    c.bench_function("metrics/all_errors_1024x768", |b| {
        b.iter(|| all_errors(black_box(&test), black_box(&reference), &tone).expect("same size"))
    });
    c.bench_function("metrics/error_map_1024x768", |b| {
        b.iter(|| error_map(black_box(&test), &reference).expect("ok"))
    });
    let counts: Vec<u32> = (0..1024 * 768u32)
        .map(|i| i.wrapping_mul(7919) % 13)
        .collect();
    c.bench_function("metrics/heatmap_1024x768", |b| {
        b.iter(|| heatmap(black_box(&counts), 1024, 768, "fragments/px").expect("ok"))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = scenes, metrics
}
criterion_main!(benches);
