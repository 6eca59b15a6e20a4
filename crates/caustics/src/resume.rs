//! Resuming a killed `caustics reproduce`: which run folders are complete, the folder
//! lock, and the clean-up of what a killed process leaves behind.
//!
//! Every file the harness writes goes through [`caustics_metrics::atomic_write`] (a
//! hidden temporary sibling `.<name>.tmp-<pid>-<n>`, synced, then renamed), so a kill
//! leaves whole files and, at worst, temporaries. A run folder's `result.json` is
//! written last, so a folder without one is incomplete. A folder with one is
//! **complete** when it was made from the inputs the run would have now ([`Expected`]):
//!
//! - the result schema, scene name, scene content hash and resolution, method, parameters
//!   (as given), warm-up and measured frames, scoring grid and exposure: what the
//!   numbers mean;
//! - the reference it was scored against: errors exist exactly when the cache holds a
//!   reference now, and against that file (a reference rendered after a run without
//!   one makes the run stale);
//! - the build (commit, dirty flag, version, profile) and the machine (CPU model, and the
//!   adapter when `--adapter`/`CAUSTICS_ADAPTER` names one): an experiment folder holds
//!   one build's and one machine's timings, as an uninterrupted run would; a changed
//!   build redoes the runs rather than mixing two builds in one table. As a dirty
//!   tree's commit does not change with its edits, the executable itself must be the
//!   same too: its size and modification time, which `reproduce` writes beside each
//!   `result.json` as `resume.json` ([`ExeStamp`], written after it: a run killed between
//!   the two is redone);
//! - every image its `result.json` lists is there (the EXRs only with `--keep-exr`).
//!
//! An animated run (the experiment's `animate`) is a folder `…/animation/` whose
//! `animation.json` is written last: it is complete when made by the same binary on the
//! same machine from the same scene (its first instant's hash), resolution, method,
//! parameters, sequence, scored instants and scoring grid, against the references the
//! cache holds now for its scored instants, with every image it lists.
//!
//! Anything else is redone from an emptied folder.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use crate::experiment::RunSpec;
use crate::machine::Build;
use crate::result::{RunResult, SCHEMA_VERSION};

/// Whether `reproduce` drops this image of a run unless `--keep-exr`: every linear EXR
/// `caustics run` writes (`surface.exr`, `surface_1spp.exr`, ...), the PNGs stay.
pub fn is_dropped_exr(file: &str) -> bool {
    file.ends_with(".exr")
}

/// The files of an experiment folder that `reproduce` writes besides `runs/` and
/// `plots/`; `manifest.json` is written last, so a folder without one is unfinished.
pub const SUMMARY_FILES: [&str; 4] = ["summary.json", "summary.md", "bmf.json", "manifest.json"];

/// The executable that made a run (`resume.json` in the run folder): a rebuilt binary
/// has another modification time even where the commit and the dirty flag read the same.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExeStamp {
    /// Bytes of the executable.
    pub size: u64,
    /// Its modification time, nanoseconds since the Unix epoch.
    pub modified_unix_ns: u64,
}

/// Name of the stamp file in a run folder.
pub const STAMP: &str = "resume.json";

impl ExeStamp {
    /// The running executable's stamp, or `None` where the platform cannot tell.
    pub fn current() -> Option<ExeStamp> {
        let meta = std::env::current_exe().ok()?.metadata().ok()?;
        let modified = meta
            .modified()
            .ok()?
            .duration_since(std::time::UNIX_EPOCH)
            .ok()?;
        Some(ExeStamp {
            size: meta.len(),
            modified_unix_ns: u64::try_from(modified.as_nanos()).ok()?,
        })
    }

    /// Writes `<dir>/resume.json` (atomically).
    pub fn write(&self, dir: &Path) -> Result<()> {
        caustics_metrics::atomic_write(&dir.join(STAMP), &serde_json::to_vec_pretty(self)?)?;
        Ok(())
    }
}

