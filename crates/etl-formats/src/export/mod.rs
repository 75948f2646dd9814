//! Exports of the camera at one setting for other tools: OpenCV's FileStorage YAML, ROS's
//! `camera_info` YAML and mrcal's `.cameramodel`.
//!
//! All three hold a pinhole camera with OpenCV's five distortion coefficients
//! (k1, k2, p1, p2, k3; mrcal's `LENSMODEL_OPENCV5`, ROS's `plumb_bob`). A calibration of
//! the opencv distortion family exports its own coefficients at the setting, exactly. The
//! paper's distortion has no exact counterpart among them when fx != fy, so its
//! coefficients are the least-squares fit over the image ([`etl_core::model::fit_opencv5`])
//! and every file states the fit's RMS and largest error, in px, in a comment;
//! [`Exported`] returns them.
//!
//! Numbers are written with 17 significant digits in a form every reader parses as a
//! float: a decimal point and a signed exponent (YAML 1.1, which ROS's PyYAML reads,
//! takes `1e-5` for a string).

use std::fmt::Write as _;
use std::path::Path;
use std::str::FromStr;

use etl_core::model::{fit_opencv5, DistortionModel, OpenCvFit};
use etl_core::runtime::CameraAt;

use crate::calibration::Calibration;
use crate::{write_atomic, Error, Result};

pub mod stereo;

/// The file an export writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExportFormat {
    /// OpenCV FileStorage YAML: `camera_matrix`, `distortion_coefficients`,
    /// `image_width`, `image_height` (read by `cv2.FileStorage`).
    OpenCv,
    /// ROS `sensor_msgs/CameraInfo` calibration YAML (camera_calibration_parsers).
    Ros,
    /// mrcal `.cameramodel`, `LENSMODEL_OPENCV5`, extrinsics of the calibration's world
    /// frame (the lens-off board) (`mrcal.cameramodel(path)`).
    Mrcal,
}

impl FromStr for ExportFormat {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "opencv" => Ok(ExportFormat::OpenCv),
            "ros" => Ok(ExportFormat::Ros),
            "mrcal" => Ok(ExportFormat::Mrcal),
            _ => Err(Error::invalid_value("format", s, format!("format {s:?} is not one of opencv, ros, mrcal"))),
        }
    }
}

/// What an export wrote: the camera it describes and the error of its distortion fit.
#[derive(Debug, Clone, PartialEq)]
pub struct Exported {
    /// The file's text.
    pub text: String,
    /// K at the setting, px (row-major).
    pub camera_matrix: [[f64; 3]; 3],
    /// The OpenCV coefficients and their fit error over the image.
    pub fit: OpenCvFit,
}

/// The text of `format` for `camera` (a setting of `cal`).
pub fn export_text(cal: &Calibration, camera: &CameraAt, format: ExportFormat) -> Result<Exported> {
    let k = camera.intrinsics();
    let fit = fit_opencv5(k, camera.distortion(), cal.image_size)?;
    let camera_matrix = k.matrix();
    let header = header(camera, &fit);
    let text = match format {
        ExportFormat::OpenCv => opencv_yaml(&header, cal.image_size, &camera_matrix, &fit.dist_coeffs),
        ExportFormat::Ros => ros_yaml(&header, cal.image_size, &camera_matrix, &fit.dist_coeffs),
        ExportFormat::Mrcal => mrcal_model(&header, cal, camera.setting_value(), &camera_matrix, &fit.dist_coeffs)?,
    };
    Ok(Exported { text, camera_matrix, fit })
}

/// Writes the export of `camera` atomically to `path` (nothing is written on error).
pub fn export(cal: &Calibration, camera: &CameraAt, format: ExportFormat, path: &Path) -> Result<Exported> {
    let e = export_text(cal, camera, format)?;
    write_atomic(path, e.text.as_bytes())?;
    Ok(e)
}

