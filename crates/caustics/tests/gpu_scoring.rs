//! The scoring frame through `caustics run`: every method gives the same image for the
//! same sub-pixel offset whatever it rendered before (so one offset at the pixel centre
//! repeats the timed frame bit for bit), and a scored run stores the pixel-averaged and
//! the 1-spp errors side by side. Runs on lavapipe on CI; without an adapter it fails
//! with the install hint.

mod common;

use caustics::reference_cmd::{ReferenceArgs, reference};
use caustics::result::RunResult;
use caustics_metrics::read_exr;
use common::{run_dir, run_options, small_scene};

#[test]
fn every_method_repeats_its_timed_frame_at_the_pixel_centre() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let scenes = ["sphere_on_plane", "fog_sphere"].map(|s| small_scene(tmp.path(), s, 32, 24));
    for info in caustics::registry::methods() {
        // The first of the two scenes the method renders (fog_sphere has volume caustics).
        let Some(scene) = scenes.iter().find(|p| {
            let scene = caustics_scene::Scene::load(p).expect("scene");
            let defaults = (info.parse)(&serde_json::Value::Null).expect("defaults parse");
            info.supports(&scene, &defaults).is_ok()
        }) else {
            panic!(
                "{} renders neither sphere_on_plane nor fog_sphere",
                info.name
            );
        };
        let mut o = run_options(scene, &tmp.path().join("runs"), info.name, &[]);
        (o.warmup, o.frames, o.score_grid) = (1, 2, 1);
        let (dir, result) = run_dir(&o);
        let scoring = result.scoring.as_ref().expect("scoring info");
        assert_eq!((scoring.grid, scoring.samples_per_pixel), (1, 1));
        let mut images = vec!["surface"];
        if info.capabilities.volume {
            images.push("volume");
        }
        for image in images {
            let scored = read_exr(&dir.join(format!("{image}.exr"))).expect("scored image");
            let timed = read_exr(&dir.join(format!("{image}_1spp.exr"))).expect("timed image");
            assert!(
                scored.pixels == timed.pixels,
                "{}: the {image} image of the scoring frame at the pixel centre differs from the timed frame's",
                info.name
            );
        }
    }
}

#[test]
fn a_scored_run_keeps_pixel_averaged_and_1spp_errors_side_by_side() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let scene = small_scene(tmp.path(), "sphere_on_plane", 48, 36);
    let references = tmp.path().join("references");
    reference(&ReferenceArgs {
        scene: Some(scene.display().to_string()),
        photons: Some(1 << 20),
        time: None,
        out: None,
        references: references.clone(),
        seed: 1,
        batches: 4,
        direct: false,
        bench: false,
    })
    .expect("reference");
    let mut o = run_options(&scene, &tmp.path().join("runs"), "wavefront", &[]);
    (o.score_grid, o.exposure, o.references) = (2, None, references);
    let (dir, result) = run_dir(&o);
    assert_eq!(result.schema_version, caustics::result::SCHEMA_VERSION);
    let scoring = result.scoring.as_ref().expect("scoring info");
    assert_eq!((scoring.grid, scoring.samples_per_pixel), (2, 4));
    assert_eq!(result.tone_map.source.as_deref(), Some("reference p99"));
    let (scored, timed) = (
        result.errors.as_ref().expect("pixel-averaged errors"),
        result.errors_1spp.as_ref().expect("1-spp errors"),
    );
    for e in [&scored.surface, &timed.surface] {
        let flux = e.flux_ratio.expect("flux ratio");
        assert!((0.5..2.0).contains(&flux), "flux ratio {flux}");
        assert!(e.hdr_flip.is_some() && e.rel_mse_after_flux.is_some());
    }
    assert!(
        scored.surface != timed.surface,
        "4 offsets and 1 scored the same"
    );

    // A version-1 file (errors scored at 1 spp) reads with its errors moved to
    // errors_1spp, so it is never compared with pixel-averaged errors.
    let text = std::fs::read_to_string(dir.join("result.json")).expect("result.json");
    let mut v1: serde_json::Value = serde_json::from_str(&text).expect("json");
    v1["schema_version"] = 1.into();
    let obj = v1.as_object_mut().expect("object");
    obj.remove("errors_1spp");
    obj.remove("scoring");
    let old = RunResult::from_json(&v1.to_string()).expect("version-1 file");
    assert!(old.errors.is_none());
    assert_eq!(
        old.errors_1spp.as_ref().map(|e| e.surface),
        Some(scored.surface)
    );
}