/// What a run would be made from now.
#[derive(Clone, Debug)]
pub struct Expected<'a> {
    /// The run.
    pub spec: &'a RunSpec,
    /// The experiment's `exposure`.
    pub exposure: Option<f32>,
    /// The reference `caustics run` would score against (as it writes it in
    /// `errors.reference`), if the cache has one; for a sequence, one per scored instant
    /// in time order ([`crate::experiment::Sequence::scored_instants`]).
    pub references: Vec<Option<String>>,
    /// This binary's build.
    pub build: &'a Build,
    /// This machine's CPU model.
    pub cpu: &'a str,
    /// The adapter name substring asked for (`--adapter`, else `CAUSTICS_ADAPTER`).
    pub adapter: Option<&'a str>,
    /// `--keep-exr`.
    pub keep_exr: bool,
    /// This executable, when the platform tells ([`ExeStamp::current`]).
    pub exe: Option<&'a ExeStamp>,
}

/// Whether a run folder can be kept.
#[derive(Debug)]
pub enum Completeness {
    /// Complete and made from the expected inputs: its result (none for a sequence).
    Complete(Option<Box<RunResult>>),
    /// Missing (never run, killed, failed or skipped before).
    Missing,
    /// Present but not what the run would make now: why.
    Stale(String),
}

/// Decides whether the run folder `dir` holds the run `x` would make.
pub fn completeness(dir: &Path, x: &Expected<'_>) -> Completeness {
    if let Some(sequence) = &x.spec.animate {
        return sequence_completeness(dir, sequence, x);
    }
    let p = dir.join("result.json");
    if !p.is_file() {
        return Completeness::Missing;
    }
    let r = match std::fs::read_to_string(&p)
        .map_err(anyhow::Error::from)
        .and_then(|t| RunResult::from_json(&t).map_err(anyhow::Error::from))
    {
        Ok(r) => r,
        Err(e) => return Completeness::Stale(format!("{}: unreadable ({e})", p.display())),
    };
    match stale_reason(dir, &r, x) {
        None => Completeness::Complete(Some(Box::new(r))),
        Some(why) => Completeness::Stale(format!("{}: {why}", p.display())),
    }
}

/// [`completeness`] of an animated run's folder (`animation.json`): the same inputs as a
/// still run's where a sequence has them (its first instant's scene hash), the sequence
/// and its scored instants, and each scored instant's reference.
fn sequence_completeness(
    dir: &Path,
    sequence: &crate::experiment::Sequence,
    x: &Expected<'_>,
) -> Completeness {
    let p = dir.join(crate::animate::ANIMATION_FILE);
    if !p.is_file() {
        return Completeness::Missing;
    }
    let a = match crate::animate::load(&p) {
        Ok(a) => a,
        Err(e) => return Completeness::Stale(format!("{}: unreadable ({e:#})", p.display())),
    };
    let s = &x.spec.scene;
    let first_hash = s
        .at_time(sequence.start_s)
        .map(|posed| posed.hash_hex())
        .unwrap_or_default();
    let want_params = serde_json::Value::Object(x.spec.params.clone());
    // Each scored instant was scored exactly when the cache has its reference now, and
    // against that one (a frame names its reference by its path; the key is its tail).
    let have_refs: Vec<Option<&str>> = sequence
        .spec()
        .scored_frames(sequence.reference_every())
        .into_iter()
        .map(|i| a.frames.get(i).and_then(|f| f.reference.as_deref()))
        .collect();
    let refs_match = have_refs.len() == x.references.len()
        && have_refs
            .iter()
            .zip(&x.references)
            .all(|(h, w)| match (h, w) {
                (Some(h), Some(w)) => h.ends_with(w.as_str()),
                (None, None) => true,
                _ => false,
            });
    let source = a.tone_map.as_ref().and_then(|t| t.source.as_deref());
    let why = differs(
        "schema_version",
        a.schema_version,
        crate::animate::ANIMATION_SCHEMA_VERSION,
    )
    .or_else(|| differs("scene.name", a.scene.name.as_str(), s.name.as_str()))
    .or_else(|| {
        differs(
            "scene.hash (first instant)",
            a.scene.hash.clone(),
            first_hash,
        )
    })
    .or_else(|| {
        differs(
            "the resolution",
            (a.scene.width, a.scene.height),
            (s.camera.width, s.camera.height),
        )
    })
    .or_else(|| {
        differs(
            "method.name",
            a.method.name.as_str(),
            x.spec.method.as_str(),
        )
    })
    .or_else(|| differs("method.params", &a.method.params, &want_params))
    .or_else(|| differs("sequence", a.sequence, sequence.spec()))
    .or_else(|| {
        differs(
            "reference_every",
            a.reference_every,
            sequence.reference_every(),
        )
    })
    .or_else(|| differs("score_grid", a.score_grid, x.spec.score_grid))
    .or_else(|| {
        (!refs_match).then(|| {
            format!(
                "its scored instants' references are {have_refs:?}, the cache now has {:?}",
                x.references
            )
        })
    })
    .or_else(|| match (x.exposure, &a.tone_map) {
        // No scored instant: no image, no LDR figure.
        (_, None) => None,
        (Some(e), Some(t)) => differs(
            "tone_map (source, exposure_scale)",
            (source, t.exposure_scale),
            (Some("--exposure"), e),
        ),
        (None, Some(_)) => (source == Some("--exposure"))
            .then(|| "tone_map.source is --exposure, the experiment sets none".to_owned()),
    })
    .or_else(|| build_machine_exe_reason(dir, &a.build, &a.machine, x))
    .or_else(|| {
        a.frames
            .iter()
            .filter_map(|f| f.image.as_deref())
            .find(|f| !dir.join(f).is_file())
            .map(|f| format!("lists image {f}, which is missing"))
    });
    match why {
        None => Completeness::Complete(None),
        Some(why) => Completeness::Stale(format!("{}: {why}", p.display())),
    }
}

