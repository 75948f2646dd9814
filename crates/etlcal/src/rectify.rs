//! `etlcal rectify --rig RIG.json --pair I,J --setting S... --t C... --out DIR
//! [--alpha -1] [--format opencv|ros|mrcal ...] [--maps] [--allow-extrapolation]
//! [--json]`: Bouguet's rectification of cameras I (left) and J (right) of a rig at one
//! setting per camera (`etl_calib::rig`), as `cv2.stereoRectify` with its defaults
//! (`CALIB_ZERO_DISPARITY`, alpha -1), the pose taken at the settings.
//!
//! Writes into DIR, as one set (all files or, on any error, none): `stereo.yaml`, OpenCV's
//! stereo FileStorage YAML (K1, D1, K2, D2, R, T, R1, R2, P1, P2, Q: what `etlcal stereo
//! --opencv-yaml` writes), always; with `--format ros`, `left.yaml` and `right.yaml`, ROS
//! `camera_info` with R = R1 / R2 and P = P1 / P2; with `--format mrcal`, one
//! `NAME.cameramodel` per camera of the rig, extrinsics relative to camera 0 at the
//! settings; with `--maps`, `left_map_x.npy`, `left_map_y.npy`, `right_map_x.npy`,
//! `right_map_y.npy`: float32 image-sized maps for `cv2.remap`, each rectified pixel's ray
//! projected through the camera's full model (exact for either distortion family; D in
//! the YAML files is OpenCV's fit for a paper-family calibration, its error in their
//! comments). `--alpha` other than -1 (OpenCV's free scaling) is not implemented and is
//! refused.
//!
//! `--json`: `{"pair", "image_size", "rotation_rodrigues", "translation_mm",
//! "baseline_mm", "R1", "R2", "P1", "P2", "Q", "files", "rig", "cameras", "extrapolated"}`.

use std::path::PathBuf;

use etl_calib::rig::{maps_files, write_files};
use etl_formats::export::ExportFormat;
use etl_formats::output::Output;
use etl_formats::{Error, Result};
use serde_json::json;

use super::print_json;
use crate::rig_setting::RigArgs;

/// Arguments of `etlcal rectify`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// The rig and its settings (one per camera of the rig).
    #[command(flatten)]
    pub rig: RigArgs,
    /// The pair, LEFT,RIGHT: two cameras' indices in the rig.
    #[arg(long, value_name = "I,J")]
    pub pair: String,
    /// cv2.stereoRectify's free scaling: only -1 (its default, no scaling) is implemented.
    #[arg(long, value_name = "A", default_value_t = -1.0)]
    pub alpha: f64,
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Exports besides stereo.yaml: ros (left.yaml, right.yaml), mrcal (one .cameramodel
    /// per camera); opencv is stereo.yaml itself.
    #[arg(long, num_args = 1.., value_name = "opencv|ros|mrcal")]
    pub format: Vec<String>,
    /// Also write both cameras' rectification maps (.npy, float32, for cv2.remap).
    #[arg(long)]
    pub maps: bool,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// `--pair I,J`.
fn pair(text: &str) -> Result<[usize; 2]> {
    let bad = || Error::invalid_value("--pair", text, format!("--pair {text:?}: give two camera indices, I,J"));
    let (a, b) = text.split_once(',').ok_or_else(bad)?;
    Ok([a.trim().parse().map_err(|_| bad())?, b.trim().parse().map_err(|_| bad())?])
}

/// The formats asked for, stereo.yaml's own first.
fn formats(given: &[String]) -> Result<Vec<ExportFormat>> {
    let mut out = vec![ExportFormat::OpenCv];
    for f in given {
        let f: ExportFormat = f.parse::<ExportFormat>().map_err(|e| e.rename_input("format", "--format"))?;
        if !out.contains(&f) {
            out.push(f);
        }
    }
    Ok(out)
}

/// Runs `etlcal rectify`.
pub fn run(args: Args) -> Result<()> {
    let [l, r] = pair(&args.pair)?;
    let formats = formats(&args.format)?;
    crate::output::check([Some(args.rig.rig.as_path())], &[Output::Dir(&args.out)])?;
    let (_, at) = args.rig.rig_at()?;
    let rect = at
        .stereo_rectify(l, r, args.alpha)
        .map_err(|e| e.rename_input("pair", "--pair").rename_input("alpha", "--alpha"))?;
    let mut files: Vec<(String, Vec<u8>)> =
        at.export_pair(&rect, &formats)?.into_iter().map(|f| (f.name, f.text.into_bytes())).collect();
    if args.maps {
        files.extend(maps_files(&at.stereo_rectify_maps(&rect)?)?);
    }
    let written = write_files(&args.out, files)?;
    let x = &rect.rectification;
    if args.json {
        let mut j = args.rig.json(&at);
        for (k, v) in [
            ("pair", json!(rect.pair)),
            ("image_size", json!(rect.image_size)),
            ("rotation_rodrigues", json!(rect.rotation_rodrigues)),
            ("translation_mm", json!(rect.translation_mm)),
            ("baseline_mm", json!(rect.baseline_mm())),
            ("R1", json!(x.r1)),
            ("R2", json!(x.r2)),
            ("P1", json!(x.p1)),
            ("P2", json!(x.p2)),
            ("Q", json!(x.q)),
            ("files", json!(written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>())),
        ] {
            j[k] = v;
        }
        print_json(&j);
        return Ok(());
    }
    outln!(
        "cameras {l} ({}) and {r} ({}): baseline {:.4} mm, rectified focal length {:.3} px{}",
        at.name(l),
        at.name(r),
        rect.baseline_mm(),
        x.p1[0][0],
        if at.extrapolated() { "; EXTRAPOLATED" } else { "" }
    );
    for p in &written {
        outln!("wrote {}", p.display());
    }
    Ok(())
}
