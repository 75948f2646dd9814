//! `etlcal undistort` as the built binary: distorted images of a known scene (made through
//! the paper rig's own model) come back as the scene; bad inputs are refused in one line
//! with exit status 1 and nothing written.
use std::path::Path;

use etl_core::model::CameraModel;
use etl_core::thermal::ThermalSurface;
use etl_formats::calibration::{Calibration, ThermalRef};
use serde_json::Value;

use super::common::etlcal;

/// The one stderr line of a failed run (exit status 1), nothing on stdout.
fn one_line_failure(args: &[&str]) -> String {
    let out = etlcal(args);
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
    assert_eq!(err.lines().count(), 1, "{args:?}: one line: {err}");
    assert!(out.stdout.is_empty(), "{args:?} printed on stdout");
    err
}

/// A smooth scene on the ideal (undistorted) pixel grid, grey levels in [20, 230].
fn scene(x: f64, y: f64) -> f64 {
    125.0 + 60.0 * (x / 37.0).sin() * (y / 53.0).cos() + 45.0 * ((x + y) / 91.0).sin()
}

/// The paper rig's calibration with the paper's thermal surface, written into `dir`.
fn paper_calibration(dir: &Path) -> String {
    let mut cal = Calibration::from_model(&CameraModel::paper_rig(), CameraModel::PAPER_IMAGE_SIZE, [80.0, 225.0]);
    cal.thermal = Some(ThermalRef::paper());
    let path = dir.join("calibration.json");
    cal.save(&path).unwrap();
    path.to_str().unwrap().to_owned()
}

#[test]
fn distorted_images_of_a_known_scene_come_back_as_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    let cal = paper_calibration(dir.path());
    let (e_in, t) = (153.0, 30.0);
    let e_com = ThermalSurface::PAPER.e_com_ma(e_in, t).unwrap();
    let cam = CameraModel::paper_rig();
    let [w, h] = CameraModel::PAPER_IMAGE_SIZE;
    // Each observed pixel shows the scene at its undistorted position.
    let mut grey = image::GrayImage::new(w, h);
    let mut rgb = image::RgbImage::new(w, h);
    for (x, y, p) in grey.enumerate_pixels_mut() {
        let ideal = cam.undistort([x as f64, y as f64], e_com).unwrap();
        let s = scene(ideal[0], ideal[1]);
        p.0 = [s.round() as u8];
        rgb.put_pixel(x, y, image::Rgb([s.round() as u8, (255.0 - s).round() as u8, 7]));
    }
    grey.save(dir.path().join("grey.png")).unwrap();
    rgb.save(dir.path().join("rgb.png")).unwrap();
    let out_dir = dir.path().join("out/nested");
    let (g, c, o) = (dir.path().join("grey.png"), dir.path().join("rgb.png"), out_dir.to_str().unwrap());
    let args = ["undistort", g.to_str().unwrap(), c.to_str().unwrap(), "--calibration", &cal];
    let mut args = args.to_vec();
    args.extend(["--e-in", "153", "--t", "30", "--out", o, "--json"]);
    let out = etlcal(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!((v["e_com_ma"].as_f64().unwrap() - e_com).abs() < 1e-9, "{v}");
    assert_eq!(v["images"][0]["input"], g.to_str().unwrap());
    assert_eq!(v["images"][1]["output"], out_dir.join("rgb.png").to_str().unwrap());
    let back = image::open(out_dir.join("grey.png")).unwrap();
    let back_rgb = image::open(out_dir.join("rgb.png")).unwrap().to_rgb8();
    let back = back.as_luma8().expect("8-bit grey stays 8-bit grey");
    let (k, d) = (cam.intrinsics(e_com).unwrap(), cam.distortion(e_com).unwrap());
    let mut worst = 0.0f64;
    for y in 0..h {
        for x in 0..w {
            // Only where the source lies inside the observed image.
            let [sx, sy] = d.distort(x as f64 - k.u0, y as f64 - k.v0);
            let (sx, sy) = (sx + k.u0, sy + k.v0);
            if sx < 0.0 || sy < 0.0 || sx > (w - 1) as f64 || sy > (h - 1) as f64 {
                continue;
            }
            let s = scene(x as f64, y as f64);
            worst = worst.max((back.get_pixel(x, y).0[0] as f64 - s).abs());
            assert_eq!(back_rgb.get_pixel(x, y).0[0], back.get_pixel(x, y).0[0]);
        }
    }
    // The input's rounding (0.5) and the output's (0.5), plus the bilinear error (0.03).
    assert!(worst <= 1.03, "worst {worst} grey levels");
}

#[test]
fn bad_inputs_are_one_line_errors_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let cal = paper_calibration(dir.path());
    let text = dir.path().join("notes.txt");
    std::fs::write(&text, "not an image").unwrap();
    let fake = dir.path().join("fake.png");
    std::fs::write(&fake, "not a PNG either").unwrap();
    let fake = fake.to_str().unwrap();
    let good = dir.path().join("good.png");
    image::GrayImage::new(1936, 1458).save(&good).unwrap();
    let small = dir.path().join("small.png");
    image::GrayImage::new(64, 48).save(&small).unwrap();
    let out = dir.path().join("out");
    let o = out.to_str().unwrap();
    let (text, good, small) = (text.to_str().unwrap(), good.to_str().unwrap(), small.to_str().unwrap());
    let run = |images: &[&str], cal: &str, e_in: &str| {
        let mut args = vec!["undistort"];
        args.extend(images);
        args.extend(["--calibration", cal, "--e-in", e_in, "--t", "30", "--out", o]);
        one_line_failure(&args)
    };
    let err = run(&[good, text], &cal, "153");
    assert!(err.contains("notes.txt") && err.contains("not an image"), "{err}");
    let err = run(&[good, fake], &cal, "153");
    assert!(err.contains("fake.png: cannot read image"), "{err}");
    let err = run(&[good], dir.path().join("missing.json").to_str().unwrap(), "153");
    assert!(err.contains("missing.json"), "{err}");
    let err = run(&[good], &cal, "60");
    assert!(err.contains("e_com_ma = 57.99") && err.contains("is outside [75, 230]"), "{err}");
    let err = run(&[good], &cal, "260");
    assert!(err.contains("e_in_ma = 260 is outside [35, 245]"), "{err}");
    let err = run(&[good, small], &cal, "153");
    assert!(err.contains("small.png") && err.contains("64 x 48 px"), "{err}");
    let err = run(&[good, good], &cal, "153");
    assert!(err.contains("two images"), "{err}");
    assert!(!out.exists(), "nothing written on failure");
    // The input's own directory as --out: refused rather than overwritten.
    let args = ["undistort", good, "--calibration", &cal, "--e-in", "153", "--t", "30"];
    let mut args = args.to_vec();
    args.extend(["--out", dir.path().to_str().unwrap()]);
    let err = one_line_failure(&args);
    assert!(err.contains("would overwrite the input"), "{err}");
}
