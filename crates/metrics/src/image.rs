//! In-memory image types: linear HDR radiance and 8-bit display images.

use crate::MetricsError;

/// Rec. 709 / sRGB luminance weights (the Y row of the linear sRGB → XYZ matrix).
pub const REC709_LUMINANCE: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// Luminance of a linear RGB value with the Rec. 709 weights
/// `0.2126 R + 0.7152 G + 0.0722 B`.
pub fn luminance(rgb: [f32; 3]) -> f32 {
    REC709_LUMINANCE[0] * rgb[0] + REC709_LUMINANCE[1] * rgb[1] + REC709_LUMINANCE[2] * rgb[2]
}

/// Linear HDR RGB image, row 0 = top, radiance in W·m⁻²·sr⁻¹.
///
/// Pixels are stored row-major: pixel `(x, y)` is `pixels[y * width + x]`.
#[derive(Debug, Clone, PartialEq)]
pub struct HdrImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major linear RGB radiance, `width * height` entries.
    pub pixels: Vec<[f32; 3]>,
}

impl HdrImage {
    /// A black image (all channels zero).
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: vec![[0.0; 3]; pixel_count(width, height)],
        }
    }

    /// Builds an image from a tightly packed RGBA `f32` buffer (e.g. a GPU readback of an
    /// `Rgba32Float` target), dropping alpha.
    ///
    /// Fails with [`MetricsError::BufferLength`] unless `rgba.len() == width * height * 4`.
    pub fn from_rgba_f32(width: u32, height: u32, rgba: &[f32]) -> Result<Self, MetricsError> {
        let expected = pixel_count(width, height) * 4;
        if rgba.len() != expected {
            return Err(MetricsError::BufferLength {
                what: format!("rgba f32 buffer for a {width}x{height} image"),
                expected,
                actual: rgba.len(),
            });
        }
        let pixels = rgba.chunks_exact(4).map(|p| [p[0], p[1], p[2]]).collect();
        Ok(Self {
            width,
            height,
            pixels,
        })
    }

    /// The pixel at column `x`, row `y` (row 0 is the top).
    ///
    /// # Panics
    /// If `(x, y)` is outside the image.
    pub fn get(&self, x: u32, y: u32) -> [f32; 3] {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside a {}x{} image",
            self.width,
            self.height
        );
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Sets the pixel at column `x`, row `y`.
    ///
    /// # Panics
    /// If `(x, y)` is outside the image.
    pub fn set(&mut self, x: u32, y: u32, rgb: [f32; 3]) {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside a {}x{} image",
            self.width,
            self.height
        );
        let w = self.width as usize;
        self.pixels[y as usize * w + x as usize] = rgb;
    }

    /// Mean of each channel over all pixels, accumulated in `f64`; zero for an empty image.
    pub fn mean(&self) -> [f64; 3] {
        if self.pixels.is_empty() {
            return [0.0; 3];
        }
        let mut sum = [0.0f64; 3];
        for p in &self.pixels {
            for c in 0..3 {
                sum[c] += f64::from(p[c]);
            }
        }
        let n = self.pixels.len() as f64;
        sum.map(|s| s / n)
    }

    /// Sum of the Rec. 709 luminance of all pixels, accumulated in `f64`.
    ///
    /// Multiplied by the solid angle of a pixel this is proportional to the power reaching
    /// the camera, which makes it a quick energy-conservation check between methods.
    pub fn sum_luminance(&self) -> f64 {
        self.pixels.iter().map(|&p| f64::from(luminance(p))).sum()
    }

    /// The largest channel value in the image (0 for an empty or all-negative image).
    pub fn max_value(&self) -> f32 {
        self.pixels
            .iter()
            .flat_map(|p| p.iter().copied())
            .fold(0.0f32, f32::max)
    }

    /// Checks that every channel of every pixel is finite.
    ///
    /// On failure returns [`MetricsError::NonFinite`] naming `what` and the first bad pixel
    /// in row-major order.
    pub fn check_finite(&self, what: &str) -> Result<(), MetricsError> {
        let w = self.width.max(1) as usize;
        for (i, p) in self.pixels.iter().enumerate() {
            if let Some(&value) = p.iter().find(|v| !v.is_finite()) {
                return Err(MetricsError::NonFinite {
                    image: what.to_owned(),
                    x: (i % w) as u32,
                    y: (i / w) as u32,
                    value,
                });
            }
        }
        Ok(())
    }

    /// Fails with [`MetricsError::SizeMismatch`] unless `other` has this image's size.
    pub fn check_same_size(&self, other: &HdrImage, what: &str) -> Result<(), MetricsError> {
        if self.width != other.width || self.height != other.height {
            return Err(MetricsError::SizeMismatch {
                what: what.to_owned(),
                expected_width: self.width,
                expected_height: self.height,
                actual_width: other.width,
                actual_height: other.height,
            });
        }
        Ok(())
    }

    /// Pixel-wise sum, e.g. direct + surface caustic + volume caustic for a composite.
    pub fn add(&self, other: &HdrImage) -> Result<HdrImage, MetricsError> {
        self.check_same_size(other, "image addition")?;
        let pixels = self
            .pixels
            .iter()
            .zip(&other.pixels)
            .map(|(a, b)| [a[0] + b[0], a[1] + b[1], a[2] + b[2]])
            .collect();
        Ok(HdrImage {
            width: self.width,
            height: self.height,
            pixels,
        })
    }

    /// Every channel multiplied by `s`.
    pub fn scaled(&self, s: f32) -> HdrImage {
        HdrImage {
            width: self.width,
            height: self.height,
            pixels: self.pixels.iter().map(|p| p.map(|c| c * s)).collect(),
        }
    }

    /// The luminance of every pixel, row-major.
    pub fn luminance_plane(&self) -> Vec<f32> {
        self.pixels.iter().map(|&p| luminance(p)).collect()
    }
}

/// 8-bit sRGB-encoded RGB image for display (composites, error maps, heatmaps), row 0 = top.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Rgb8Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major sRGB-encoded pixels, `width * height` entries.
    pub pixels: Vec<[u8; 3]>,
}

impl Rgb8Image {
    /// An image filled with `colour`.
    pub fn filled(width: u32, height: u32, colour: [u8; 3]) -> Self {
        Self {
            width,
            height,
            pixels: vec![colour; pixel_count(width, height)],
        }
    }

    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        Self::filled(width, height, [0; 3])
    }

    /// The pixel at column `x`, row `y` (row 0 is the top).
    ///
    /// # Panics
    /// If `(x, y)` is outside the image.
    pub fn get(&self, x: u32, y: u32) -> [u8; 3] {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside a {}x{} image",
            self.width,
            self.height
        );
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Sets the pixel at `(x, y)`; writes outside the image are ignored (handy when drawing).
    pub fn set(&mut self, x: u32, y: u32, colour: [u8; 3]) {
        if x < self.width && y < self.height {
            let w = self.width as usize;
            self.pixels[y as usize * w + x as usize] = colour;
        }
    }

    /// The pixels as a tightly packed `RGBRGB…` byte buffer.
    pub fn as_bytes(&self) -> Vec<u8> {
        self.pixels.iter().flatten().copied().collect()
    }
}

pub(crate) fn pixel_count(width: u32, height: u32) -> usize {
    width as usize * height as usize
}
