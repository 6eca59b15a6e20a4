//! EXR and PNG round trips and the atomic-write guarantees.

mod common;

use std::fs;
use std::io::Write;
use std::path::Path;

use caustics_metrics::{
    HdrImage, MetricsError, Rgb8Image, atomic_write, atomic_write_with, read_exr, read_png,
    write_exr, write_png,
};

/// Names in `dir` that look like our temporary files.
fn temp_files(dir: &Path) -> Vec<String> {
    fs::read_dir(dir)
        .expect("read_dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp-"))
        .collect()
}

#[test]
fn exr_round_trip_is_bit_exact() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("img.exr");
    let mut img = common::structured(37, 23); // odd sizes: no tile alignment by luck
    img.set(0, 0, [0.1, 1e-30, -3.5]); // -3.5: negative values survive
    img.set(36, 22, [f32::MIN_POSITIVE / 4.0, 65_504.0 * 8.0, 1.0e20]); // subnormal, > f16
    img.set(5, 7, [f32::MAX, 0.0, -0.0]);
    write_exr(&path, &img).expect("write_exr");
    let back = read_exr(&path).expect("read_exr");
    assert_eq!((back.width, back.height), (37, 23));
    for (i, (a, b)) in img.pixels.iter().zip(&back.pixels).enumerate() {
        assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits), "pixel {i}");
    }
    assert!(temp_files(dir.path()).is_empty());
}

#[test]
fn exr_errors_name_the_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let missing = dir.path().join("missing.exr");
    match read_exr(&missing) {
        Err(e @ MetricsError::Io { .. }) => assert!(e.to_string().contains("missing.exr")),
        other => panic!("expected Io error, got {other:?}"),
    }
    let garbage = dir.path().join("garbage.exr");
    fs::write(&garbage, b"this is not an exr file").expect("write");
    match read_exr(&garbage) {
        Err(e @ MetricsError::Exr { .. }) => assert!(e.to_string().contains("garbage.exr")),
        other => panic!("expected Exr error, got {other:?}"),
    }
}

#[test]
fn png_round_trip() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("img.png");
    let mut img = Rgb8Image::new(13, 5);
    for (i, p) in img.pixels.iter_mut().enumerate() {
        *p = [(i * 7) as u8, (i * 13 + 1) as u8, (255 - i) as u8];
    }
    write_png(&path, &img).expect("write_png");
    assert_eq!(read_png(&path).expect("read_png"), img);
    assert!(temp_files(dir.path()).is_empty());

    let bad = dir.path().join("bad.png");
    fs::write(&bad, b"nope").expect("write");
    match read_png(&bad) {
        Err(e @ MetricsError::Png { .. }) => assert!(e.to_string().contains("bad.png")),
        other => panic!("expected Png error, got {other:?}"),
    }
}

#[test]
fn atomic_write_replaces_content_and_leaves_no_temp_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("result.json");
    atomic_write(&path, b"first").expect("write 1");
    atomic_write(&path, b"second").expect("write 2");
    assert_eq!(fs::read(&path).expect("read"), b"second");
    let names: Vec<_> = fs::read_dir(dir.path())
        .expect("read_dir")
        .map(|e| e.expect("entry").file_name())
        .collect();
    assert_eq!(names, ["result.json"]);
}

#[test]
fn failed_write_keeps_the_old_file_and_cleans_up() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("result.json");
    fs::write(&path, b"old").expect("seed");
    let err = atomic_write_with(&path, |f| {
        f.write_all(b"partial new con")?;
        Err(std::io::Error::other("simulated failure mid-write"))
    })
    .expect_err("must fail");
    assert!(err.to_string().contains("simulated failure"), "{err}");
    assert_eq!(fs::read(&path).expect("read"), b"old");
    assert!(
        temp_files(dir.path()).is_empty(),
        "{:?}",
        temp_files(dir.path())
    );
}

#[test]
fn write_into_a_path_whose_parent_is_a_file_fails_naming_it() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = dir.path().join("not_a_dir");
    fs::write(&file, b"keep me").expect("seed");
    let target = file.join("result.json");
    let err = atomic_write(&target, b"data").expect_err("must fail");
    assert!(matches!(err, MetricsError::Io { .. }));
    assert!(err.to_string().contains("not_a_dir"), "{err}");
    assert_eq!(fs::read(&file).expect("read"), b"keep me");
    // Same through the image writers.
    assert!(write_exr(&target.with_extension("exr"), &HdrImage::new(2, 2)).is_err());
    assert!(write_png(&target.with_extension("png"), &Rgb8Image::new(2, 2)).is_err());
    assert!(temp_files(dir.path()).is_empty());
}

