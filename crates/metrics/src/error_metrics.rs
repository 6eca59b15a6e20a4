//! Pixel-wise error metrics against a reference: RMSE, relMSE, PSNR, best scale, and the
//! bundle [`Errors`] that result files store.

use serde::{Deserialize, Serialize};

use crate::{HdrImage, MetricsError, ToneMap};

/// Default `eps` of [`rel_mse`]: `1e-2` (W·m⁻²·sr⁻¹)², i.e. errors in pixels darker than
/// about 0.1 W·m⁻²·sr⁻¹ are weighted as absolute rather than relative errors.
pub const REL_MSE_EPS: f64 = 1e-2;

/// Validates a (test, reference) pair: same size, at least one pixel, all values finite.
///
/// Every metric calls this first, so none ever turns a NaN or a size mismatch into a number.
pub fn check_pair(test: &HdrImage, reference: &HdrImage) -> Result<(), MetricsError> {
    reference.check_same_size(test, "test vs reference")?;
    if test.pixels.is_empty() {
        return Err(MetricsError::Empty {
            what: "test vs reference".to_owned(),
            width: test.width,
            height: test.height,
        });
    }
    for (img, what) in [(test, "test"), (reference, "reference")] {
        if img.pixels.len() != crate::image::pixel_count(img.width, img.height) {
            return Err(MetricsError::BufferLength {
                what: format!("{what} image pixels ({}x{})", img.width, img.height),
                expected: crate::image::pixel_count(img.width, img.height),
                actual: img.pixels.len(),
            });
        }
    }
    test.check_finite("test")?;
    reference.check_finite("reference")
}

/// Mean over all pixels and channels of `f(t, r)`, in `f64`.
fn mean_over_channels(test: &HdrImage, reference: &HdrImage, f: impl Fn(f64, f64) -> f64) -> f64 {
    let mut sum = 0.0;
    for (t, r) in test.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            sum += f(f64::from(t[c]), f64::from(r[c]));
        }
    }
    sum / (3 * test.pixels.len()) as f64
}

fn mse(test: &HdrImage, reference: &HdrImage) -> f64 {
    mean_over_channels(test, reference, |t, r| (t - r) * (t - r))
}

/// Root-mean-square error over all pixels and all three channels, in W·m⁻²·sr⁻¹.
pub fn rmse(test: &HdrImage, reference: &HdrImage) -> Result<f64, MetricsError> {
    check_pair(test, reference)?;
    Ok(mse(test, reference).sqrt())
}

/// Relative mean squared error `mean((t − r)² / (r² + eps))` over all pixels and channels.
///
/// `eps > 0` keeps black reference pixels from dividing by zero; use [`REL_MSE_EPS`]
/// (`1e-2`) unless a study states otherwise. It is in squared radiance units, so it
/// should be scaled with the square of the scene's radiance range.
pub fn rel_mse(test: &HdrImage, reference: &HdrImage, eps: f64) -> Result<f64, MetricsError> {
    if !(eps > 0.0 && eps.is_finite()) {
        return Err(MetricsError::InvalidParameter {
            name: "eps",
            message: format!("must be positive and finite, got {eps}"),
        });
    }
    check_pair(test, reference)?;
    Ok(mean_over_channels(test, reference, |t, r| {
        (t - r) * (t - r) / (r * r + eps)
    }))
}

/// Peak signal-to-noise ratio in dB: `10 log10(peak² / MSE)`, MSE over all channels.
///
/// `peak` defaults to the largest channel value of the reference. Identical images
/// (MSE = 0) give `f64::INFINITY`. Fails with [`MetricsError::InvalidParameter`] when the
/// peak is not positive (e.g. a black reference and no explicit peak).
pub fn psnr(test: &HdrImage, reference: &HdrImage, peak: Option<f64>) -> Result<f64, MetricsError> {
    check_pair(test, reference)?;
    let peak = peak.unwrap_or_else(|| f64::from(reference.max_value()));
    if !(peak > 0.0 && peak.is_finite()) {
        return Err(MetricsError::InvalidParameter {
            name: "peak",
            message: format!(
                "must be positive and finite, got {peak} (a black reference needs an explicit peak)"
            ),
        });
    }
    let mse = mse(test, reference);
    if mse == 0.0 {
        return Ok(f64::INFINITY);
    }
    Ok(10.0 * (peak * peak / mse).log10())
}

