//! Colour-mapped images with a labelled colour bar: fill-rate heatmaps, error maps, and
//! the fill-rate histogram.

use serde::{Deserialize, Serialize};

use crate::colorbar::{ColourBar, with_colour_bar};
use crate::colormap::inferno;
use crate::error_metrics::check_pair;
use crate::{HdrImage, MetricsError, Rgb8Image};

/// Width in pixels of the colour-bar panel appended on the right of every heatmap and
/// error map: output width = image width + `COLOR_BAR_WIDTH`.
pub const COLOR_BAR_WIDTH: u32 = 80;
/// Minimum output height, so that the three labels fit even for tiny images; rows below
/// the image area are filled with [`PANEL_BACKGROUND`].
pub const MIN_MAP_HEIGHT: u32 = 32;
/// Colour of the panel behind the colour bar and its labels.
pub const PANEL_BACKGROUND: [u8; 3] = [40, 40, 40];
/// Colour of pixels with a count of zero in a [`heatmap`].
pub const ZERO_COUNT_COLOUR: [u8; 3] = [0, 0, 0];

/// Options for [`heatmap_with`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct HeatmapOptions {
    /// Count mapped to the top of the colour scale; counts above it saturate. `None` uses
    /// the image's maximum. Fix it to compare several methods' heatmaps on one scale.
    pub max: Option<u32>,
    /// Map `ln(1 + count)` instead of `count`, for long-tailed fill-rate distributions.
    pub log: bool,
}

impl HeatmapOptions {
    /// Options whose `max` is the largest count over all `panels`, so that every panel of
    /// a figure is drawn on one scale.
    pub fn shared(panels: &[&[u32]], log: bool) -> Self {
        let max = panels.iter().flat_map(|p| p.iter().copied()).max();
        Self { max, log }
    }
}

/// Fill-rate heatmap of per-pixel counts (row 0 top) with a linear colour scale from 0 to
/// the maximum count, see [`heatmap_with`].
pub fn heatmap(
    counts: &[u32],
    width: u32,
    height: u32,
    title: &str,
) -> Result<Rgb8Image, MetricsError> {
    heatmap_with(counts, width, height, title, &HeatmapOptions::default())
}

/// Fill-rate heatmap: each count is colour-mapped with inferno, zero counts are
/// [`ZERO_COUNT_COLOUR`] (black), and a [`COLOR_BAR_WIDTH`]-wide panel on the right holds
/// the colour bar, labelled with whole counts ([`count_ticks`]; counts ≥ 10⁴ are written
/// with `k` or `M`), and `title` written vertically.
///
/// A figure comparing methods passes one `options.max` to every panel (e.g. from
/// [`HeatmapOptions::shared`]), linear or log: a count then has the same colour in every
/// panel, and counts above the shared maximum saturate.
pub fn heatmap_with(
    counts: &[u32],
    width: u32,
    height: u32,
    title: &str,
    options: &HeatmapOptions,
) -> Result<Rgb8Image, MetricsError> {
    let expected = crate::image::pixel_count(width, height);
    if counts.len() != expected {
        return Err(MetricsError::BufferLength {
            what: format!("fragment counts for a {width}x{height} heatmap"),
            expected,
            actual: counts.len(),
        });
    }
    let max = options
        .max
        .unwrap_or_else(|| counts.iter().copied().max().unwrap_or(0));
    let max_f = f64::from(max);
    // t in [0, 1] of a count; 0 only for a zero count.
    let to_t = |c: f64| -> f64 {
        if max == 0 || c <= 0.0 {
            0.0
        } else if options.log {
            (c.ln_1p() / max_f.ln_1p()).min(1.0)
        } else {
            (c / max_f).min(1.0)
        }
    };
    let colour = |t: f64| {
        if t <= 0.0 {
            ZERO_COUNT_COLOUR
        } else {
            inferno(t as f32)
        }
    };
    let pixels = counts.iter().map(|&c| colour(to_t(f64::from(c)))).collect();
    let area = Rgb8Image {
        width,
        height,
        pixels,
    };
    let mut ticks: Vec<(f64, String)> = vec![(1.0, format_count(max_f)), (0.0, "0".to_owned())];
    ticks.extend(
        count_ticks(max, options.log)
            .into_iter()
            .filter(|&v| v != 0 && v != max)
            .map(|v| (to_t(f64::from(v)), format_count(f64::from(v)))),
    );
    let colour = &colour;
    Ok(with_colour_bar(
        &area,
        &ColourBar {
            colour,
            ticks,
            title,
            caps: None,
        },
    ))
}

