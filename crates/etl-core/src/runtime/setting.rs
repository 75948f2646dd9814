//! [`CameraAt`]: the camera at one setting, with everything a measurement needs.

use crate::error::Result;
use crate::model::{CameraModel, Distortion, Intrinsics, Ray};
use crate::pnp::{solve_pnp, BoardPose};

/// Which calibrated ranges a setting lies outside of (margins included).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Extrapolated {
    /// The temperature is outside the thermal calibration's range.
    pub temperature: bool,
    /// The driver current is outside the thermal calibration's E_in range.
    pub e_in: bool,
    /// The compensated current is outside the calibrated E_com range.
    pub e_com: bool,
    /// The focal power is outside the calibrated focal-power range (a focal-power
    /// calibration, [`SettingKind::FocalPower`]).
    pub focal_power: bool,
}

/// What a calibration's setting is: the quantity its polynomials (Eq. 15-18) are in.
///
/// A current calibration's setting is E_com, mA: the driver current compensated for the
/// lens's temperature by the calibration's thermal part (Eq. 7). A focal-power calibration's
/// is the focal power the Lens Driver 4 was commanded in its focal-power mode, dpt: the
/// driver's firmware compensates the temperature itself from the lens's EEPROM, so the
/// calibration has no thermal part. Its zero is not the lens off (the liquid lens has its
/// own power with no current), so its kf0 is fitted, not taken from the lens-off views.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SettingKind {
    /// E_com, mA.
    #[default]
    Current,
    /// Commanded focal power, dpt.
    FocalPower,
}

impl SettingKind {
    /// The file's and the messages' name: `"current"` or `"focal_power"`.
    pub const fn name(self) -> &'static str {
        match self {
            SettingKind::Current => "current",
            SettingKind::FocalPower => "focal_power",
        }
    }

    /// The setting's unit: `"mA"` or `"dpt"`.
    pub const fn unit(self) -> &'static str {
        match self {
            SettingKind::Current => "mA",
            SettingKind::FocalPower => "dpt",
        }
    }
}

impl Extrapolated {
    /// Inside every range.
    pub const NONE: Extrapolated = Extrapolated { temperature: false, e_in: false, e_com: false, focal_power: false };

    /// Whether any range was left.
    pub fn any(&self) -> bool {
        self.temperature || self.e_in || self.e_com || self.focal_power
    }
}

/// The camera at one setting: the setting (E_com, or a focal power), K there, the
/// distortion there, and the pose.
///
/// Built by [`super::Camera::at`] or [`super::Camera::at_focal_power`]; the methods are
/// those of [`CameraModel`] at [`Self::setting_value`], so they agree with it exactly.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraAt {
    model: CameraModel,
    kind: SettingKind,
    e_in_ma: f64,
    temperature_c: f64,
    /// E_com (mA) or the focal power (dpt), as `kind` says: the model's abscissa.
    setting: f64,
    intrinsics: Intrinsics,
    distortion: Distortion,
    flags: Extrapolated,
}

impl CameraAt {
    pub(super) fn new(
        model: &CameraModel,
        (kind, setting): (SettingKind, f64),
        e_in_ma: f64,
        temperature_c: f64,
        flags: Extrapolated,
    ) -> Result<Self> {
        let intrinsics = model.intrinsics(setting)?;
        let distortion = model.distortion(setting)?;
        Ok(CameraAt { model: *model, kind, e_in_ma, temperature_c, setting, intrinsics, distortion, flags })
    }

