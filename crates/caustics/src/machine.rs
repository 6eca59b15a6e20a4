//! Facts about the machine and the build, for result files.

use serde::{Deserialize, Serialize};

/// Where and with what a run was made.
#[derive(Clone, Debug, Serialize, Deserialize)]
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
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Build {
    /// `git rev-parse HEAD` of the working tree, or "unknown".
    pub commit: String,
    /// Whether the tree had uncommitted changes.
    pub dirty: bool,
    /// Crate version.
    pub version: String,
    /// "release" or "debug": only release timings are reportable.
    pub profile: String,
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

fn git(args: &[&str]) -> Option<String> {
    let out = std::process::Command::new("git")
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_owned())
}

/// The commit and dirtiness of the source tree, read at run time. Changes under
/// `results/` do not make a build dirty: they are what runs write, not what they run
/// (a reproduction committed beside others would otherwise call itself dirty).
pub fn build() -> Build {
    let commit = git(&["rev-parse", "HEAD"]).unwrap_or_else(|| "unknown".into());
    let dirty = git(&[
        "status",
        "--porcelain",
        "--untracked-files=no",
        "--",
        ":(top)",
        ":(top,exclude)results",
    ])
    .is_some_and(|s| !s.is_empty());
    Build {
        commit,
        dirty,
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
