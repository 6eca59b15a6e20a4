//! The error type shared by every function of this crate.

use std::path::PathBuf;

/// Everything that can go wrong while reading, writing or comparing images.
///
/// Messages name the file or the image involved, so that a failure in a long
/// benchmark run can be traced without a debugger.
#[derive(Debug, thiserror::Error)]
pub enum MetricsError {
    /// Two images (or an image and a buffer) that must have the same size do not.
    #[error(
        "{what}: size mismatch, expected {expected_width}x{expected_height}, got {actual_width}x{actual_height}"
    )]
    SizeMismatch {
        /// What was being compared, e.g. `"test vs reference"`.
        what: String,
        /// Width of the image that sets the expectation (the reference, or the left operand).
        expected_width: u32,
        /// Height of the image that sets the expectation.
        expected_height: u32,
        /// Width of the other image.
        actual_width: u32,
        /// Height of the other image.
        actual_height: u32,
    },
    /// A flat buffer does not hold exactly `width * height * channels` values.
    #[error("{what}: buffer holds {actual} values, expected {expected}")]
    BufferLength {
        /// What the buffer is, e.g. `"rgba readback"` or `"fragment counts"`.
        what: String,
        /// The number of values the stated size requires.
        expected: usize,
        /// The number of values that were passed.
        actual: usize,
    },
    /// An image holds a NaN or an infinity; metrics refuse to turn it into a number.
    #[error(
        "{image} image has a non-finite value {value} at pixel ({x}, {y}) (first one in row-major order)"
    )]
    NonFinite {
        /// Which image, e.g. `"test"` or `"reference"`.
        image: String,
        /// Column of the first offending pixel.
        x: u32,
        /// Row of the first offending pixel (row 0 is the top).
        y: u32,
        /// The offending channel value.
        value: f32,
    },
    /// An image with no pixels was given where a metric needs at least one.
    #[error("{what}: image has no pixels ({width}x{height})")]
    Empty {
        /// What the image is.
        what: String,
        /// Its width.
        width: u32,
        /// Its height.
        height: u32,
    },
    /// A parameter is outside its valid range (e.g. a non-positive epsilon or peak).
    #[error("invalid parameter `{name}`: {message}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// What is wrong with it.
        message: String,
    },
    /// An operating-system I/O error on a file.
    #[error("I/O error on {}: {source}", path.display())]
    Io {
        /// The file (or its temporary sibling) being read or written.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The `exr` crate could not decode or encode a file.
    #[error("EXR error in {}: {message}", path.display())]
    Exr {
        /// The EXR file.
        path: PathBuf,
        /// The decoder's or encoder's message.
        message: String,
    },
    /// The `image` crate could not decode or encode a PNG file.
    #[error("PNG error in {}: {message}", path.display())]
    Png {
        /// The PNG file.
        path: PathBuf,
        /// The decoder's or encoder's message.
        message: String,
    },
}

impl MetricsError {
    /// Builds an [`MetricsError::Io`] for `path`.
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }
}