    /// Driver current, mA (NaN when built from a known E_com or a focal power).
    pub fn e_in_ma(&self) -> f64 {
        self.e_in_ma
    }
    /// Lens temperature, degC (NaN when built from a known E_com).
    pub fn temperature_c(&self) -> f64 {
        self.temperature_c
    }
    /// Compensated current E_com, mA (Eq. 7); NaN for a focal-power calibration's camera.
    pub fn e_com_ma(&self) -> f64 {
        match self.kind {
            SettingKind::Current => self.setting,
            SettingKind::FocalPower => f64::NAN,
        }
    }
    /// The commanded focal power, dpt; NaN for a current calibration's camera.
    pub fn focal_power_dpt(&self) -> f64 {
        match self.kind {
            SettingKind::Current => f64::NAN,
            SettingKind::FocalPower => self.setting,
        }
    }
    /// What the setting is ([`SettingKind`]).
    pub fn setting_kind(&self) -> SettingKind {
        self.kind
    }
    /// The setting the model is evaluated at: E_com in mA, or the focal power in dpt
    /// ([`Self::setting_kind`]); what [`CameraModel`]'s functions take as their `e_com_ma`.
    pub fn setting_value(&self) -> f64 {
        self.setting
    }
    /// fx, fy, u0, v0 at E_com (Eq. 16).
    pub fn intrinsics(&self) -> &Intrinsics {
        &self.intrinsics
    }
    /// k1, p1, p2 at E_com (Eq. 18).
    pub fn distortion(&self) -> &Distortion {
        &self.distortion
    }
    /// Which calibrated ranges this setting is outside of.
    pub fn flags(&self) -> Extrapolated {
        self.flags
    }
    /// Whether any calibrated range was left ([`super::Trust::Extrapolate`]).
    pub fn extrapolated(&self) -> bool {
        self.flags.any()
    }
    /// The camera model this setting was taken from.
    pub fn model(&self) -> &CameraModel {
        &self.model
    }

    /// World point (mm) -> observed pixel ([`CameraModel::project`]).
    pub fn project(&self, world_mm: [f64; 3]) -> Result<[f64; 2]> {
        self.model.project(world_mm, self.setting)
    }
    /// A point in this camera's own frame at this setting (mm: origin at the projection
    /// centre where the lens puts it, Eq. C2) -> observed pixel (Eq. 15, 17): the
    /// projection without the calibration's pose, as a rig uses it.
    pub fn project_camera_point(&self, camera_mm: [f64; 3]) -> Result<[f64; 2]> {
        crate::error::all_finite(&camera_mm, "camera_mm")?;
        crate::model::projection::project_camera_point(camera_mm, &self.intrinsics, &self.distortion)
    }
    /// The unit direction, in this camera's frame, of the ray of an observed pixel: the
    /// undistorted pixel back-projected through K at this setting.
    pub fn camera_ray(&self, pixel: [f64; 2]) -> Result<[f64; 3]> {
        let [x, y] = self.undistort_point(pixel)?;
        let k = &self.intrinsics;
        let d = [(x - k.u0) / k.fx, (y - k.v0) / k.fy, 1.0];
        let n = libm::sqrt(d[0] * d[0] + d[1] * d[1] + 1.0);
        Ok([d[0] / n, d[1] / n, 1.0 / n])
    }
    /// Observed pixel -> undistorted pixel ([`CameraModel::undistort`]).
    pub fn undistort_point(&self, pixel: [f64; 2]) -> Result<[f64; 2]> {
        self.model.undistort(pixel, self.setting)
    }
    /// Undistorts `pixels` into `out` (same length); on error `out` holds those before.
    pub fn undistort_points(&self, pixels: &[[f64; 2]], out: &mut [[f64; 2]]) -> Result<()> {
        if out.len() < pixels.len() {
            return Err(crate::Error::BufferTooSmall { what: "out", needed: pixels.len(), got: out.len() });
        }
        for (p, o) in pixels.iter().zip(out.iter_mut()) {
            *o = self.undistort_point(*p)?;
        }
        Ok(())
    }
    /// The world ray of a pixel ([`CameraModel::ray`]).
    pub fn ray(&self, pixel: [f64; 2]) -> Result<Ray> {
        self.model.ray(pixel, self.setting)
    }
    /// The pose of a planar board (points on its Z = 0) from its pixels ([`solve_pnp`]).
    pub fn solve_pnp(&self, board_mm: &[[f64; 3]], pixels: &[[f64; 2]]) -> Result<BoardPose> {
        solve_pnp(&self.model, self.setting, board_mm, pixels)
    }
}
