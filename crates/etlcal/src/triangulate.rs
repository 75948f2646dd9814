//! `etlcal triangulate --rig RIG.json --setting S... --t C... (--pixels FILE.json |
//! --pixel CAM:U,V ...) [--sigma-px PX] [--pixel-only] [--allow-extrapolation] [--json]`:
//! points seen by two or more cameras of a rig at one setting per camera
//! (`etl_calib::rig`), with their covariance.
//!
//! `--pixel CAM:U,V` (repeated: one point, CAM a camera's index or name) or `--pixels
//! FILE.json`: a JSON array of points, each an array with one entry per camera in the
//! rig's order, `[u, v]` (px) or `null` where the camera does not see it:
//! `[[[1010.5, 702.25], [871.0, 698.5]], [[400.0, 300.0], null, [380.5, 296.0]]]`.
//!
//! The point is the least-squares triangulation through every camera's full model, in
//! camera 0's frame at its setting (mm). Its covariance is the pixel noise's
//! (`--sigma-px`, per coordinate, default 0.1 px, printed with the result) plus the
//! calibration's, propagated to the point: from the rig file's `joint_covariance` when it
//! has one (a rig from `calibrate-rig`: every camera's numbers together, cross-covariances
//! kept), else each used camera's model numbers (its file's `covariance`) and pose (the
//! rig file's) as independent groups, which over-states the depth sigma of a rig
//! calibrated jointly. A calibration or pose without a covariance is refused (independent
//! groups) unless `--pixel-only` leaves that part out.
//!
//! Output per point: `point_mm`, `covariance_mm2`, `std_mm` (the square roots of its
//! diagonal), `from_pixels_mm2`, `from_calibration_mm2` (null with `--pixel-only`),
//! `calibration_covariance` (`"joint"` or `"independent"`, null with `--pixel-only`),
//! `cameras_used`, `rms_px`, `extrapolated`; `--json` wraps them as `{"points": [...],
//! "sigma_px", "pixel_only", "rig", "cameras", "extrapolated"}`.

use std::path::PathBuf;

use etl_calib::rig::{CalibrationPart, RigAt, Triangulated};
use etl_formats::{Error, Result};
use serde_json::{json, Value};

use super::print_json;
use crate::rig_setting::RigArgs;

/// Arguments of `etlcal triangulate`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
#[command(group(clap::ArgGroup::new("observed").required(true).args(["pixels", "pixel"])))]
pub struct Args {
    /// The rig and its settings.
    #[command(flatten)]
    pub rig: RigArgs,
    /// The points' pixels: a JSON array of points, each one entry per camera ([u, v] or
    /// null).
    #[arg(long, value_name = "FILE.json")]
    pub pixels: Option<PathBuf>,
    /// One point's pixel in one camera, CAM:U,V (CAM the camera's index or name);
    /// repeated for each camera that sees it.
    #[arg(long, value_name = "CAM:U,V")]
    pub pixel: Vec<String>,
    /// The pixel noise, px per coordinate (the covariance's pixel part).
    #[arg(long, value_name = "PX", default_value_t = 0.1)]
    pub sigma_px: f64,
    /// Leave the calibration's part of the covariance out (required when a calibration or
    /// pose has no covariance).
    #[arg(long)]
    pub pixel_only: bool,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// The camera `cam` names (an index or a name).
fn camera_index(at: &RigAt, cam: &str) -> Option<usize> {
    let names: Vec<&str> = (0..at.len()).map(|k| at.name(k)).collect();
    crate::rig_setting::camera_index(&names, cam)
}

/// One point from `--pixel CAM:U,V ...`.
fn point_of_flags(at: &RigAt, flags: &[String]) -> Result<Vec<Option<[f64; 2]>>> {
    let mut point = vec![None; at.len()];
    for f in flags {
        let bad = |why: &str| Error::invalid_value("--pixel", f.as_str(), format!("--pixel {f:?}: {why}"));
        let (cam, uv) = f.split_once(':').ok_or_else(|| bad("give CAM:U,V"))?;
        let k = camera_index(at, cam).ok_or_else(|| bad("CAM is not a camera of the rig (an index or a name)"))?;
        let parsed: Vec<f64> = uv
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| bad("U,V must be two numbers"))?;
        let [u, v] = parsed[..] else { return Err(bad("U,V must be two numbers")) };
        if point[k].is_some() {
            return Err(bad("a camera given twice"));
        }
        point[k] = Some([u, v]);
    }
    Ok(point)
}

/// The points of a `--pixels` file.
fn points_of_file(path: &std::path::Path, cameras: usize) -> Result<Vec<Vec<Option<[f64; 2]>>>> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io { path: path.to_owned(), source })?;
    let points: Vec<Vec<Option<[f64; 2]>>> = serde_json::from_str(&text).map_err(|e| Error::Parse {
        path: path.to_owned(),
        message: format!("a JSON array of points, each one [u, v] or null per camera: {e}"),
    })?;
    if let Some((i, p)) = points.iter().enumerate().find(|(_, p)| p.len() != cameras) {
        return Err(Error::Parse {
            path: path.to_owned(),
            message: format!(
                "[{i}]: {} entries, the rig has {cameras} cameras (one per camera, null where unseen)",
                p.len()
            ),
        });
    }
    Ok(points)
}

fn point_json(t: &Triangulated) -> Value {
    json!({
        "point_mm": t.point_mm, "covariance_mm2": t.covariance_mm2, "std_mm": t.std_mm(),
        "from_pixels_mm2": t.from_pixels, "from_calibration_mm2": t.from_calibration,
        "calibration_covariance": t.calibration_covariance.map(|c| c.as_str()),
        "cameras_used": t.cameras_used, "rms_px": t.rms_px, "extrapolated": t.extrapolated,
    })
}

/// Runs `etlcal triangulate`.
pub fn run(args: Args) -> Result<()> {
    crate::output::check([Some(args.rig.rig.as_path()), args.pixels.as_deref()], &[])?;
    let (_, at) = args.rig.rig_at()?;
    let points = match &args.pixels {
        Some(path) => points_of_file(path, at.len())?,
        None => vec![point_of_flags(&at, &args.pixel)?],
    };
    let part = if args.pixel_only { CalibrationPart::PixelOnly } else { CalibrationPart::Include };
    let results: Vec<Triangulated> = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            at.triangulate(p, args.sigma_px, part).map_err(|e| {
                let e = e.rename_input("sigma_px", "--sigma-px");
                if points.len() > 1 {
                    e.within(format!("point {i}"), None)
                } else {
                    e
                }
            })
        })
        .collect::<Result<_>>()?;
    if args.json {
        let mut j = args.rig.json(&at);
        j["points"] = results.iter().map(point_json).collect();
        j["sigma_px"] = json!(args.sigma_px);
        j["pixel_only"] = json!(args.pixel_only);
        print_json(&j);
        return Ok(());
    }
    let part = if args.pixel_only { "pixel noise only" } else { "pixel noise and calibration" };
    for (i, t) in results.iter().enumerate() {
        let [x, y, z] = t.point_mm;
        let [sx, sy, sz] = t.std_mm();
        outln!(
            "point {i}: ({x:.4}, {y:.4}, {z:.4}) mm +- ({sx:.4}, {sy:.4}, {sz:.4}) mm ({part}, sigma {} px); rms {:.4} px over cameras {:?}{}",
            args.sigma_px,
            t.rms_px,
            t.cameras_used,
            if t.extrapolated { "; EXTRAPOLATED" } else { "" }
        );
    }
    Ok(())
}
