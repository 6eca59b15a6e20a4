//! Error metrics: known values, sensitivity to a one-pixel change, and refusal of bad input.

mod common;

use caustics_metrics::{
    Errors, HdrImage, MetricsError, REL_MSE_EPS, ToneMap, all_errors, best_scale, error_map, flip,
    psnr, rel_mse, rmse, ssim,
};
use common::{noisy, structured};

/// ref = [(1,2,3), (4,5,6)], test = [(3,2,1), (4,5,6)]: channel errors (2, 0, −2, 0, 0, 0).
fn pair() -> (HdrImage, HdrImage) {
    let reference = HdrImage {
        width: 2,
        height: 1,
        pixels: vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]],
    };
    let test = HdrImage {
        width: 2,
        height: 1,
        pixels: vec![[3.0, 2.0, 1.0], [4.0, 5.0, 6.0]],
    };
    (test, reference)
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn rmse_of_known_images() {
    let (t, r) = pair();
    // MSE = (4 + 4) / 6 = 4/3.
    let e = rmse(&t, &r).expect("rmse");
    assert!(close(e, (4.0f64 / 3.0).sqrt(), 1e-12), "{e}");
    assert!(close(e, 1.154_700_538_379_251_5, 1e-12));
    assert_eq!(rmse(&r, &r).expect("rmse"), 0.0);
}

#[test]
fn psnr_of_known_images() {
    let (t, r) = pair();
    // Peak = max(reference) = 6: 10 log10(36 / (4/3)) = 10 log10(27).
    let p = psnr(&t, &r, None).expect("psnr");
    assert!(close(p, 14.313_637_641_589_873, 1e-9), "{p}");
    // Explicit peak 2: 10 log10(4 / (4/3)) = 10 log10(3).
    let p2 = psnr(&t, &r, Some(2.0)).expect("psnr");
    assert!(close(p2, 4.771_212_547_196_624, 1e-9), "{p2}");
    assert_eq!(psnr(&r, &r, None).expect("psnr"), f64::INFINITY);
    assert!(matches!(
        psnr(&t, &r, Some(0.0)),
        Err(MetricsError::InvalidParameter { name: "peak", .. })
    ));
}

#[test]
fn rel_mse_of_known_images() {
    let (t, r) = pair();
    // (2² / (1² + eps) + 2² / (3² + eps)) / 6 with eps = 0.01.
    let v = rel_mse(&t, &r, REL_MSE_EPS).expect("rel_mse");
    let want = (4.0 / 1.01 + 4.0 / 9.01) / 6.0;
    assert!(close(v, want, 1e-12), "{v} vs {want}");
    assert!(close(v, 0.734_057_867_5, 1e-9), "{v}");
    // eps = 1: (4/2 + 4/10) / 6 = 0.4.
    assert!(close(rel_mse(&t, &r, 1.0).expect("rel_mse"), 0.4, 1e-12));
    for eps in [0.0, -1.0, f64::NAN] {
        assert!(matches!(
            rel_mse(&t, &r, eps),
            Err(MetricsError::InvalidParameter { name: "eps", .. })
        ));
    }
}

#[test]
fn ssim_identical_is_one_and_noisy_is_less() {
    let r = structured(48, 40);
    let s = ssim(&r, &r).expect("ssim");
    assert!(close(s, 1.0, 1e-12), "{s}");
    let n = ssim(&noisy(&r, 0.2, 7), &r).expect("ssim");
    assert!(n < 0.99, "noisy SSIM {n}");
    let n2 = ssim(&noisy(&r, 0.5, 7), &r).expect("ssim");
    assert!(n2 < n, "more noise must lower SSIM: {n2} vs {n}");
    // Works for images smaller than the 11x11 window.
    let tiny = structured(3, 2);
    assert!(close(ssim(&tiny, &tiny).expect("ssim"), 1.0, 1e-12));
}

#[test]
fn flip_identical_is_zero_and_different_is_positive() {
    let r = structured(40, 32);
    let tone = ToneMap::new(0.5);
    assert_eq!(flip(&r, &r, &tone).expect("flip"), 0.0);
    let f = flip(&noisy(&r, 0.3, 3), &r, &tone).expect("flip");
    assert!(f > 0.0 && f <= 1.0, "{f}");
    let black = HdrImage::new(40, 32);
    let fb = flip(&black, &r, &tone).expect("flip");
    assert!(
        fb > f,
        "black image must be worse than a noisy one: {fb} vs {f}"
    );
}

#[test]
fn best_scale_recovers_factor_two() {
    let r = structured(32, 24);
    let t = r.scaled(0.5);
    let (s, e) = best_scale(&t, &r).expect("best_scale");
    assert_eq!(s, 2.0);
    assert!(e < 1e-12, "{e}");
    // A black test image: every scale fits; 1 is reported with the plain RMSE.
    let black = HdrImage::new(32, 24);
    let (s0, e0) = best_scale(&black, &r).expect("best_scale");
    assert_eq!(s0, 1.0);
    assert!(close(e0, rmse(&black, &r).expect("rmse"), 1e-12));
    // Shape errors survive rescaling.
    let (_, e_noisy) = best_scale(&noisy(&r, 0.3, 1), &r).expect("best_scale");
    assert!(e_noisy > 1e-3);
}

