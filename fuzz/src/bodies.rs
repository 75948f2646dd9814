//! The bodies of the fuzz targets: what each does with the fuzzer's bytes and the
//! properties it checks beyond "no panic, no hang, bounded memory". One function per
//! target in `fuzz_targets/`; `crates/etlcal/tests/fuzz_corpus.rs` includes this file too
//! and replays every committed corpus input on stable.

#![allow(dead_code)]

use std::path::PathBuf;
use std::sync::OnceLock;

use etl_core::thermal::ThermalSurface;
use etl_formats::observations::Observations;
use etl_formats::{A0File, Calibration, Dataset, ThermalFile, ThermalRef};

/// A scratch file of this process for the readers, which take paths (`tag` keeps the
/// targets apart when a test runs several in one process).
fn scratch(tag: &str) -> PathBuf {
    std::env::temp_dir().join(format!("etlcal-fuzz-{}-{tag}", std::process::id()))
}

/// `json_readers`: the bytes as every etlcal file the readers take. Each reader returns a
/// value or an error; a value a reader accepts is written back by its writer (which
/// validates as the reader does) and read again.
pub fn json_readers(data: &[u8]) {
    let (path, again) = (scratch("in.json"), scratch("again.json"));
    if std::fs::write(&path, data).is_err() {
        return;
    }
    if let Ok(c) = Calibration::load(&path) {
        c.save(&again).expect("a calibration the reader accepts is written");
        Calibration::load(&again).expect("a written calibration reads back");
    }
    if let Ok(o) = Observations::load(&path) {
        o.save(&again).expect("observations the reader accepts are written");
        Observations::load(&again).expect("written observations read back");
    }
    if let Ok(d) = Dataset::load(&path) {
        d.save(&again).expect("a dataset the reader accepts is written");
        Dataset::load(&again).expect("a written dataset reads back");
    }
    let _ = A0File::load(&path);
    let _ = ThermalFile::load(&path);
    let _ = etl_formats::thermal::read_thermal_table(&path);
}

/// `image_detect`: the bytes as an image file (PNG, JPEG, TIFF by content) through the
/// reader and the checkerboard detector; with a leading 0 byte, as a raw grey image of at
/// most 255 x 255 px (its side in the next two bytes) straight into the detector.
pub fn image_detect(data: &[u8]) {
    let Ok(pattern) = etl_image::detect::Pattern::new(4, 3) else { return };
    match data.split_first() {
        Some((0, rest)) if rest.len() >= 2 => {
            let (w, h) = (usize::from(rest[0]).max(1), usize::from(rest[1]).max(1));
            let mut pixels = rest[2..].to_vec();
            pixels.resize(w * h, 128);
            if let Some(img) = image::GrayImage::from_raw(w as u32, h as u32, pixels) {
                check_corners(etl_image::detect::detect_corners(&img, pattern), w, h);
            }
        }
        _ => {
            let path = scratch("image");
            if std::fs::write(&path, data).is_ok() {
                if let Ok(img) = etl_image::read_image(&path) {
                    let (w, h) = (img.width() as usize, img.height() as usize);
                    check_corners(etl_image::detect::detect_dynamic(&img, pattern), w, h);
                }
            }
        }
    }
}

/// Every corner a detection returns is a finite point inside the image.
fn check_corners(found: etl_image::Result<etl_image::detect::Detection>, w: usize, h: usize) {
    if let Ok(d) = found {
        for c in &d.corners_px {
            assert!(c[0].is_finite() && c[1].is_finite(), "corner {c:?} not finite");
            assert!(c[0] >= -0.5 && c[1] >= -0.5 && c[0] <= w as f64 - 0.5 && c[1] <= h as f64 - 0.5, "{c:?} outside");
        }
    }
}

/// The noise-free paper rig's observations and A0, built once per process.
fn paper_rig() -> &'static etl_sim::simulate::Simulation {
    static RIG: OnceLock<etl_sim::simulate::Simulation> = OnceLock::new();
    RIG.get_or_init(|| etl_sim::simulate::paper_rig(&etl_sim::simulate::NoiseModel::NONE, 1))
}

