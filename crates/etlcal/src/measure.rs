//! `etlcal measure --calibration FILE --e-in MA --t C IMAGE_A IMAGE_B --pattern CxR
//! --square MM [--json]`: the board's pose in both images at the compensated current
//! (E_com from E_in and T through the calibration's thermal surface) by plane-based PnP,
//! and the displacement of the board between them, mm (the paper's measurement of a
//! stage move, section 5.2.3).

use std::path::PathBuf;

use etl_core::pnp::{displacement_mm, solve_pnp, BoardPose};
use etl_core::thermal::ThermalCalibration;
use serde_json::json;

use super::print_json;
use super::zhang::parse_pattern;
use etl_calib::pipeline::dataset::{default_detector, CornerDetector};
use etl_formats::calibration::Calibration;
use etl_formats::dataset::Board;
use etl_formats::{Error, Result};

/// How far outside the calibrated current range a measurement may go, mA.
pub const CURRENT_MARGIN_MA: f64 = 5.0;

/// Arguments of `etlcal measure`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// The calibration (etlcal.calibration/1).
    #[arg(long, value_name = "FILE")]
    pub calibration: PathBuf,
    /// Commanded lens current, mA.
    #[arg(long = "e-in", value_name = "MA")]
    pub e_in_ma: f64,
    /// Lens temperature, degC.
    #[arg(long = "t", value_name = "C")]
    pub temperature_c: f64,
    /// The image before the move.
    pub image_a: PathBuf,
    /// The image after the move.
    pub image_b: PathBuf,
    /// Inner corners, columns x rows (e.g. 14x12).
    #[arg(long, value_parser = parse_pattern)]
    pub pattern: [usize; 2],
    /// Side of a square, mm.
    #[arg(long, value_name = "MM")]
    pub square: f64,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

fn pose_json(p: &BoardPose) -> serde_json::Value {
    json!({"rotation_rodrigues": p.rotation_rodrigues, "translation_mm": p.translation_mm, "rms_px": p.rms_px})
}

/// Runs `etlcal measure`.
pub fn run(args: Args) -> Result<()> {
    let board = Board { inner_corners: args.pattern, square_mm: args.square };
    board.validate()?;
    let cal = Calibration::load(&args.calibration)?;
    let thermal = ThermalCalibration { surface: cal.thermal_surface(), ..ThermalCalibration::PAPER };
    let e_com = thermal.compensate(args.temperature_c, args.e_in_ma)?.e_com_ma;
    cal.check_current(e_com, CURRENT_MARGIN_MA)?;
    let model = cal.model();
    let det = default_detector();
    let mut poses = vec![];
    for path in [&args.image_a, &args.image_b] {
        std::fs::metadata(path).map_err(|source| Error::Io { path: path.clone(), source })?;
        let d = det.detect(path, board.inner_corners)?;
        if d.image_size != cal.image_size {
            return Err(Error::Image {
                path: path.clone(),
                message: format!(
                    "{} x {} px, the calibration is for {} x {}",
                    d.image_size[0], d.image_size[1], cal.image_size[0], cal.image_size[1]
                ),
            });
        }
        let sq = board.square_mm;
        let pts: Vec<[f64; 3]> = d.corners.iter().map(|(ij, _)| [ij[0] as f64 * sq, ij[1] as f64 * sq, 0.0]).collect();
        let px: Vec<[f64; 2]> = d.corners.iter().map(|c| c.1).collect();
        poses.push(solve_pnp(&model, e_com, &pts, &px)?);
    }
    let d = displacement_mm(&poses[0], &poses[1]);
    let dist = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if args.json {
        print_json(&json!({"e_com_ma": e_com, "pose_a": pose_json(&poses[0]), "pose_b": pose_json(&poses[1]),
            "displacement_mm": d, "distance_mm": dist}));
    } else {
        outln!("E_com {e_com:.3} mA");
        for (name, p) in ["A", "B"].iter().zip(&poses) {
            let t = p.translation_mm;
            outln!("pose {name}: T = [{:.4}, {:.4}, {:.4}] mm, rms {:.3} px", t[0], t[1], t[2], p.rms_px);
        }
        outln!("displacement [{:.4}, {:.4}, {:.4}] mm, distance {dist:.4} mm", d[0], d[1], d[2]);
    }
    Ok(())
}