/// The comment lines that open every export: the setting, whether it is extrapolated,
/// and whether the five coefficients are exact or fitted (with the fit's error).
pub fn header(c: &CameraAt, fit: &OpenCvFit) -> String {
    let mut h = String::from("# etlcal: the camera at one setting");
    if c.e_in_ma().is_finite() {
        let _ = write!(h, ", E_in {} mA at {} degC", num(c.e_in_ma()), num(c.temperature_c()));
    }
    let _ = match c.setting_kind() {
        crate::SettingKind::Current => write!(h, ", E_com {} mA", num(c.e_com_ma())),
        crate::SettingKind::FocalPower => write!(
            h,
            ", focal power {} dpt at {} degC (setting: focal_power)",
            num(c.focal_power_dpt()),
            num(c.temperature_c())
        ),
    };
    if c.extrapolated() {
        h.push_str(" (EXTRAPOLATED beyond the calibrated ranges)");
    }
    if c.distortion().model() == DistortionModel::OpenCv {
        h.push_str("\n# distortion: OpenCV (k1, k2, p1, p2, k3): etlcal's opencv model at this setting, exact\n");
        return h;
    }
    let _ = write!(
        h,
        "\n# distortion: OpenCV (k1, k2, p1, p2, k3) fitted to etlcal's model over the image: rms {} px, max {} px\n",
        num(fit.rms_px),
        num(fit.max_px)
    );
    h
}

/// A float every reader takes as one (OpenCV's FileStorage YAML included): the shortest
/// digits that read back exactly, a decimal point, a signed exponent when there is one.
pub fn num(x: f64) -> String {
    let s = format!("{x:?}");
    match s.split_once('e') {
        Some((m, e)) => {
            let m = if m.contains('.') { m.to_owned() } else { format!("{m}.0") };
            let e = if e.starts_with('-') { e.to_owned() } else { format!("+{e}") };
            format!("{m}e{e}")
        }
        None => s,
    }
}

/// Numbers as a comma-separated list ([`num`]).
pub fn list(xs: impl IntoIterator<Item = f64>) -> String {
    xs.into_iter().map(num).collect::<Vec<_>>().join(", ")
}

fn opencv_yaml(header: &str, [w, h]: [u32; 2], k: &[[f64; 3]; 3], d: &[f64; 5]) -> String {
    let m = |rows: usize, cols: usize, data: String| {
        format!("!!opencv-matrix\n   rows: {rows}\n   cols: {cols}\n   dt: d\n   data: [ {data} ]\n")
    };
    format!(
        "%YAML:1.0\n---\n{header}image_width: {w}\nimage_height: {h}\ncamera_matrix: {}distortion_coefficients: {}",
        m(3, 3, list(k.iter().flatten().copied())),
        m(1, 5, list(d.iter().copied()))
    )
}

fn ros_yaml(header: &str, size: [u32; 2], k: &[[f64; 3]; 3], d: &[f64; 5]) -> String {
    let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let p = [[k[0][0], 0.0, k[0][2], 0.0], [0.0, k[1][1], k[1][2], 0.0], [0.0, 0.0, 1.0, 0.0]];
    ros_camera_info(header, "etlcal", size, (k, d), (&identity, &p))
}

/// ROS's `camera_info` YAML (camera_calibration_parsers' keys) of camera `name`: K and
/// the plumb_bob D, the rectification R and the projection P (a single camera: I and
/// [K | 0]; a stereo pair's: R1 or R2 and P1 or P2, as stereo_image_proc reads them).
pub fn ros_camera_info(
    header: &str,
    name: &str,
    [w, h]: [u32; 2],
    (k, d): (&[[f64; 3]; 3], &[f64; 5]),
    (r, p): (&[[f64; 3]; 3], &[[f64; 4]; 3]),
) -> String {
    let m = |rows: usize, cols: usize, data: String| format!("\n  rows: {rows}\n  cols: {cols}\n  data: [{data}]\n");
    format!(
        "{header}image_width: {w}\nimage_height: {h}\ncamera_name: {name}\ncamera_matrix:{}distortion_model: plumb_bob\n\
         distortion_coefficients:{}rectification_matrix:{}projection_matrix:{}",
        m(3, 3, list(k.iter().flatten().copied())),
        m(1, 5, list(d.iter().copied())),
        m(3, 3, list(r.iter().flatten().copied())),
        m(3, 4, list(p.iter().flatten().copied()))
    )
}

