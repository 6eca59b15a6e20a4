//! Temporal error: how much of a method's frame-to-frame change is not the caustic's own.
//!
//! A still error cannot see flicker: a method whose beams or photon triangles pop in and
//! out between instants can score well on every frame alone. Video metrics built on
//! this idea compare the *change* between consecutive frames with the ground truth's
//! change (tOF/tLP of Chu et al. 2020, "Learning temporal coherence via
//! self-supervision for GAN-based video generation", ACM TOG 39(4): the distance of the
//! frame-to-frame optical flow, or of the perceptual distance between consecutive frames,
//! between output and truth). Perceptual video metrics (FovVideoVDP, Mantiuk et al.
//! 2021) need display parameters and a viewing setup; here the question is the light,
//! so [`temporal_error`] takes the same comparison on linear luminance: per pixel, the
//! method's change `Δm = m₁ − m₀` against the reference's `Δr = r₁ − r₀`.
//!
//! A method that is off by a constant everywhere moves with the caustic and has a small
//! temporal error even where its still error is large; one that flickers has a large
//! temporal error even where each frame alone is close. The references are Monte Carlo
//! images, so `Δr` carries their noise; its expected contribution `σ₀² + σ₁²` (from the
//! references' per-pixel standard-error images) is subtracted, so a converged method is
//! not charged for the reference's noise.

use crate::{HdrImage, MetricsError, check_pair, luminance};

/// The temporal error of one pair of consecutive frames (see the module doc).
#[derive(
    Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
pub struct TemporalError {
    /// √(Σ[(Δm − Δr)² − σ₀² − σ₁²] / Σ r̄²) over all pixels, luminance, r̄ the mean of the
    /// two reference frames; clamped at 0 when the reference noise explains it all.
    pub temporal_rel_rmse: f64,
    /// √(Σ[(m₀ − r₀)² + (m₁ − r₁)² − σ₀² − σ₁²] / (2 Σ r̄²)): the pair's still error on
    /// the same scale (the references' noise removed alike), so that `temporal_rel_rmse / still_rel_rmse` says how much of the error
    /// changes from frame to frame.
    pub still_rel_rmse: f64,
    /// Σ Δm² / Σ Δr² (the reference's noise removed from both sums where known): how much
    /// the method's image changes against how much the caustic does (1 = as much; above:
    /// flicker or a sharper caustic; below: a blurred or lagging one). `None` when the
    /// reference does not change.
    pub change_ratio: Option<f64>,
}

/// [`TemporalError`] of the method's frames `m0`, `m1` against the reference's `r0`,
/// `r1` at the same instants; `stderr0`/`stderr1` are the references' per-pixel
/// standard-error images (luminance of the per-channel errors), if known.
pub fn temporal_error(
    m0: &HdrImage,
    m1: &HdrImage,
    r0: &HdrImage,
    r1: &HdrImage,
    stderr: Option<(&HdrImage, &HdrImage)>,
) -> Result<TemporalError, MetricsError> {
    check_pair(m0, r0)?;
    check_pair(m1, r1)?;
    check_pair(r1, r0)?;
    if let Some((s0, s1)) = stderr {
        check_pair(s0, r0)?;
        check_pair(s1, r0)?;
    }
    let (mut diff, mut noise, mut still, mut energy, mut change_m, mut change_r) =
        (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for p in 0..r0.pixels.len() {
        let l = |img: &HdrImage| f64::from(luminance(img.pixels[p]));
        let (lm0, lm1, lr0, lr1) = (l(m0), l(m1), l(r0), l(r1));
        let (dm, dr) = (lm1 - lm0, lr1 - lr0);
        diff += (dm - dr) * (dm - dr);
        if let Some((s0, s1)) = stderr {
            noise += l(s0).powi(2) + l(s1).powi(2);
        }
        // (m − r)² carries the reference's variance too: removed below like Δr's.
        still += (lm0 - lr0).powi(2) + (lm1 - lr1).powi(2);
        let mean = 0.5 * (lr0 + lr1);
        energy += mean * mean;
        change_m += dm * dm;
        change_r += dr * dr;
    }
    if energy <= 0.0 {
        return Err(MetricsError::InvalidParameter {
            name: "reference",
            message: "both reference frames are black: no relative temporal error exists".into(),
        });
    }
    // Δr's noise inflates Σ Δr² by the same amount it inflates Σ (Δm − Δr)².
    let true_change_r = (change_r - noise).max(0.0);
    Ok(TemporalError {
        temporal_rel_rmse: ((diff - noise).max(0.0) / energy).sqrt(),
        still_rel_rmse: ((still - noise).max(0.0) / (2.0 * energy)).sqrt(),
        change_ratio: (true_change_r > 0.0).then(|| change_m / true_change_r),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(values: &[f32]) -> HdrImage {
        let mut i = HdrImage::new(values.len() as u32, 1);
        for (p, &v) in values.iter().enumerate() {
            i.pixels[p] = [v, v, v];
        }
        i
    }

    #[test]
    fn a_biased_method_that_moves_with_the_caustic_has_a_small_temporal_error() {
        // A caustic moving one pixel right; the method is 20% too dark but moves with it.
        let (r0, r1) = (img(&[0.0, 4.0, 1.0, 0.0]), img(&[0.0, 1.0, 4.0, 0.0]));
        let (m0, m1) = (r0.scaled(0.8), r1.scaled(0.8));
        let e = temporal_error(&m0, &m1, &r0, &r1, None).expect("valid pair");
        // Σ r̄² = 12.5; still: 0.04·34 / 25; temporal: 0.04·Σ Δr² = 0.04·18 over 12.5.
        assert!(
            (e.still_rel_rmse - 0.2 * (34.0f64 / 25.0).sqrt()).abs() < 1e-6,
            "{e:?}"
        );
        assert!((e.temporal_rel_rmse - 0.24).abs() < 1e-6, "{e:?}");
        assert!((e.change_ratio.expect("it moves") - 0.64).abs() < 1e-6);
        // A method right on every frame alone except one pixel that pops on and off.
        let (f0, f1) = (img(&[0.0, 4.0, 1.0, 0.0]), img(&[0.0, 1.0, 4.0, 2.0]));
        let flicker = temporal_error(&f0, &f1, &r0, &r1, None).expect("valid pair");
        assert!(
            flicker.temporal_rel_rmse > flicker.still_rel_rmse,
            "{flicker:?}"
        );
    }

    #[test]
    fn reference_noise_is_not_charged() {
        // The truth does not change; the references differ by their noise alone, and the
        // method is exact: with the standard errors given, no temporal error is left.
        let truth = img(&[1.0, 2.0, 3.0, 2.0]);
        // Each reference off by σ/√2 the other way: Δr² = 2σ², its expectation.
        let h = 0.1 / std::f32::consts::SQRT_2;
        let r0 = img(&[1.0 + h, 2.0 - h, 3.0 + h, 2.0]);
        let r1 = img(&[1.0 - h, 2.0 + h, 3.0 - h, 2.0]);
        let s = img(&[0.1, 0.1, 0.1, 0.0]);
        let e = temporal_error(&truth, &truth, &r0, &r1, Some((&s, &s))).expect("valid");
        assert!(e.temporal_rel_rmse < 1e-3, "{e:?}");
        let without = temporal_error(&truth, &truth, &r0, &r1, None).expect("valid");
        assert!(without.temporal_rel_rmse > 0.05, "{without:?}");
        assert!(
            temporal_error(&truth, &truth, &img(&[0.0; 4]), &img(&[0.0; 4]), None).is_err(),
            "a black reference has no relative error"
        );
    }
}