/// An f64 from 8 bytes, or a value near `scale` from fewer (so that most inputs stay
/// physical and reach deep into the pipeline, while raw bit patterns reach NaN, inf, 1e308).
fn number(bytes: &[u8], scale: f64) -> f64 {
    match bytes.len() {
        8.. => f64::from_le_bytes(bytes[..8].try_into().unwrap_or([0; 8])),
        1.. => scale * (f64::from(bytes[0] as i8) / 16.0),
        0 => 0.0,
    }
}

/// `calibrate_observations`: the paper rig's 2311 corners with the bytes' edits (11-byte
/// records: view, point, what, value) through the whole calibration pipeline (thermal
/// surface the paper's, errors-in-variables). It returns a calibration or an error; a
/// calibration it returns has finite numbers.
pub fn calibrate_observations(data: &[u8]) {
    let _ = calibrate_edited(data);
}

/// [`calibrate_observations`]'s work: whether the edited observations calibrated.
pub fn calibrate_edited(data: &[u8]) -> bool {
    let rig = paper_rig();
    let mut obs: Observations = rig.observations.clone();
    for rec in data.chunks(11).take(64) {
        let (Some(&v), Some(&what)) = (rec.first(), rec.get(3)) else { break };
        let Some(view) = obs.views.get_mut(usize::from(v) % 15) else { continue };
        let p = usize::from(u16::from_le_bytes([rec.get(1).copied().unwrap_or(0), rec.get(2).copied().unwrap_or(0)]));
        let value = number(&rec[4.min(rec.len())..], 100.0);
        let n = view.points.len().max(1);
        match what % 8 {
            0 => {
                if let Some(pt) = view.points.get_mut(p % n) {
                    pt.pixel[0] += value;
                }
            }
            1 => {
                if let Some(pt) = view.points.get_mut(p % n) {
                    pt.pixel[1] += value;
                }
            }
            2 => {
                if let Some(pt) = view.points.get_mut(p % n) {
                    pt.world_mm[(p / n) % 3] += value / 100.0;
                }
            }
            3 => view.e_in_ma += value,
            4 => view.temperature_c += value / 10.0,
            5 => view.e_com_ma = Some(view.e_in_ma + value),
            6 => view.points.truncate(p % n),
            _ => {
                let keep = p % n;
                view.points.swap(0, keep);
            }
        }
    }
    let options = etl_calib::pipeline::CalibrateOptions::default();
    match etl_calib::pipeline::calibrate(&obs, &rig.a0, Some(&ThermalRef::paper()), &options) {
        Ok(result) => {
            let cal = result.calibration;
            assert!(cal.rms_reprojection_px.is_finite(), "rms {}", cal.rms_reprojection_px);
            assert!(cal.kf_x.iter().chain(&cal.kf_y).all(|k| k.is_finite()), "kf {:?} {:?}", cal.kf_x, cal.kf_y);
            true
        }
        Err(_) => false,
    }
}

/// `thermal_inverse`: a surface (the paper's with each coefficient scaled by the bytes, or
/// raw f64 coefficients with a leading 0 byte), an E_com and a temperature. The inverse
/// returns an error or an E_in at which the forward model gives E_com back to 1e-6 mA.
pub fn thermal_inverse(data: &[u8]) {
    let Some((&mode, rest)) = data.split_first() else { return };
    let mut coefficients = ThermalSurface::PAPER.coefficients;
    let mut at = 0;
    let mut take = |len: usize| -> &[u8] {
        let s = rest.get(at..(at + len).min(rest.len())).unwrap_or(&[]);
        at += len;
        s
    };
    for c in coefficients.iter_mut() {
        *c = if mode == 0 { number(take(8), 1.0) } else { *c * (1.0 + number(take(1), 0.05)) };
    }
    let (e_com_ma, t_c) = if mode == 0 {
        (number(take(8), 1.0), number(take(8), 1.0))
    } else {
        (150.0 + number(take(1), 20.0), 32.0 + number(take(1), 1.0))
    };
    let surface = ThermalSurface { coefficients };
    if let Ok(e_in_ma) = surface.e_in_for_e_com(e_com_ma, t_c) {
        let e_t_ma = surface.e_t_ma(e_in_ma, t_c).expect("the inverse's E_in is in the surface's domain");
        let back = e_in_ma - e_t_ma;
        assert!(
            (back - e_com_ma).abs() <= 1e-6 * e_com_ma.abs().max(1.0),
            "E_com {e_com_ma} -> E_in {e_in_ma} -> {back}"
        );
    }
}
