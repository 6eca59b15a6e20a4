//! Every error metric of a method's image against its reference.

use caustics_metrics::{Errors, HdrImage, ToneMap, all_errors};

/// Percentile of the reference's luminance mapped to white by [`reference_tone`], as the
/// harness's default exposure (`caustics run` without `--exposure`).
const EXPOSURE_PERCENTILE: f64 = 0.99;

/// The tone map `caustics run` scores LDR metrics at by default: the reference's 99th
/// percentile luminance to white.
pub fn reference_tone(reference: &HdrImage) -> ToneMap {
    ToneMap::fit_percentile(reference, EXPOSURE_PERCENTILE)
}

/// [`all_errors`] of `test` against `reference` (LDR metrics at `tone`): energy first
/// (`flux_ratio`, `flux_ratio_image`), then shape (`rel_mse_after_flux`, `hdr_flip`,
/// `hdr_flip_after_flux`), then the rest (RMSE, SSIM, LDR-FLIP, best scale).
///
/// # Panics
/// If the images differ in size or hold a non-finite pixel.
pub fn score(test: &HdrImage, reference: &HdrImage, tone: &ToneMap) -> Errors {
    all_errors(test, reference, tone).unwrap_or_else(|e| panic!("scoring: {e}"))
}