fn differs<T: std::fmt::Debug + PartialEq>(what: &str, have: T, want: T) -> Option<String> {
    (have != want).then(|| format!("{what} is {have:?}, the run now has {want:?}"))
}

fn stale_reason(dir: &Path, r: &RunResult, x: &Expected<'_>) -> Option<String> {
    let s = &x.spec.scene;
    let want_params = serde_json::Value::Object(x.spec.params.clone());
    let source = r.tone_map.source.as_deref();
    let errors_ref = r.errors.as_ref().map(|e| e.reference.as_str());
    differs("schema_version", r.schema_version, SCHEMA_VERSION)
        .or_else(|| differs("scene.name", r.scene.name.as_str(), s.name.as_str()))
        .or_else(|| differs("scene.hash", r.scene.hash.clone(), s.hash_hex()))
        .or_else(|| {
            differs(
                "the resolution",
                (r.scene.width, r.scene.height),
                (s.camera.width, s.camera.height),
            )
        })
        .or_else(|| {
            differs(
                "method.name",
                r.method.name.as_str(),
                x.spec.method.as_str(),
            )
        })
        .or_else(|| differs("method.params", &r.method.params, &want_params))
        .or_else(|| differs("frames.warmup", r.frames.warmup, x.spec.warmup))
        .or_else(|| differs("frames.measured", r.frames.measured, x.spec.frames))
        .or_else(|| {
            differs(
                "scoring.grid",
                r.scoring.as_ref().map(|g| g.grid),
                Some(x.spec.score_grid),
            )
        })
        .or_else(|| match x.exposure {
            Some(e) => differs(
                "tone_map (source, exposure_scale)",
                (source, r.tone_map.exposure_scale),
                (Some("--exposure"), e),
            ),
            None => (source == Some("--exposure"))
                .then(|| "tone_map.source is --exposure, the experiment sets none".to_owned()),
        })
        .or_else(|| {
            differs(
                "errors.reference",
                errors_ref,
                x.references.first().and_then(Option::as_deref),
            )
        })
        .or_else(|| build_machine_exe_reason(dir, &r.build, &r.machine, x))
        .or_else(|| {
            r.images
                .values()
                .filter(|f| x.keep_exr || !is_dropped_exr(f))
                .find(|f| !dir.join(f).is_file())
                .map(|f| format!("lists image {f}, which is missing"))
        })
}

