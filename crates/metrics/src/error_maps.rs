//! Signed error maps with units: test − reference per pixel on a diverging scale
//! (too bright is red, too dark is blue, zero is neutral grey), absolute in
//! W·m⁻²·sr⁻¹ or relative in percent.

use crate::colorbar::{ColourBar, with_colour_bar};
use crate::colormap::cool_warm;
use crate::error_metrics::check_pair;
use crate::flux::positive_luminance_quantile;
use crate::heatmap::format_value;
use crate::{CAUSTIC_REGION_FRACTION, HdrImage, MetricsError, Rgb8Image, luminance};

/// Colour of pixels whose error is above `+max` (clipped): saturated yellow, outside the
/// blue–grey–red map; also the cap drawn above the colour bar.
pub const CLIP_HIGH_COLOUR: [u8; 3] = [255, 214, 0];
/// Colour of pixels whose error is below `−max` (clipped): saturated green; also the cap
/// drawn below the colour bar.
pub const CLIP_LOW_COLOUR: [u8; 3] = [0, 190, 80];

/// Quantile of `|Y(t) − Y(r)|` (over the pixels where it is non-zero) that tops the
/// default scale of [`signed_error_map`].
pub const SIGNED_ERROR_QUANTILE: f64 = 0.99;

fn signed_differences(test: &HdrImage, reference: &HdrImage) -> Vec<f32> {
    test.pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(&t, &r)| luminance(t) - luminance(r))
        .collect()
}

/// The default scale of [`signed_error_map`]: the [`SIGNED_ERROR_QUANTILE`] (99th
/// percentile, nearest rank) of `|Y(t) − Y(r)|` over the pixels where it is non-zero, in
/// W·m⁻²·sr⁻¹; 1 when the images have the same luminance everywhere. A figure takes the
/// largest of its panels' values and passes it to every panel.
pub fn signed_error_max(test: &HdrImage, reference: &HdrImage) -> Result<f32, MetricsError> {
    check_pair(test, reference)?;
    let mut e: Vec<f32> = signed_differences(test, reference)
        .into_iter()
        .map(f32::abs)
        .filter(|&v| v > 0.0)
        .collect();
    if e.is_empty() {
        return Ok(1.0);
    }
    e.sort_by(f32::total_cmp);
    Ok(e[((e.len() - 1) as f64 * SIGNED_ERROR_QUANTILE).round() as usize])
}

/// Signed error map: `Y(t) − Y(r)` per pixel (Rec. 709 luminance, W·m⁻²·sr⁻¹) on
/// Moreland's cool-warm diverging map, symmetric about 0: `−max_abs` is blue, 0 the
/// neutral grey [`COOL_WARM_NEUTRAL`](crate::COOL_WARM_NEUTRAL), `+max_abs` red, linear in
/// between. A colour bar on the right is labelled in W·m⁻²·sr⁻¹ (title `test − ref, W·m⁻²·sr⁻¹`: the luminance difference).
///
/// Clipping rule: a pixel with an error above `+max_abs` is drawn [`CLIP_HIGH_COLOUR`]
/// (yellow), below `−max_abs` [`CLIP_LOW_COLOUR`] (green); the bar carries caps in those
/// colours at its ends, so a clipped pixel never passes for an in-range one.
///
/// `max_abs` defaults to [`signed_error_max`]; pass one value to every panel of a figure.
/// Fails on a non-positive or non-finite `max_abs` and on images that do not pair up.
pub fn signed_error_map(
    test: &HdrImage,
    reference: &HdrImage,
    max_abs: Option<f32>,
) -> Result<Rgb8Image, MetricsError> {
    check_pair(test, reference)?;
    let max = match max_abs {
        Some(m) => positive("max_abs", m)?,
        None => signed_error_max(test, reference)?,
    };
    let d = signed_differences(test, reference);
    let ticks = symmetric_ticks(|v| format_signed(f64::from(v) * f64::from(max)));
    Ok(diverging(test, &d, max, ticks, "test − ref, W·m⁻²·sr⁻¹"))
}

/// The floor of [`relative_error_map`]'s denominator: [`CAUSTIC_REGION_FRACTION`] (1%) of
/// the 99th percentile of the reference's non-zero luminances, in W·m⁻²·sr⁻¹ — the
/// threshold of [`caustic_region`](crate::caustic_region). Inside the caustic region the
/// map is the plain relative error; outside it, errors are measured against the floor, so
/// black and noise-floor pixels do not explode. `None` for a black reference.
pub fn relative_error_floor(reference: &HdrImage) -> Option<f32> {
    positive_luminance_quantile(reference, crate::CAUSTIC_REGION_PERCENTILE)
        .map(|p| CAUSTIC_REGION_FRACTION * p)
}

