//! A rig of N >= 2 ETL cameras (`etlcal.rig/1`) at run time: load it ([`Rig::load`]), take
//! it at one setting and temperature per camera ([`Rig::at`] -> [`RigAt`]: each camera's
//! `CameraAt` and its pose relative to camera 0 at those settings), triangulate a point
//! seen by two or more cameras with its covariance ([`RigAt::triangulate`]), and rectify a
//! pair with maps exact to the model ([`RigAt::stereo_rectify`]).
//!
//! The pose follows the settings: each camera's projection centre moves along its own +Z
//! by dz(E) (Eq. C1), so the file's pose (R_k, T_k), which holds at its
//! `reference_setting` (E_0,ref, E_k,ref), becomes at (E_0, E_k)
//!
//! ```text
//! T_k(E_0, E_k) = T_k + (dz_0(E_0) - dz_0(E_0,ref)) R_k e_z - (dz_k(E_k) - dz_k(E_k,ref)) e_z
//! ```
//!
//! with R_k unchanged (derivation: [`etl_core::runtime::rig`]). A setting is each
//! calibration's own: the driver current E_in (mA, with the lens temperature: E_com by the
//! calibration's thermal part) or the commanded focal power (dpt) ([`RigSetting`]).

mod at;
mod export;
mod rectify;

mod setting;
mod triangulate;

use std::path::Path;

use etl_core::runtime::rig::RigPose;
use etl_formats::calibration::Calibration;
use etl_formats::rig::{RigExtrinsics, RigFile};
use etl_formats::{Camera, Error, Result, Trust};

pub use at::RigAt;
pub use export::{maps_files, write_files, ExportFile};
pub use rectify::{StereoRectification, StereoRectifyMaps};

pub use setting::RigSetting;
pub use triangulate::{CalibrationCovariance, CalibrationPart, Triangulated};

/// A calibrated rig: the file, each camera's calibration and run-time camera.
#[derive(Debug, Clone)]
pub struct Rig {
    file: RigFile,
    calibrations: Vec<Calibration>,
    cameras: Vec<Camera>,
}

impl Rig {
    /// Reads and checks `etlcal.rig/1` at `path`, its calibrations loaded (relative paths
    /// from the file's directory). Errors: those of the format's reader, one line naming
    /// the key (a missing calibration among them).
    pub fn load(path: &Path) -> Result<Self> {
        let r = RigFile::load(path)?;
        Rig::new(r.file, r.calibrations)
    }

    /// The rig of `file`, its calibration paths relative to `dir`; checked as by the reader.
    pub fn from_file(file: RigFile, dir: &Path) -> Result<Self> {
        // `validate` resolves paths from the rig file's directory and names the file in
        // its messages: the file is in memory, so it is named by its directory.
        let calibrations = file.validate(&dir.join("(rig in memory)"))?;
        Rig::new(file, calibrations)
    }

    fn new(file: RigFile, calibrations: Vec<Calibration>) -> Result<Self> {
        let cameras = calibrations.iter().map(Calibration::camera).collect::<Result<Vec<_>>>()?;
        Ok(Rig { file, calibrations, cameras })
    }

    /// Number of cameras.
    pub fn len(&self) -> usize {
        self.cameras.len()
    }

    /// Never empty (at least 2 cameras); for the `len`/`is_empty` convention.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The file.
    pub fn file(&self) -> &RigFile {
        &self.file
    }

    /// Camera `k`'s calibration.
    pub fn calibration(&self, k: usize) -> Option<&Calibration> {
        self.calibrations.get(k)
    }

    /// The cameras' calibrations in order.
    pub fn calibrations(&self) -> &[Calibration] {
        &self.calibrations
    }

    /// Camera `k`'s name.
    pub fn name(&self, k: usize) -> &str {
        self.file.cameras.get(k).map_or("", |c| c.name.as_str())
    }

    /// Camera `k`'s pose relative to camera 0 as the file gives it (camera 0: None).
    pub fn extrinsics(&self, k: usize) -> Option<&RigExtrinsics> {
        self.file.extrinsics_of(k)
    }

    /// The rig at `settings` and `temperatures_c`, one of each per camera in the cameras'
    /// order, each setting in its calibration's own unit ([`RigSetting`]): every camera's
    /// `CameraAt` (refused outside its calibrated ranges unless `trust` is
    /// [`Trust::Extrapolate`]) and its pose at these settings.
    ///
    /// Errors (one line naming the camera): a count that is not the number of cameras
    /// (`"settings"`, `"temperatures_c"`), a setting of the other kind than the
    /// calibration's (`"settings"`), and each camera's own.
    pub fn at(&self, settings: &[RigSetting], temperatures_c: &[f64], trust: Trust) -> Result<RigAt> {
        let n = self.len();
        for (key, got) in [("settings", settings.len()), ("temperatures_c", temperatures_c.len())] {
            if got != n {
                return Err(Error::invalid(key, format!("{key}: the rig has {n} cameras, got {got} (one per camera)")));
            }
        }
        let mut cameras = Vec::with_capacity(n);
        for (k, (s, &t)) in settings.iter().zip(temperatures_c).enumerate() {
            let at = s.camera_at(&self.cameras[k], t, trust).map_err(|e| self.name_camera(k, e))?;
            cameras.push(at);
        }
        let poses = (0..n).map(|k| self.pose_at(k, &cameras)).collect();
        Ok(RigAt::new(self, cameras, poses))
    }

    /// The error `e` with camera `k` named.
    fn name_camera(&self, k: usize, e: Error) -> Error {
        e.within(format!("camera {k} ({})", self.name(k)), None)
    }

    /// Camera `k`'s pose relative to camera 0 at the cameras' settings (Eq. R2 of
    /// [`etl_core::runtime::rig`]; camera 0's is the identity).
    fn pose_at(&self, k: usize, cameras: &[etl_formats::CameraAt]) -> RigPose {
        let Some(e) = self.extrinsics(k) else { return RigPose::IDENTITY };
        let pose = RigPose::from_rodrigues(e.rotation_rodrigues, e.translation_mm);
        let Some([ref0, refk]) = e.reference_setting else { return pose };
        let shift = |c: usize, reference: f64| {
            let at = &cameras[c];
            etl_core::runtime::rig::centre_shift_mm(at.model(), at.setting_value(), reference)
        };
        pose.at_settings(shift(0, ref0), shift(k, refk))
    }
}
