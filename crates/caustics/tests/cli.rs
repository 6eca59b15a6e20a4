//! The `caustics` binary's handling of bad input: clear message, non-zero exit, and
//! nothing already written is touched.

use std::path::Path;
use std::process::Command;

mod common;
use common::{caustics, stderr};

/// An output folder holding an earlier `result.json` for `<scene>/<method>`.
fn earlier_result(out: &Path, scene: &str, method: &str) -> std::path::PathBuf {
    let dir = out.join(scene).join(method);
    std::fs::create_dir_all(&dir).expect("mkdir");
    let file = dir.join("result.json");
    std::fs::write(&file, b"{\"earlier\": true}").expect("write");
    file
}

fn assert_untouched(file: &Path) {
    assert_eq!(
        std::fs::read(file).expect("read"),
        b"{\"earlier\": true}",
        "{} was modified",
        file.display()
    );
    let dir = file.parent().expect("parent");
    let entries: Vec<_> = std::fs::read_dir(dir)
        .expect("read_dir")
        .map(|e| e.expect("entry").file_name())
        .collect();
    assert_eq!(entries.len(), 1, "unexpected files written: {entries:?}");
}

#[test]
fn bad_scene_path_fails_clearly_and_keeps_results() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().to_str().expect("utf-8");
    let earlier = earlier_result(tmp.path(), "water_pool", "wavefront");
    let o = caustics(&[
        "run",
        "--scene",
        "no/such/scene.json",
        "--method",
        "wavefront",
        "--out",
        out,
    ]);
    assert!(!o.status.success());
    assert_ne!(
        o.status.code(),
        Some(3),
        "a missing scene is an error, not a skip"
    );
    assert!(stderr(&o).contains("no/such/scene.json"), "{}", stderr(&o));
    let o = caustics(&[
        "run",
        "--scene",
        "no_such_builtin",
        "--method",
        "wavefront",
        "--out",
        out,
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("water_pool"),
        "unknown scene should list the built-ins: {}",
        stderr(&o)
    );
    assert_untouched(&earlier);
}

#[test]
fn unknown_method_fails_listing_the_known_ones_and_keeps_results() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().to_str().expect("utf-8");
    let earlier = earlier_result(tmp.path(), "water_pool", "wavefrnt");
    let o = caustics(&[
        "run",
        "--scene",
        "water_pool",
        "--method",
        "wavefrnt",
        "--out",
        out,
    ]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("unknown method \"wavefrnt\"") && e.contains("wavefront"),
        "{e}"
    );
    assert_untouched(&earlier);
}

#[test]
fn bad_parameters_and_flags_fail_before_any_work() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().to_str().expect("utf-8");
    let earlier = earlier_result(tmp.path(), "water_pool", "wavefront");
    for (args, needle) in [
        (vec!["--param", "grid=1"], "grid"),
        (vec!["--param", "gird=64"], "known parameters"),
        (vec!["--param", "grid"], "key=value"),
        (vec!["--frames", "0"], "--frames"),
        (vec!["--exposure=-1"], "--exposure"),
        (vec!["--reference", "missing.exr"], "missing.exr"),
    ] {
        let mut all = vec![
            "run",
            "--scene",
            "water_pool",
            "--method",
            "wavefront",
            "--out",
            out,
        ];
        all.extend(args.iter());
        let o = caustics(&all);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(stderr(&o).contains(needle), "{args:?}: {}", stderr(&o));
    }
    assert_untouched(&earlier);
}

#[test]
fn unsupported_scene_is_skipped_with_reason_and_exit_code_3() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().to_str().expect("utf-8");
    let o = caustics(&[
        "run",
        "--scene",
        "fog_sphere",
        "--method",
        "wavefront",
        "--out",
        out,
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("skipped") && stderr(&o).contains("medium"),
        "{}",
        stderr(&o)
    );
    assert!(
        std::fs::read_dir(tmp.path())
            .expect("read_dir")
            .next()
            .is_none(),
        "a skipped run wrote files"
    );
}

#[test]
fn list_shows_every_builtin_scene_and_method_defaults() {
    let o = caustics(&["list"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = String::from_utf8_lossy(&o.stdout);
    for name in caustics_scene::builtin_names() {
        assert!(s.contains(&name), "{name} missing from list");
    }
    assert!(
        s.contains("wavefront") && s.contains("--param grid=512"),
        "{s}"
    );
    // Each method's counters, with what they count (families once, as `_N`).
    for counter in [
        "counter beams: ",
        "counter beams_level_N: ",
        "counter photon_hits: ",
        "counter triangles_kept: ",
        "counter kernel_px: ",
        "counter sample_pixel_pairs: ",
        "counter vertices_landed: ",
    ] {
        assert!(s.contains(counter), "{counter:?} missing from list:\n{s}");
    }
    assert!(
        !s.contains("does not load"),
        "a built-in scene does not load:\n{s}"
    );
}

/// A binary run away from the checkout it was built in (copied to a machine with a
/// GPU, installed) reads the scenes of the checkout `CAUSTICS_ROOT` names; where that
/// holds none, an unknown scene's error says where it looked and what to set.
#[test]
fn caustics_root_names_the_checkout_of_a_moved_binary() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let root = tmp.path().join("checkout");
    std::fs::create_dir_all(root.join("scenes")).expect("scenes");
    std::fs::copy(
        caustics_scene::resolve("ring").expect("ring"),
        root.join("scenes").join("only_here.json"),
    )
    .expect("copy ring");
    let o = Command::new(env!("CARGO_BIN_EXE_caustics"))
        .arg("list")
        .env(caustics_scene::ROOT_ENV, &root)
        .output()
        .expect("run caustics");
    assert!(o.status.success(), "{}", stderr(&o));
    let listed = String::from_utf8_lossy(&o.stdout);
    assert!(
        listed.contains("only_here") && !listed.contains("water_pool"),
        "{listed}"
    );

    let empty = tmp.path().join("no-checkout");
    std::fs::create_dir_all(&empty).expect("empty");
    let o = Command::new(env!("CARGO_BIN_EXE_caustics"))
        .args(["run", "--scene", "water_pool", "--method", "wavefront"])
        .env(caustics_scene::ROOT_ENV, &empty)
        .output()
        .expect("run caustics");
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains("no built-in scenes in")
            && err.contains(&empty.join("scenes").display().to_string())
            && err.contains(caustics_scene::ROOT_ENV),
        "{err}"
    );
}

