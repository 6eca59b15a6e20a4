//! Energy before shape: the caustic region, flux ratios, and the errors after flux
//! normalization that `all_errors` stores.

mod common;

use anyhow::Result;
use caustics_metrics::{
    Errors, HdrImage, ToneMap, all_errors, caustic_region, flux_ratio, luminance,
};
use common::structured;

/// A black floor with a caustic: a ring of radiance 1 around a focus of 500 at (20, 12),
/// and one faint noise-floor hit of 1e-3.
fn caustic(shift: u32) -> HdrImage {
    let mut img = HdrImage::new(40, 24);
    for y in 0..24u32 {
        for x in 0..40u32 {
            let r = ((x as f32 - 20.0 - shift as f32).powi(2) + (y as f32 - 12.0).powi(2)).sqrt();
            if (4.0..7.0).contains(&r) {
                img.set(x, y, [1.0, 1.0, 1.0]);
            }
        }
    }
    img.set(20 + shift, 12, [500.0; 3]);
    img.set(2, 2, [1e-3; 3]);
    img
}

#[test]
fn flux_ratio_of_a_scaled_image_is_the_scale() -> Result<()> {
    let reference = caustic(0);
    let region = caustic_region(&reference);
    for k in [0.5f32, 1.0, 3.0] {
        let test = reference.scaled(k);
        let image = flux_ratio(&test, &reference, None)?.expect("ratio");
        let inside = flux_ratio(&test, &reference, Some(&region))?.expect("ratio");
        assert!((image - f64::from(k)).abs() < 1e-6, "{image}");
        assert!((inside - f64::from(k)).abs() < 1e-6, "{inside}");
    }
    // Light missing from the ring (the focus kept) shows as a ratio below 1.
    let mut test = reference.clone();
    for p in &mut test.pixels {
        if p[0] == 1.0 {
            *p = [0.0; 3];
        }
    }
    let r = flux_ratio(&test, &reference, Some(&region))?.expect("ratio");
    assert!(r < 1.0 && r > 0.5, "{r}");
    // No ratio against a black reference; a wrong-length region is an error.
    let black = HdrImage::new(40, 24);
    assert_eq!(flux_ratio(&reference, &black, None)?, None);
    assert!(flux_ratio(&reference, &reference, Some(&region[1..])).is_err());
    Ok(())
}

#[test]
fn caustic_region_rule() {
    let reference = caustic(0);
    let region = caustic_region(&reference);
    let at = |x: u32, y: u32| region[(y * 40 + x) as usize];
    assert!(at(20, 12), "the focus");
    assert!(at(25, 12), "the ring");
    assert!(
        !at(2, 2),
        "the 1e-3 noise-floor hit is below 1% of the 99th percentile"
    );
    assert!(!at(0, 0), "black");
    // The 99th percentile of the non-zero luminances is the ring's 1, not the focus's 500:
    // a pixel at 0.02 is in, one at 0.005 is out.
    let mut r2 = reference.clone();
    r2.set(0, 23, [0.02; 3]);
    r2.set(1, 23, [0.005; 3]);
    let region2 = caustic_region(&r2);
    assert!(region2[23 * 40] && !region2[23 * 40 + 1]);
    assert!(caustic_region(&HdrImage::new(5, 5)).iter().all(|&b| !b));
    let n = region.iter().filter(|&&b| b).count();
    let ring = reference
        .pixels
        .iter()
        .filter(|p| luminance(**p) >= 1.0 - 1e-6)
        .count();
    assert_eq!(n, ring);
}

#[test]
fn rel_mse_after_flux_vanishes_for_brightness_and_stays_for_shape() -> Result<()> {
    let reference = caustic(0);
    let tone = ToneMap::fit_percentile(&reference, 0.99);
    let bright = all_errors(&reference.scaled(1.7), &reference, &tone)?;
    assert!((bright.flux_ratio.expect("flux") - 1.7).abs() < 1e-6);
    assert!((bright.flux_ratio_image.expect("flux") - 1.7).abs() < 1e-6);
    assert!(bright.rel_mse > 0.02, "{}", bright.rel_mse);
    assert!(bright.rel_mse_after_flux.expect("relmse") < 1e-10);
    assert!(bright.hdr_flip.expect("hdr") > 0.01);
    assert!(bright.hdr_flip_after_flux.expect("hdr") < 1e-3);
    // A shape error (the caustic moved by 2 px, same flux): the ratio is 1, the error stays.
    let moved = all_errors(&caustic(2), &reference, &tone)?;
    assert!((moved.flux_ratio_image.expect("flux") - 1.0).abs() < 1e-6);
    assert!(moved.rel_mse_after_flux.expect("relmse") > 0.02);
    assert!(moved.hdr_flip_after_flux.expect("hdr") > 0.05);
    let (start, stop) = (
        moved.hdr_flip_start_exposure.expect("start"),
        moved.hdr_flip_stop_exposure.expect("stop"),
    );
    assert!(start < stop);
    // Identical images: every error is zero (and the comparator above shows it is not
    // zero when the images differ).
    let same = all_errors(&reference, &reference, &tone)?;
    assert_eq!(same.hdr_flip, Some(0.0));
    assert_eq!(same.rel_mse_after_flux, Some(0.0));
    assert_eq!(same.flux_ratio, Some(1.0));
    Ok(())
}

#[test]
fn new_fields_round_trip_and_old_files_still_read() -> Result<()> {
    let reference = structured(24, 16);
    let e = all_errors(&reference.scaled(0.8), &reference, &ToneMap::new(1.0))?;
    let json = serde_json::to_string(&e)?;
    for key in [
        "flux_ratio",
        "flux_ratio_image",
        "rel_mse_after_flux",
        "hdr_flip",
        "hdr_flip_after_flux",
        "hdr_flip_start_exposure",
        "hdr_flip_stop_exposure",
    ] {
        assert!(
            json.contains(&format!("\"{key}\"")),
            "{key} missing in {json}"
        );
    }
    let back: Errors = serde_json::from_str(&json)?;
    assert_eq!(back, e);
    let old = r#"{"rmse":1.0,"rel_mse":0.5,"psnr_db":"inf","ssim":1.0,"flip":0.0,
                  "best_scale":1.0,"rmse_after_best_scale":0.0}"#;
    let old: Errors = serde_json::from_str(old)?;
    assert_eq!((old.flux_ratio, old.hdr_flip), (None, None));
    // A black reference: no flux ratio and no HDR-FLIP, the rest still scored.
    let black = HdrImage::new(24, 16);
    let e = all_errors(&reference, &black, &ToneMap::new(1.0))?;
    assert_eq!(
        (e.flux_ratio, e.flux_ratio_image, e.hdr_flip),
        (None, None, None)
    );
    assert!(!serde_json::to_string(&e)?.contains("hdr_flip"));
    Ok(())
}