#[test]
fn every_comparator_sees_a_one_pixel_change() {
    let r = structured(32, 32);
    let mut t = r.clone();
    let p = t.get(20, 9);
    t.set(20, 9, [p[0] + 0.5, p[1] + 0.5, p[2] + 0.5]);
    let tone = ToneMap::new(0.5);

    assert!(rmse(&t, &r).expect("rmse") > 0.0);
    assert!(rel_mse(&t, &r, REL_MSE_EPS).expect("rel_mse") > 0.0);
    assert!(psnr(&t, &r, None).expect("psnr").is_finite());
    assert!(ssim(&t, &r).expect("ssim") < 1.0);
    assert!(flip(&t, &r, &tone).expect("flip") > 0.0);
    let (s, e) = best_scale(&t, &r).expect("best_scale");
    assert!(s != 1.0 && e > 0.0);

    let same = error_map(&r, &r).expect("error_map");
    let diff = error_map(&t, &r).expect("error_map");
    assert_ne!(same, diff);
    // Identical images map every pixel to the bottom of the scale; the changed pixel is
    // the maximum error, i.e. the top of the scale.
    assert_eq!(same.get(20, 9), caustics_metrics::inferno(0.0));
    assert_eq!(diff.get(20, 9), caustics_metrics::inferno(1.0));
    assert_eq!(diff.get(0, 0), caustics_metrics::inferno(0.0));
}

#[test]
fn error_map_sees_a_pure_chroma_change() {
    // Same luminance, different colour: |t - r| per channel still shows.
    let r = HdrImage {
        width: 2,
        height: 1,
        pixels: vec![[1.0, 0.0, 0.0], [0.0; 3]],
    };
    let t = HdrImage {
        width: 2,
        height: 1,
        pixels: vec![[0.0, 0.2126 / 0.7152, 0.0], [0.0; 3]],
    };
    let m = error_map(&t, &r).expect("error_map");
    assert_eq!(m.get(0, 0), caustics_metrics::inferno(1.0));
    assert_eq!(m.get(1, 0), caustics_metrics::inferno(0.0));
}

#[test]
fn all_errors_bundles_the_individual_metrics() {
    let r = structured(24, 24);
    let t = noisy(&r, 0.1, 11);
    let tone = ToneMap::new(0.5);
    let e = all_errors(&t, &r, &tone).expect("all_errors");
    assert_eq!(e.rmse, rmse(&t, &r).expect("rmse"));
    assert_eq!(e.rel_mse, rel_mse(&t, &r, REL_MSE_EPS).expect("rel_mse"));
    // PSNR and SSIM are taken on the display-referred images (peak and range 1).
    let (dt, dr) = (tone.display(&t), tone.display(&r));
    assert_eq!(e.psnr_db, psnr(&dt, &dr, Some(1.0)).expect("psnr"));
    assert_eq!(
        e.ssim,
        caustics_metrics::ssim_with_range(&dt, &dr, Some(1.0)).expect("ssim")
    );
    assert_eq!(e.flip, flip(&t, &r, &tone).expect("flip"));
    let (s, after) = best_scale(&t, &r).expect("best_scale");
    assert_eq!((e.best_scale, e.rmse_after_best_scale), (s, after));
}

#[test]
fn errors_round_trip_through_json_even_with_infinite_psnr() {
    let r = structured(16, 16);
    let e = all_errors(&r, &r, &ToneMap::default()).expect("all_errors");
    assert_eq!(e.psnr_db, f64::INFINITY);
    assert_eq!(e.rmse, 0.0);
    assert_eq!(e.flip, 0.0);
    let json = serde_json::to_string(&e).expect("serialize");
    assert!(json.contains("\"psnr_db\":\"inf\""), "{json}");
    let back: Errors = serde_json::from_str(&json).expect("deserialize");
    assert_eq!(back, e);

    let finite = all_errors(&noisy(&r, 0.1, 2), &r, &ToneMap::default()).expect("all_errors");
    let back: Errors =
        serde_json::from_str(&serde_json::to_string(&finite).expect("ser")).expect("de");
    // serde_json without its `float_roundtrip` feature may be 1 ulp off when parsing.
    let pairs = [
        (back.rmse, finite.rmse),
        (back.rel_mse, finite.rel_mse),
        (back.psnr_db, finite.psnr_db),
        (back.ssim, finite.ssim),
        (back.flip, finite.flip),
        (back.best_scale, finite.best_scale),
        (back.rmse_after_best_scale, finite.rmse_after_best_scale),
    ];
    for (a, b) in pairs {
        assert!(close(a, b, 1e-14 * b.abs()), "{a} vs {b}");
    }
}

