//! What a traced rig is at each current, for the files `etlcal simulate --optics` writes
//! beside its observations (`truth.json`, format `etlcal.optics-truth/1`): the paraxial
//! focal length of the centred system, the entrance pupil (the pinhole's centre of a
//! camera model, which moves along the axis with the ETL's power: docs/METHOD.md), the
//! distance in focus and the stage position of the ETL view.

use etl_formats::Result;
use serde::Serialize;

use super::paraxial::focal_length_mm;
use super::OpticalRig;

/// The format key of the truth file.
pub const TRUTH_FORMAT: &str = "etlcal.optics-truth/1";

/// The centred rig at one current.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SettingTruth {
    /// The current, mA.
    pub e_com_ma: f64,
    /// The effective focal length, mm (paraxial, centred system).
    pub focal_length_mm: f64,
    /// The same in pixels of the sensor: focal_length_mm / pixel pitch.
    pub focal_length_px: f64,
    /// The entrance pupil's position on the axis in the camera frame, mm (z towards the
    /// object, origin at the ETL's rim plane: negative behind it).
    pub entrance_pupil_z_mm: f64,
    /// The distance in focus (the smallest traced spot), camera z, mm.
    pub focus_distance_mm: f64,
    /// The stage position of the ETL view at this current, mm.
    pub stage_z_mm: f64,
}

/// The truth of every current of the rig's procedure, in its order. Errors: a singular
/// system or a failed trace at some current, naming the surface.
pub fn setting_truths(rig: &OpticalRig) -> Result<Vec<SettingTruth>> {
    let pitch = rig.file.sensor.pixel_pitch_mm;
    rig.file
        .procedure
        .e_com_ma
        .iter()
        .map(|&e| {
            let f = focal_length_mm(&rig.file.centred_surfaces(e))?;
            let focus_distance_mm = rig.focus_distance_mm(e)?;
            Ok(SettingTruth {
                e_com_ma: e,
                focal_length_mm: f,
                focal_length_px: f / pitch,
                // The tracer's lens frame has z towards the sensor (rig module docs).
                entrance_pupil_z_mm: -rig.at(e)?.pupil.z_mm,
                focus_distance_mm,
                stage_z_mm: rig.stage_z_at_distance_mm(focus_distance_mm),
            })
        })
        .collect()
}
