//! The README's commands run as written: every `caustics …` command in its `sh` blocks
//! (as `cargo run … -- …` or on PATH) parses with the binary's own command line, names
//! scenes, methods, parameters and experiments that exist, and the ones that only read
//! committed files run here for real (`list`, `compare` of two committed folders).
//! Commands with placeholders (`<…>`, `$…`) are parsed only where they can be.

use std::path::{Path, PathBuf};
use std::process::Command;

use caustics::cli::{Cli, Command as Sub};
use clap::Parser;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The `caustics` argument lists of the README's `sh` blocks, with their line numbers
/// (comments stripped, `\` continuations joined).
fn readme_commands() -> Vec<(usize, Vec<String>)> {
    let text = std::fs::read_to_string(root().join("README.md")).expect("README.md");
    let mut out = Vec::new();
    let (mut in_sh, mut pending, mut start) = (false, String::new(), 0);
    for (i, line) in text.lines().enumerate() {
        if line.starts_with("```") {
            in_sh = line.trim() == "```sh";
            continue;
        }
        if !in_sh {
            continue;
        }
        if pending.is_empty() {
            start = i + 1;
        }
        let code = match line.find(" #") {
            Some(k) => &line[..k],
            None if line.trim_start().starts_with('#') => "",
            None => line,
        };
        if let Some(head) = code.trim_end().strip_suffix('\\') {
            pending.push_str(head);
            pending.push(' ');
            continue;
        }
        pending.push_str(code);
        let full = std::mem::take(&mut pending);
        let words: Vec<String> = full.split_whitespace().map(str::to_owned).collect();
        let args = match words.iter().position(|w| w == "--") {
            Some(k)
                if words.first().map(String::as_str) == Some("cargo")
                    && words.get(1).map(String::as_str) == Some("run") =>
            {
                words[k + 1..].to_vec()
            }
            _ if words.first().map(String::as_str) == Some("caustics") => words[1..].to_vec(),
            _ => continue,
        };
        out.push((start, args));
    }
    out
}

#[test]
fn every_readme_command_parses_and_names_what_exists() {
    let commands = readme_commands();
    assert!(
        commands.len() >= 15,
        "found only {} commands",
        commands.len()
    );
    let mut failures = Vec::new();
    for (line, args) in &commands {
        let text = args.join(" ");
        if text.contains('<') || text.contains('$') {
            continue;
        }
        let cli = match Cli::try_parse_from(
            std::iter::once("caustics".to_owned()).chain(args.iter().cloned()),
        ) {
            Ok(c) => c,
            Err(e) => {
                failures.push(format!("README.md:{line}: caustics {text}: {e}"));
                continue;
            }
        };
        let checked: anyhow::Result<()> = (|| {
            match &cli.command {
                Sub::Run(o) => {
                    caustics_scene::resolve(&o.scene)?;
                    let info = caustics::registry::find(&o.method)?;
                    let params = caustics::run::parse_param_flags(&o.params)?;
                    caustics::registry::parse_params(&info, &serde_json::Value::Object(params))?;
                }
                Sub::Reference(r) => {
                    if let Some(s) = &r.scene {
                        caustics_scene::resolve(s)?;
                    }
                }
                Sub::Reproduce(r) => {
                    caustics::experiment::resolve(&r.name, &caustics::experiment::builtin_dir())?;
                }
                _ => {}
            }
            Ok(())
        })();
        if let Err(e) = checked {
            failures.push(format!("README.md:{line}: caustics {text}: {e:#}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn the_readme_commands_that_read_committed_files_run() {
    let mut ran = 0;
    for (line, args) in readme_commands() {
        let reads_only = match args.first().map(String::as_str) {
            Some("list") => true,
            // A comparison of two committed folders (not one a README command makes).
            Some("compare") => args[1..]
                .iter()
                .filter(|a| !a.starts_with("--"))
                .all(|a| a.starts_with("results/") && root().join(a).is_dir()),
            _ => false,
        };
        if !reads_only {
            continue;
        }
        let o = Command::new(env!("CARGO_BIN_EXE_caustics"))
            .args(&args)
            .current_dir(root())
            .output()
            .expect("run caustics");
        assert_eq!(
            o.status.code(),
            Some(0),
            "README.md:{line}: caustics {}\n{}{}",
            args.join(" "),
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
        ran += 1;
    }
    assert!(ran >= 2, "ran {ran} README commands");
}