type Metric = fn(&HdrImage, &HdrImage) -> Result<(), MetricsError>;

fn every_metric() -> Vec<(&'static str, Metric)> {
    vec![
        ("rmse", |t, r| rmse(t, r).map(drop)),
        ("rel_mse", |t, r| rel_mse(t, r, REL_MSE_EPS).map(drop)),
        ("psnr", |t, r| psnr(t, r, None).map(drop)),
        ("ssim", |t, r| ssim(t, r).map(drop)),
        ("flip", |t, r| flip(t, r, &ToneMap::default()).map(drop)),
        ("best_scale", |t, r| best_scale(t, r).map(drop)),
        ("all_errors", |t, r| {
            all_errors(t, r, &ToneMap::default()).map(drop)
        }),
        ("error_map", |t, r| error_map(t, r).map(drop)),
    ]
}

#[test]
fn size_mismatch_is_an_error_not_a_number() {
    let r = structured(8, 8);
    for t in [structured(8, 7), structured(7, 8), structured(64, 1)] {
        for (name, metric) in every_metric() {
            match metric(&t, &r) {
                Err(MetricsError::SizeMismatch {
                    expected_width: 8,
                    expected_height: 8,
                    actual_width,
                    actual_height,
                    ..
                }) => assert_eq!((actual_width, actual_height), (t.width, t.height)),
                other => panic!("{name}: expected SizeMismatch, got {other:?}"),
            }
        }
    }
}

#[test]
fn non_finite_values_are_errors_naming_the_image_and_pixel() {
    let r = structured(8, 8);
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let mut poisoned = r.clone();
        poisoned.set(5, 3, [0.0, bad, 0.0]);
        poisoned.set(6, 7, [bad, 0.0, 0.0]); // later pixel: not the one reported
        for (name, metric) in every_metric() {
            for (t, rr, which) in [(&poisoned, &r, "test"), (&r, &poisoned, "reference")] {
                let err = metric(t, rr).expect_err(name);
                match &err {
                    MetricsError::NonFinite { image, x, y, value } => {
                        assert_eq!((image.as_str(), *x, *y), (which, 5, 3), "{name}");
                        assert!(value.is_nan() == bad.is_nan(), "{name}");
                    }
                    other => panic!("{name}: expected NonFinite, got {other:?}"),
                }
                let msg = err.to_string();
                assert!(msg.contains(which) && msg.contains("(5, 3)"), "{msg}");
            }
        }
    }
}

#[test]
fn empty_images_are_errors() {
    let e = HdrImage::new(0, 0);
    assert!(matches!(rmse(&e, &e), Err(MetricsError::Empty { .. })));
    assert!(matches!(
        flip(&e, &e, &ToneMap::default()),
        Err(MetricsError::Empty { .. })
    ));
}

#[test]
fn a_hot_spot_does_not_swamp_psnr_and_ssim() {
    // A reference with one pixel a thousand times brighter than the rest (a caustic
    // focus): an error everywhere else must still show in PSNR and SSIM.
    let mut r = structured(32, 32);
    r.pixels[0] = [1000.0; 3];
    let t = noisy(&r, 0.3, 5);
    let tone = ToneMap::new(1.0);
    let e = all_errors(&t, &r, &tone).expect("all_errors");
    assert!(e.ssim < 0.95, "ssim {}", e.ssim);
    assert!(e.psnr_db < 40.0, "psnr {}", e.psnr_db);
    // While on the linear image with the peak as range both look near-perfect.
    assert!(ssim(&t, &r).expect("ssim") > 0.999);
}

#[test]
fn ssim_range_must_be_positive() {
    let r = structured(8, 8);
    assert!(caustics_metrics::ssim_with_range(&r, &r, Some(0.0)).is_err());
    assert!(caustics_metrics::ssim_with_range(&r, &r, Some(f64::NAN)).is_err());
}

#[test]
fn error_quantile_ignores_equal_pixels_and_picks_the_quantile() {
    let r = HdrImage::new(4, 1);
    let mut t = HdrImage::new(4, 1);
    t.pixels[1] = [1.0; 3];
    t.pixels[2] = [2.0; 3];
    t.pixels[3] = [100.0; 3];
    assert_eq!(
        caustics_metrics::error_quantile(&r, &r, 0.99).expect("ok"),
        0.0
    );
    let q0 = caustics_metrics::error_quantile(&t, &r, 0.0).expect("ok");
    let q1 = caustics_metrics::error_quantile(&t, &r, 1.0).expect("ok");
    assert!(
        (q0 - 1.0).abs() < 1e-6 && (q1 - 100.0).abs() < 1e-4,
        "{q0} {q1}"
    );
    assert!(caustics_metrics::error_quantile(&t, &r, 1.5).is_err());
}
