//! File I/O: atomic writes, EXR (linear `f32` RGB) and PNG (8-bit sRGB).

use std::fs::{self, File, OpenOptions};
use std::io::{Cursor, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::{HdrImage, MetricsError, Rgb8Image};

/// Writes `bytes` to `path` atomically: a reader sees either the old file or the complete
/// new one, never a partial write.
///
/// The bytes go to a hidden temporary file in the same directory
/// (`.<name>.tmp-<pid>-<n>`), which is flushed to disk (`fsync`) and then renamed over
/// `path`; on Unix the directory is synced afterwards so the rename itself survives a
/// crash. If any step fails the temporary file is removed and an existing file at `path`
/// is left untouched.
pub fn atomic_write(path: &Path, bytes: &[u8]) -> Result<(), MetricsError> {
    atomic_write_with(path, |file| file.write_all(bytes))
}

/// Like [`atomic_write`], but the content is produced by `write` streaming into the
/// temporary file. If `write` fails, nothing is renamed and the temporary file is removed.
pub fn atomic_write_with(
    path: &Path,
    write: impl FnOnce(&mut File) -> std::io::Result<()>,
) -> Result<(), MetricsError> {
    let tmp = temp_sibling(path)?;
    let result = (|| {
        let mut file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
            .map_err(|e| MetricsError::io(&tmp, e))?;
        write(&mut file).map_err(|e| MetricsError::io(&tmp, e))?;
        file.sync_all().map_err(|e| MetricsError::io(&tmp, e))?;
        drop(file);
        fs::rename(&tmp, path).map_err(|e| MetricsError::io(path, e))
    })();
    if result.is_err() {
        // Best effort: the temporary may not exist if its creation was what failed.
        let _ = fs::remove_file(&tmp);
        return result;
    }
    sync_parent_dir(path);
    Ok(())
}

/// A unique hidden sibling of `path` for [`atomic_write_with`].
fn temp_sibling(path: &Path) -> Result<PathBuf, MetricsError> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name().ok_or_else(|| {
        MetricsError::io(
            path,
            std::io::Error::new(std::io::ErrorKind::InvalidInput, "path has no file name"),
        )
    })?;
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let tmp_name = format!(".{}.tmp-{}-{n}", name.to_string_lossy(), std::process::id());
    Ok(path.with_file_name(tmp_name))
}

#[cfg(unix)]
fn sync_parent_dir(path: &Path) {
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    // Best effort: the data is already durable in the renamed file; a failure here only
    // weakens the crash guarantee for the directory entry.
    if let Ok(dir) = File::open(parent) {
        let _ = dir.sync_all();
    }
}

#[cfg(not(unix))]
fn sync_parent_dir(_path: &Path) {}

/// Reads the first RGB(A) layer of an EXR file at its largest resolution level.
///
/// Half, float and uint channels are converted to `f32`; alpha and any other channels are
/// ignored. A missing file gives [`MetricsError::Io`], anything else [`MetricsError::Exr`].
pub fn read_exr(path: &Path) -> Result<HdrImage, MetricsError> {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |resolution: Vec2<usize>, _channels: &RgbaChannels| HdrImage {
            width: resolution.width() as u32,
            height: resolution.height() as u32,
            pixels: vec![[0.0; 3]; resolution.width() * resolution.height()],
        },
        |img: &mut HdrImage, pos: Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
            let w = img.width as usize;
            img.pixels[pos.y() * w + pos.x()] = [r, g, b];
        },
    )
    .map_err(|e| exr_error(path, e))?;
    Ok(image.layer_data.channel_data.pixels)
}

/// Writes `img` as an EXR file with three `f32` channels R, G, B (ZIP compression,
/// lossless), atomically (see [`atomic_write`]).
pub fn write_exr(path: &Path, img: &HdrImage) -> Result<(), MetricsError> {
    use exr::prelude::*;
    check_buffer(
        img.pixels.len(),
        img.width,
        img.height,
        "HDR image to write",
    )?;
    if img.width == 0 || img.height == 0 {
        return Err(MetricsError::Empty {
            what: format!("EXR {}", path.display()),
            width: img.width,
            height: img.height,
        });
    }
    let w = img.width as usize;
    let channels = SpecificChannels::rgb(|pos: Vec2<usize>| {
        let p = img.pixels[pos.y() * w + pos.x()];
        (p[0], p[1], p[2])
    });
    let image = Image::from_encoded_channels(
        (img.width as usize, img.height as usize),
        Encoding::SMALL_LOSSLESS,
        channels,
    );
    let mut buf = Cursor::new(Vec::new());
    image
        .write()
        .to_buffered(&mut buf)
        .map_err(|e| exr_error(path, e))?;
    atomic_write(path, buf.get_ref())
}

