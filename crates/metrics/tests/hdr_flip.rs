//! HDR-FLIP against the authors' implementation (flip-evaluator 1.7, fixture made by
//! `tests/data/make_hdr_flip_fixture.py`), and what it sees that LDR-FLIP at one exposure
//! does not.

use std::path::PathBuf;

use anyhow::{Context, Result};
use caustics_metrics::{
    FLIP_PIXELS_PER_DEGREE, HdrImage, ToneMap, flip, hdr_flip, hdr_flip_exposures, read_exr,
};
use serde_json::Value;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn fixture() -> Result<(HdrImage, HdrImage, Value)> {
    let reference = read_exr(&data("hdr_flip_reference.exr"))?;
    let test = read_exr(&data("hdr_flip_test.exr"))?;
    let json = std::fs::read_to_string(data("hdr_flip_fixture.json"))?;
    Ok((test, reference, serde_json::from_str(&json)?))
}

fn num(v: &Value, key: &str) -> Result<f64> {
    v[key]
        .as_f64()
        .with_context(|| format!("fixture key {key}"))
}

#[test]
fn hdr_flip_matches_the_authors_implementation() -> Result<()> {
    let (test, reference, fx) = fixture()?;
    assert_eq!(
        num(&fx, "pixels_per_degree")?,
        f64::from(FLIP_PIXELS_PER_DEGREE)
    );
    assert_eq!((reference.width, reference.height), (64, 48));
    let ours = hdr_flip(&test, &reference)?;
    let (mean, start, stop) = (
        num(&fx, "mean")?,
        num(&fx, "start_exposure")?,
        num(&fx, "stop_exposure")?,
    );
    println!(
        "HDR-FLIP mean: ours {:.6}, authors {mean:.6}, diff {:+.2e}; start {} vs {start}; stop {} vs {stop}; n {} vs {}",
        ours.mean,
        ours.mean - mean,
        ours.start_exposure,
        ours.stop_exposure,
        ours.exposures,
        fx["num_exposures"]
    );
    assert!((f64::from(ours.start_exposure) - start).abs() < 1e-3);
    assert!((f64::from(ours.stop_exposure) - stop).abs() < 1e-3);
    assert_eq!(
        u64::from(ours.exposures),
        fx["num_exposures"].as_u64().context("n")?
    );
    assert!((ours.mean - mean).abs() < 1e-3, "{} vs {mean}", ours.mean);
    // The map, block by block (8x8 means): the same structure, not only the same mean.
    let b = fx["block_size"].as_u64().context("block")? as usize;
    let blocks = fx["block_means"].as_array().context("blocks")?;
    let w = reference.width as usize;
    let mut worst = 0.0f64;
    for (by, row) in blocks.iter().enumerate() {
        for (bx, want) in row.as_array().context("row")?.iter().enumerate() {
            let want = want.as_f64().context("block value")?;
            let mut sum = 0.0;
            for y in by * b..(by + 1) * b {
                for x in bx * b..(bx + 1) * b {
                    sum += f64::from(ours.hdr_flip_map[y * w + x]);
                }
            }
            worst = worst.max((sum / (b * b) as f64 - want).abs());
        }
    }
    println!("largest 8x8 block deviation: {worst:.2e}");
    assert!(worst < 5e-3, "{worst}");
    Ok(())
}

/// A 64x48 receiver at `floor` (the test at `test_gain × floor`) with a bright focus
/// (peak 8 W·m⁻²·sr⁻¹, the same in both) in the left third.
fn dark_receiver(floor: f32, test_gain: f32) -> (HdrImage, HdrImage) {
    let (w, h) = (64u32, 48u32);
    let mut reference = HdrImage::new(w, h);
    let mut test = HdrImage::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let d2 = (x as f32 - 10.5).powi(2) + (y as f32 - 23.5).powi(2);
            let focus = 8.0 * (-d2 / 8.0).exp();
            reference.set(x, y, [floor + focus; 3]);
            test.set(x, y, [test_gain * floor + focus; 3]);
        }
    }
    (test, reference)
}

