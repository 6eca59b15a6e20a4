//! Every `#[repr(C)]` struct in the workspace's crates is shared with the GPU, so every
//! one must have its layout checked against the WGSL struct it mirrors with
//! `caustics_gpu::assert_wgsl_layout!` (field names in order, offsets, size) in the crate
//! that owns it. This test finds the structs by reading the sources and fails for any
//! without a check, so a new struct cannot slip past (STYLE 13).

use std::path::{Path, PathBuf};

/// Structs checked another way, with where.
const CHECKED_ELSEWHERE: &[(&str, &str)] = &[(
    "SceneVertex",
    "a vertex buffer, not a WGSL struct: scene_upload.rs's `vertex_layout_matches_the_struct` \
     checks its attribute offsets",
)];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Names of the structs declared right after a `#[repr(C)]` line.
fn repr_c_structs(source: &str) -> Vec<String> {
    let lines: Vec<&str> = source.lines().collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        if line.trim() != "#[repr(C)]" {
            continue;
        }
        for next in lines.iter().skip(i + 1).take(4) {
            let t = next.trim();
            if let Some(rest) = t
                .strip_prefix("pub struct ")
                .or_else(|| t.strip_prefix("pub(crate) struct "))
                .or_else(|| t.strip_prefix("struct "))
            {
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                out.push(name);
                break;
            }
        }
    }
    out
}

/// Whether some `assert_wgsl_layout!(source, Name …` in `sources` names `name`.
fn has_layout_check(sources: &[String], name: &str) -> bool {
    sources.iter().any(|s| {
        s.match_indices("assert_wgsl_layout!(").any(|(at, _)| {
            let tail = &s[at..s.len().min(at + 600)];
            let end = tail.find("});").unwrap_or(tail.len());
            let call = &tail[..end];
            call.contains(&format!(", {name} {{"))
                || call.contains(&format!(", {name} as "))
                || call.contains(&format!(",\n{name} "))
                || call
                    .split_whitespace()
                    .any(|w| w.trim_start_matches(',') == name)
        })
    })
}

#[test]
fn every_repr_c_struct_has_a_wgsl_layout_check() {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut missing = Vec::new();
    let mut checked = 0;
    let mut dirs: Vec<_> = std::fs::read_dir(&crates)
        .expect("crates/ is readable")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.join("Cargo.toml").exists())
        .collect();
    dirs.sort();
    for dir in dirs {
        let mut files = Vec::new();
        rust_files(&dir.join("src"), &mut files);
        rust_files(&dir.join("tests"), &mut files);
        let sources: Vec<String> = files
            .iter()
            .map(|f| std::fs::read_to_string(f).unwrap_or_default())
            .collect();
        for (file, source) in files.iter().zip(&sources) {
            // The layout module's own tests declare deliberately wrong structs.
            if file.ends_with("gpu/src/layout.rs") || file.ends_with("tests/struct_layouts.rs") {
                continue;
            }
            for name in repr_c_structs(source) {
                if CHECKED_ELSEWHERE.iter().any(|(n, _)| *n == name) {
                    continue;
                }
                if has_layout_check(&sources, &name) {
                    checked += 1;
                } else {
                    missing.push(format!("{} ({})", name, file.display()));
                }
            }
        }
    }
    assert!(
        missing.is_empty(),
        "#[repr(C)] structs without an assert_wgsl_layout! check against their WGSL struct:\n  {}",
        missing.join("\n  ")
    );
    assert!(
        checked >= 20,
        "only {checked} structs found: is the scan broken?"
    );
}

#[test]
fn the_scan_finds_structs_and_checks() {
    let src = "#[repr(C)]\n#[derive(Clone, Copy)]\npub struct A {\n x: u32 }\n#[repr(C)]\nstruct B { y: f32 }";
    assert_eq!(repr_c_structs(src), ["A", "B"]);
    let check = "caustics_gpu::assert_wgsl_layout!(WGSL, A { x });".to_owned();
    assert!(has_layout_check(std::slice::from_ref(&check), "A"));
    assert!(!has_layout_check(&[check], "B"));
}