/// mrcal's `.cameramodel` at E_com `e_com_ma`. Its extrinsics are rt_cam_ref
/// (x_cam = R x_ref + t): the calibration's R and T(E) of Eq. C2, the pose of the centre
/// at this setting relative to the calibration's frame (T itself for a fixed centre).
fn mrcal_model(header: &str, cal: &Calibration, e_com_ma: f64, k: &[[f64; 3]; 3], d: &[f64; 5]) -> Result<String> {
    let t = cal.model()?.translation_at(e_com_ma);
    let r = cal.rotation_rodrigues;
    Ok(mrcal_cameramodel(header, cal.image_size, (k, d), [r[0], r[1], r[2], t[0], t[1], t[2]]))
}

/// mrcal's `.cameramodel` (`LENSMODEL_OPENCV5`) of K `k`, coefficients `d` and extrinsics
/// `rt_cam_ref` (Rodrigues, rad, then translation, mm: x_cam = R x_ref + t).
pub fn mrcal_cameramodel(
    header: &str,
    [w, h]: [u32; 2],
    (k, d): (&[[f64; 3]; 3], &[f64; 5]),
    rt_cam_ref: [f64; 6],
) -> String {
    let intrinsics = [k[0][0], k[1][1], k[0][2], k[1][2], d[0], d[1], d[2], d[3], d[4]];
    format!(
        "{header}{{\n    'lensmodel': 'LENSMODEL_OPENCV5',\n    'intrinsics': [ {} ],\n    'extrinsics': [ {} ],\n    \
         'imagersize': [ {w}, {h} ],\n}}\n",
        list(intrinsics),
        list(rt_cam_ref),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_floats_to_every_reader() {
        assert_eq!(num(1e-5), "1.0e-5");
        assert_eq!(num(1.5e20), "1.5e+20");
        assert_eq!(num(5380.0), "5380.0");
        assert_eq!(num(-0.0561972549810319), "-0.0561972549810319");
        for x in [1e-5, 1.5e20, -3.3e-300, 0.1 + 0.2] {
            assert_eq!(num(x).parse::<f64>().unwrap(), x);
        }
    }

    /// An opencv-family calibration exports its own coefficients at the setting, with
    /// error 0, and says it is exact.
    #[test]
    fn an_opencv_family_export_is_exact() {
        use etl_core::model::CameraModel;
        use etl_core::runtime::Trust;
        let model = CameraModel::strong_distortion_rig();
        let cal = Calibration::from_model(&model, [1936, 1458], [80.0, 225.0]);
        let at = cal.camera().unwrap().at_e_com(150.0, Trust::Refuse).unwrap();
        for format in [ExportFormat::OpenCv, ExportFormat::Ros, ExportFormat::Mrcal] {
            let e = export_text(&cal, &at, format).unwrap();
            assert_eq!((e.fit.rms_px, e.fit.max_px), (0.0, 0.0));
            assert_eq!(&e.fit.dist_coeffs[..], model.distortion(150.0).unwrap().coefficients());
            assert!(e.text.contains("etlcal's opencv model at this setting, exact"), "{}", e.text);
            // Each coefficient is in the file as written (17 digits round-trip).
            for c in e.fit.dist_coeffs {
                assert!(e.text.contains(&num(c)), "{c}");
            }
        }
    }

    #[test]
    fn unknown_formats_are_named() {
        let e = "json".parse::<ExportFormat>().unwrap_err();
        assert!(e.to_string().contains("\"json\""), "{e}");
        assert_eq!("mrcal".parse::<ExportFormat>().unwrap(), ExportFormat::Mrcal);
    }
}