/// The scale `s` minimising `Σ (s·t − r)²` over all pixels and channels, and the RMSE of
/// `s·t` against `r`.
///
/// `s = Σ t·r / Σ t²`. It separates "wrong overall brightness" (e.g. a missing factor of π)
/// from "wrong shape" of a caustic. If the test image is entirely black every scale fits
/// equally; `s = 1` is returned and the RMSE is the plain RMSE.
pub fn best_scale(test: &HdrImage, reference: &HdrImage) -> Result<(f64, f64), MetricsError> {
    check_pair(test, reference)?;
    let mut tt = 0.0f64;
    let mut tr = 0.0f64;
    for (t, r) in test.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            let (t, r) = (f64::from(t[c]), f64::from(r[c]));
            tt += t * t;
            tr += t * r;
        }
    }
    let s = if tt > 0.0 { tr / tt } else { 1.0 };
    let err = mean_over_channels(test, reference, |t, r| (s * t - r) * (s * t - r)).sqrt();
    Ok((s, err))
}

/// Every error metric of one test image against its reference, as stored in result files.
///
/// `psnr_db` is `+inf` for identical images; since JSON has no infinity it is serialized as
/// the string `"inf"` (and `"-inf"`, `"nan"`), and a number or such a string is accepted
/// when reading.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Errors {
    /// [`rmse`], W·m⁻²·sr⁻¹.
    pub rmse: f64,
    /// [`rel_mse`] with `eps = REL_MSE_EPS`.
    pub rel_mse: f64,
    /// [`psnr`] of the display-referred images ([`ToneMap::display`], peak 1), dB.
    /// Taken after tone mapping so that a hot caustic focus does not set the peak.
    #[serde(with = "non_finite_f64")]
    #[schemars(schema_with = "non_finite_f64::schema")]
    pub psnr_db: f64,
    /// [`ssim`](crate::ssim) of the display-referred luminance (range 1), in `[-1, 1]`,
    /// 1 = identical.
    pub ssim: f64,
    /// Mean LDR-[`flip`](crate::flip) of the images tone-mapped at the stated [`ToneMap`]
    /// exposure, in `[0, 1]`, 0 = identical. Blind to what saturates or quantises to one
    /// code at that exposure; `hdr_flip` is not.
    pub flip: f64,
    /// The first value of [`best_scale`]: a diagnostic, set by the brightest pixels (the
    /// focus); normalize with `flux_ratio_image` instead.
    pub best_scale: f64,
    /// The second value of [`best_scale`], W·m⁻²·sr⁻¹.
    pub rmse_after_best_scale: f64,
    /// [`rel_mse`] of the test image times `best_scale`: what is left of relMSE once
    /// the overall brightness is fixed (a shape error, not a normalization error).
    /// Absent in result files written before it existed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rel_mse_after_best_scale: Option<f64>,
    /// Mean [`flip`](crate::flip) of the test image times `best_scale`, tone-mapped the
    /// same way. Absent in result files written before it existed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flip_after_best_scale: Option<f64>,
    /// [`flux_ratio`](crate::flux_ratio) over the reference's
    /// [`caustic_region`](crate::caustic_region): `Σ Y(test) / Σ Y(reference)` there, 1 =
    /// all the light is there. Absent when the reference is black, and in result files
    /// written before it existed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flux_ratio: Option<f64>,
    /// [`flux_ratio`](crate::flux_ratio) over the whole image. Absent when the reference
    /// is black, and in older result files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flux_ratio_image: Option<f64>,
    /// [`rel_mse`] (`eps = REL_MSE_EPS`) of the test image divided by `flux_ratio_image`:
    /// the shape error once the total light is made equal. The whole-image ratio is used,
    /// not the region's, so that the normalization conserves all the light the method
    /// drew: light it misplaced outside the caustic region still counts as an error
    /// instead of being scaled away. Absent when the ratio is absent or 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rel_mse_after_flux: Option<f64>,
    /// Mean HDR-FLIP (exposure-bracketed LDR-FLIP, Andersson et al. 2021), in `[0, 1]`,
    /// over the bracket of [`hdr_flip_exposures_over`](crate::hdr_flip_exposures_over)
    /// over the reference's caustic region: its brightest pixel just below white at the first
    /// exposure, the region's median at 0.85 at the last (the authors' whole-image median
    /// is 0 on a caustic image and would score the reference's photon noise). Absent
    /// when the reference is black, and in older result files.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hdr_flip: Option<f64>,
    /// Mean HDR-FLIP of the test image divided by `flux_ratio_image`, over the same
    /// exposure bracket as `hdr_flip`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hdr_flip_after_flux: Option<f64>,
    /// First exposure of the HDR-FLIP bracket, in stops (from the reference).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hdr_flip_start_exposure: Option<f64>,
    /// Last exposure of the HDR-FLIP bracket, in stops (from the reference).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hdr_flip_stop_exposure: Option<f64>,
}

