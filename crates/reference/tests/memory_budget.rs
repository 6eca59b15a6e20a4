//! The reference's memory budget (issue 18): a render whose images cannot fit is refused
//! before they are allocated, one whose batch sums outgrow the budget stops with the
//! figure and what to lower, and a budget that holds the render changes nothing in it.

use caustics_reference::{MEMORY_BUDGET_ENV, Reference, ReferenceError, ReferenceOptions};
use caustics_scene::{Scene, resolve};

fn sphere_on_plane(width: u32, height: u32) -> Scene {
    let mut s = Scene::load(&resolve("sphere_on_plane").expect("built-in")).expect("loads");
    s.camera.width = width;
    s.camera.height = height;
    s
}

const OPTS: ReferenceOptions = ReferenceOptions {
    photons: 1 << 18,
    batches: 16,
    seed: 7,
    direct: false,
};

#[test]
fn images_past_the_budget_are_refused_before_tracing() {
    // 16384 x 12288 with 16 batches: the finished images alone are 4.5 GiB.
    let scene = sphere_on_plane(16384, 12288);
    let reference = Reference::new(&scene)
        .expect("prepares")
        .with_memory_budget(1 << 30);
    let start = std::time::Instant::now();
    let e = reference
        .render(&OPTS, &|_| {})
        .expect_err("past the budget");
    assert!(
        start.elapsed() < std::time::Duration::from_secs(5),
        "refused after {:?}: it must be refused before tracing",
        start.elapsed()
    );
    assert!(
        matches!(e, ReferenceError::OverMemoryBudget { .. }),
        "{e:?}"
    );
    let text = e.to_string();
    for needle in [
        "16384x12288",
        "16 batches",
        "1.00 GiB",
        MEMORY_BUDGET_ENV,
        "lower camera.width",
    ] {
        assert!(text.contains(needle), "{needle:?} missing from: {text}");
    }
}

#[test]
fn batch_sums_that_outgrow_the_budget_stop_the_render() {
    let scene = sphere_on_plane(64, 48);
    let pixels = 64 * 48;
    // The images (tile indices and finished images, 24 bytes a pixel) fit; 16 batches
    // of sums over the caustic (24 bytes a pixel each) do not.
    let budget = 16 * pixels / 16 * 4 + 24 * pixels + 4096;
    let reference = Reference::new(&scene)
        .expect("prepares")
        .with_memory_budget(budget as u64);
    let e = reference
        .render(&OPTS, &|_| {})
        .expect_err("past the budget");
    let text = e.to_string();
    assert!(
        text.contains("batch sums of 16 batches") && text.contains("--batches"),
        "{text}"
    );
}

#[test]
fn a_budget_that_holds_the_render_changes_nothing() {
    let scene = sphere_on_plane(64, 48);
    let free = Reference::new(&scene)
        .expect("prepares")
        .render(&OPTS, &|_| {})
        .expect("renders");
    // 16 batches of dense sums and the images: the most this render can hold.
    let most = 16 * 64 * 48 * 24 + 2 * 64 * 48 * 24;
    let bounded = Reference::new(&scene)
        .expect("prepares")
        .with_memory_budget(most)
        .render(&OPTS, &|_| {})
        .expect("fits");
    assert!(bounded.caustic == free.caustic && bounded.caustic_stderr == free.caustic_stderr);
}
