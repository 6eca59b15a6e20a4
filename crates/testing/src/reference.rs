//! The CPU reference of a test scene at a fixed photon budget and seed, cached under the
//! target folder.
//!
//! The cache key is everything the image depends on: the scene's content hash (which
//! covers its camera, hence the resolution), the resolution again for the reader, the
//! photons, seed, batches, whether the direct image was asked for, and a hash of the
//! reference's and the scene crate's sources (`build.rs`), so a changed renderer never
//! meets an image it did not make. A reference is rendered into a private folder and
//! renamed into place, so tests running at once never read half a cache entry.
//! (`caustics reference` keeps its own cache under `results/references`, keyed by scene
//! only: it is the harness's, for full-size runs.)

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use caustics_metrics::{HdrImage, luminance, read_exr, write_exr};
use caustics_reference::{Reference, ReferenceImage, ReferenceOptions};
use caustics_scene::Scene;

/// Hash of the sources the reference image depends on (from `build.rs`).
const REFERENCE_CODE: &str = env!("CAUSTICS_TESTING_REFERENCE_CODE");

/// A CPU reference's images (DESIGN "Units and what an image means").
#[derive(Clone, Debug)]
pub struct ReferenceImages {
    /// The surface caustic image (L S+ D E).
    pub surface: HdrImage,
    /// Its per-pixel standard error.
    pub surface_stderr: HdrImage,
    /// The volume caustic image, for a scene with a medium.
    pub volume: Option<HdrImage>,
    /// Its per-pixel standard error.
    pub volume_stderr: Option<HdrImage>,
    /// The direct image (L D E), if asked for.
    pub direct: Option<HdrImage>,
    /// The cache folder the images are in.
    pub dir: PathBuf,
    /// Whether they were read from the cache (`false`: rendered by this call).
    pub cached: bool,
}

impl ReferenceImages {
    /// Mean standard error over the caustic pixels (luminance > 0) relative to their
    /// mean luminance (the figure `caustics reference` prints): the reference's own noise.
    pub fn relative_stderr(&self) -> f64 {
        let (mut sum_c, mut sum_e) = (0.0f64, 0.0f64);
        for (c, e) in self.surface.pixels.iter().zip(&self.surface_stderr.pixels) {
            let lc = f64::from(luminance(*c));
            if lc > 0.0 {
                sum_c += lc;
                sum_e += f64::from(luminance(*e));
            }
        }
        if sum_c > 0.0 {
            sum_e / sum_c
        } else {
            f64::INFINITY
        }
    }
}

/// The cache folder of `scene` rendered with `opts`.
fn cache_dir(scene: &Scene, opts: &ReferenceOptions) -> PathBuf {
    let c = &scene.camera;
    crate::target_dir()
        .join("caustics-testing")
        .join("references")
        .join(&scene.name)
        .join(format!(
            "{}-{}x{}-p{}-s{}-b{}{}-code{REFERENCE_CODE}",
            scene.hash_hex(),
            c.width,
            c.height,
            opts.photons,
            opts.seed,
            opts.batches,
            if opts.direct { "-direct" } else { "" }
        ))
}

fn hdr(img: &ReferenceImage) -> HdrImage {
    HdrImage {
        width: img.width,
        height: img.height,
        pixels: img.pixels.clone(),
    }
}

const FILES: [&str; 5] = [
    "caustic.exr",
    "stderr.exr",
    "volume.exr",
    "volume_stderr.exr",
    "direct.exr",
];

fn load(dir: &Path, scene: &Scene, opts: &ReferenceOptions) -> Option<ReferenceImages> {
    let read = |name: &str| -> Option<HdrImage> {
        let p = dir.join(name);
        p.is_file()
            .then(|| read_exr(&p).unwrap_or_else(|e| panic!("cached reference: {e}")))
    };
    let images = ReferenceImages {
        surface: read(FILES[0])?,
        surface_stderr: read(FILES[1])?,
        volume: read(FILES[2]),
        volume_stderr: read(FILES[3]),
        direct: read(FILES[4]),
        dir: dir.to_owned(),
        cached: true,
    };
    let complete = images.volume.is_some() == scene.medium.is_some()
        && images.volume_stderr.is_some() == scene.medium.is_some()
        && images.direct.is_some() == opts.direct;
    assert!(
        complete,
        "cached reference {} lacks an image (delete the folder to render it again)",
        dir.display()
    );
    Some(images)
}

/// The CPU reference of `scene` with `opts` (photons, batches, seed, direct): read from
/// the cache under `target/caustics-testing/references/` when there, else rendered (on
/// every core, with rayon) and stored there. Test references are small (a few million
/// photons at a test's resolution): seconds, once per checkout and reference change.
///
/// # Panics
/// If the reference cannot render the scene or the cache cannot be read or written.
pub fn reference(scene: &Scene, opts: &ReferenceOptions) -> ReferenceImages {
    // One render at a time in a test binary: a second test asking for the same
    // reference waits and reads it from the cache instead of tracing it again.
    static RENDERING: Mutex<()> = Mutex::new(());
    let _one_at_a_time = RENDERING
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    let dir = cache_dir(scene, opts);
    if let Some(found) = load(&dir, scene, opts) {
        eprintln!("CPU reference from the cache: {}", dir.display());
        return found;
    }
    let started = std::time::Instant::now();
    let result = Reference::new(scene)
        .and_then(|r| r.render(opts, &|_| {}))
        .unwrap_or_else(|e| panic!("CPU reference of {}: {e}", scene.name));
    eprintln!(
        "CPU reference of {} at {}x{}: {} photons in {:.1} s, cached in {}",
        scene.name,
        scene.camera.width,
        scene.camera.height,
        result.photons,
        started.elapsed().as_secs_f64(),
        dir.display()
    );
    let images = ReferenceImages {
        surface: hdr(&result.caustic),
        surface_stderr: hdr(&result.caustic_stderr),
        volume: result.volume.as_ref().map(hdr),
        volume_stderr: result.volume_stderr.as_ref().map(hdr),
        direct: result.direct.as_ref().map(hdr),
        dir: dir.clone(),
        cached: false,
    };
    store(&dir, &images);
    images
}

/// Writes the images into a private sibling folder, then renames it into place; if
/// another test got there first, its (identical) entry stays.
fn store(dir: &Path, images: &ReferenceImages) {
    let parent = dir.parent().expect("cache folders have a parent");
    std::fs::create_dir_all(parent)
        .unwrap_or_else(|e| panic!("creating {}: {e}", parent.display()));
    let unique = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    let tmp = parent.join(format!(".tmp-{}-{unique}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap_or_else(|e| panic!("creating {}: {e}", tmp.display()));
    let all = [
        Some(&images.surface),
        Some(&images.surface_stderr),
        images.volume.as_ref(),
        images.volume_stderr.as_ref(),
        images.direct.as_ref(),
    ];
    for (name, img) in FILES.iter().zip(all) {
        if let Some(img) = img {
            write_exr(&tmp.join(name), img)
                .unwrap_or_else(|e| panic!("caching the reference: {e}"));
        }
    }
    if std::fs::rename(&tmp, dir).is_err() {
        // Another test stored the same entry meanwhile (a rename onto a non-empty
        // folder fails); keep that one.
        let _ = std::fs::remove_dir_all(&tmp);
        assert!(
            dir.is_dir(),
            "could not store the reference in {}",
            dir.display()
        );
    }
}
