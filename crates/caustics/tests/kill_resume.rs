//! `caustics reproduce` killed with SIGKILL at several points (issue 18, point 4): every
//! file it leaves is whole, the same command again resumes (complete runs kept, the rest
//! redone) and ends equal to an uninterrupted run (`caustics compare --no-timings` exits
//! 0, the same files), with no temporary left anywhere. Also: `compare`, `merge` and
//! `report` never change their inputs.
//!
//! Runs the built binary as a child on lavapipe: three 24×18 wavefront runs with one
//! frame, no warm-up and a 1×1 scoring grid, and a 1M-photon reference (a few tenths of a
//! second, wide enough to be killed inside). Takes a few seconds in the debug build.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

const EXPERIMENT: &str = r#"{
  "name": "killme",
  "description": "kill -9 test: three tiny wavefront runs",
  "resolution": {"width": 24, "height": 18},
  "frames": 1, "warmup": 0, "score_grid": 1,
  "reference": {"photons": 1000000, "seed": 1, "batches": 4},
  "runs": [{"scenes": ["sphere_on_plane"], "methods": ["wavefront"],
            "params": {"grid": [32, 48, 64]}}]
}"#;

const RUNS: [&str; 3] = ["grid=32", "grid=48", "grid=64"];

struct Setup {
    _tmp: tempfile::TempDir,
    root: PathBuf,
}

impl Setup {
    fn new() -> Setup {
        let tmp = tempfile::tempdir().expect("tempdir");
        let root = tmp.path().to_path_buf();
        std::fs::create_dir_all(root.join("experiments")).expect("mkdir");
        std::fs::write(root.join("experiments/killme.json"), EXPERIMENT).expect("write");
        Setup { _tmp: tmp, root }
    }
    fn reproduce(&self, out: &str, extra: &[&str]) -> Command {
        let mut c = Command::new(env!("CARGO_BIN_EXE_caustics"));
        c.current_dir(&self.root)
            .args([
                "reproduce",
                "killme",
                "--experiments",
                "experiments",
                "--references",
                "refs",
                "--out",
                out,
            ])
            .args(extra)
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        c
    }
    fn run_dir(&self, out: &str, run: &str) -> PathBuf {
        self.root
            .join(out)
            .join("killme/runs")
            .join(run)
            .join("sphere_on_plane/wavefront")
    }
}

fn finish(c: &mut Command) -> Output {
    let o = c.output().expect("spawn caustics");
    assert!(
        o.status.success(),
        "reproduce failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// Starts `c`, waits until `point` holds (polling every millisecond), then SIGKILLs it.
/// Returns whether the child was still running when killed (false: it ended first).
fn kill_when(c: &mut Command, what: &str, point: impl Fn() -> bool) -> bool {
    let mut child: Child = c.stderr(Stdio::null()).spawn().expect("spawn caustics");
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().expect("wait") {
            eprintln!("kill point {what:?}: the child ended first ({status})");
            return false;
        }
        if point() {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "kill point {what:?} never came"
        );
        std::thread::sleep(Duration::from_millis(1));
    }
    child.kill().expect("SIGKILL");
    let status = child.wait().expect("wait");
    eprintln!(
        "kill point {what:?}: killed after {:.0} ms ({status})",
        start.elapsed().as_secs_f64() * 1e3
    );
    true
}

fn is_temp(name: &str) -> bool {
    name.starts_with('.') && name.contains(".tmp-")
}

/// Every file under `root`, relative, with its bytes.
fn tree(root: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p
                    .strip_prefix(root)
                    .expect("under root")
                    .display()
                    .to_string();
                out.insert(rel, std::fs::read(&p).expect("read"));
            }
        }
    }
    out
}

