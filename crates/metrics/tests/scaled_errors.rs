//! The errors after the best single scale tell a brightness (normalization) error from a
//! shape error: a comparator must report each difference when it exists (STYLE 6).

use caustics_metrics::{HdrImage, ToneMap, all_errors};

fn caustic(width: u32, height: u32, cx: f32) -> HdrImage {
    let mut img = HdrImage::new(width, height);
    for y in 0..height {
        for x in 0..width {
            let d2 = (x as f32 - cx).powi(2) + (y as f32 - height as f32 / 2.0).powi(2);
            let v = 2.0 * (-d2 / 8.0).exp();
            img.set(x, y, [v, v, 0.8 * v]);
        }
    }
    img
}

#[test]
fn wrong_brightness_vanishes_after_the_best_scale_but_wrong_shape_does_not() {
    let reference = caustic(32, 24, 16.0);
    let tone = ToneMap {
        exposure_scale: 1.0,
    };

    // Right shape, a factor of π too dark: large plain errors, none after scaling.
    let dark = reference.scaled(1.0 / std::f32::consts::PI);
    let e = all_errors(&dark, &reference, &tone).expect("errors");
    assert!((e.best_scale - std::f64::consts::PI).abs() < 1e-4, "{e:?}");
    assert!(e.rmse > 0.05 && e.rel_mse > 0.02 && e.flip > 0.01, "{e:?}");
    assert!(e.rmse_after_best_scale < 1e-6, "{e:?}");
    assert!(e.rel_mse_after_best_scale.expect("set") < 1e-10, "{e:?}");
    assert!(e.flip_after_best_scale.expect("set") < 1e-3, "{e:?}");

    // Right brightness, caustic in the wrong place: scaling cannot help.
    let moved = caustic(32, 24, 8.0);
    let e = all_errors(&moved, &reference, &tone).expect("errors");
    assert!(e.rmse_after_best_scale > 0.5 * e.rmse, "{e:?}");
    // (relMSE drops a lot by scaling the misplaced spot towards black, but far from 0.)
    assert!(e.rel_mse_after_best_scale.expect("set") > 0.05, "{e:?}");
    assert!(e.flip_after_best_scale.expect("set") > 0.01, "{e:?}");
}

#[test]
fn result_files_without_the_scaled_fields_still_read() {
    let old = r#"{"rmse": 0.1, "rel_mse": 0.2, "psnr_db": "inf", "ssim": 1.0, "flip": 0.0,
                  "best_scale": 1.0, "rmse_after_best_scale": 0.1}"#;
    let e: caustics_metrics::Errors = serde_json::from_str(old).expect("old file");
    assert_eq!(e.rel_mse_after_best_scale, None);
    assert_eq!(e.flip_after_best_scale, None);
}