/// The counts a heatmap's colour bar labels for a scale topped at `max`: whole numbers
/// only (no "2.5 fragments"), always 0 and `max`. Linear: multiples of a step of 1, 2 or
/// 5 × 10ᵏ giving at most 5 intervals. Log: 0, 1, 10, 100, … below `max`, and `max`.
/// Labels that would overlap on a short bar are left out when drawn, the ends first kept.
pub fn count_ticks(max: u32, log: bool) -> Vec<u32> {
    let mut ticks = vec![0u32];
    if max == 0 {
        return ticks;
    }
    if log {
        let mut v = 1u64;
        while v < u64::from(max) {
            ticks.push(v as u32);
            v *= 10;
        }
    } else {
        let mut step = 1u64;
        'search: for k in 0..10 {
            for m in [1u64, 2, 5] {
                step = m * 10u64.pow(k);
                if u64::from(max) <= 5 * step {
                    break 'search;
                }
            }
        }
        ticks.extend(
            (1..)
                .map(|i| i * step)
                .take_while(|&v| v < u64::from(max))
                .map(|v| v as u32),
        );
    }
    ticks.push(max);
    ticks
}

/// Error map (unsigned; [`signed_error_map`](crate::signed_error_map) replaces it in
/// figures, since it says whether a method is too bright or too dark): per-pixel luminance
/// of the absolute difference, `Y(|t − r|)` with the
/// Rec. 709 weights applied to the per-channel absolute errors (so a pure chroma error
/// still shows), colour-mapped with inferno on a linear scale from 0 to the maximum error,
/// with a colour bar labelled 0, mid and max (in W·m⁻²·sr⁻¹) on the right.
pub fn error_map(test: &HdrImage, reference: &HdrImage) -> Result<Rgb8Image, MetricsError> {
    error_map_with_max(test, reference, None)
}

/// Per-pixel `Y(|t − r|)` of two checked images.
fn error_luminance(test: &HdrImage, reference: &HdrImage) -> Vec<f64> {
    test.pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(t, r)| {
            let d = [0, 1, 2].map(|c| (f64::from(t[c]) - f64::from(r[c])).abs());
            crate::image::REC709_LUMINANCE
                .iter()
                .zip(d)
                .map(|(&w, d)| f64::from(w) * d)
                .sum()
        })
        .collect()
}

/// The `q`-quantile (0..=1) of the per-pixel error luminance `Y(|t − r|)` over the
/// pixels where it is non-zero (0 when the images are equal). A caustic's cusps put a
/// few pixels orders of magnitude above the rest; a scale topped at, say, the 0.99
/// quantile shows where the error is instead of only where it peaks.
pub fn error_quantile(test: &HdrImage, reference: &HdrImage, q: f64) -> Result<f64, MetricsError> {
    check_pair(test, reference)?;
    if !(0.0..=1.0).contains(&q) {
        return Err(MetricsError::InvalidParameter {
            name: "q",
            message: format!("must be in [0, 1], got {q}"),
        });
    }
    let mut e: Vec<f64> = error_luminance(test, reference)
        .into_iter()
        .filter(|&v| v > 0.0)
        .collect();
    if e.is_empty() {
        return Ok(0.0);
    }
    e.sort_by(f64::total_cmp);
    Ok(e[((e.len() - 1) as f64 * q).round() as usize])
}

/// [`error_map`] with the top of the scale fixed at `max` (errors above it saturate), so
/// that several methods' error maps share one scale. `None` uses the largest error.
pub fn error_map_with_max(
    test: &HdrImage,
    reference: &HdrImage,
    max: Option<f64>,
) -> Result<Rgb8Image, MetricsError> {
    check_pair(test, reference)?;
    let errors = error_luminance(test, reference);
    let max = match max {
        Some(m) if m > 0.0 && m.is_finite() => m,
        Some(m) => {
            return Err(MetricsError::InvalidParameter {
                name: "max",
                message: format!("error-map scale must be positive and finite, got {m}"),
            });
        }
        None => errors.iter().copied().fold(0.0, f64::max),
    };
    let to_t = |e: f64| if max > 0.0 { (e / max).min(1.0) } else { 0.0 };
    let colour = |t: f64| inferno(t as f32);
    let area = Rgb8Image {
        width: test.width,
        height: test.height,
        pixels: errors.iter().map(|&e| colour(to_t(e))).collect(),
    };
    let ticks = vec![
        (1.0, format_value(max)),
        (0.0, "0".to_owned()),
        (0.5, format_value(0.5 * max)),
    ];
    let colour = &colour;
    Ok(with_colour_bar(
        &area,
        &ColourBar {
            colour,
            ticks,
            title: "|test − ref|, luminance",
            caps: None,
        },
    ))
}

/// Formats a count for a colour-bar label: plain below 10 000, then `12.3k`, `1.23M`.
pub fn format_count(v: f64) -> String {
    let v = v.max(0.0);
    let sig3 = |x: f64| {
        if x < 10.0 {
            format!("{x:.2}")
        } else if x < 100.0 {
            format!("{x:.1}")
        } else {
            format!("{x:.0}")
        }
    };
    if v < 10.0 && v.fract() != 0.0 {
        // Mid-scale labels of small maxima (e.g. 0.5 for a maximum of 1 fragment/px).
        format!("{v:.1}")
    } else if v < 10_000.0 {
        format!("{}", v.round())
    } else if v < 999_500.0 {
        format!("{}k", sig3(v / 1e3))
    } else {
        format!("{}M", sig3(v / 1e6))
    }
}

