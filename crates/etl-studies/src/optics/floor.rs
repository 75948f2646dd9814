//! What any per-current central camera model can reach on a ray-traced rig, noise-free:
//! the floor under any figure a model of every current can reach on those optics.
//!
//! At each current, Zhang's method in OpenCV's family on that current's tilted views
//! (`setting_views`, traced without noise) calibrates a camera for that current alone,
//! which is the best a central model with a per-current centre, principal point and
//! distortion can do. The board is then traced on the stage 1 mm before and 1 mm behind
//! the position in focus, and the 2.000 mm move solved by planar PnP with that camera
//! (`super::measured_mm`). Everything runs twice, with the corners as:
//! - the spot's centroid ([`CornerAs::Centroid`], what the procedure records and a
//!   detector sees of a defocused, aberrated spot), and
//! - the chief ray's hit ([`CornerAs::Chief`], a central projection but for the pupil's
//!   own aberration).
//!
//! A model fitted to every current at once can do no better on the same data than the
//! per-current fit of its own family, so the centroid column bounds from below the error
//! of a 2 mm move for any central model, moving centre included; the chief column says
//! how much of that is the fan (defocus, coma, vignetting) rather than the pupil.
//!
//! Run: `cargo run --release -p etl-studies --example optics_floor` (docs/RESULTS.md).

use etl_calib::zhang::{zhang_with, PlanarView, ZhangOptions, ZhangResult};
use etl_core::model::{DistortionModel, OpenCvFlags};
use etl_formats::Result;
use etl_sim::optics::procedure::{board_view_as, setting_poses, CornerAs};
use etl_sim::optics::rig::Setting;
use etl_sim::optics::OpticalRig;

use super::{measured_mm, monofocal, planar, MOVE_MM};

/// The floor at one current, for one kind of corner.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Floor {
    /// RMS reprojection error of the per-current Zhang fit, px (noise-free data).
    pub rms_px: f64,
    /// Its fx, px.
    pub fx_px: f64,
    /// The error of the 2.000 mm move by PnP with it, um.
    pub move_error_um: f64,
}

/// The floors at one current.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FloorRow {
    /// The current, mA.
    pub e_com_ma: f64,
    /// The distance in focus, mm.
    pub distance_mm: f64,
    /// With the corners as spot centroids.
    pub centroid: Floor,
    /// With the corners as chief-ray hits.
    pub chief: Floor,
}

/// The study on one rig.
#[derive(Debug, Clone, PartialEq)]
pub struct CentralFloor {
    /// The rig's name (its optics file's).
    pub rig: String,
    /// Tilted views per current, and their largest tilt (degrees).
    pub views_per_current: usize,
    /// The largest tilt of those views, degrees.
    pub tilt_deg: f64,
    /// One row per current.
    pub rows: Vec<FloorRow>,
}

/// The floor at `setting` (its focus `distance_mm` found once for both kinds of corner:
/// the search is the costly part) with the corners as `corner`.
fn floor_at(rig: &OpticalRig, setting: &Setting, distance_mm: f64, corner: CornerAs) -> Result<Floor> {
    let p = &rig.file.procedure;
    let views: Vec<PlanarView> = setting_poses(&p.board, distance_mm, p.setting_views_per_current, p.setting_tilt_deg)
        .iter()
        .map(|pose| planar(&board_view_as(rig, setting, &p.board, pose, 0.0, corner)))
        .collect();
    let options = ZhangOptions { model: DistortionModel::OpenCv, flags: OpenCvFlags::NONE };
    let z: ZhangResult = zhang_with(&views, rig.file.sensor.size_px, &options)?;
    let stage_z = rig.stage_z_at_distance_mm(distance_mm);
    let at = |dz: f64| board_view_as(rig, setting, &p.board, &rig.stage_pose(), stage_z + dz, corner);
    let moved = measured_mm(&monofocal(&z)?, setting.e_ma, &[at(-MOVE_MM / 2.0), at(MOVE_MM / 2.0)])?;
    Ok(Floor { rms_px: z.rms_px, fx_px: z.fx, move_error_um: (moved - MOVE_MM) * 1000.0 })
}

/// The study on `rig` at `currents` (mA). Errors: a failed trace, Zhang fit or PnP.
pub fn central_floor(rig: &OpticalRig, currents: &[f64]) -> Result<CentralFloor> {
    let rows = currents
        .iter()
        .map(|&e| {
            let (setting, distance_mm) = (rig.at(e)?, rig.focus_distance_mm(e)?);
            let centroid = floor_at(rig, &setting, distance_mm, CornerAs::Centroid)?;
            let chief = floor_at(rig, &setting, distance_mm, CornerAs::Chief)?;
            Ok(FloorRow { e_com_ma: e, distance_mm, centroid, chief })
        })
        .collect::<Result<Vec<_>>>()?;
    let p = &rig.file.procedure;
    Ok(CentralFloor {
        rig: rig.file.name.clone(),
        views_per_current: p.setting_views_per_current,
        tilt_deg: p.setting_tilt_deg,
        rows,
    })
}

impl CentralFloor {
    /// The table as Markdown: one row per current.
    pub fn markdown(&self) -> String {
        let mut s = format!(
            "{} ({} tilted views per current up to {} degrees, noise-free): per-current Zhang (OpenCV's 5 \
             terms) and the {MOVE_MM:.3} mm move by PnP with it\n\n| E_com (mA) | distance in focus (mm) | \
             centroids: RMS (px) | fx (px) | move error (um) | chief rays: RMS (px) | fx (px) | move error \
             (um) |\n|---|---|---|---|---|---|---|---|\n",
            self.rig, self.views_per_current, self.tilt_deg
        );
        for r in &self.rows {
            let cells = |f: &Floor| format!("{:.4} | {:.1} | {:+.2}", f.rms_px, f.fx_px, f.move_error_um);
            s += &format!(
                "| {:.0} | {:.2} | {} | {} |\n",
                r.e_com_ma,
                r.distance_mm,
                cells(&r.centroid),
                cells(&r.chief)
            );
        }
        s
    }
}
