//! FLIP (Andersson et al. 2020) through the `nv-flip` bindings to NVIDIA's reference code.

use crate::error_metrics::check_pair;
use crate::{HdrImage, MetricsError, Rgb8Image, ToneMap};

/// Pixels per degree of visual angle used for FLIP: `nv_flip::DEFAULT_PIXELS_PER_DEGREE`
/// (≈ 67, a 0.7 m wide 4K monitor seen from 0.7 m), the FLIP paper's default.
pub const FLIP_PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

/// Mean LDR-FLIP error of `test` against `reference`, in `[0, 1]` (0 = identical).
///
/// How HDR is handled: `nv-flip` 0.1.2 only exposes LDR-FLIP, so both images are first
/// tone-mapped with the same stated [`ToneMap`] (exposure, clip to `[0, 1]`, sRGB curve,
/// 8 bits) and FLIP compares those display images at [`FLIP_PIXELS_PER_DEGREE`]. FLIP
/// therefore measures what a viewer sees at that exposure: differences in regions that
/// saturate (radiance above `1 / exposure_scale`) or that quantise to the same 8-bit code
/// are not counted. Choose the exposure from the reference (e.g.
/// [`ToneMap::fit_percentile`]) and keep it fixed across methods. The mean is taken in
/// `f64` over the per-pixel FLIP map.
pub fn flip(test: &HdrImage, reference: &HdrImage, tone: &ToneMap) -> Result<f64, MetricsError> {
    let map = flip_map(test, reference, tone)?;
    Ok(map.iter().map(|&v| f64::from(v)).sum::<f64>() / map.len() as f64)
}

/// The per-pixel FLIP error map (row-major, values in `[0, 1]`), see [`flip`].
pub fn flip_map(
    test: &HdrImage,
    reference: &HdrImage,
    tone: &ToneMap,
) -> Result<Vec<f32>, MetricsError> {
    check_pair(test, reference)?;
    if !(tone.exposure_scale.is_finite() && tone.exposure_scale > 0.0) {
        return Err(MetricsError::InvalidParameter {
            name: "exposure_scale",
            message: format!("must be positive and finite, got {}", tone.exposure_scale),
        });
    }
    Ok(flip_ldr(&tone.apply(test), &tone.apply(reference)))
}

/// LDR-FLIP map of two 8-bit sRGB images of equal size.
pub(crate) fn flip_ldr(test: &Rgb8Image, reference: &Rgb8Image) -> Vec<f32> {
    let r =
        nv_flip::FlipImageRgb8::with_data(reference.width, reference.height, &reference.as_bytes());
    let t = nv_flip::FlipImageRgb8::with_data(test.width, test.height, &test.as_bytes());
    nv_flip::flip(r, t, FLIP_PIXELS_PER_DEGREE).to_vec()
}