fn exr_error(path: &Path, e: exr::error::Error) -> MetricsError {
    match e {
        exr::error::Error::Io(source) => MetricsError::io(path, source),
        other => MetricsError::Exr {
            path: path.to_owned(),
            message: other.to_string(),
        },
    }
}

/// Writes `img` as an 8-bit RGB PNG, atomically (see [`atomic_write`]).
pub fn write_png(path: &Path, img: &Rgb8Image) -> Result<(), MetricsError> {
    use image::ImageEncoder;
    check_buffer(
        img.pixels.len(),
        img.width,
        img.height,
        "RGB8 image to write",
    )?;
    let mut buf = Vec::new();
    image::codecs::png::PngEncoder::new(&mut buf)
        .write_image(
            &img.as_bytes(),
            img.width,
            img.height,
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| MetricsError::Png {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
    atomic_write(path, &buf)
}

/// Reads a PNG file as 8-bit RGB (grey, alpha and 16-bit PNGs are converted; alpha is dropped).
pub fn read_png(path: &Path) -> Result<Rgb8Image, MetricsError> {
    let bytes = fs::read(path).map_err(|e| MetricsError::io(path, e))?;
    let decoded = image::load_from_memory_with_format(&bytes, image::ImageFormat::Png)
        .map_err(|e| MetricsError::Png {
            path: path.to_owned(),
            message: e.to_string(),
        })?
        .into_rgb8();
    let (width, height) = decoded.dimensions();
    let pixels = decoded
        .into_raw()
        .chunks_exact(3)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    Ok(Rgb8Image {
        width,
        height,
        pixels,
    })
}

/// Largest per-pixel count [`write_counts_png`] stores as one 16-bit grey sample; above
/// it the file holds each count in two 16-bit samples.
pub const MAX_PNG_COUNT: u32 = u16::MAX as u32;

/// Writes per-pixel counts (row-major, row 0 at the top) as a lossless, compressed PNG,
/// so figures drawn later from several runs (shared-scale heatmaps) read the exact
/// counts back with [`read_counts_png`]: 16-bit grey where every count is at most
/// [`MAX_PNG_COUNT`], else 16-bit RGB holding each count's high half in red and its low
/// half in green (a beam method under 16 lights stacks over 65,535 fragments on a
/// pixel). Never clipped.
pub fn write_counts_png(
    path: &Path,
    counts: &[u32],
    width: u32,
    height: u32,
) -> Result<(), MetricsError> {
    use image::ImageEncoder;
    check_buffer(counts.len(), width, height, "counts to write")?;
    let wide = counts.iter().any(|&c| c > MAX_PNG_COUNT);
    let mut bytes = Vec::with_capacity(counts.len() * if wide { 6 } else { 2 });
    // `image` takes 16-bit samples in native byte order (it writes PNG's big-endian).
    for &c in counts {
        if wide {
            for half in [(c >> 16) as u16, c as u16, 0] {
                bytes.extend_from_slice(&half.to_ne_bytes());
            }
        } else {
            bytes.extend_from_slice(&(c as u16).to_ne_bytes());
        }
    }
    let color = if wide {
        image::ExtendedColorType::Rgb16
    } else {
        image::ExtendedColorType::L16
    };
    let mut buf = Vec::new();
    image::codecs::png::PngEncoder::new(&mut buf)
        .write_image(&bytes, width, height, color)
        .map_err(|e| MetricsError::Png {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
    atomic_write(path, &buf)
}

/// Reads counts written by [`write_counts_png`]: `(counts, width, height)`.
pub fn read_counts_png(path: &Path) -> Result<(Vec<u32>, u32, u32), MetricsError> {
    let bytes = fs::read(path).map_err(|e| MetricsError::io(path, e))?;
    let decoded =
        image::load_from_memory_with_format(&bytes, image::ImageFormat::Png).map_err(|e| {
            MetricsError::Png {
                path: path.to_owned(),
                message: e.to_string(),
            }
        })?;
    let (width, height) = (decoded.width(), decoded.height());
    let counts = match decoded {
        image::DynamicImage::ImageLuma16(grey) => {
            grey.into_raw().into_iter().map(u32::from).collect()
        }
        image::DynamicImage::ImageRgb16(rgb) => rgb
            .into_raw()
            .chunks_exact(3)
            .map(|p| (u32::from(p[0]) << 16) | u32::from(p[1]))
            .collect(),
        _ => {
            return Err(MetricsError::Png {
                path: path.to_owned(),
                message: "expected a 16-bit greyscale or 16-bit RGB PNG of counts".to_owned(),
            });
        }
    };
    Ok((counts, width, height))
}

fn check_buffer(len: usize, width: u32, height: u32, what: &str) -> Result<(), MetricsError> {
    let expected = crate::image::pixel_count(width, height);
    if len != expected {
        return Err(MetricsError::BufferLength {
            what: format!("{what} ({width}x{height})"),
            expected,
            actual: len,
        });
    }
    Ok(())
}
