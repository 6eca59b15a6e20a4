//! Images written when a bound fails (STYLE 9: a failure can be looked at, not only read).

use std::path::{Path, PathBuf};

use caustics_metrics::{HdrImage, signed_error_map, write_exr, write_png};

/// The cargo target folder the running test binary was built in
/// (`<target>/<profile>/deps/<test>-<hash>`), else the system's temporary folder.
pub fn target_dir() -> PathBuf {
    let exe = std::env::current_exe().ok();
    exe.as_deref()
        .and_then(Path::parent)
        .filter(|deps| deps.file_name().is_some_and(|n| n == "deps"))
        .and_then(Path::parent)
        .and_then(Path::parent)
        .map(Path::to_owned)
        .unwrap_or_else(|| std::env::temp_dir().join("caustics-testing"))
}

/// The folder a test writes its images into when a bound fails:
/// `<target>/test-artifacts/<crate>/<test>/`, emptied when the test starts so what is
/// there belongs to its last run. Make one with [`artifacts!`](crate::artifacts).
#[derive(Clone, Debug)]
pub struct Artifacts {
    dir: PathBuf,
}

/// [`Artifacts`] of the calling test: the calling package's name and the running test's
/// (libtest names each test's thread after the test), or `artifacts!("name")`.
#[macro_export]
macro_rules! artifacts {
    () => {
        $crate::Artifacts::new(
            env!("CARGO_PKG_NAME"),
            ::std::thread::current().name().unwrap_or("unnamed-test"),
        )
    };
    ($test:expr) => {
        $crate::Artifacts::new(env!("CARGO_PKG_NAME"), $test)
    };
}

impl Artifacts {
    /// The folder of test `test` of crate `crate_name`, emptied.
    pub fn new(crate_name: &str, test: &str) -> Self {
        let safe: String = test
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        let dir = target_dir()
            .join("test-artifacts")
            .join(crate_name)
            .join(safe);
        let _ = std::fs::remove_dir_all(&dir);
        Self { dir }
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Writes `<name>-actual.exr/.png`, `<name>-expected.exr/.png` (tone-mapped at the
    /// expected image's 99th percentile, both alike) and `<name>-difference.exr` (actual −
    /// expected, signed, per channel) with `<name>-difference.png` (signed luminance error
    /// map, W·m⁻²·sr⁻¹, blue too dark, red too bright). Returns what it wrote, for a
    /// message; a file it could not write is named with the reason.
    pub fn write(&self, name: &str, actual: &HdrImage, expected: &HdrImage) -> String {
        if let Err(e) = std::fs::create_dir_all(&self.dir) {
            return format!("no images: could not create {}: {e}", self.dir.display());
        }
        let tone = crate::reference_tone(expected);
        let mut notes: Vec<String> = Vec::new();
        let mut put = |file: String, written: Result<(), caustics_metrics::MetricsError>| {
            notes.push(match written {
                Ok(()) => file,
                Err(e) => format!("({file} not written: {e})"),
            });
        };
        for (suffix, img) in [("actual", actual), ("expected", expected)] {
            let stem = format!("{name}-{suffix}");
            let exr = self.dir.join(format!("{stem}.exr"));
            put(format!("{stem}.exr"), write_exr(&exr, img));
            let png = self.dir.join(format!("{stem}.png"));
            put(format!("{stem}.png"), write_png(&png, &tone.apply(img)));
        }
        let stem = format!("{name}-difference");
        match difference(actual, expected) {
            Some(d) => {
                let exr = self.dir.join(format!("{stem}.exr"));
                put(format!("{stem}.exr"), write_exr(&exr, &d));
                let png = self.dir.join(format!("{stem}.png"));
                let map = signed_error_map(actual, expected, None);
                put(format!("{stem}.png"), map.and_then(|m| write_png(&png, &m)));
            }
            None => put(
                format!("{stem}.exr"),
                Err(caustics_metrics::MetricsError::InvalidParameter {
                    name: "actual",
                    message: format!(
                        "{}x{}, but expected is {}x{}",
                        actual.width, actual.height, expected.width, expected.height
                    ),
                }),
            ),
        }
        format!("images in {}: {}", self.dir.display(), notes.join(" "))
    }

    /// Passes if `ok`; else writes the images of [`Artifacts::write`] and panics with
    /// `message()` and where the images are.
    #[track_caller]
    pub fn ensure(
        &self,
        ok: bool,
        name: &str,
        actual: &HdrImage,
        expected: &HdrImage,
        message: impl FnOnce() -> String,
    ) {
        if !ok {
            let message = message();
            let written = self.write(name, actual, expected);
            panic!("{message}\n  {written}");
        }
    }
}

fn difference(actual: &HdrImage, expected: &HdrImage) -> Option<HdrImage> {
    ((actual.width, actual.height) == (expected.width, expected.height)).then(|| HdrImage {
        width: actual.width,
        height: actual.height,
        pixels: actual
            .pixels
            .iter()
            .zip(&expected.pixels)
            .map(|(a, e)| [a[0] - e[0], a[1] - e[1], a[2] - e[2]])
            .collect(),
    })
}
