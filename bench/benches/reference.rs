//! Photons per second of the CPU reference (`caustics-reference`) on the built-in
//! scenes at their 1024×768 resolution: 8 rounds of work units (16 batches × 16,384
//! photons) per iteration, restricted emission, surface (and volume) caustic images.
//!
//! `cargo bench -p caustics-benches --bench reference` measures; `cargo test -p
//! caustics-benches --benches` runs each once as a smoke test.

use std::hint::black_box;

use caustics_reference::{Reference, ReferenceOptions};
use caustics_scene::{Scene, resolve};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};

/// Photons per iteration: 8 rounds of 16 units of 2^14 (the fixed cost of a
/// 1024×768 render, its 16 batch images, is then small beside the tracing).
const PHOTONS: u64 = 8 * (16 << 14);

fn reference(c: &mut Criterion) {
    let mut group = c.benchmark_group("reference");
    group.sample_size(10);
    group.throughput(Throughput::Elements(PHOTONS));
    for name in ["sphere_on_plane", "ring", "water_pool"] {
        let scene = Scene::load(&resolve(name).expect("built-in scene")).expect("loads");
        let reference = Reference::new(&scene).expect("prepares");
        let opts = ReferenceOptions {
            photons: PHOTONS,
            ..Default::default()
        };
        group.bench_function(format!("photons/{name}"), |b| {
            b.iter(|| {
                reference
                    .render(black_box(&opts), &|_| {})
                    .expect("renders")
                    .photons
            })
        });
    }
    group.finish();
}

criterion_group!(benches, reference);
criterion_main!(benches);
