//! Tone mapping, fill-rate heatmaps with their colour bar, and the histogram.

use caustics_metrics::{
    COLOR_BAR_WIDTH, HdrImage, HeatmapOptions, MIN_MAP_HEIGHT, MetricsError, PANEL_BACKGROUND,
    ToneMap, ZERO_COUNT_COLOUR, heatmap, heatmap_with, histogram, inferno, srgb_oetf,
};

#[test]
fn tone_map_encodes_known_values() {
    let tm = ToneMap::new(1.0);
    // 0.5 linear → 1.055·0.5^(1/2.4) − 0.055 = 0.7354 → 187.5 → 188.
    assert_eq!(tm.encode(0.5), 188);
    assert_eq!(tm.encode(0.0), 0);
    assert_eq!(tm.encode(1.0), 255);
    assert_eq!(tm.encode(7.0), 255, "clipped");
    assert_eq!(tm.encode(-1.0), 0, "clipped");
    assert_eq!(tm.encode(f32::NAN), 0);
    // Linear segment: 0.002 · 12.92 · 255 = 6.59 → 7.
    assert_eq!(tm.encode(0.002), 7);
    assert!((srgb_oetf(0.18) - 0.461_356).abs() < 1e-5);
    // Exposure scales before the curve: 0.25 at exposure 2 is 0.5 at exposure 1.
    let tm2 = ToneMap::new(2.0);
    assert_eq!(tm2.encode(0.25), 188);
    assert_eq!(tm2.encode(0.5), 255);
    let img = HdrImage {
        width: 2,
        height: 1,
        pixels: vec![[0.25, 0.5, 0.0], [1.0, 0.125, 0.0]],
    };
    let out = tm2.apply(&img);
    assert_eq!((out.width, out.height), (2, 1));
    assert_eq!(out.pixels, vec![[188, 255, 0], [255, tm.encode(0.25), 0]]);
}

#[test]
fn fit_percentile_maps_the_percentile_to_white() {
    let mut img = HdrImage::new(10, 10);
    for (i, p) in img.pixels.iter_mut().enumerate() {
        *p = [(i + 1) as f32; 3]; // luminance 1..=100
    }
    let tm = ToneMap::fit_percentile(&img, 1.0);
    assert!((tm.exposure_scale - 0.01).abs() < 1e-6);
    let tm = ToneMap::fit_percentile(&img, 0.5);
    assert!((tm.exposure_scale - 1.0 / 51.0).abs() < 1e-4, "{tm:?}");
    assert_eq!(
        ToneMap::fit_percentile(&HdrImage::new(3, 3), 0.99),
        ToneMap::default()
    );
}

/// 4x40 counts: column x holds count x (0, 1, 2, 4 → max 4).
fn columns() -> (Vec<u32>, u32, u32) {
    let (w, h) = (4u32, 40u32);
    let counts = (0..w * h).map(|i| [0, 1, 2, 4][(i % w) as usize]).collect();
    (counts, w, h)
}

#[test]
fn heatmap_colours_known_counts() {
    let (counts, w, h) = columns();
    let img = heatmap(&counts, w, h, "fragments/px").expect("heatmap");
    // As high as the map, or as the colour bar's title needs (the panel's background
    // continues below a small map).
    let title_h = caustics_metrics::text_width("fragments/px") + 10;
    assert_eq!(
        (img.width, img.height),
        (w + COLOR_BAR_WIDTH, h.max(title_h))
    );
    for y in [0, 17, 39] {
        assert_eq!(img.get(0, y), ZERO_COUNT_COLOUR, "zero count is dark");
        assert_eq!(img.get(1, y), inferno(0.25));
        assert_eq!(img.get(2, y), inferno(0.5));
        assert_eq!(img.get(3, y), inferno(1.0));
    }
    assert_eq!(inferno(1.0), [252, 255, 164]);
}

