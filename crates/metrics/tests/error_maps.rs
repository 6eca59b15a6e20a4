//! Signed and relative error maps (diverging, with units and clip marks), and heatmaps of
//! one figure drawn on one scale.

use anyhow::Result;
use caustics_metrics::{
    CLIP_HIGH_COLOUR, CLIP_LOW_COLOUR, COLOR_BAR_WIDTH, COOL_WARM_NEUTRAL, HdrImage,
    HeatmapOptions, ZERO_COUNT_COLOUR, cool_warm, count_ticks, heatmap_with, relative_error_floor,
    relative_error_map, signed_error_map, signed_error_max,
};

/// Reference: luminance 1 everywhere (grey 1.0). Test: column 0 exact, column 1 +0.5,
/// column 2 −0.5, column 3 +5 (beyond a ±1 scale), column 4 −5.
fn pair() -> (HdrImage, HdrImage) {
    let (w, h) = (5u32, 40u32);
    let reference = HdrImage {
        width: w,
        height: h,
        pixels: vec![[1.0; 3]; (w * h) as usize],
    };
    let mut test = reference.clone();
    for y in 0..h {
        for (x, d) in [0.0f32, 0.5, -0.5, 5.0, 0.0].into_iter().enumerate() {
            test.set(x as u32, y, [1.0 + d; 3]);
        }
        test.set(4, y, [-4.0; 3]);
    }
    (test, reference)
}

fn is_reddish(c: [u8; 3]) -> bool {
    c[0] > c[2] + 40
}
fn is_bluish(c: [u8; 3]) -> bool {
    c[2] > c[0] + 40
}

#[test]
fn signed_map_tells_too_bright_from_too_dark_and_marks_clipping() -> Result<()> {
    let (test, reference) = pair();
    let img = signed_error_map(&test, &reference, Some(1.0))?;
    assert_eq!(img.width, 5 + COLOR_BAR_WIDTH);
    assert_eq!(
        img.get(0, 7),
        COOL_WARM_NEUTRAL,
        "zero error is neutral grey"
    );
    assert_eq!(img.get(1, 7), cool_warm(0.75));
    assert!(
        is_reddish(img.get(1, 7)),
        "too bright is red: {:?}",
        img.get(1, 7)
    );
    assert_eq!(img.get(2, 7), cool_warm(0.25));
    assert!(
        is_bluish(img.get(2, 7)),
        "too dark is blue: {:?}",
        img.get(2, 7)
    );
    assert_eq!(
        img.get(3, 7),
        CLIP_HIGH_COLOUR,
        "+5 beyond +1 is clipped and marked"
    );
    assert_eq!(
        img.get(4, 7),
        CLIP_LOW_COLOUR,
        "-5 beyond -1 is clipped and marked"
    );
    // The bar carries both clip colours as caps, red above blue.
    let bar: Vec<[u8; 3]> = (0..img.height).map(|y| img.get(5 + 10, y)).collect();
    let first = |c: [u8; 3]| bar.iter().position(|&b| b == c);
    assert!(first(CLIP_HIGH_COLOUR) < first(cool_warm(1.0)));
    assert!(first(cool_warm(1.0)) < first(cool_warm(0.0)));
    assert!(first(cool_warm(0.0)) < first(CLIP_LOW_COLOUR));
    // Comparator: identical images give a neutral map everywhere (and above, a difference
    // gives colours).
    let same = signed_error_map(&reference, &reference, None)?;
    assert!((0..40).all(|y| (0..5).all(|x| same.get(x, y) == COOL_WARM_NEUTRAL)));
    // Default scale: the 99th percentile of |error| over erring pixels (here 5).
    assert_eq!(signed_error_max(&test, &reference)?, 5.0);
    let auto = signed_error_map(&test, &reference, None)?;
    assert_eq!(
        auto.get(3, 0),
        cool_warm(1.0),
        "at the default scale +5 is the top"
    );
    assert_eq!(auto.get(1, 0), cool_warm(0.5 + 0.5 * 0.5 / 5.0));
    // Different scales label the bar differently (units on the bar).
    assert_ne!(
        signed_error_map(&test, &reference, Some(2.0))?,
        signed_error_map(&test, &reference, Some(1.0))?
    );
    assert!(signed_error_map(&test, &reference, Some(0.0)).is_err());
    assert!(signed_error_map(&test, &reference, Some(f32::NAN)).is_err());
    Ok(())
}

