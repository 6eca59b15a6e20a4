//! Image I/O (EXR, PNG), tone mapping, heatmaps and error metrics (RMSE, relMSE, PSNR,
//! SSIM, FLIP) for caustics-bench.
//!
//! Images are linear HDR radiance ([`HdrImage`], W·m⁻²·sr⁻¹, row 0 at the top). Every
//! metric compares a *test* image against a *reference* and refuses (returns an error
//! naming the image and the first bad pixel) when the sizes differ or either image holds a
//! NaN or an infinity, so a broken method can never score a number.
//!
//! ```
//! use caustics_metrics::{all_errors, HdrImage, ToneMap};
//!
//! let mut reference = HdrImage::new(16, 16);
//! reference.set(8, 8, [1.0, 0.5, 0.25]);
//! let test = reference.scaled(0.5);
//! let tone = ToneMap::fit_percentile(&reference, 0.99);
//! let e = all_errors(&test, &reference, &tone)?;
//! assert!((e.best_scale - 2.0).abs() < 1e-9);
//! assert!(e.rmse_after_best_scale < 1e-9);
//! # Ok::<(), caustics_metrics::MetricsError>(())
//! ```
//!
//! Energy before shape: [`flux_ratio`] over the reference's [`caustic_region`] says whether
//! the light is all there; relMSE and [`hdr_flip`] (exposure-bracketed, Andersson et al.
//! 2021) after dividing by the whole-image flux ratio say whether it is in the right place
//! (all in [`Errors`]). [`signed_error_map`] and [`relative_error_map`] draw the error with
//! its sign and unit; heatmaps and maps of one figure take one shared scale.
//!
//! Files are written atomically ([`atomic_write`]): readers never see a partial EXR, PNG
//! or result file.

mod colorbar;
mod colormap;
mod error;
mod error_maps;
mod error_metrics;
mod flip;
mod flux;
mod font;
mod hdr_flip;
mod heatmap;
mod image;
mod io;
mod ssim;
mod temporal;
mod tonemap;

pub use crate::colormap::{COOL_WARM_NEUTRAL, cool_warm, inferno};
pub use crate::error::MetricsError;
pub use crate::error_maps::{
    CLIP_HIGH_COLOUR, CLIP_LOW_COLOUR, SIGNED_ERROR_QUANTILE, relative_error_floor,
    relative_error_map, signed_error_map, signed_error_max,
};
pub use crate::error_metrics::{
    Errors, REL_MSE_EPS, all_errors, best_scale, check_pair, psnr, rel_mse, rmse,
};
pub use crate::flip::{FLIP_PIXELS_PER_DEGREE, flip, flip_map};
pub use crate::flux::{
    CAUSTIC_REGION_FRACTION, CAUSTIC_REGION_PERCENTILE, caustic_region, flux_ratio,
};
pub use crate::font::{DESCENT, GLYPH_H, draw_text, draw_text_vertical, text_width};
pub use crate::hdr_flip::{
    HDR_FLIP_ACES, HdrFlip, hdr_flip, hdr_flip_exposures, hdr_flip_exposures_over,
    hdr_flip_with_exposures,
};
pub use crate::heatmap::{
    COLOR_BAR_WIDTH, HeatmapOptions, Histogram, HistogramBucket, MIN_MAP_HEIGHT, PANEL_BACKGROUND,
    ZERO_COUNT_COLOUR, count_ticks, error_map, error_map_with_max, error_quantile, format_count,
    format_value, heatmap, heatmap_with, histogram,
};
pub use crate::image::{HdrImage, REC709_LUMINANCE, Rgb8Image, luminance};
pub use crate::io::{
    MAX_PNG_COUNT, atomic_write, atomic_write_with, read_counts_png, read_exr, read_png,
    write_counts_png, write_exr, write_png,
};
pub use crate::ssim::{ssim, ssim_with_range};
pub use crate::temporal::{TemporalError, temporal_error};
pub use crate::tonemap::{ToneMap, srgb_oetf};
