//! The stated tone mapping used for composites and for FLIP.

use serde::{Deserialize, Serialize};

use crate::{HdrImage, Rgb8Image, luminance};

/// The sRGB opto-electronic transfer function (IEC 61966-2-1) for `v` in `[0, 1]`:
/// `12.92 v` for `v ≤ 0.0031308`, else `1.055 v^(1/2.4) − 0.055`.
pub fn srgb_oetf(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// The stated tone mapping: a linear exposure scale, a hard clip, then the sRGB curve.
///
/// For each channel of a linear radiance value `L`:
///
/// ```text
/// v    = clamp(L * exposure_scale, 0, 1)
/// byte = round(255 * srgb_oetf(v))
/// ```
///
/// There is no shoulder or highlight compression: radiance above `1 / exposure_scale`
/// saturates to 255, so differences there are invisible in the tone-mapped image (and to
/// [`flip`](crate::flip)). A NaN channel maps to 0. Record `exposure_scale` beside every
/// image it produced.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ToneMap {
    /// Multiplier applied to linear radiance before clipping to `[0, 1]`.
    pub exposure_scale: f32,
}

impl Default for ToneMap {
    /// Exposure scale 1: radiance 1 W·m⁻²·sr⁻¹ maps to white.
    fn default() -> Self {
        Self {
            exposure_scale: 1.0,
        }
    }
}

impl ToneMap {
    /// A tone map with the given exposure scale.
    pub fn new(exposure_scale: f32) -> Self {
        Self { exposure_scale }
    }

    /// A tone map whose exposure puts the `percentile` (in `[0, 1]`, e.g. 0.99) of the
    /// image's non-zero pixel luminances at 1.0. Falls back to exposure 1 when the image
    /// has no positive finite luminance. Compute it once from the reference and use it for
    /// every method so that their images stay comparable.
    pub fn fit_percentile(img: &HdrImage, percentile: f64) -> Self {
        let mut lum: Vec<f32> = img
            .pixels
            .iter()
            .map(|&p| luminance(p))
            .filter(|l| l.is_finite() && *l > 0.0)
            .collect();
        if lum.is_empty() {
            return Self::default();
        }
        lum.sort_by(f32::total_cmp);
        let p = percentile.clamp(0.0, 1.0);
        let idx = ((lum.len() - 1) as f64 * p).round() as usize;
        Self::new(1.0 / lum[idx])
    }

    /// Tone-maps one linear channel value to an 8-bit sRGB code value.
    pub fn encode(&self, linear: f32) -> u8 {
        let v = (linear * self.exposure_scale).clamp(0.0, 1.0);
        if v.is_nan() {
            return 0;
        }
        (srgb_oetf(v) * 255.0).round() as u8
    }

    /// The display-referred image: `srgb_oetf(clamp(linear × exposure, 0, 1))` per
    /// channel, in [0, 1] and not quantized. PSNR and SSIM in [`crate::all_errors`]
    /// are taken on it, like FLIP, so a hot caustic focus does not set their range.
    pub fn display(&self, img: &HdrImage) -> HdrImage {
        HdrImage {
            width: img.width,
            height: img.height,
            pixels: img
                .pixels
                .iter()
                .map(|p| {
                    p.map(|c| {
                        let v = (c * self.exposure_scale).clamp(0.0, 1.0);
                        if v.is_nan() { 0.0 } else { srgb_oetf(v) }
                    })
                })
                .collect(),
        }
    }

    /// Tone-maps a whole image.
    pub fn apply(&self, img: &HdrImage) -> Rgb8Image {
        Rgb8Image {
            width: img.width,
            height: img.height,
            pixels: img
                .pixels
                .iter()
                .map(|p| p.map(|c| self.encode(c)))
                .collect(),
        }
    }
}