/// Relative error map: `(Y(t) − Y(r)) / max(Y(r), floor)` per pixel with the floor of
/// [`relative_error_floor`], on the same diverging map and clipping rule as
/// [`signed_error_map`], symmetric over `±max_rel` (default 1, i.e. ±100%); the colour bar
/// is labelled in percent (title `(test − ref) / ref, %`).
///
/// Fails with [`MetricsError::InvalidParameter`] for a black reference (no relative error
/// exists) or a non-positive `max_rel`.
pub fn relative_error_map(
    test: &HdrImage,
    reference: &HdrImage,
    max_rel: Option<f32>,
) -> Result<Rgb8Image, MetricsError> {
    check_pair(test, reference)?;
    let max = positive("max_rel", max_rel.unwrap_or(1.0))?;
    let floor = relative_error_floor(reference).ok_or_else(|| MetricsError::InvalidParameter {
        name: "reference",
        message: "a black reference has no relative error".to_owned(),
    })?;
    let d: Vec<f32> = test
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(&t, &r)| (luminance(t) - luminance(r)) / luminance(r).max(floor))
        .collect();
    let ticks = symmetric_ticks(|v| format_percent(f64::from(v) * f64::from(max)));
    Ok(diverging(test, &d, max, ticks, "(test − ref) / ref, %"))
}

fn positive(name: &'static str, v: f32) -> Result<f32, MetricsError> {
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(MetricsError::InvalidParameter {
            name,
            message: format!("scale must be positive and finite, got {v}"),
        })
    }
}

/// Ticks at ±1, 0, ±½ of the scale (in that priority), labelled by `label(fraction)`.
fn symmetric_ticks(label: impl Fn(f32) -> String) -> Vec<(f64, String)> {
    [
        (1.0, 1.0),
        (0.0, -1.0),
        (0.5, 0.0),
        (0.75, 0.5),
        (0.25, -0.5),
    ]
    .into_iter()
    .map(|(t, v)| (t, label(v)))
    .collect()
}

/// Colour of a signed value `v` on a ±`max` diverging scale, clipped values marked.
pub(crate) fn diverging_colour(v: f32, max: f32) -> [u8; 3] {
    if v > max {
        CLIP_HIGH_COLOUR
    } else if v < -max {
        CLIP_LOW_COLOUR
    } else {
        cool_warm(0.5 + 0.5 * v / max)
    }
}

fn diverging(
    like: &HdrImage,
    values: &[f32],
    max: f32,
    ticks: Vec<(f64, String)>,
    title: &str,
) -> Rgb8Image {
    let area = Rgb8Image {
        width: like.width,
        height: like.height,
        pixels: values.iter().map(|&v| diverging_colour(v, max)).collect(),
    };
    let colour = |t: f64| cool_warm(t as f32);
    with_colour_bar(
        &area,
        &ColourBar {
            colour: &colour,
            ticks,
            title,
            caps: Some((CLIP_HIGH_COLOUR, CLIP_LOW_COLOUR)),
        },
    )
}

/// A signed colour-bar label of at most 8 characters: `0`, `+0.500`, `-12.3`, `+1.2e-5`.
pub(crate) fn format_signed(v: f64) -> String {
    if v == 0.0 {
        return "0".to_owned();
    }
    let sign = if v < 0.0 { '-' } else { '+' };
    let a = v.abs();
    if (0.01..999.5).contains(&a) {
        return format!("{sign}{}", format_value(a));
    }
    let mut exp = a.log10().floor() as i32;
    let mut mant = a / 10f64.powi(exp);
    if mant >= 9.95 {
        mant /= 10.0;
        exp += 1;
    }
    format!("{sign}{mant:.1}e{exp}")
}

/// A signed percent label: `+100%`, `-50%`, `+2.5%`, `0%`.
pub(crate) fn format_percent(fraction: f64) -> String {
    let p = fraction * 100.0;
    if p == 0.0 {
        return "0%".to_owned();
    }
    let sign = if p < 0.0 { '-' } else { '+' };
    let a = p.abs();
    if (a - a.round()).abs() < 1e-9 && a >= 1.0 {
        format!("{sign}{a:.0}%")
    } else {
        format!("{sign}{}%", format_value(a))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels() {
        assert_eq!(format_signed(0.5), "+0.500");
        assert_eq!(format_signed(-12.34), "-12.3");
        assert_eq!(format_signed(1.234e-5), "+1.2e-5");
        assert_eq!(format_signed(-0.000_999), "-1.0e-3");
        assert_eq!(format_signed(0.0), "0");
        assert_eq!(format_percent(1.0), "+100%");
        assert_eq!(format_percent(-0.5), "-50%");
        assert_eq!(format_percent(0.025), "+2.50%");
        assert_eq!(format_percent(0.0), "0%");
        for v in [1.0e-12, -3.3e7, 0.0123, -999.0] {
            assert!(format_signed(v).len() <= 8, "{}", format_signed(v));
        }
    }
}
