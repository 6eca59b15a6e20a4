//! Hashes the sources of the CPU reference and of the scene crate it reads, so that a
//! cached reference (see `src/reference.rs`) is keyed by the code that rendered it: an
//! edited reference never meets a stale image under `target/`.

use std::path::{Path, PathBuf};

/// FNV-1a 64, the scene crate's content hash too.
fn fnv(hash: &mut u64, bytes: &[u8]) {
    for &b in bytes {
        *hash ^= u64::from(b);
        *hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
    }
}

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            files(&path, out);
        } else {
            out.push(path);
        }
    }
}

fn main() {
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let crates = manifest.parent().expect("crates/testing has a parent");
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for part in [
        "reference/src",
        "reference/Cargo.toml",
        "scene/src",
        "scene/Cargo.toml",
    ] {
        let path = crates.join(part);
        // A directory is scanned recursively for changes.
        println!("cargo:rerun-if-changed={}", path.display());
        let mut all = Vec::new();
        if path.is_dir() {
            files(&path, &mut all);
        } else {
            all.push(path);
        }
        all.sort();
        for file in all {
            let rel = file.strip_prefix(crates).unwrap_or(&file);
            fnv(&mut hash, rel.to_string_lossy().as_bytes());
            fnv(&mut hash, &std::fs::read(&file).unwrap_or_default());
        }
    }
    println!("cargo:rustc-env=CAUSTICS_TESTING_REFERENCE_CODE={hash:016x}");
}
