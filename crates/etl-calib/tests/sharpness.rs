//! Sharpness against the reference: CPBD against the PyPI package `cpbd` 1.0.7 and the
//! simple measures against NumPy, on the images of fixtures/cpbd/ (natural images and
//! drawn boards at several blurs and noise levels; values in reference.json, written by
//! benches/cpbd_reference.py). Plus the bad inputs of the library and the CLI.

use std::path::{Path, PathBuf};
use std::process::Command;

use etl_calib::sharpness::{sharpness, sharpness_u16, Gray16Image, Metric};
use image::{GrayImage, Luma};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/cpbd")
}

fn reference() -> Vec<serde_json::Value> {
    let text = std::fs::read_to_string(fixtures().join("reference.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["images"].as_array().unwrap().clone()
}

fn load(file: &str) -> GrayImage {
    image::open(fixtures().join(file)).unwrap().to_luma8()
}

#[test]
fn cpbd_equals_the_reference_package_bit_for_bit() {
    let refs = reference();
    assert!(refs.len() >= 10);
    let mut boards = 0;
    for r in &refs {
        let file = r["file"].as_str().unwrap();
        let img = load(file);
        assert_eq!(img.width() as u64, r["width"].as_u64().unwrap());
        let want = r["cpbd"].as_f64().unwrap();
        let got = sharpness(&img, Metric::Cpbd).unwrap();
        assert_eq!(got.to_bits(), want.to_bits(), "{file}: etlcal {got:?} vs package {want:?}");
        boards += file.starts_with("board") as usize;
    }
    assert!(boards >= 5);
}

#[test]
fn simple_measures_match_numpy() {
    for r in reference() {
        let file = r["file"].as_str().unwrap();
        let img = load(file);
        for (metric, key) in [
            (Metric::Tenengrad, "tenengrad"),
            (Metric::Laplacian, "laplacian"),
            (Metric::Brenner, "brenner"),
            (Metric::Normvar, "normvar"),
        ] {
            let want = r[key].as_f64().unwrap();
            let got = sharpness(&img, metric).unwrap();
            assert!((got - want).abs() <= 1e-12 * want.abs(), "{file} {key}: {got} vs numpy {want}");
        }
    }
}

#[test]
fn sixteen_bit_images() {
    let img = load("camera.png");
    let wide = Gray16Image::from_fn(img.width(), img.height(), |x, y| Luma([img.get_pixel(x, y)[0] as u16 * 257]));
    // CPBD converts back to the same 8-bit image.
    assert_eq!(sharpness_u16(&wide, Metric::Cpbd).unwrap(), sharpness(&img, Metric::Cpbd).unwrap());
    // The gradient measures scale with the square of the gain.
    let t8 = sharpness(&img, Metric::Tenengrad).unwrap();
    let t16 = sharpness_u16(&wide, Metric::Tenengrad).unwrap();
    assert!((t16 / t8 - 257.0 * 257.0).abs() < 1e-9);
    // Full-range 16-bit data (values above 255 * 257 + 128 map to 255, none panic).
    let full = Gray16Image::from_fn(200, 130, |x, y| Luma([((x * 331 + y * 977) % 65536) as u16]));
    let c = sharpness_u16(&full, Metric::Cpbd).unwrap();
    assert!((0.0..=1.0).contains(&c));
}

#[test]
fn metric_names_round_trip_and_unknown_names_are_refused() {
    for m in Metric::ALL {
        assert_eq!(m.name().parse::<Metric>().unwrap(), m);
    }
    let e = "sobel".parse::<Metric>().unwrap_err().to_string();
    assert!(e.contains("unknown sharpness metric") && e.contains("tenengrad"), "{e}");
}

#[test]
fn constant_tiny_and_black_images() {
    let flat = GrayImage::from_pixel(128, 96, Luma([77]));
    assert_eq!(sharpness(&flat, Metric::Cpbd).unwrap(), 0.0);
    for m in [Metric::Tenengrad, Metric::Laplacian, Metric::Brenner, Metric::Normvar] {
        assert_eq!(sharpness(&flat, m).unwrap(), 0.0);
    }
    let small = GrayImage::from_pixel(63, 200, Luma([10]));
    let e = sharpness(&small, Metric::Cpbd).unwrap_err().to_string();
    assert!(e.contains("64 x 64"), "{e}");
    let tiny = GrayImage::from_pixel(2, 5, Luma([10]));
    let e = sharpness(&tiny, Metric::Tenengrad).unwrap_err().to_string();
    assert!(e.contains("too few") && e.contains("needs at least 3"), "{e}");
    let empty = GrayImage::new(0, 0);
    for m in Metric::ALL {
        assert!(sharpness(&empty, m).is_err(), "{m}");
    }
    let black = GrayImage::new(10, 10);
    let e = sharpness(&black, Metric::Normvar).unwrap_err().to_string();
    assert!(e.contains("black"), "{e}");
}

#[test]
fn cpbd_sees_only_vertical_edges_and_falls_with_blur() {
    // A slightly tilted vertical step, sharp, and the same step smeared over 6 px.
    let step = |x: u32, y: u32, ramp: f64| {
        let t = ((x as f64 - 64.0 - 0.05 * y as f64) / ramp).clamp(-0.5, 0.5) + 0.5;
        Luma([(40.0 + 170.0 * t).round() as u8])
    };
    let sharp = GrayImage::from_fn(128, 128, |x, y| step(x, y, 0.5));
    let soft = GrayImage::from_fn(128, 128, |x, y| step(x, y, 6.0));
    assert!(sharpness(&sharp, Metric::Cpbd).unwrap() > 0.9);
    assert_eq!(sharpness(&soft, Metric::Cpbd).unwrap(), 0.0);
    // The same steps turned horizontal: no width is measured along rows.
    let turned = GrayImage::from_fn(128, 128, |x, y| step(y, x, 0.5));
    assert_eq!(sharpness(&turned, Metric::Cpbd).unwrap(), 0.0);
}

fn etlcal() -> Command {
    Command::new(env!("CARGO_BIN_EXE_etlcal"))
}

#[test]
fn cli_prints_json_values_and_refuses_bad_files() {
    let dir = tempfile::tempdir().unwrap();
    let camera = fixtures().join("camera.png");
    let out = etlcal().arg("sharpness").arg(&camera).arg(fixtures().join("coins.png")).args(["--metric", "cpbd", "--json"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let images = v["images"].as_array().unwrap();
    assert_eq!(images.len(), 2);
    assert_eq!(images[0]["path"].as_str().unwrap(), camera.display().to_string());
    let want = reference().into_iter().find(|r| r["file"] == "camera.png").unwrap()["cpbd"].as_f64().unwrap();
    assert_eq!(images[0]["value"].as_f64().unwrap(), want);

    // A truncated PNG, a file of garbage, a missing file, an unknown metric.
    let bytes = std::fs::read(&camera).unwrap();
    let truncated = dir.path().join("truncated.png");
    std::fs::write(&truncated, &bytes[..bytes.len() / 3]).unwrap();
    let garbage = dir.path().join("garbage.jpg");
    std::fs::write(&garbage, b"this is not a JPEG at all").unwrap();
    for (args, needle) in [
        (vec![truncated.display().to_string()], "truncated.png"),
        (vec![garbage.display().to_string()], "garbage.jpg"),
        (vec![dir.path().join("missing.tif").display().to_string()], "missing.tif"),
    ] {
        let out = etlcal().arg("sharpness").args(&args).args(["--metric", "brenner"]).output().unwrap();
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle) && err.lines().count() == 1, "{err}");
    }
    let out = etlcal().arg("sharpness").arg(&camera).args(["--metric", "sobel"]).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown sharpness metric"));
}