/// A mesh over a scene limit is refused naming the flag that raises it, by `run` and
/// by `reference`, before anything is written; the same flag raised lets it load.
#[test]
fn mesh_limits_are_flags_and_the_refusal_names_them() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("runs");
    let out_s = out.display().to_string();
    let o = caustics(&[
        "run",
        "--scene",
        "bumpy_glass",
        "--method",
        "wavefront",
        "--out",
        &out_s,
        "--max-scene-triangles",
        "10",
    ]);
    assert!(
        !o.status.success(),
        "a 10-triangle limit must refuse bumpy_glass"
    );
    let e = stderr(&o);
    assert!(
        e.contains("more than the limit of 10") && e.contains("--max-scene-triangles"),
        "{e}"
    );
    assert!(!out.exists(), "nothing may be written");
    let refs = tmp.path().join("refs").display().to_string();
    let o = caustics(&[
        "reference",
        "--scene",
        "bumpy_glass",
        "--photons",
        "1000",
        "--references",
        &refs,
        "--max-mesh-triangles",
        "10",
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("--max-mesh-triangles"),
        "{}",
        stderr(&o)
    );
    // Raised above the mesh's size, the scene loads and the reference renders.
    let o = caustics(&[
        "reference",
        "--scene",
        "bumpy_glass",
        "--photons",
        "1000",
        "--references",
        &refs,
        "--max-mesh-triangles",
        "100000000",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// `caustics list | head -1`: a reader that closes the pipe early is not a panic.
#[test]
fn a_closed_stdout_is_not_a_panic() {
    for args in [&["list"][..], &["schema", "result"]] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_caustics"))
            .args(args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("spawn");
        // The reading end closed before the first write: every write meets a broken pipe.
        drop(child.stdout.take());
        let o = child.wait_with_output().expect("wait");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert_eq!(o.status.code(), Some(0), "{args:?}: {err}");
    }
}

/// Requests past what the device can hold are refused before anything large is made,
/// naming the limit and what to lower: a camera image past the device's texture side
/// or the memory budget (`CAUSTICS_GPU_MEMORY_MIB`, set low here so that the test
/// needs no large device), a beam buffer and photon hit images past its largest storage
/// binding (lavapipe: 128 MiB), a budget that is not a number of MiB. Nothing is written.
#[test]
fn requests_past_the_devices_limits_are_refused_before_allocating() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("runs");
    let out_s = out.display().to_string();
    let scene = tmp.path().join("huge.json");
    let mut doc: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/ring.json"),
        )
        .expect("ring.json"),
    )
    .expect("json");
    doc["camera"]["width"] = 16384.into();
    doc["camera"]["height"] = 12288.into();
    std::fs::write(&scene, doc.to_string()).expect("write scene");
    let scene_s = scene.display().to_string();
    let run = |args: &[&str], budget_mib: Option<&str>| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_caustics"));
        c.args(["run", "--out", &out_s, "--frames", "1", "--warmup", "0"])
            .args(["--quick-reference-photons", "0"])
            .args(args);
        if let Some(b) = budget_mib {
            c.env("CAUSTICS_GPU_MEMORY_MIB", b);
        }
        let start = std::time::Instant::now();
        let o = c.output().expect("run caustics");
        (o, start.elapsed())
    };
    for (args, budget, needles) in [
        (
            vec!["--scene", scene_s.as_str(), "--method", "static-grid"],
            None,
            vec!["camera.width", "16384x12288", "lower camera.width"],
        ),
        (
            vec![
                "--scene",
                "ring",
                "--method",
                "static-grid",
                "--param",
                "max_beams=4194240",
            ],
            None,
            vec!["max_beams", "max_storage_buffer_binding_size", "at most"],
        ),
        (
            vec![
                "--scene",
                "sphere_on_plane",
                "--method",
                "splatting",
                "--param",
                "resolution=1024",
                "--param",
                "bounces=4",
                "--param",
                "reflections=true",
            ],
            None,
            vec!["resolution", "sheet(s)", "max_storage_buffer_binding_size"],
        ),
        (
            vec!["--scene", "ring", "--method", "static-grid"],
            Some("32"),
            vec![
                "camera-sized targets",
                "CAUSTICS_GPU_MEMORY_MIB",
                "32.00 MiB",
            ],
        ),
        (
            vec!["--scene", "ring", "--method", "static-grid"],
            Some("0"),
            vec!["CAUSTICS_GPU_MEMORY_MIB=\"0\"", "whole number of MiB"],
        ),
    ] {
        let (o, took) = run(&args, budget);
        let e = stderr(&o);
        assert!(!o.status.success(), "{args:?} succeeded");
        for n in needles {
            assert!(e.contains(n), "{args:?}: {n:?} missing from: {e}");
        }
        assert!(
            took < std::time::Duration::from_secs(30),
            "{args:?} took {took:?} to be refused"
        );
    }
    assert!(!out.exists(), "nothing may be written");
}