/// Every file a killed reproduce left is whole: JSON parses, PNG and EXR decode; only
/// atomic_write's temporaries (hidden, never read) and the lock may be partial.
fn assert_whole(root: &Path) {
    for (rel, bytes) in tree(root) {
        let name = Path::new(&rel)
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if is_temp(&name) || name == ".reproduce.lock" {
            continue;
        }
        let p = root.join(&rel);
        let ok = match Path::new(&rel).extension().and_then(|e| e.to_str()) {
            Some("json") => serde_json::from_slice::<serde_json::Value>(&bytes).is_ok(),
            Some("png") => caustics_metrics::read_png(&p).is_ok(),
            Some("exr") => caustics_metrics::read_exr(&p).is_ok(),
            Some("md") => std::str::from_utf8(&bytes).is_ok(),
            _ => true,
        };
        assert!(ok, "{rel}: half-written");
    }
}

fn leftovers(root: &Path) -> Vec<String> {
    tree(root)
        .into_keys()
        .filter(|rel| {
            let n = Path::new(rel)
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            is_temp(&n) || n == ".reproduce.lock"
        })
        .collect()
}

fn compare(root: &Path, a: &str, b: &str) -> Output {
    Command::new(env!("CARGO_BIN_EXE_caustics"))
        .current_dir(root)
        .args(["compare", a, b, "--no-timings"])
        .output()
        .expect("compare")
}

#[test]
fn reproduce_killed_at_any_point_resumes_to_the_uninterrupted_result() {
    let started = Instant::now();
    let s = Setup::new();
    let out = s.root.join("a/killme");
    let reference_done = || {
        std::fs::read_dir(s.root.join("refs/sphere_on_plane"))
            .into_iter()
            .flatten()
            .flatten()
            .any(|e| e.path().join("meta.json").is_file())
    };
    let mut hits = 0;
    // 1. While the reference renders: 100 ms after the folder is locked (experiment
    //    loaded, references next).
    let locked = std::cell::Cell::new(None::<Instant>);
    if kill_when(&mut s.reproduce("a", &[]), "reference rendering", || {
        if locked.get().is_none() && out.join(".reproduce.lock").is_file() {
            locked.set(Some(Instant::now()));
        }
        locked
            .get()
            .is_some_and(|t| t.elapsed() > Duration::from_millis(100))
    }) {
        hits += 1;
        eprintln!("  reference finished before the kill: {}", reference_done());
    }
    assert_whole(&s.root);
    // 2. After the first run folder is complete (during the second run).
    let first = s.run_dir("a", RUNS[0]).join("result.json");
    hits += kill_when(&mut s.reproduce("a", &[]), "first run complete", || {
        first.is_file()
    }) as usize;
    assert_whole(&s.root);
    assert!(
        !out.join("manifest.json").exists(),
        "a killed reproduction has no manifest"
    );
    // 3. Inside a run folder being written (some image there, no result.json yet).
    let last = s.run_dir("a", RUNS[2]);
    hits += kill_when(&mut s.reproduce("a", &[]), "run folder half made", || {
        last.is_dir() && !last.join("result.json").exists()
    }) as usize;
    assert_whole(&s.root);
    // 4. While the summary is written (plots or summary there, no manifest yet).
    hits += kill_when(&mut s.reproduce("a", &[]), "summary", || {
        (out.join("plots").is_dir() || out.join("summary.json").is_file())
            && !out.join("manifest.json").exists()
    }) as usize;
    assert_whole(&s.root);
    assert!(hits >= 2, "only {hits} of 4 kills hit a running reproduce");
    assert!(
        reference_done(),
        "the reference was rendered by some attempt"
    );

    // Resumed to the end.
    let resumed = finish(&mut s.reproduce("a", &[]));
    let err = String::from_utf8_lossy(&resumed.stderr);
    eprintln!("resumed: {}", err.lines().last().unwrap_or(""));
    assert!(out.join("manifest.json").is_file());
    // EXRs only with --keep-exr (the timed frame's too).
    let exrs: Vec<String> = tree(&out)
        .into_keys()
        .filter(|k| k.ends_with(".exr"))
        .collect();
    assert!(exrs.is_empty(), "{exrs:?}");
    // The uninterrupted run (the same reference cache, now complete).
    finish(&mut s.reproduce("b", &[]));
    let (ta, tb) = (tree(&out), tree(&s.root.join("b/killme")));
    assert_eq!(
        ta.keys().collect::<Vec<_>>(),
        tb.keys().collect::<Vec<_>>(),
        "the resumed folder holds other files than the uninterrupted one"
    );
    let c = compare(&s.root, "a/killme", "b/killme");
    assert_eq!(
        c.status.code(),
        Some(0),
        "{}{}",
        String::from_utf8_lossy(&c.stdout),
        String::from_utf8_lossy(&c.stderr)
    );
    assert!(
        leftovers(&s.root).is_empty(),
        "left behind: {:?}",
        leftovers(&s.root)
    );

    // Again: every run is complete and kept, byte for byte.
    let again = finish(&mut s.reproduce("a", &[]));
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(err.contains("kept 3 complete runs"), "{err}");
    for r in RUNS {
        let p = format!("runs/{r}/sphere_on_plane/wavefront/result.json");
        assert_eq!(ta[&p], tree(&out)[&p], "{p} was redone");
    }
    // A result made from other inputs is redone, and said so.
    let tampered = s.run_dir("a", RUNS[1]).join("result.json");
    let mut v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&tampered).expect("read")).expect("json");
    v["frames"]["measured"] = serde_json::json!(7);
    std::fs::write(&tampered, serde_json::to_vec_pretty(&v).expect("json")).expect("write");
    let again = finish(&mut s.reproduce("a", &[]));
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(
        err.contains("redoing sphere_on_plane/wavefront/grid=48")
            && err.contains("frames.measured is 7")
            && err.contains("kept 2 complete runs"),
        "{err}"
    );
    // --fresh redoes everything.
    let fresh = finish(&mut s.reproduce("a", &["--fresh"]));
    assert!(!String::from_utf8_lossy(&fresh.stderr).contains("kept"));
    let c = compare(&s.root, "a/killme", "b/killme");
    assert_eq!(c.status.code(), Some(0));
    assert!(leftovers(&s.root).is_empty());
    eprintln!("took {:.1} s", started.elapsed().as_secs_f64());
}