/// Formats a real value with 3 significant digits for a colour-bar label: fixed notation
/// for 0.01 ≤ |v| < 1000, else `1.23e-05` style.
pub fn format_value(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v == 0.0 {
            "0".to_owned()
        } else {
            format!("{v}")
        };
    }
    let a = v.abs();
    let sign = if v < 0.0 { "-" } else { "" };
    if (0.01..999.5).contains(&a) {
        let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
        return format!("{sign}{a:.decimals$}");
    }
    let mut exp = a.log10().floor() as i32;
    let mut mant = a / 10f64.powi(exp);
    if mant >= 9.995 {
        mant /= 10.0;
        exp += 1;
    }
    let esign = if exp < 0 { '-' } else { '+' };
    format!("{sign}{mant:.2}e{esign}{:02}", exp.abs())
}

/// A fill-rate histogram, see [`histogram`].
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Histogram {
    /// Buckets in increasing order of count, from 0 up to the one holding the maximum.
    pub buckets: Vec<HistogramBucket>,
}

impl Histogram {
    /// Total pixels over all buckets (equals the number of counts).
    pub fn total_pixels(&self) -> u64 {
        self.buckets.iter().map(|b| b.pixels).sum()
    }
}

/// One bucket of a [`Histogram`]: the pixels whose count lies in `min_count..=max_count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct HistogramBucket {
    /// Smallest count in the bucket (inclusive).
    pub min_count: u32,
    /// Largest count in the bucket (inclusive).
    pub max_count: u32,
    /// Number of pixels whose count falls in the bucket.
    pub pixels: u64,
}

/// Index of the bucket holding count `c`: 0 → 0, 1 → 1, 2 → 2, 3–4 → 3, 5–8 → 4, …
fn bucket_index(c: u32) -> usize {
    if c == 0 {
        0
    } else {
        1 + (32 - (c - 1).leading_zeros()) as usize
    }
}

fn bucket_range(k: usize) -> (u32, u32) {
    match k {
        0 => (0, 0),
        1 => (1, 1),
        _ => {
            let hi = 1u64 << (k - 1);
            ((hi / 2 + 1) as u32, hi.min(u64::from(u32::MAX)) as u32)
        }
    }
}

/// Histogram of per-pixel counts with power-of-two buckets: 0, 1, 2, 3–4, 5–8, 9–16, …,
/// up to the bucket holding the largest count (empty buckets in between are kept, so
/// histograms of different methods line up). An empty slice gives one empty bucket `0`.
pub fn histogram(counts: &[u32]) -> Histogram {
    let max = counts.iter().copied().max().unwrap_or(0);
    let mut pixels = vec![0u64; bucket_index(max) + 1];
    for &c in counts {
        pixels[bucket_index(c)] += 1;
    }
    let buckets = pixels
        .into_iter()
        .enumerate()
        .map(|(k, pixels)| {
            let (min_count, max_count) = bucket_range(k);
            HistogramBucket {
                min_count,
                max_count,
                pixels,
            }
        })
        .collect();
    Histogram { buckets }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buckets_are_powers_of_two() {
        let ranges: Vec<_> = (0..6).map(bucket_range).collect();
        assert_eq!(ranges, [(0, 0), (1, 1), (2, 2), (3, 4), (5, 8), (9, 16)]);
        for c in [0u32, 1, 2, 3, 4, 5, 8, 9, 16, 17, 1000, u32::MAX] {
            let (lo, hi) = bucket_range(bucket_index(c));
            assert!(lo <= c && c <= hi, "{c} not in {lo}..={hi}");
        }
    }

    #[test]
    fn label_formats() {
        assert_eq!(format_count(0.0), "0");
        assert_eq!(format_count(9999.0), "9999");
        assert_eq!(format_count(0.5), "0.5");
        assert_eq!(format_count(2.0), "2");
        assert_eq!(format_count(12_345.0), "12.3k");
        assert_eq!(format_count(123_456.0), "123k");
        assert_eq!(format_count(1_234_567.0), "1.23M");
        assert_eq!(format_count(f64::from(u32::MAX)), "4295M");
        assert_eq!(format_value(0.5), "0.500");
        assert_eq!(format_value(0.0123), "0.0123");
        assert_eq!(format_value(123.4), "123");
        assert_eq!(format_value(1.234e-5), "1.23e-05");
        assert_eq!(format_value(9.999e-3), "1.00e-02");
        assert_eq!(format_value(12345.0), "1.23e+04");
    }
}