/// Computes every metric of [`Errors`]: RMSE, relMSE and the best scale on the linear
/// HDR images; PSNR, SSIM and (LDR-)FLIP on the images tone-mapped by `tone` (the stated
/// exposure), where a caustic's hot spot cannot swamp the range; the flux ratios, relMSE
/// after flux normalization, and HDR-FLIP (its exposure bracket from the reference) before
/// and after flux normalization.
///
/// The flux-based fields lead: they separate "is the light all there" from "is it in the
/// right place". RMSE and the best scale are dominated by the brightest pixels and kept
/// as diagnostics. Fields that have no value for a black reference are `None`.
pub fn all_errors(
    test: &HdrImage,
    reference: &HdrImage,
    tone: &ToneMap,
) -> Result<Errors, MetricsError> {
    check_pair(test, reference)?;
    let (best_scale, rmse_after_best_scale) = best_scale(test, reference)?;
    let (display_test, display_reference) = (tone.display(test), tone.display(reference));
    let rescaled = test.scaled(best_scale as f32);
    let region = crate::caustic_region(reference);
    let flux_ratio = crate::flux_ratio(test, reference, Some(&region))?;
    let flux_ratio_image = crate::flux_ratio(test, reference, None)?;
    let flux_normalized = flux_ratio_image
        .filter(|&k| k > 0.0 && k.is_finite())
        .map(|k| test.scaled((1.0 / k) as f32));
    let rel_mse_after_flux = match &flux_normalized {
        Some(t) => Some(rel_mse(t, reference, REL_MSE_EPS)?),
        None => None,
    };
    // HDR-FLIP (twice), LDR-FLIP (twice) and SSIM are most of a run's CPU time at
    // 1024x768 (NVIDIA's FLIP runs on one thread): they are independent, so they run in
    // parallel; each is computed exactly as alone.
    let hdr_flips = || -> Result<_, MetricsError> {
        if !reference.pixels.iter().any(|&p| crate::luminance(p) > 0.0) {
            return Ok(None);
        }
        let (first, last) = crate::hdr_flip_exposures_over(reference, &region)?;
        let (h, after) = rayon::join(
            || crate::hdr_flip_with_exposures(test, reference, first, last),
            || {
                flux_normalized
                    .as_ref()
                    .map(|t| crate::hdr_flip_with_exposures(t, reference, first, last))
                    .transpose()
            },
        );
        Ok(Some((h?, after?.map(|a| a.mean))))
    };
    let ((flip, flip_after_best_scale), (hdr_flips, ssim)) = rayon::join(
        || {
            rayon::join(
                || crate::flip(test, reference, tone),
                || crate::flip(&rescaled, reference, tone),
            )
        },
        || {
            rayon::join(hdr_flips, || {
                crate::ssim_with_range(&display_test, &display_reference, Some(1.0))
            })
        },
    );
    let (hdr, hdr_after, start, stop) = match hdr_flips? {
        Some((h, after)) => (
            Some(h.mean),
            after,
            Some(f64::from(h.start_exposure)),
            Some(f64::from(h.stop_exposure)),
        ),
        None => (None, None, None, None),
    };
    Ok(Errors {
        rmse: rmse(test, reference)?,
        rel_mse: rel_mse(test, reference, REL_MSE_EPS)?,
        psnr_db: psnr(&display_test, &display_reference, Some(1.0))?,
        ssim: ssim?,
        flip: flip?,
        best_scale,
        rmse_after_best_scale,
        rel_mse_after_best_scale: Some(rel_mse(&rescaled, reference, REL_MSE_EPS)?),
        flip_after_best_scale: Some(flip_after_best_scale?),
        flux_ratio,
        flux_ratio_image,
        rel_mse_after_flux,
        hdr_flip: hdr,
        hdr_flip_after_flux: hdr_after,
        hdr_flip_start_exposure: start,
        hdr_flip_stop_exposure: stop,
    })
}

/// Serde helper writing non-finite `f64` values as the strings `"inf"`, `"-inf"`, `"nan"`.
mod non_finite_f64 {
    use serde::de::{self, Visitor};
    use serde::{Deserializer, Serializer};

    /// A number, or one of the strings non-finite values are written as.
    pub(super) fn schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "oneOf": [{"type": "number"}, {"enum": ["inf", "-inf", "nan"]}]
        })
    }

    pub(super) fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        if v.is_finite() {
            s.serialize_f64(*v)
        } else if v.is_nan() {
            s.serialize_str("nan")
        } else if *v > 0.0 {
            s.serialize_str("inf")
        } else {
            s.serialize_str("-inf")
        }
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = f64;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a number or one of \"inf\", \"-inf\", \"nan\"")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<f64, E> {
                Ok(v)
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<f64, E> {
                Ok(v as f64)
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<f64, E> {
                Ok(v as f64)
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<f64, E> {
                match v {
                    "inf" | "+inf" | "infinity" => Ok(f64::INFINITY),
                    "-inf" | "-infinity" => Ok(f64::NEG_INFINITY),
                    "nan" => Ok(f64::NAN),
                    other => Err(E::invalid_value(de::Unexpected::Str(other), &self)),
                }
            }
        }
        d.deserialize_any(V)
    }
}
