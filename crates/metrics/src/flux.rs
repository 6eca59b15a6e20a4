//! Energy before shape: the caustic region of a reference and flux ratios over it.

use crate::error_metrics::check_pair;
use crate::{HdrImage, MetricsError, luminance};

/// Percentile of the reference's non-zero luminances that sets the caustic-region
/// threshold, see [`caustic_region`].
pub const CAUSTIC_REGION_PERCENTILE: f64 = 0.99;
/// Fraction of that percentile a pixel must reach to be in the caustic region.
pub const CAUSTIC_REGION_FRACTION: f32 = 0.01;

/// The `q`-quantile (nearest rank, `q` in `[0, 1]`) of the positive finite luminances of
/// `img`, or `None` when there is none.
pub(crate) fn positive_luminance_quantile(img: &HdrImage, q: f64) -> Option<f32> {
    let mut lum: Vec<f32> = img
        .pixels
        .iter()
        .map(|&p| luminance(p))
        .filter(|l| l.is_finite() && *l > 0.0)
        .collect();
    if lum.is_empty() {
        return None;
    }
    lum.sort_by(f32::total_cmp);
    Some(lum[((lum.len() - 1) as f64 * q.clamp(0.0, 1.0)).round() as usize])
}

/// The pixels (row-major) that hold the reference's caustic: luminance ≥
/// [`CAUSTIC_REGION_FRACTION`] (1%) of the [`CAUSTIC_REGION_PERCENTILE`] (99th percentile,
/// nearest rank) of the reference's non-zero luminances.
///
/// Why this rule: a caustic image is black wherever no specular path lands, so the
/// percentile is taken over the non-zero pixels only (the black ones would otherwise pull it
/// to 0); the 99th percentile rather than the maximum keeps a single hot focus (a cusp can
/// be 10⁴× its surroundings) from pushing the threshold above the rest of the caustic; and
/// 1% of it excludes the noise floor of a light-traced reference (isolated faint photon
/// hits) while keeping the dim tails of the caustic, about 6.6 stops below its bright part.
/// Every pixel is `false` when the reference is black (or has no positive luminance).
pub fn caustic_region(reference: &HdrImage) -> Vec<bool> {
    let Some(p) = positive_luminance_quantile(reference, CAUSTIC_REGION_PERCENTILE) else {
        return vec![false; reference.pixels.len()];
    };
    let threshold = CAUSTIC_REGION_FRACTION * p;
    reference
        .pixels
        .iter()
        .map(|&px| luminance(px) >= threshold)
        .collect()
}

/// `Σ Y(test) / Σ Y(reference)` (Rec. 709 luminance, summed in `f64`) over the pixels where
/// `region` is `true`, or over the whole image when `region` is `None`: whether the light
/// is all there (1 = same flux, 0.5 = half the light missing).
///
/// `Ok(None)` when the reference's sum is 0 (black reference, or an empty region): no ratio
/// exists. Fails when the images do not pair up ([`check_pair`]) or `region` does not hold
/// one entry per pixel.
pub fn flux_ratio(
    test: &HdrImage,
    reference: &HdrImage,
    region: Option<&[bool]>,
) -> Result<Option<f64>, MetricsError> {
    check_pair(test, reference)?;
    if let Some(region) = region
        && region.len() != reference.pixels.len()
    {
        return Err(MetricsError::BufferLength {
            what: format!(
                "flux-ratio region for a {}x{} image",
                reference.width, reference.height
            ),
            expected: reference.pixels.len(),
            actual: region.len(),
        });
    }
    let (mut t_sum, mut r_sum) = (0.0f64, 0.0f64);
    for (i, (t, r)) in test.pixels.iter().zip(&reference.pixels).enumerate() {
        if region.is_none_or(|reg| reg[i]) {
            t_sum += f64::from(luminance(*t));
            r_sum += f64::from(luminance(*r));
        }
    }
    Ok((r_sum != 0.0).then(|| t_sum / r_sum))
}
