//! Facts about the machine and the build, for result files.

use serde::{Deserialize, Serialize};

/// Where and with what a run was made.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Machine {
    /// Adapter name, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
    pub adapter: String,
    /// Backend, e.g. "Vulkan".
    pub backend: String,
    /// "Cpu" for software rasterizers: absolute times are CPU times there.
    pub device_type: String,
    /// Driver name.
    pub driver: String,
    /// Driver version.
    pub driver_info: String,
    /// CPU model.
    pub cpu: String,
    /// Logical CPUs.
    pub cpu_threads: usize,
    /// Operating system.
    pub os: String,
}

/// The source the binary was built from.
#[derive(Clone, Debug, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Build {
    /// `git rev-parse HEAD` of the working tree; where the tree is no git checkout (a
    /// copy sent to another machine), the commit `CAUSTICS_SOURCE_COMMIT` declares; else
    /// "unknown".
    pub commit: String,
    /// Whether the tree had uncommitted changes (outside `results/`).
    pub dirty: bool,
    /// When dirty: FNV-1a 64 (16 hex digits) of `git diff HEAD --binary` outside
    /// `results/`, so runs from differently edited trees of one commit tell apart.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diff_hash: Option<String>,
    /// Crate version.
    pub version: String,
    /// "release" or "debug": only release timings are reportable.
    pub profile: String,
}

/// The checkout a run reads and writes in ([`caustics_scene::workspace_root`]: the one
/// the binary was built in, unless it was moved), canonical.
pub fn checkout_root() -> std::path::PathBuf {
    let root = caustics_scene::workspace_root();
    root.canonicalize().unwrap_or(root)
}

/// How a result file names a file: relative to the checkout (with `/`) when the file
/// lies inside it, else as given, so that committed results carry no machine's
/// absolute paths.
pub fn portable_path(p: &std::path::Path) -> String {
    let canonical = p.canonicalize().unwrap_or_else(|_| p.to_path_buf());
    match canonical.strip_prefix(checkout_root()) {
        Ok(rel) if rel.as_os_str().is_empty() => ".".to_owned(),
        Ok(rel) => rel
            .components()
            .map(|c| c.as_os_str().to_string_lossy())
            .collect::<Vec<_>>()
            .join("/"),
        Err(_) => p.display().to_string(),
    }
}

/// Whether files written to `dir` would be committed: `dir` lies inside the checkout
/// and git does not ignore it (`results/reproduce`, `results/baselines`; not
/// `results/runs`, `results/references` or `target/`).
pub fn is_committed_path(dir: &std::path::Path) -> bool {
    let abs = if dir.is_absolute() {
        dir.to_path_buf()
    } else {
        std::env::current_dir().map_or_else(|_| dir.to_path_buf(), |c| c.join(dir))
    };
    // The folder may not exist yet: its nearest existing ancestor says where it lies.
    let existing = abs.ancestors().find(|a| a.exists()).unwrap_or(&abs);
    let Ok(canonical) = existing.canonicalize() else {
        return false;
    };
    let rest = abs
        .strip_prefix(existing)
        .unwrap_or(std::path::Path::new(""));
    let full = canonical.join(rest);
    let Ok(rel) = full.strip_prefix(checkout_root()) else {
        return false;
    };
    let probe = rel.join("result.json");
    // `git check-ignore` exits 0 when ignored, 1 when not, 128 outside a repository.
    std::process::Command::new("git")
        .args(["check-ignore", "-q", "--"])
        .arg(&probe)
        .current_dir(checkout_root())
        .status()
        .is_ok_and(|s| s.code() == Some(1))
}

/// CPU model from /proc/cpuinfo (Linux), else the architecture.
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_owned())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_owned())
}

/// Runs git in the checkout the binary was built in, not [`checkout_root`]: a binary
/// moved to another checkout must not name that one's commit as its own (where the
/// build checkout is gone, [`SOURCE_COMMIT_ENV`] names it).
fn git_bytes(args: &[&str]) -> Option<Vec<u8>> {
    let out = std::process::Command::new("git")
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .ok()?;
    out.status.success().then_some(out.stdout)
}