/// Why a run made by `build` on `machine` into `dir` is not this binary's on this
/// machine: an experiment folder holds one build's and one machine's timings.
fn build_machine_exe_reason(
    dir: &Path,
    build: &Build,
    machine: &crate::machine::Machine,
    x: &Expected<'_>,
) -> Option<String> {
    let adapter_ok = x
        .adapter
        .is_none_or(|a| machine.adapter.to_lowercase().contains(&a.to_lowercase()));
    differs(
        "build (commit, dirty, diff hash, version, profile)",
        (
            &build.commit,
            build.dirty,
            &build.diff_hash,
            &build.version,
            &build.profile,
        ),
        (
            &x.build.commit,
            x.build.dirty,
            &x.build.diff_hash,
            &x.build.version,
            &x.build.profile,
        ),
    )
    .or_else(|| differs("machine.cpu", machine.cpu.as_str(), x.cpu))
    .or_else(|| {
        (!adapter_ok).then(|| {
            format!(
                "machine.adapter is {:?}, the adapter asked for is {:?}",
                machine.adapter,
                x.adapter.unwrap_or_default()
            )
        })
    })
    .or_else(|| {
        let want = x.exe?;
        let p = dir.join(STAMP);
        let have: Option<ExeStamp> = std::fs::read(&p)
            .ok()
            .and_then(|b| serde_json::from_slice(&b).ok());
        match have {
            Some(h) if h == *want => None,
            Some(_) => Some(format!("{STAMP}: made by another build of the executable")),
            None => Some(format!("{STAMP}: missing or unreadable")),
        }
    })
}

/// Removes the EXRs `reproduce` does not keep (see [`is_dropped_exr`]): those the run's
/// `result.json` lists.
pub fn drop_exrs(dir: &Path, images: &std::collections::BTreeMap<String, String>) {
    for f in images.values().filter(|f| is_dropped_exr(f)) {
        let _ = std::fs::remove_file(dir.join(f));
    }
}

/// The process id in an [`caustics_metrics::atomic_write`] temporary's name
/// (`.<name>.tmp-<pid>-<n>`), or `None` when `name` is not one.
pub fn temp_file_pid(name: &str) -> Option<u32> {
    let rest = name.strip_prefix('.')?;
    let (_, tail) = rest.rsplit_once(".tmp-")?;
    let (pid, n) = tail.split_once('-')?;
    n.parse::<u64>().ok()?;
    pid.parse().ok()
}

/// Whether process `pid` is alive. Linux only (`/proc`); elsewhere every other process
/// counts as alive, so nothing of another process's is removed.
fn alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    let proc = Path::new("/proc");
    !proc.is_dir() || proc.join(pid.to_string()).exists()
}

/// Removes the temporaries of dead writers under `dir` (recursively); with `all`, every
/// temporary not of this process (for a folder this process holds the lock of). Returns
/// the files removed.
pub fn remove_temp_files(dir: &Path, all: bool) -> Result<Vec<PathBuf>> {
    let mut removed = Vec::new();
    if !dir.is_dir() {
        return Ok(removed);
    }
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).with_context(|| format!("reading {}", d.display()))? {
            let entry = entry.with_context(|| format!("reading {}", d.display()))?;
            let path = entry.path();
            let kind = entry
                .file_type()
                .with_context(|| format!("reading {}", path.display()))?;
            if kind.is_dir() {
                stack.push(path);
                continue;
            }
            let Some(pid) = temp_file_pid(&entry.file_name().to_string_lossy()) else {
                continue;
            };
            let ours = pid == std::process::id();
            if !ours && (all || !alive(pid)) {
                std::fs::remove_file(&path)
                    .with_context(|| format!("removing {}", path.display()))?;
                removed.push(path);
            }
        }
    }
    Ok(removed)
}