#[test]
fn relative_map_is_in_percent_with_a_floor() -> Result<()> {
    let (w, h) = (4u32, 40u32);
    let mut reference = HdrImage::new(w, h);
    let mut test = HdrImage::new(w, h);
    for y in 0..h {
        // Bright pixel 10 → 15 (+50%), dim 2 → 1 (−50%), black 0 → 0.05 (floor), exact.
        for (x, (r, t)) in [(10.0f32, 15.0f32), (2.0, 1.0), (0.0, 0.05), (4.0, 4.0)]
            .into_iter()
            .enumerate()
        {
            reference.set(x as u32, y, [r; 3]);
            test.set(x as u32, y, [t; 3]);
        }
    }
    // 99th percentile of the non-zero luminances is 10: floor 0.1.
    let floor = relative_error_floor(&reference).expect("floor");
    assert!((floor - 0.1).abs() < 1e-6, "{floor}");
    let img = relative_error_map(&test, &reference, None)?;
    assert_eq!(img.get(0, 3), cool_warm(0.75), "+50% of ±100%");
    assert_eq!(img.get(1, 3), cool_warm(0.25), "−50%");
    // 0.05 over the floor 0.1 is +50%, not infinity.
    assert_eq!(img.get(2, 3), cool_warm(0.75));
    assert_eq!(img.get(3, 3), COOL_WARM_NEUTRAL);
    let tight = relative_error_map(&test, &reference, Some(0.25))?;
    assert_eq!(tight.get(0, 3), CLIP_HIGH_COLOUR);
    assert_eq!(tight.get(1, 3), CLIP_LOW_COLOUR);
    assert!(relative_error_map(&test, &HdrImage::new(w, h), None).is_err());
    Ok(())
}

#[test]
fn heatmaps_share_one_scale_linear_and_log() -> Result<()> {
    let (w, h) = (3u32, 40u32);
    // Panel A tops out at 10, panel B at 100; both hold a pixel with count 5.
    let a: Vec<u32> = (0..w * h).map(|i| [0, 5, 10][(i % w) as usize]).collect();
    let b: Vec<u32> = (0..w * h).map(|i| [0, 5, 100][(i % w) as usize]).collect();
    for log in [false, true] {
        let own = |c: &[u32]| heatmap_with(c, w, h, "f", &HeatmapOptions { max: None, log });
        assert_ne!(
            own(&a)?.get(1, 0),
            own(&b)?.get(1, 0),
            "own maxima: 5 differs"
        );
        let shared = HeatmapOptions::shared(&[&a, &b], log);
        assert_eq!(
            shared,
            HeatmapOptions {
                max: Some(100),
                log
            }
        );
        let pa = heatmap_with(&a, w, h, "f", &shared)?;
        let pb = heatmap_with(&b, w, h, "f", &shared)?;
        assert_eq!(
            pa.get(1, 0),
            pb.get(1, 0),
            "shared max: 5 is one colour (log {log})"
        );
        assert_eq!(pa.get(0, 0), ZERO_COUNT_COLOUR);
        assert_eq!(pb.get(2, 0), caustics_metrics::inferno(1.0));
        assert_ne!(pa.get(2, 0), pb.get(2, 0), "10 is below the shared top");
        // The bars of both panels are identical: one scale, one legend.
        let bar = |img: &caustics_metrics::Rgb8Image| -> Vec<[u8; 3]> {
            (0..h)
                .flat_map(|y| (w..img.width).map(move |x| (x, y)))
                .map(|(x, y)| img.get(x, y))
                .collect()
        };
        assert_eq!(bar(&pa), bar(&pb));
        // Counts above a shared max saturate.
        let low = HeatmapOptions { max: Some(4), log };
        assert_eq!(
            heatmap_with(&a, w, h, "f", &low)?.get(1, 0),
            caustics_metrics::inferno(1.0)
        );
    }
    Ok(())
}

#[test]
fn count_ticks_are_whole_counts() {
    assert_eq!(count_ticks(0, false), [0]);
    assert_eq!(count_ticks(1, false), [0, 1]);
    assert_eq!(count_ticks(5, false), [0, 1, 2, 3, 4, 5]);
    assert_eq!(count_ticks(7, false), [0, 2, 4, 6, 7]);
    assert_eq!(count_ticks(100, false), [0, 20, 40, 60, 80, 100]);
    assert_eq!(count_ticks(1234, false), [0, 500, 1000, 1234]);
    assert_eq!(count_ticks(1234, true), [0, 1, 10, 100, 1000, 1234]);
    assert_eq!(count_ticks(1, true), [0, 1]);
    assert_eq!(count_ticks(u32::MAX, false).last(), Some(&u32::MAX));
    assert_eq!(count_ticks(u32::MAX, true).len(), 12);
}
