//! What the method crates' tests stand on: the GPU base renderer agrees with the CPU
//! reference where neither approximates, its pass timestamps are usable, and a failed
//! bound leaves images to look at. On whatever adapter the machine has (lavapipe on CI;
//! without an adapter the GPU tests fail with the install hint, never skip).

use caustics_gpu::{FrameMode, PassProfiler};
use caustics_scene::Vec3;
use caustics_testing::{Artifacts, Gpu, HdrImage, ReferenceOptions, builtin, reference};

/// The GPU base renderer and the CPU reference are independent implementations of
/// the same DESIGN conventions; their direct images (L D E) must agree where neither
/// has an approximation (away from shadow edges, where the GPU uses a shadow map).
#[test]
fn gpu_direct_image_matches_the_reference_direct_image() {
    let scene = builtin("sphere_on_plane", 96, 72);
    let opts = ReferenceOptions {
        photons: 1 << 21,
        batches: 8,
        seed: 7,
        direct: true,
    };
    let cpu = reference(&scene, &opts).direct.expect("direct image");
    let gpu = Gpu::new(scene);
    let mut profiler = PassProfiler::new(&gpu.ctx, 1);
    gpu.renderer
        .begin_frame(&mut profiler, FrameMode::Timed)
        .expect("frame")
        .submit(&gpu.ctx)
        .expect("submit");
    let direct = gpu.direct();
    let pos = gpu.positions();

    // Sum over floor pixels whose shadow ray clears the sphere by a margin (lit) or
    // passes well inside it (shadowed): the two renderers must agree on both sums.
    let light = Vec3::new(0.2, -1.0, 0.1).normalize();
    let (center, radius) = (Vec3::new(0.0, 1.5, 0.0), 1.0f32);
    let (mut lit_gpu, mut lit_cpu, mut dark_cpu, mut n_lit, mut n_dark) =
        (0.0f64, 0.0f64, 0.0f64, 0, 0);
    for (i, cpu_px) in cpu.pixels.iter().enumerate() {
        let p = Vec3::new(pos[4 * i], pos[4 * i + 1], pos[4 * i + 2]);
        // The floor, away from its far edge (where a pixel straddles floor and sky:
        // the reference averages over the pixel, the G-buffer samples its centre).
        if pos[4 * i + 3] < 0.5 || p.y.abs() > 1e-3 || p.x.abs() > 9.0 || p.z.abs() > 9.0 {
            continue;
        }
        let t = (center - p).dot(-light).max(0.0);
        let miss = (p - t * light - center).length() - radius;
        if miss > 0.1 {
            lit_gpu += direct.pixels[i][0] as f64;
            lit_cpu += cpu_px[0] as f64;
            n_lit += 1;
        } else if miss < -0.1 {
            assert_eq!(
                direct.pixels[i][0], 0.0,
                "GPU lights a shadowed floor pixel"
            );
            dark_cpu += cpu_px[0] as f64;
            n_dark += 1;
        }
    }
    assert!(
        n_lit > 2000 && n_dark > 50,
        "{n_lit} lit, {n_dark} shadowed pixels"
    );
    let rel = (lit_gpu - lit_cpu).abs() / lit_cpu;
    eprintln!(
        "lit floor: GPU {lit_gpu:.4}, reference {lit_cpu:.4}, {n_lit} px; relative difference {rel:.5}"
    );
    // 2^21 photons over the whole scene put ~10^5 on the lit pixels: ~0.3% noise.
    // Measured (seed 7, lavapipe): 0.20%.
    caustics_testing::artifacts!().ensure(rel < 0.01, "direct", &direct, &cpu, || {
        format!(
            "lit floor: GPU {lit_gpu:.3} vs reference {lit_cpu:.3} ({:.2}%)",
            rel * 100.0
        )
    });
    assert_eq!(
        dark_cpu, 0.0,
        "the reference lights a floor pixel in the sphere's shadow"
    );
}

#[test]
fn timestamps_are_nonzero_and_increase_through_a_frame() {
    let gpu = Gpu::new(builtin("sphere_on_plane", 128, 96));
    assert!(
        gpu.ctx.has_timestamps(),
        "adapter {} lacks timestamp queries",
        gpu.ctx.summary.name
    );
    let mut profiler = PassProfiler::new(&gpu.ctx, 3);
    for _ in 0..3 {
        let frame = gpu
            .renderer
            .begin_frame(&mut profiler, FrameMode::Timed)
            .expect("frame");
        frame.submit(&gpu.ctx).expect("submit");
    }
    let frames = profiler.collect(&gpu.ctx).expect("collect");
    assert_eq!(frames.len(), 3);
    for f in &frames {
        assert_eq!(f.rejected_timestamps, 0);
        let mut last_end = 0u64;
        for p in &f.passes {
            let (b, e) = p
                .ticks
                .unwrap_or_else(|| panic!("pass {} has no timestamps", p.name));
            assert!(b > 0, "{}: zero begin timestamp", p.name);
            assert!(e >= b, "{}: end {e} before begin {b}", p.name);
            assert!(
                b >= last_end,
                "{}: begins at {b} before the previous pass ended at {last_end}",
                p.name
            );
            last_end = e;
        }
    }
    // Frames run one after another.
    let first_end = frames[0]
        .passes
        .last()
        .and_then(|p| p.ticks)
        .map(|t| t.1)
        .expect("ticks");
    let second_begin = frames[1].passes[0].ticks.map(|t| t.0).expect("ticks");
    assert!(second_begin > first_end);
}

/// STYLE 6 and 9: a failed bound panics naming its folder, where the actual, expected
/// and difference images lie; a bound that holds writes nothing.
#[test]
fn a_failed_bound_writes_actual_expected_and_difference_images_and_says_where() {
    let mut expected = HdrImage::new(8, 6);
    expected.set(3, 2, [1.0, 0.5, 0.25]);
    let actual = expected.scaled(2.0);
    let artifacts = Artifacts::new("caustics-testing", "comparator_self_test");
    artifacts.ensure(true, "same", &expected, &expected, || unreachable!());
    assert!(!artifacts.dir().exists(), "a bound that holds wrote images");

    let failed = std::panic::catch_unwind(|| {
        artifacts.ensure(false, "double", &actual, &expected, || {
            "twice as bright".into()
        });
    })
    .expect_err("a failed bound panics");
    let message = failed.downcast_ref::<String>().cloned().unwrap_or_default();
    let dir = artifacts.dir().display().to_string();
    assert!(
        message.contains("twice as bright") && message.contains(&dir),
        "{message}"
    );
    for file in [
        "double-actual.exr",
        "double-actual.png",
        "double-expected.exr",
        "double-expected.png",
        "double-difference.exr",
        "double-difference.png",
    ] {
        assert!(message.contains(file), "{file} not named in: {message}");
        assert!(artifacts.dir().join(file).is_file(), "{file} not written");
    }
    let difference =
        caustics_metrics::read_exr(&artifacts.dir().join("double-difference.exr")).expect("exr");
    assert_eq!(difference.get(3, 2), [1.0, 0.5, 0.25], "actual − expected");
    assert_eq!(difference.get(0, 0), [0.0; 3]);
    // The folder is for failures: a passing self-test leaves nothing behind.
    std::fs::remove_dir_all(artifacts.dir()).expect("remove the self-test's images");
}