fn git(args: &[&str]) -> Option<String> {
    git_bytes(args).map(|b| String::from_utf8_lossy(&b).trim().to_owned())
}

/// The pathspec of the source: the whole checkout but `results/`.
const SOURCE_PATHSPEC: [&str; 3] = ["--", ":(top)", ":(top,exclude)results"];

/// Names the commit of a source tree that is no git checkout (a clean commit's files
/// copied to a machine with a GPU): read only where git cannot read the tree, and
/// taken only as 40 hex digits.
pub const SOURCE_COMMIT_ENV: &str = "CAUSTICS_SOURCE_COMMIT";

fn declared_commit() -> Option<String> {
    std::env::var(SOURCE_COMMIT_ENV)
        .ok()
        .map(|c| c.trim().to_ascii_lowercase())
        .filter(|c| c.len() == 40 && c.bytes().all(|b| b.is_ascii_hexdigit()))
}

/// The commit and dirtiness of the source tree, read once per process, when first
/// asked: every run of one `reproduce` names the same build, the tree as the command
/// found it. Read per run, a commit or an edit made in the build checkout while a long
/// reproduction ran was recorded as the build of the runs made after it, though the
/// binary stayed the same (a `reproduce all` of 3173a72's binary: 17 of all-methods'
/// 92 runs and ci-smoke's 46 called themselves dirty with the diff of an edit made
/// beside it, and extended-lights' runs after that edit's commit named the new commit).
/// Changes under `results/` do not make a build dirty: they are what runs write, not
/// what they run (a reproduction committed beside others would otherwise call itself
/// dirty).
pub fn build() -> Build {
    static BUILD: std::sync::OnceLock<Build> = std::sync::OnceLock::new();
    BUILD.get_or_init(read_build).clone()
}

fn read_build() -> Build {
    let commit = git(&["rev-parse", "HEAD"])
        .or_else(declared_commit)
        .unwrap_or_else(|| "unknown".into());
    let status = [
        &["status", "--porcelain", "--untracked-files=no"][..],
        &SOURCE_PATHSPEC,
    ]
    .concat();
    let dirty = git(&status).is_some_and(|s| !s.is_empty());
    let diff_hash = dirty
        .then(|| git_bytes(&[&["diff", "HEAD", "--binary"][..], &SOURCE_PATHSPEC].concat()))
        .flatten()
        .map(|diff| crate::experiment::fnv_hex(&diff));
    Build {
        commit,
        dirty,
        diff_hash,
        version: env!("CARGO_PKG_VERSION").to_owned(),
        profile: if cfg!(debug_assertions) {
            "debug".into()
        } else {
            "release".into()
        },
    }
}

/// Machine facts for an adapter.
pub fn machine(adapter: &caustics_gpu::AdapterSummary) -> Machine {
    Machine {
        adapter: adapter.name.clone(),
        backend: adapter.backend.clone(),
        device_type: adapter.device_type.clone(),
        driver: adapter.driver.clone(),
        driver_info: adapter.driver_info.clone(),
        cpu: cpu_model(),
        cpu_threads: std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1),
        os: format!("{} {}", std::env::consts::OS, std::env::consts::ARCH),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_inside_the_checkout_are_named_relative_to_it() {
        let ring = checkout_root().join("scenes").join("ring.json");
        assert_eq!(portable_path(&ring), "scenes/ring.json");
        assert_eq!(portable_path(&checkout_root()), ".");
        let elsewhere = std::path::Path::new("/nonexistent/scene.json");
        assert_eq!(portable_path(elsewhere), "/nonexistent/scene.json");
    }

    #[test]
    fn committed_folders_are_the_ones_git_does_not_ignore() {
        let root = checkout_root();
        if !root.join(".git").exists() {
            // A source tarball without git: nothing is committed.
            assert!(!is_committed_path(&root.join("results/reproduce")));
            return;
        }
        assert!(is_committed_path(&root.join("results/reproduce/x")));
        assert!(is_committed_path(&root.join("results/baselines")));
        assert!(!is_committed_path(&root.join("results/runs/x")));
        assert!(!is_committed_path(&root.join("target/ci-smoke")));
        assert!(!is_committed_path(std::path::Path::new("/nonexistent/out")));
    }
}
