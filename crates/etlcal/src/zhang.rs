//! `etlcal zhang IMAGE... --pattern CxR --square MM [--model paper|opencv] [--fix-k3]
//! [--zero-tangent] [--json]`: monofocal calibration of one fixed-focus camera (Zhang 2000).
//!
//! `--model paper` (the default): the paper's distortion k1, p1, p2 in centred pixels;
//! `--json` prints `{"fx", "fy", "u0", "v0", "k1", "p1", "p2", "rms_px", "views_used"}`.
//! `--model opencv`: OpenCV's model (k1, k2, p1, p2, k3 in normalised coordinates, the
//! same least-squares problem as `cv2.calibrateCamera`; `--fix-k3`, `--zero-tangent` as
//! its `CALIB_FIX_K3`, `CALIB_ZERO_TANGENT_DIST`); `--json` prints `{"model", "fx", "fy",
//! "u0", "v0", "camera_matrix" (3 x 3), "dist_coeffs" ([k1, k2, p1, p2, k3]), "rms_px",
//! "views_used", "images_used", "per_view_rms_px", "std" (one standard deviation of fx,
//! fy, u0, v0, k1, k2, p1, p2, k3, as `calibrateCameraExtended`; 0 for a held one),
//! "fix_k3", "zero_tangent", "outliers" (points left out)}`.
//! Images whose board is not found are named on stderr and skipped; at least 3 views must
//! remain.

use std::path::PathBuf;

use serde_json::{json, Value};

use super::print_json;
use crate::board::BoardArgs;
use etl_calib::pipeline::detect_views;
use etl_calib::pipeline::select::refuse_opencv_flags;
use etl_calib::zhang::{zhang_with, ZhangOptions, ZhangResult};
use etl_core::model::{DistortionModel, OpenCvFlags};
use etl_formats::{Error, Result};

/// The distortion model of `--model`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelArg {
    /// The paper's: k1, p1, p2 in centred pixel coordinates (Eq. 17).
    Paper,
    /// OpenCV's: k1, k2, p1, p2, k3 in normalised coordinates (cv2.calibrateCamera's).
    Opencv,
}

/// Arguments of `etlcal zhang`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Images of the board (at least 3 in distinct orientations).
    #[arg(required = true, value_name = "IMAGE")]
    pub images: Vec<PathBuf>,
    /// The board.
    #[command(flatten)]
    pub board: BoardArgs,
    /// The distortion model.
    #[arg(long, value_enum, default_value = "paper")]
    pub model: ModelArg,
    /// Hold k3 at 0 (OpenCV's CALIB_FIX_K3; --model opencv only).
    #[arg(long)]
    pub fix_k3: bool,
    /// Hold p1 = p2 = 0 (OpenCV's CALIB_ZERO_TANGENT_DIST; --model opencv only).
    #[arg(long)]
    pub zero_tangent: bool,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// The options of `--model`, `--fix-k3`, `--zero-tangent`; an OpenCV flag with the paper's
/// model is refused, naming the flag.
fn options(args: &Args) -> Result<ZhangOptions> {
    let model = match args.model {
        ModelArg::Paper => DistortionModel::Paper,
        ModelArg::Opencv => DistortionModel::OpenCv,
    };
    let flags = OpenCvFlags { fix_k3: args.fix_k3, zero_tangent: args.zero_tangent };
    refuse_opencv_flags(Some(model), flags, ["--fix-k3", "--zero-tangent"], "--model opencv")?;
    Ok(ZhangOptions { model, flags })
}

/// The `--json` object of an opencv-family result.
fn opencv_json(z: &ZhangResult, images: &[PathBuf]) -> Value {
    let names = ["fx", "fy", "u0", "v0", "k1", "k2", "p1", "p2", "k3"];
    let std: serde_json::Map<String, Value> =
        names.iter().zip(&z.std).map(|(n, s)| (n.to_string(), json!(s))).collect();
    json!({"model": "opencv", "fx": z.fx, "fy": z.fy, "u0": z.u0, "v0": z.v0,
        "camera_matrix": z.camera_matrix(), "dist_coeffs": z.dist_coeffs(),
        "rms_px": z.rms_px, "views_used": z.views_used,
        "images_used": images.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
        "per_view_rms_px": z.per_view_rms_px, "std": std,
        "fix_k3": z.options.flags.fix_k3, "zero_tangent": z.options.flags.zero_tangent,
        "outliers": z.outliers.len()})
}

/// Runs `etlcal zhang`.
pub fn run(args: Args) -> Result<()> {
    let opts = options(&args)?;
    let board = args.board.board();
    let found = detect_views(&args.images, &board, &crate::progress::Bar::new(!args.json))?;
    for m in &found.skipped {
        eprintln!("etlcal: warning: skipped: {m}");
    }
    let (views, size) = (found.views, found.image_size);
    if views.len() < 3 {
        return Err(Error::BoardNotFound(format!(
            "the board was found in {} of {} images; Zhang's method needs at least 3",
            views.len(),
            args.images.len()
        )));
    }
    let z = zhang_with(&views, size, &opts)?;
    let [c0, c1, c2, c3, c4] = z.coefficients;
    if args.json {
        print_json(&match opts.model {
            // Today's keys exactly (the golden output of `zhang`).
            DistortionModel::Paper => json!({"fx": z.fx, "fy": z.fy, "u0": z.u0, "v0": z.v0, "k1": c0, "p1": c1,
                "p2": c2, "rms_px": z.rms_px, "views_used": z.views_used}),
            DistortionModel::OpenCv => opencv_json(&z, &found.images),
        });
        return Ok(());
    }
    outln!(
        "fx {:.3} +- {:.3}, fy {:.3} +- {:.3}, u0 {:.3} +- {:.3}, v0 {:.3} +- {:.3} px",
        z.fx,
        z.std[0],
        z.fy,
        z.std[1],
        z.u0,
        z.std[2],
        z.v0,
        z.std[3]
    );
    let (rms, n) = (z.rms_px, z.views_used);
    match opts.model {
        DistortionModel::Paper => outln!("k1 {c0:.4e}, p1 {c1:.4e}, p2 {c2:.4e}; rms {rms:.4} px over {n} views"),
        DistortionModel::OpenCv => {
            outln!("dist_coeffs (k1, k2, p1, p2, k3) {c0:.6}, {c1:.6}, {c2:.6}, {c3:.6}, {c4:.6}; rms {rms:.4} px over {n} views")
        }
    }
    Ok(())
}