/// A receiver 13 stops below the focus, 2× too bright in the test: at the harness's fixed
/// exposure (ToneMap exposure_scale 2) reference 1e-4 and test 2e-4 W·m⁻²·sr⁻¹ both encode
/// to sRGB code 1, so LDR-FLIP sees almost nothing (measured 0.0013, all of it next to the
/// focus); HDR-FLIP brackets exposures up to the reference's median and reports 0.433.
/// At 1e-2 W·m⁻²·sr⁻¹ the same exposure does see the error (codes 39 vs 56, LDR-FLIP 0.235,
/// HDR-FLIP 0.442): the blind spot is the receiver within a few codes of black.
#[test]
fn hdr_flip_sees_a_dark_receiver_error_that_ldr_flip_misses() -> Result<()> {
    let tone = ToneMap::new(2.0);
    let (test, reference) = dark_receiver(1e-4, 2.0);
    assert_eq!((tone.encode(1e-4), tone.encode(2e-4)), (1, 1));
    let ldr = flip(&test, &reference, &tone)?;
    let hdr = hdr_flip(&test, &reference)?;
    println!(
        "LDR-FLIP {ldr:.5}, HDR-FLIP {:.5} over {} exposures {}..{}",
        hdr.mean, hdr.exposures, hdr.start_exposure, hdr.stop_exposure
    );
    assert!(ldr < 0.005, "LDR-FLIP {ldr}");
    assert!(hdr.mean > 0.4, "HDR-FLIP {}", hdr.mean);
    // The bracket: the focus (luminance ≈ 7.8) just below white, the receiver (the median,
    // 1e-4) at 0.85: log2(2.1189 / 7.79) ≈ −1.83 and log2(2.1189 / 1e-4) ≈ 14.37.
    assert!(
        (hdr.start_exposure + 1.83).abs() < 0.01,
        "{}",
        hdr.start_exposure
    );
    assert!(
        (hdr.stop_exposure - 14.37).abs() < 0.01,
        "{}",
        hdr.stop_exposure
    );
    assert_eq!(hdr.exposures, 17);
    // Comparator check: an identical pair scores exactly 0.
    assert_eq!(hdr_flip(&reference, &reference)?.mean, 0.0);
    // At 1e-2 the fixed exposure sees the error too.
    let (test, reference) = dark_receiver(1e-2, 2.0);
    assert!(flip(&test, &reference, &tone)? > 0.2);
    Ok(())
}

#[test]
fn hdr_flip_refuses_a_black_reference_and_bad_brackets() {
    let black = HdrImage::new(8, 8);
    assert!(hdr_flip_exposures(&black).is_err());
    assert!(hdr_flip(&black, &black).is_err());
    let (t, r) = dark_receiver(1e-3, 2.0);
    assert!(caustics_metrics::hdr_flip_with_exposures(&t, &r, 2.0, 1.0).is_err());
    assert!(caustics_metrics::hdr_flip_with_exposures(&t, &r, 0.0, f32::INFINITY).is_err());
    let mut nan = r.clone();
    nan.set(1, 1, [f32::NAN; 3]);
    assert!(hdr_flip(&t, &nan).is_err());
}

/// On a caustic image (black outside its caustic) the whole-image median is 0 and the
/// authors' bracket runs to ~24 stops; the bracket over the caustic region stops where
/// the region's median content sits at 0.85, a few stops below the start.
#[test]
fn the_caustic_region_bracket_ends_at_the_regions_median() {
    let mut reference = HdrImage::new(40, 30);
    for y in 10..20 {
        for x in 10..30 {
            reference.set(x, y, [0.5 + 0.1 * (x % 3) as f32; 3]);
        }
    }
    reference.set(20, 15, [8.0; 3]);
    let region = caustics_metrics::caustic_region(&reference);
    let (start, whole) = caustics_metrics::hdr_flip_exposures(&reference).expect("whole image");
    let (start_r, stop_r) =
        caustics_metrics::hdr_flip_exposures_over(&reference, &region).expect("region");
    assert_eq!(start, start_r);
    assert!(whole - start > 20.0, "whole-image bracket {start}..{whole}");
    // Median content 0.6: log2(8 / 0.6) ≈ 3.7 stops wide.
    assert!(
        ((stop_r - start_r) - (8.0f32 / 0.6).log2()).abs() < 0.05,
        "region bracket {start_r}..{stop_r}"
    );
    // A wrong-length region is an error, not a panic.
    assert!(caustics_metrics::hdr_flip_exposures_over(&reference, &region[1..]).is_err());
}