#[test]
fn failed_rename_over_a_directory_cleans_up() {
    let dir = tempfile::tempdir().expect("tempdir");
    let target = dir.path().join("occupied");
    fs::create_dir(&target).expect("mkdir");
    fs::write(target.join("inside"), b"x").expect("seed");
    let err = atomic_write(&target, b"data").expect_err("rename over a directory must fail");
    assert!(err.to_string().contains("occupied"), "{err}");
    assert_eq!(fs::read(target.join("inside")).expect("read"), b"x");
    assert!(
        temp_files(dir.path()).is_empty(),
        "{:?}",
        temp_files(dir.path())
    );
}

#[test]
fn from_rgba_f32_drops_alpha_and_checks_length() {
    let rgba = [1.0, 2.0, 3.0, 9.0, 4.0, 5.0, 6.0, 9.0];
    let img = HdrImage::from_rgba_f32(2, 1, &rgba).expect("from_rgba");
    assert_eq!(img.pixels, vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    assert_eq!(img.get(1, 0), [4.0, 5.0, 6.0]);
    assert!(matches!(
        HdrImage::from_rgba_f32(2, 2, &rgba),
        Err(MetricsError::BufferLength {
            expected: 16,
            actual: 8,
            ..
        })
    ));
}

#[test]
fn image_helpers() {
    let img = HdrImage {
        width: 2,
        height: 1,
        pixels: vec![[1.0, 2.0, 3.0], [3.0, 4.0, 5.0]],
    };
    assert_eq!(img.mean(), [2.0, 3.0, 4.0]);
    let y = caustics_metrics::luminance([1.0, 1.0, 1.0]);
    assert!((y - 1.0).abs() < 1e-6);
    let want = f64::from(caustics_metrics::luminance([1.0, 2.0, 3.0]))
        + f64::from(caustics_metrics::luminance([3.0, 4.0, 5.0]));
    assert!((img.sum_luminance() - want).abs() < 1e-9);
    let sum = img.add(&img.scaled(2.0)).expect("add");
    assert_eq!(sum.pixels, vec![[3.0, 6.0, 9.0], [9.0, 12.0, 15.0]]);
    assert!(matches!(
        img.add(&HdrImage::new(1, 2)),
        Err(MetricsError::SizeMismatch { .. })
    ));
    assert!(img.check_finite("x").is_ok());
    let mut bad = img.clone();
    bad.pixels[1][2] = f32::NAN;
    assert!(matches!(
        bad.check_finite("composite"),
        Err(MetricsError::NonFinite { ref image, x: 1, y: 0, .. }) if image == "composite"
    ));
}

#[test]
fn counts_png_round_trip_is_exact_past_16_bits() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = tmp.path().join("fill_counts.png");
    let counts: Vec<u32> = (0..12u32).map(|i| i * 5000 + i).collect();
    caustics_metrics::write_counts_png(&path, &counts, 4, 3).expect("write");
    let (back, w, h) = caustics_metrics::read_counts_png(&path).expect("read");
    assert_eq!((w, h), (4, 3));
    assert_eq!(back, counts);
    // Grey while every count fits 16 bits (the files committed before stay readable).
    let png = image::open(&path).expect("png");
    assert!(matches!(png, image::DynamicImage::ImageLuma16(_)));
    // Past 16 bits (66,272 fragments on a pixel under 16 lights): still exact.
    let big = [0, caustics_metrics::MAX_PNG_COUNT + 1, 66_272, u32::MAX];
    let big_path = tmp.path().join("big.png");
    caustics_metrics::write_counts_png(&big_path, &big, 2, 2).expect("write wide");
    let (back, w, h) = caustics_metrics::read_counts_png(&big_path).expect("read wide");
    assert_eq!((w, h), (2, 2));
    assert_eq!(back, big);
    // An 8-bit colour PNG is not a counts file.
    let rgb = caustics_metrics::Rgb8Image::new(2, 2);
    caustics_metrics::write_png(&tmp.path().join("rgb.png"), &rgb).expect("rgb");
    assert!(caustics_metrics::read_counts_png(&tmp.path().join("rgb.png")).is_err());
}