#[test]
fn heatmap_has_a_colour_bar_with_labels() {
    let (counts, w, h) = columns();
    let img = heatmap(&counts, w, h, "fragments/px").expect("heatmap");
    let panel: Vec<[u8; 3]> = (0..img.height)
        .flat_map(|y| (w..img.width).map(move |x| (x, y)))
        .map(|(x, y)| img.get(x, y))
        .collect();
    // The panel is not a copy of the image area: it has background, bar and label pixels.
    assert!(panel.contains(&PANEL_BACKGROUND));
    let bar_x = w + 10;
    let column: Vec<_> = (0..img.height).map(|y| img.get(bar_x, y)).collect();
    assert!(
        column.contains(&inferno(1.0)),
        "top of bar is the maximum colour"
    );
    assert!(
        column.contains(&ZERO_COUNT_COLOUR),
        "bottom of bar is the zero colour"
    );
    // Bar runs from bright at the top to dark at the bottom.
    let lum = |p: [u8; 3]| u32::from(p[0]) + u32::from(p[1]) + u32::from(p[2]);
    let at = |f: f64| column[(f * f64::from(img.height)) as usize];
    assert!(lum(at(0.12)) > lum(at(0.5)) && lum(at(0.5)) > lum(at(0.85)));
    // Labels and title are drawn in a light colour that appears nowhere in the image area.
    let light = panel.iter().filter(|p| p.iter().all(|&c| c > 200)).count();
    assert!(light > 30, "labels missing: {light} light pixels");
    // Different labels give different panels.
    let counts2: Vec<u32> = counts.iter().map(|c| c * 1000).collect();
    let img2 = heatmap(&counts2, w, h, "fragments/px").expect("heatmap");
    let panel2: Vec<_> = (0..img2.height)
        .flat_map(|y| (w..img2.width).map(move |x| (x, y)))
        .map(|(x, y)| img2.get(x, y))
        .collect();
    assert_ne!(panel, panel2, "max label 4 vs 4.00k must differ");
    // The image area is the same, since the scale is relative to the maximum.
    assert_eq!(img.get(2, 3), img2.get(2, 3));
}

#[test]
fn heatmap_options_fixed_max_and_log() {
    let (counts, w, h) = columns();
    let fixed = heatmap_with(
        &counts,
        w,
        h,
        "f",
        &HeatmapOptions {
            max: Some(8),
            log: false,
        },
    )
    .expect("heatmap");
    assert_eq!(fixed.get(3, 0), inferno(0.5));
    let log = heatmap_with(
        &counts,
        w,
        h,
        "f",
        &HeatmapOptions {
            max: None,
            log: true,
        },
    )
    .expect("heatmap");
    let t1 = (2.0f64.ln() / 5.0f64.ln()) as f32;
    assert_eq!(log.get(1, 0), inferno(t1));
    assert_eq!(log.get(3, 0), inferno(1.0));
    assert_eq!(log.get(0, 0), ZERO_COUNT_COLOUR);
}

#[test]
fn heatmap_of_tiny_or_empty_input() {
    let img = heatmap(&[0, 0, 0, 0], 2, 2, "fragments/px").expect("heatmap");
    assert_eq!(
        (img.width, img.height),
        (
            2 + COLOR_BAR_WIDTH,
            MIN_MAP_HEIGHT.max(caustics_metrics::text_width("fragments/px") + 10)
        )
    );
    assert_eq!(img.get(1, 1), ZERO_COUNT_COLOUR);
    assert_eq!(
        img.get(0, 5),
        PANEL_BACKGROUND,
        "padding below a short image"
    );
    assert!(matches!(
        heatmap(&[1, 2, 3], 2, 2, "x"),
        Err(MetricsError::BufferLength {
            expected: 4,
            actual: 3,
            ..
        })
    ));
}

#[test]
fn histogram_buckets_sum_to_the_pixel_count() {
    let counts = [0, 0, 1, 2, 3, 4, 5, 8, 9, 100, 2, 0];
    let h = histogram(&counts);
    assert_eq!(h.total_pixels(), counts.len() as u64);
    let got: Vec<(u32, u32, u64)> = h
        .buckets
        .iter()
        .map(|b| (b.min_count, b.max_count, b.pixels))
        .collect();
    assert_eq!(
        got,
        [
            (0, 0, 3),
            (1, 1, 1),
            (2, 2, 2),
            (3, 4, 2),
            (5, 8, 2),
            (9, 16, 1),
            (17, 32, 0),
            (33, 64, 0),
            (65, 128, 1),
        ]
    );
    let (c, ..) = columns();
    assert_eq!(histogram(&c).total_pixels(), c.len() as u64);
    let empty = histogram(&[]);
    assert_eq!(empty.total_pixels(), 0);
    assert_eq!(empty.buckets.len(), 1);
    let big = histogram(&[u32::MAX, 0]);
    assert_eq!(big.buckets.last().map(|b| b.max_count), Some(u32::MAX));
    assert_eq!(big.total_pixels(), 2);
}
