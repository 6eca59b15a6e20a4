//! Structural similarity (SSIM) on luminance.

use crate::error_metrics::check_pair;
use crate::{HdrImage, MetricsError};

/// Radius of the Gaussian window: 11×11 taps.
const RADIUS: usize = 5;
/// Standard deviation of the Gaussian window in pixels.
const SIGMA: f64 = 1.5;
/// SSIM stabilising constants `C1 = (K1 L)²`, `C2 = (K2 L)²`.
const K1: f64 = 0.01;
const K2: f64 = 0.03;

/// Mean SSIM of the Rec. 709 luminance of `test` against `reference`.
///
/// This is the SSIM of Wang, Bovik, Sheikh and Simoncelli (IEEE TIP 2004) with their
/// standard parameters: an 11×11 Gaussian window with σ = 1.5 px, `K1 = 0.01`,
/// `K2 = 0.03`. Because the images are HDR, the dynamic range is
/// `L = max(reference luminance)` (or 1 if the reference is black), so the constants scale
/// with the scene's brightness. Near the borders the window is truncated to the image and
/// its weights renormalised, so every pixel contributes and images smaller than the window
/// work. The result is the mean of the per-pixel SSIM map: 1 for identical images, lower
/// for any structural, contrast or brightness difference.
pub fn ssim(test: &HdrImage, reference: &HdrImage) -> Result<f64, MetricsError> {
    ssim_with_range(test, reference, None)
}

/// [`ssim`] with an explicit dynamic range `L` (e.g. 1 for display-referred images in
/// [0, 1]); `None` takes the reference's maximum luminance as [`ssim`] does.
pub fn ssim_with_range(
    test: &HdrImage,
    reference: &HdrImage,
    range: Option<f64>,
) -> Result<f64, MetricsError> {
    check_pair(test, reference)?;
    if let Some(l) = range.filter(|l| !(l.is_finite() && *l > 0.0)) {
        return Err(MetricsError::InvalidParameter {
            name: "range",
            message: format!("must be positive and finite, got {l}"),
        });
    }
    let map = ssim_map(test, reference, range);
    Ok(map.iter().sum::<f64>() / map.len() as f64)
}

/// The per-pixel SSIM map (row-major), see [`ssim`]; the inputs must already be checked.
pub(crate) fn ssim_map(test: &HdrImage, reference: &HdrImage, range: Option<f64>) -> Vec<f64> {
    let (w, h) = (test.width as usize, test.height as usize);
    let x: Vec<f64> = test
        .pixels
        .iter()
        .map(|&p| f64::from(crate::luminance(p)))
        .collect();
    let y: Vec<f64> = reference
        .pixels
        .iter()
        .map(|&p| f64::from(crate::luminance(p)))
        .collect();
    let peak = y.iter().copied().fold(0.0f64, f64::max);
    let l = range.unwrap_or(if peak > 0.0 { peak } else { 1.0 });
    let c1 = (K1 * l) * (K1 * l);
    let c2 = (K2 * l) * (K2 * l);

    let kernel: Vec<f64> = (0..=2 * RADIUS)
        .map(|i| {
            let d = i as f64 - RADIUS as f64;
            (-d * d / (2.0 * SIGMA * SIGMA)).exp()
        })
        .collect();
    let xx: Vec<f64> = x.iter().map(|v| v * v).collect();
    let yy: Vec<f64> = y.iter().map(|v| v * v).collect();
    let xy: Vec<f64> = x.iter().zip(&y).map(|(a, b)| a * b).collect();
    let mu_x = blur(&x, w, h, &kernel);
    let mu_y = blur(&y, w, h, &kernel);
    let e_xx = blur(&xx, w, h, &kernel);
    let e_yy = blur(&yy, w, h, &kernel);
    let e_xy = blur(&xy, w, h, &kernel);

    (0..w * h)
        .map(|i| {
            let (mx, my) = (mu_x[i], mu_y[i]);
            let sxx = e_xx[i] - mx * mx;
            let syy = e_yy[i] - my * my;
            let sxy = e_xy[i] - mx * my;
            ((2.0 * mx * my + c1) * (2.0 * sxy + c2))
                / ((mx * mx + my * my + c1) * (sxx + syy + c2))
        })
        .collect()
}

/// Separable normalised Gaussian blur with the window truncated at the borders.
fn blur(src: &[f64], w: usize, h: usize, kernel: &[f64]) -> Vec<f64> {
    let mut tmp = vec![0.0; w * h];
    for row in 0..h {
        for col in 0..w {
            let (mut acc, mut wsum) = (0.0, 0.0);
            for (k, &kw) in kernel.iter().enumerate() {
                let c = col as isize + k as isize - RADIUS as isize;
                if c >= 0 && (c as usize) < w {
                    acc += kw * src[row * w + c as usize];
                    wsum += kw;
                }
            }
            tmp[row * w + col] = acc / wsum;
        }
    }
    let mut out = vec![0.0; w * h];
    for row in 0..h {
        for col in 0..w {
            let (mut acc, mut wsum) = (0.0, 0.0);
            for (k, &kw) in kernel.iter().enumerate() {
                let r = row as isize + k as isize - RADIUS as isize;
                if r >= 0 && (r as usize) < h {
                    acc += kw * tmp[r as usize * w + col];
                    wsum += kw;
                }
            }
            out[row * w + col] = acc / wsum;
        }
    }
    out
}
