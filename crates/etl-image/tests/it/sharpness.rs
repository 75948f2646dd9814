//! Sharpness against the reference values of `fixtures/cpbd/reference.json`: CPBD computed
//! by the PyPI package `cpbd` 1.0.7 itself, the other measures by NumPy
//! (`benches/cpbd_reference.py` writes the file), on natural images (scikit-image's data
//! set) and rendered boards at several blurs and noise levels.
use std::path::PathBuf;

use etl_image::sharpness::{sharpness, sharpness_u16, Metric};

fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/cpbd")
}

#[test]
fn every_measure_matches_the_reference_on_every_fixture() {
    let text = std::fs::read_to_string(fixtures().join("reference.json")).unwrap();
    let reference: serde_json::Value = serde_json::from_str(&text).unwrap();
    let images = reference["images"].as_array().unwrap();
    assert!(images.len() >= 10, "{} fixtures", images.len());
    let mut worst_cpbd = 0.0f64;
    for entry in images {
        let file = entry["file"].as_str().unwrap();
        let img = image::open(fixtures().join(file)).unwrap().to_luma8();
        for (name, metric, tol) in [
            ("cpbd", Metric::Cpbd, 0.0),
            ("tenengrad", Metric::Tenengrad, 1e-9),
            ("laplacian", Metric::Laplacian, 1e-9),
            ("brenner", Metric::Brenner, 1e-9),
            ("normvar", Metric::Normvar, 1e-9),
        ] {
            let want = entry[name].as_f64().unwrap();
            let got = sharpness(&img, metric).unwrap();
            let err = (got - want).abs() / want.abs().max(1e-300);
            if metric == Metric::Cpbd {
                worst_cpbd = worst_cpbd.max((got - want).abs());
            }
            assert!(err <= tol || (got - want).abs() <= tol, "{file} {name}: {got} vs reference {want}");
        }
    }
    // Bit for bit, not merely within the 1e-3.
    assert_eq!(worst_cpbd, 0.0);
}

#[test]
fn sixteen_bit_input_widened_from_eight_bits_gives_the_same_cpbd() {
    let img = image::open(fixtures().join("camera.png")).unwrap().to_luma8();
    let wide = image::ImageBuffer::from_fn(img.width(), img.height(), |x, y| {
        image::Luma([u16::from(img.get_pixel(x, y)[0]) * 257])
    });
    assert_eq!(sharpness_u16(&wide, Metric::Cpbd).unwrap(), sharpness(&img, Metric::Cpbd).unwrap());
}

#[test]
fn bad_images_are_errors() {
    let tiny = image::GrayImage::new(10, 10);
    let e = sharpness(&tiny, Metric::Cpbd).unwrap_err().to_string();
    assert!(e.contains("64"), "{e}");
    let empty = image::GrayImage::new(0, 0);
    for m in [Metric::Cpbd, Metric::Tenengrad, Metric::Laplacian, Metric::Brenner, Metric::Normvar] {
        assert!(sharpness(&empty, m).is_err(), "{m:?} on an empty image");
    }
    assert!("sharpest".parse::<Metric>().is_err());
    // A constant image has no edge: CPBD 0 as in the package, zero gradient energy.
    let flat = image::GrayImage::from_pixel(128, 128, image::Luma([90]));
    assert_eq!(sharpness(&flat, Metric::Cpbd).unwrap(), 0.0);
    assert_eq!(sharpness(&flat, Metric::Tenengrad).unwrap(), 0.0);
}
