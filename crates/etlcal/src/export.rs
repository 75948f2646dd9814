//! `etlcal export --calibration FILE (--e-in MA --t C | --e-com MA) --format
//! opencv|ros|mrcal --out FILE [--allow-extrapolation] [--json]`: the camera at one setting
//! (a driver current and temperature, or a known E_com) as an OpenCV FileStorage
//! YAML, a ROS camera_info YAML or an mrcal .cameramodel (etl_formats::export). The
//! distortion is OpenCV's five coefficients fitted to etlcal's model; the fit error is
//! printed and written into the file.

use std::path::PathBuf;

use serde_json::json;

use super::print_json;
use crate::setting::SettingArgs;
use etl_formats::export::{export, ExportFormat};
use etl_formats::output::Output;
use etl_formats::Result;

/// Arguments of `etlcal export`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// The calibration and the setting.
    #[command(flatten)]
    pub setting: SettingArgs,
    /// opencv (FileStorage YAML), ros (camera_info YAML) or mrcal (.cameramodel).
    #[arg(long, value_name = "opencv|ros|mrcal")]
    pub format: String,
    /// The file to write (atomically; its directory is created if missing).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// Runs `etlcal export`.
pub fn run(args: Args) -> Result<()> {
    let format: ExportFormat = args.format.parse()?;
    // The calibration is an input: an --out that is it (or a link to it) would replace it
    // with the export.
    crate::output::check([Some(args.setting.calibration.as_path())], &[Output::File(&args.out)])?;
    let (cal, camera) = args.setting.camera()?;
    crate::output::create_parent(&args.out)?;
    let e = export(&cal, &camera, format, &args.out)?;
    if args.json {
        let mut j = args.setting.json(&camera);
        j["format"] = json!(args.format);
        j["out"] = json!(args.out.display().to_string());
        j["camera_matrix"] = json!(e.camera_matrix);
        j["dist_coeffs"] = json!(e.fit.dist_coeffs);
        j["fit_rms_px"] = json!(e.fit.rms_px);
        j["fit_max_px"] = json!(e.fit.max_px);
        print_json(&j);
    } else {
        outln!(
            "wrote {} ({} at {}{}); OpenCV distortion fit: rms {:.4} px, max {:.4} px",
            args.out.display(),
            args.format,
            etl_formats::setting_label(&camera),
            if camera.extrapolated() { ", EXTRAPOLATED" } else { "" },
            e.fit.rms_px,
            e.fit.max_px
        );
    }
    Ok(())
}
