//! The reference cache: `<root>/<scene>/<hash>-<width>x<height>/` holds `caustic.exr`,
//! `stderr.exr`, `volume.exr` (scenes with a medium), `volume_stderr.exr` and
//! `meta.json`. The key is the scene's content hash, the resolution and the reference's
//! [`TRANSPORT_VERSION`] (`<hash>-<width>x<height>-t<version>`), so neither an edited
//! scene nor a changed light tracer meets a stale reference; `caustics run` uses a
//! cached reference on its own.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use caustics_reference::TRANSPORT_VERSION;
use caustics_scene::Scene;
use serde::{Deserialize, Serialize};

/// Default cache root (relative to the working directory).
pub const DEFAULT_ROOT: &str = "results/references";

/// `meta.json` of a cached reference.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ReferenceMeta {
    /// Bumped when a field changes meaning.
    pub schema_version: u32,
    /// Scene name.
    pub scene: String,
    /// Scene content hash the reference was rendered from.
    pub scene_hash: String,
    /// The reference's light-transport version ([`TRANSPORT_VERSION`]).
    pub transport_version: u32,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Photons traced.
    pub photons: u64,
    /// Wall time (s).
    pub seconds: f64,
    /// Photons per second.
    pub photons_per_second: f64,
    /// RNG seed.
    pub seed: u64,
    /// Independent batches behind the standard-error images.
    pub batches: u32,
    /// Commit of the renderer.
    pub commit: String,
    /// Mean over caustic pixels (luminance > 0) of the per-pixel standard error
    /// relative to the mean caustic luminance there.
    pub relative_stderr: f64,
    /// The instant (s) an animated scene was posed at; absent for a still scene.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_s: Option<f32>,
}

/// A reference found on disk.
#[derive(Clone, Debug)]
pub struct CachedReference {
    /// Its folder.
    pub dir: PathBuf,
    /// What it is.
    pub meta: ReferenceMeta,
}

impl CachedReference {
    /// The surface caustic image.
    pub fn caustic(&self) -> PathBuf {
        self.dir.join("caustic.exr")
    }
    /// The surface caustic image as result files name it: its path inside the cache,
    /// `<scene>/<hash>-<width>x<height>-t<version>/caustic.exr` (the key says what it
    /// was made from; the cache's own location is the machine's business).
    pub fn caustic_key(&self) -> String {
        let part = |p: Option<&std::ffi::OsStr>| {
            p.map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        };
        let scene = part(self.dir.parent().and_then(Path::file_name));
        format!("{scene}/{}/caustic.exr", part(self.dir.file_name()))
    }
    /// Its per-pixel standard error.
    pub fn stderr(&self) -> PathBuf {
        self.dir.join("stderr.exr")
    }
    /// The volume caustic image, if the scene has a medium.
    pub fn volume(&self) -> Option<PathBuf> {
        Some(self.dir.join("volume.exr")).filter(|p| p.is_file())
    }
}

/// The cache folder of `scene` under `root`.
pub fn cache_dir(root: &Path, scene: &Scene) -> PathBuf {
    root.join(&scene.name).join(format!(
        "{}-{}x{}-t{TRANSPORT_VERSION}",
        scene.hash_hex(),
        scene.camera.width,
        scene.camera.height
    ))
}

/// The cached reference of `scene`, if one exists and its `meta.json` matches the
/// scene. A folder with a corrupt or mismatched `meta.json` is an error, not a miss,
/// so a broken cache is noticed instead of silently re-rendered over.
pub fn find(root: &Path, scene: &Scene) -> Result<Option<CachedReference>> {
    let dir = cache_dir(root, scene);
    let meta_path = dir.join("meta.json");
    if !meta_path.is_file() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(&meta_path)
        .with_context(|| format!("reading {}", meta_path.display()))?;
    let meta: ReferenceMeta = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a reference meta.json", meta_path.display()))?;
    let (w, h) = (scene.camera.width, scene.camera.height);
    if meta.scene_hash != scene.hash_hex()
        || (meta.width, meta.height) != (w, h)
        || meta.transport_version != TRANSPORT_VERSION
    {
        bail!(
            "{}: made for scene hash {} at {}x{} by reference transport {}, but the scene is {} at {w}x{h} and the reference transport {TRANSPORT_VERSION}",
            meta_path.display(),
            meta.scene_hash,
            meta.width,
            meta.height,
            meta.transport_version,
            scene.hash_hex()
        );
    }
    let found = CachedReference { dir, meta };
    for p in [found.caustic(), found.stderr()] {
        if !p.is_file() {
            bail!("{}: missing beside its meta.json", p.display());
        }
    }
    Ok(Some(found))
}