/// Hashes (here: the bytes) of every file under `root` but `except`.
fn snapshot(root: &Path, except: &[&str]) -> BTreeMap<String, Vec<u8>> {
    let mut t = tree(root);
    t.retain(|k, _| !except.iter().any(|e| k.starts_with(e)));
    t
}

#[test]
fn compare_merge_and_report_never_change_their_inputs() {
    let s = Setup::new();
    finish(&mut s.reproduce("whole", &[]));
    finish(&mut s.reproduce("s1", &["--shard", "1/2"]));
    finish(&mut s.reproduce("s2", &["--shard", "2/2"]));
    let before = snapshot(&s.root, &[]);
    let bin = env!("CARGO_BIN_EXE_caustics");
    let run = |args: &[&str]| {
        let o = Command::new(bin)
            .current_dir(&s.root)
            .args(args)
            .output()
            .expect("caustics");
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    };
    run(&["compare", "s1/killme", "whole/killme", "--no-timings"]);
    run(&[
        "merge",
        "s1/killme",
        "s2/killme",
        "--out",
        "merged",
        "--experiments",
        "experiments",
    ]);
    run(&["report", "whole", "--out", "report"]);
    run(&["compare", "whole/killme", "merged", "--no-timings"]);
    let after = snapshot(&s.root, &["merged", "report"]);
    assert_eq!(
        before.keys().collect::<Vec<_>>(),
        after.keys().collect::<Vec<_>>()
    );
    for (k, v) in &before {
        assert!(after[k] == *v, "{k} changed");
    }
    // The report's default output, DIR/report, is the only thing added inside DIR.
    run(&["report", "whole"]);
    let after = snapshot(&s.root, &["merged", "report", "whole/report"]);
    assert!(before == after, "report changed an experiment folder");
    // An interrupted merge (its manifest, written last, missing) is merged again.
    std::fs::remove_file(s.root.join("merged/manifest.json")).expect("rm");
    run(&[
        "merge",
        "s1/killme",
        "s2/killme",
        "--out",
        "merged",
        "--experiments",
        "experiments",
    ]);
    assert!(s.root.join("merged/manifest.json").is_file());
}
