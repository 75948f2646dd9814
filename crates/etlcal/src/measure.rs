//! `etlcal measure --calibration FILE (--e-in MA --t C | --e-com MA) IMAGE_A IMAGE_B
//! (--pattern CxR --square MM | --board FILE) [--allow-extrapolation] [--json]`: the board's
//! pose in both images (a ChArUco board from the corners each image shows) at the
//! compensated current (E_com from E_in and T through the calibration's thermal part, or
//! given; refused outside the calibrated ranges unless extrapolation is asked for) by
//! plane-based PnP,
//! and the displacement of the board between them, mm (the paper's measurement of a
//! stage move, section 5.2.3), with one standard deviation per component from the pixel
//! noise (estimated from each PnP's residual) and the calibration's covariance together
//! (`--json` keys `displacement_mm`, `displacement_std_mm`, `distance_mm`; each pose's
//! `sigma_px`). A calibration file without a covariance gives the pixel noise's part alone,
//! said on stderr and by `"std_includes_calibration": false`.

use std::path::PathBuf;

use etl_core::pnp::{BoardPose, PoseUncertainty};
use serde_json::json;

use super::print_json;
use crate::board::BoardArgs;
use crate::setting::SettingArgs;
use etl_calib::pipeline::dataset::default_detector;
use etl_calib::pipeline::measure::measure_displacement;
use etl_formats::Result;

/// Arguments of `etlcal measure`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// The calibration and the setting both images were taken at.
    #[command(flatten)]
    pub setting: SettingArgs,
    /// The image before the move.
    pub image_a: PathBuf,
    /// The image after the move.
    pub image_b: PathBuf,
    /// The board.
    #[command(flatten)]
    pub board: BoardArgs,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

fn pose_json(p: &BoardPose, u: &PoseUncertainty) -> serde_json::Value {
    json!({"rotation_rodrigues": p.rotation_rodrigues, "translation_mm": p.translation_mm, "rms_px": p.rms_px,
        "sigma_px": u.sigma_px})
}

/// Runs `etlcal measure`: [`measure_displacement`] with the default detector.
pub fn run(args: Args) -> Result<()> {
    let board = args.board.board()?;
    let at = &args.setting;
    let (cal, camera) = at.camera()?;
    let images = [args.image_a.as_path(), args.image_b.as_path()];
    let m = measure_displacement(&cal, &camera, &board, images, &default_detector())?;
    let (d, dist, e_com, s) = (m.displacement_mm, m.distance_mm, m.e_com_ma, m.displacement_std_mm);
    if !m.std_includes_calibration {
        eprintln!(
            "etlcal: warning: {} has no covariance: displacement_std_mm is from the pixel noise alone",
            at.calibration.display()
        );
    }
    let [ua, ub] = &m.pose_uncertainty;
    if args.json {
        print_json(&json!({"e_com_ma": e_com, "pose_a": pose_json(&m.poses[0], ua),
            "pose_b": pose_json(&m.poses[1], ub), "displacement_mm": d, "displacement_std_mm": s,
            "std_includes_calibration": m.std_includes_calibration, "distance_mm": dist,
            "extrapolated": m.extrapolated}));
    } else {
        outln!(
            "E_com {e_com:.3} mA{}",
            if m.extrapolated { " (EXTRAPOLATED: outside the calibrated ranges)" } else { "" }
        );
        for (name, p) in ["A", "B"].iter().zip(&m.poses) {
            let t = p.translation_mm;
            outln!("pose {name}: T = [{:.4}, {:.4}, {:.4}] mm, rms {:.3} px", t[0], t[1], t[2], p.rms_px);
        }
        outln!("displacement [{:.4}, {:.4}, {:.4}] mm, distance {dist:.4} mm", d[0], d[1], d[2]);
        outln!("displacement std [{:.4}, {:.4}, {:.4}] mm (one sigma per component)", s[0], s[1], s[2]);
    }
    Ok(())
}