/// `<dir>/.reproduce.lock` holding this process's id while it writes `dir`; removed
/// when dropped. A lock whose process is dead (killed) is taken over.
#[derive(Debug)]
pub struct DirLock {
    path: PathBuf,
}

impl DirLock {
    /// Name of the lock file.
    pub const NAME: &'static str = ".reproduce.lock";

    /// Takes the lock of `dir`, or fails naming the process that holds it.
    pub fn take(dir: &Path) -> Result<DirLock> {
        let path = dir.join(Self::NAME);
        for _ in 0..2 {
            match std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&path)
            {
                Ok(mut f) => {
                    use std::io::Write as _;
                    f.write_all(std::process::id().to_string().as_bytes())
                        .with_context(|| format!("writing {}", path.display()))?;
                    return Ok(DirLock { path });
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let holder = std::fs::read_to_string(&path)
                        .ok()
                        .and_then(|s| s.trim().parse::<u32>().ok());
                    if let Some(pid) = holder.filter(|&p| alive(p) && p != std::process::id()) {
                        bail!(
                            "{}: another `caustics reproduce` (process {pid}) is writing this folder; wait for it, or remove the file if no such process runs",
                            path.display()
                        );
                    }
                    std::fs::remove_file(&path)
                        .with_context(|| format!("removing the stale lock {}", path.display()))?;
                }
                Err(e) => return Err(e).with_context(|| format!("creating {}", path.display())),
            }
        }
        bail!("{}: could not take the lock", path.display())
    }
}

impl Drop for DirLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Removes what `reproduce` wrote into an experiment folder (`runs/`, `plots/`, `figures/` and
/// [`SUMMARY_FILES`]), for `--fresh`; other files stay.
pub fn clear_outputs(out: &Path) -> Result<()> {
    for d in ["runs", "plots", "figures"] {
        let p = out.join(d);
        if p.is_dir() {
            std::fs::remove_dir_all(&p).with_context(|| format!("removing {}", p.display()))?;
        }
    }
    mark_unfinished(out)
}

/// Removes the summary files and `manifest.json` (written last): the folder then reads
/// as unfinished (`merge`, `report` and `--summary-only` refuse or skip it) until the
/// reproduction ends.
pub fn mark_unfinished(out: &Path) -> Result<()> {
    // manifest.json first: with it gone the folder is unfinished whatever else remains.
    for f in SUMMARY_FILES.iter().rev() {
        let p = out.join(f);
        match std::fs::remove_file(&p) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(e).with_context(|| format!("removing {}", p.display())),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temp_names_are_recognised() {
        assert_eq!(temp_file_pid(".result.json.tmp-123-0"), Some(123));
        assert_eq!(temp_file_pid(".a.tmp-b.png.tmp-7-42"), Some(7));
        for n in [
            "result.json",
            ".result.json",
            ".x.tmp-12",
            ".x.tmp-a-1",
            ".x.tmp-1-b",
            "x.tmp-1-2",
        ] {
            assert_eq!(temp_file_pid(n), None, "{n}");
        }
    }

    #[test]
    fn a_stale_lock_is_taken_over_a_live_one_refused() {
        let tmp = tempfile::tempdir().expect("tempdir");
        let lock = DirLock::take(tmp.path()).expect("lock");
        drop(lock);
        assert!(!tmp.path().join(DirLock::NAME).exists());
        // A dead process's lock (pid far above any pid_max) is taken over.
        std::fs::write(tmp.path().join(DirLock::NAME), "4294967").expect("write");
        let lock = DirLock::take(tmp.path()).expect("stale lock taken over");
        drop(lock);
        // A live one (pid 1 always runs) is refused, naming it.
        if Path::new("/proc/1").exists() {
            std::fs::write(tmp.path().join(DirLock::NAME), "1").expect("write");
            let e = DirLock::take(tmp.path()).expect_err("live lock");
            assert!(format!("{e:#}").contains("process 1"), "{e:#}");
        }
    }
}
