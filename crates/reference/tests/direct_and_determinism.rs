//! The direct image of sphere_on_plane, determinism across threads and runs, and
//! option errors.

use caustics_reference::{Reference, ReferenceError, ReferenceOptions};
use caustics_scene::{Scene, Vec3, resolve};

fn sphere_on_plane(width: u32, height: u32) -> Scene {
    let mut s = Scene::load(&resolve("sphere_on_plane").expect("built-in")).expect("loads");
    s.camera.width = width;
    s.camera.height = height;
    s
}

/// The light direction and sphere of sphere_on_plane (checked against the file).
fn in_shadow(p: Vec3, to_light: Vec3) -> bool {
    let (c, r) = (Vec3::new(0.0, 1.5, 0.0), 1.0);
    let oc = p - c;
    let b = oc.dot(to_light);
    let disc = b * b - (oc.length_squared() - r * r);
    disc > 0.0 && -b - disc.sqrt() > 0.0
}

/// Lit floor: ρ/π·E·cos θ; floor in the sphere's shadow: exactly 0. Pixels are
/// classified by their 4 corners and centre (all lit, or all shadowed, and the floor
/// not hidden by the sphere from the eye). The tolerance is 4σ of the block mean
/// with σ from the spread of the lit pixels (the direct image has no batch error).
#[test]
fn direct_image_is_rho_over_pi_e_cos() {
    let scene = sphere_on_plane(32, 24);
    let light = match &scene.lights[0] {
        caustics_scene::Light::Directional { direction, .. } => direction.normalize(),
        _ => unreachable!("sphere_on_plane has a directional light"),
    };
    let reference = Reference::new(&scene).expect("prepares");
    let r = reference
        .render(
            &ReferenceOptions {
                photons: 1 << 21,
                direct: true,
                ..Default::default()
            },
            &|_| {},
        )
        .expect("renders");
    let direct = r.direct.as_ref().expect("asked for");
    let cam = &scene.camera;
    let expected = 0.8 / std::f64::consts::PI * (-light.y) as f64;
    let (mut lit, mut shadow_max, mut shadow_n) = (Vec::new(), 0f32, 0);
    for y in 0..cam.height {
        for x in 0..cam.width {
            let mut states = Vec::new();
            for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.5, 0.5)] {
                let (o, d) = cam.ray_through_pixel(x as f32 + dx, y as f32 + dy);
                let t = -o.y / d.y;
                let p = o + t * d;
                // The floor point is seen unless the sphere is hit before it.
                let oc = o - Vec3::new(0.0, 1.5, 0.0);
                let b = oc.dot(d);
                let disc = b * b - (oc.length_squared() - 1.0);
                let seen = t > 0.0
                    && p.x.abs() < 10.0
                    && p.z.abs() < 10.0
                    && (disc <= 0.0 || -b - disc.sqrt() > t);
                states.push((seen, in_shadow(p, -light)));
            }
            let v = direct.at(x, y)[0];
            if states.iter().all(|s| s.0 && !s.1) {
                lit.push(v as f64);
            } else if states.iter().all(|s| s.0 && s.1) {
                shadow_max = shadow_max.max(v);
                shadow_n += 1;
            }
        }
    }
    let n = lit.len() as f64;
    let mean = lit.iter().sum::<f64>() / n;
    let sd = (lit.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let se = sd / n.sqrt();
    eprintln!(
        "direct: lit {mean:.5} vs {expected:.5} (σ {se:.2e}, {n} px), shadow max {shadow_max} over {shadow_n} px"
    );
    assert!(n > 200.0 && shadow_n > 10);
    assert!(
        (mean - expected).abs() < 4.0 * se,
        "{mean} vs {expected}, σ {se}"
    );
    assert_eq!(shadow_max, 0.0);
}

#[test]
fn images_are_bit_identical_across_threads_and_runs() {
    let scene = sphere_on_plane(40, 30);
    let reference = Reference::new(&scene).expect("prepares");
    let opts = ReferenceOptions {
        photons: 200_000,
        batches: 4,
        seed: 7,
        direct: true,
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| reference.render(&opts, &|_| {}).expect("renders"))
    };
    let (a, b, c) = (run(1), run(2), run(3));
    assert_eq!(a.caustic, b.caustic);
    assert_eq!(a.caustic_stderr, b.caustic_stderr);
    assert_eq!(a.direct, b.direct);
    assert_eq!(a.caustic, c.caustic);
    assert_eq!(b.caustic, run(2).caustic);
    assert!(a.caustic.pixels.iter().any(|p| p[0] > 0.0));
    // Another seed gives another image.
    let other = reference
        .render(
            &ReferenceOptions {
                seed: 8,
                ..opts.clone()
            },
            &|_| {},
        )
        .expect("renders");
    assert_ne!(other.caustic, a.caustic);

    // render_for: re-rendering with the photon count it reports is bit-identical.
    let timed = reference.render_for(0.0, &opts, &|_| {}).expect("renders");
    let again = reference
        .render(
            &ReferenceOptions {
                photons: timed.photons,
                ..opts.clone()
            },
            &|_| {},
        )
        .expect("renders");
    assert_eq!(timed.photons, again.photons);
    assert_eq!(timed.caustic, again.caustic);
    assert_eq!(timed.caustic_stderr, again.caustic_stderr);
}

#[test]
fn bad_options_are_clear_errors() {
    let reference = Reference::new(&sphere_on_plane(8, 6)).expect("prepares");
    let none = |opts: ReferenceOptions| reference.render(&opts, &|_| {}).expect_err("bad");
    assert_eq!(
        none(ReferenceOptions {
            photons: 0,
            ..Default::default()
        }),
        ReferenceError::NoPhotons
    );
    let e = none(ReferenceOptions {
        batches: 1,
        ..Default::default()
    });
    assert_eq!(e, ReferenceError::BadBatches { batches: 1 });
    assert_eq!(e.to_string(), "batches must be in 2..=1024, got 1");
    assert_eq!(
        ReferenceError::NoPhotons.to_string(),
        "photons must be at least 1, got 0"
    );
    let e = reference
        .render_for(f64::NAN, &ReferenceOptions::default(), &|_| {})
        .expect_err("bad");
    assert!(matches!(e, ReferenceError::BadSeconds { .. }));
}

#[test]
fn progress_is_reported_and_photons_rounded_up() {
    let reference = Reference::new(&sphere_on_plane(8, 6)).expect("prepares");
    let last = std::sync::atomic::AtomicU64::new(0);
    let r = reference
        .render(
            &ReferenceOptions {
                photons: 1000,
                ..Default::default()
            },
            &|n| last.store(n, std::sync::atomic::Ordering::Relaxed),
        )
        .expect("renders");
    assert!(r.photons >= 1000);
    assert_eq!(last.into_inner(), r.photons);
}
