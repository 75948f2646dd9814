//! The run-time camera: a calibration as a vision service uses it, thousands of times a
//! second. Read the lens current and temperature, get the camera at that setting
//! ([`Camera::at`]), then project, undistort, cast rays or solve PnP on it.
//!
//! Named `runtime` for when it is used: [`crate::model`] holds the camera model being
//! calibrated (its numbers and projection), this module the calibrated camera at run time,
//! with the ranges it can be trusted over ([`Trust`]) and its state at one lens setting
//! ([`CameraAt`]).
//!
//! ```
//! use etl_core::runtime::{Camera, ThermalTrust, Trust};
//! use etl_core::model::CameraModel;
//! use etl_core::thermal::ThermalCalibration;
//!
//! let thermal = ThermalTrust::from_calibration(&ThermalCalibration::PAPER);
//! let cam = Camera::new(CameraModel::paper_rig(), Some(thermal), [80.0, 225.0])?;
//! let at = cam.at(150.0, 30.0)?; // E_in = 150 mA at 30 degC
//! assert!(!at.extrapolated());
//! let px = at.project([3.0, 4.5, 22.0])?;
//! assert!(px[0] > 0.0 && px[0] < 1936.0);
//! // 80 degC is outside the calibrated 27..37 degC (+- 1): refused unless asked for.
//! assert!(cam.at(150.0, 80.0).is_err());
//! assert!(cam.at_with(150.0, 39.0, Trust::Extrapolate)?.flags().temperature);
//! # Ok::<(), etl_core::Error>(())
//! ```

pub mod rig;
mod setting;
mod trust;

pub use setting::{CameraAt, Extrapolated, SettingKind};
pub use trust::{ThermalTrust, Trust, E_COM_MARGIN_MA, E_IN_MARGIN_MA, FOCAL_POWER_MARGIN_DPT, T_MARGIN_C};

use crate::error::{Error, Result};
use crate::model::CameraModel;

/// A calibrated ETL camera with the ranges its calibration can be trusted over.
///
/// Invariants (checked by [`Camera::new`] and [`Camera::new_focal_power`], the constructors
/// of the two kinds of setting, [`SettingKind`]): the model's numbers are finite; the
/// setting's range is finite and ordered; the thermal part, if any, is valid (a focal-power
/// camera has none: the driver compensates the temperature); a temperature range, if any,
/// is finite and ordered. The fields are private so that a `Camera` is always one that
/// passed these checks.
/// `Camera` is `Copy`, `Send` and `Sync` and holds no reference: share it between threads
/// freely.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    model: CameraModel,
    kind: SettingKind,
    thermal: Option<ThermalTrust>,
    /// E_com range (mA) or focal-power range (dpt), as `kind` says.
    setting_range: [f64; 2],
    /// The temperatures a focal-power calibration's views were taken at, degC.
    focal_power_t_range_c: Option<[f64; 2]>,
}

impl Camera {
    /// A camera of `model`, compensated by `thermal` (None: the calibration has no
    /// temperature compensation, and only [`Camera::at_e_com`] can be used), calibrated over
    /// compensated currents `e_com_range_ma` = [min, max] mA.
    pub fn new(model: CameraModel, thermal: Option<ThermalTrust>, e_com_range_ma: [f64; 2]) -> Result<Self> {
        model.validate()?;
        let [lo, hi] = e_com_range_ma;
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return Err(Error::InvalidArgument { what: "e_com_range_ma must be a finite [min, max]" });
        }
        if let Some(t) = &thermal {
            t.validate()?;
        }
        let kind = SettingKind::Current;
        Ok(Camera { model, kind, thermal, setting_range: e_com_range_ma, focal_power_t_range_c: None })
    }

    /// A camera of `model` whose setting is the commanded focal power ([`SettingKind`]),
    /// calibrated over `focal_power_range_dpt` = [min, max] dpt from views taken at
    /// lens temperatures `t_range_c` = [min, max] degC (None: not known, so every
    /// temperature is outside it and only [`Trust::Extrapolate`] uses the camera).
    pub fn new_focal_power(
        model: CameraModel,
        focal_power_range_dpt: [f64; 2],
        t_range_c: Option<[f64; 2]>,
    ) -> Result<Self> {
        model.validate()?;
        let ordered = |[lo, hi]: [f64; 2]| lo.is_finite() && hi.is_finite() && lo <= hi;
        if !ordered(focal_power_range_dpt) {
            return Err(Error::InvalidArgument { what: "focal_power_range_dpt must be a finite [min, max]" });
        }
        if !t_range_c.is_none_or(ordered) {
            return Err(Error::InvalidArgument { what: "t_range_c must be a finite [min, max]" });
        }
        Ok(Camera {
            model,
            kind: SettingKind::FocalPower,
            thermal: None,
            setting_range: focal_power_range_dpt,
            focal_power_t_range_c: t_range_c,
        })
    }

    /// What the camera's setting is: E_com or the focal power ([`SettingKind`]).
    pub fn setting_kind(&self) -> SettingKind {
        self.kind
    }

    /// The camera model (the numbers of Eq. 13-18, in its layout).
    pub fn model(&self) -> &CameraModel {
        &self.model
    }

    /// The temperature compensation and its calibrated ranges, if the calibration has one.
    pub fn thermal(&self) -> Option<&ThermalTrust> {
        self.thermal.as_ref()
    }

    /// The calibrated E_com range, [min, max] mA (a focal-power camera's: its
    /// focal-power range in dpt, [`Self::setting_range`]).
    pub fn e_com_range_ma(&self) -> [f64; 2] {
        self.setting_range
    }

    /// The calibrated range of the setting, [min, max] in its unit ([`SettingKind::unit`]).
    pub fn setting_range(&self) -> [f64; 2] {
        self.setting_range
    }

    /// The camera at driver current `e_in_ma` and lens temperature `temperature_c`:
    /// E_com = E_in - E_T(T, E_in) (Eq. 7), then K(E_com) (Eq. 15-16) and the distortion
    /// (Eq. 18). Refuses ([`Error::OutOfRange`] naming `temperature_c`, `e_in_ma` or
    /// `e_com_ma`) a setting outside the calibrated ranges by more than their margins
    /// ([`T_MARGIN_C`], [`E_IN_MARGIN_MA`], [`E_COM_MARGIN_MA`]); see [`Self::at_with`].
    pub fn at(&self, e_in_ma: f64, temperature_c: f64) -> Result<CameraAt> {
        self.at_with(e_in_ma, temperature_c, Trust::Refuse)
    }

    /// As [`Self::at`], with the out-of-range policy chosen by the caller:
    /// [`Trust::Extrapolate`] returns the camera outside the calibrated ranges (never outside
    /// the lens's operating domain) with [`CameraAt::flags`] saying which range was left.
    /// Errors: no thermal part in the calibration ([`Error::InvalidArgument`]); the
    /// temperature is checked first, then E_in, then E_com.
    pub fn at_with(&self, e_in_ma: f64, temperature_c: f64, trust: Trust) -> Result<CameraAt> {
        self.require(SettingKind::Current)?;
        let Some(thermal) = &self.thermal else {
            return Err(Error::InvalidArgument {
                what: "this calibration has no temperature compensation: use at_e_com with a known E_com",
            });
        };
        let (e_t_ma, mut flags) = thermal.e_t_ma(e_in_ma, temperature_c, trust)?;
        let e_com_ma = crate::error::finite(e_in_ma - e_t_ma, "e_com_ma")?;
        flags.e_com = self.check_e_com(e_com_ma, trust)?;
        CameraAt::new(&self.model, (SettingKind::Current, e_com_ma), e_in_ma, temperature_c, flags)
    }

    /// The camera at a known compensated current `e_com_ma` (temperature unknown or
    /// already compensated): the E_com range is checked as in [`Self::at_with`].
    pub fn at_e_com(&self, e_com_ma: f64, trust: Trust) -> Result<CameraAt> {
        self.require(SettingKind::Current)?;
        crate::error::finite(e_com_ma, "e_com_ma")?;
        let flags = Extrapolated { e_com: self.check_e_com(e_com_ma, trust)?, ..Extrapolated::NONE };
        CameraAt::new(&self.model, (SettingKind::Current, e_com_ma), f64::NAN, f64::NAN, flags)
    }

    /// The camera of a focal-power calibration at commanded focal power `focal_power_dpt`
    /// and lens temperature `temperature_c` (the driver's firmware compensated it: the
    /// temperature only decides whether the calibration can be trusted there). Refuses
    /// ([`Error::OutOfRange`] naming `temperature_c` or `focal_power_dpt`) a temperature
    /// outside the views' range by more than [`T_MARGIN_C`] (or outside the lens's
    /// operating domain) and a power outside the calibrated range by more than
    /// [`FOCAL_POWER_MARGIN_DPT`]; the temperature is checked first, as in [`Self::at`].
    pub fn at_focal_power(&self, focal_power_dpt: f64, temperature_c: f64) -> Result<CameraAt> {
        self.at_focal_power_with(focal_power_dpt, temperature_c, Trust::Refuse)
    }

    /// As [`Self::at_focal_power`], with the out-of-range policy chosen by the caller
    /// ([`Self::at_with`]). Errors: a current calibration ([`Error::InvalidArgument`]).
    pub fn at_focal_power_with(&self, focal_power_dpt: f64, temperature_c: f64, trust: Trust) -> Result<CameraAt> {
        self.require(SettingKind::FocalPower)?;
        crate::error::finite(temperature_c, "temperature_c")?;
        let [t0, t1] = crate::thermal::T_DOMAIN_C;
        if !(t0..=t1).contains(&temperature_c) {
            return Err(Error::OutOfRange { what: "temperature_c", value: temperature_c, min: t0, max: t1 });
        }
        let temperature = match self.focal_power_t_range_c {
            Some(r) => trust::check("temperature_c", temperature_c, r, T_MARGIN_C, trust)?,
            None if trust == Trust::Extrapolate => true,
            None => {
                return Err(Error::InvalidArgument {
                    what: "this focal-power calibration records no temperature range: extrapolate explicitly",
                })
            }
        };
        let power =
            trust::check("focal_power_dpt", focal_power_dpt, self.setting_range, FOCAL_POWER_MARGIN_DPT, trust)?;
        let flags = Extrapolated { temperature, focal_power: power, ..Extrapolated::NONE };
        CameraAt::new(&self.model, (SettingKind::FocalPower, focal_power_dpt), f64::NAN, temperature_c, flags)
    }

    /// The temperatures a focal-power calibration's views were taken at, [min, max] degC
    /// (None for a current calibration, whose thermal part has its own).
    pub fn focal_power_t_range_c(&self) -> Option<[f64; 2]> {
        self.focal_power_t_range_c
    }

    /// An error naming the other way in unless the camera's setting is `kind`.
    fn require(&self, kind: SettingKind) -> Result<()> {
        match (self.kind, kind) {
            (a, b) if a == b => Ok(()),
            (SettingKind::FocalPower, _) => Err(Error::InvalidArgument {
                what: "this calibration's setting is the focal power (dpt): use at_focal_power, not a current",
            }),
            (SettingKind::Current, _) => Err(Error::InvalidArgument {
                what: "this calibration's setting is the lens current (mA): use at or at_e_com, not a focal power",
            }),
        }
    }

    /// Whether `e_com_ma` is outside the calibrated range widened by [`E_COM_MARGIN_MA`];
    /// an error if it is and `trust` refuses.
    fn check_e_com(&self, e_com_ma: f64, trust: Trust) -> Result<bool> {
        let [lo, hi] = self.setting_range;
        trust::check("e_com_ma", e_com_ma, [lo, hi], E_COM_MARGIN_MA, trust)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::thermal::{ThermalCalibration, ThermalSurface};

    fn paper() -> Camera {
        Camera::new(
            CameraModel::paper_rig(),
            Some(ThermalTrust::from_calibration(&ThermalCalibration::PAPER)),
            [80.0, 225.0],
        )
        .unwrap()
    }

    #[test]
    fn at_is_the_model_at_the_compensated_current() {
        let cam = paper();
        let at = cam.at(150.0, 32.0).unwrap();
        let e_com = ThermalSurface::PAPER.e_com_ma(150.0, 32.0).unwrap();
        assert_eq!(at.e_com_ma(), e_com);
        assert_eq!(*at.intrinsics(), CameraModel::paper_rig().intrinsics(e_com).unwrap());
        let w = [4.5, 6.0, 22.0];
        assert_eq!(at.project(w).unwrap(), CameraModel::paper_rig().project(w, e_com).unwrap());
        let px = at.project(w).unwrap();
        let ray = at.ray(px).unwrap();
        let s = (0..3).map(|i| (w[i] - ray.origin_mm[i]).powi(2)).sum::<f64>().sqrt();
        let back = ray.at(s);
        assert!((0..3).all(|i| (back[i] - w[i]).abs() < 1e-6), "{back:?}");
        assert!(!at.extrapolated());
    }

    /// Each quantity is named when it is the one out of range; the temperature first.
    #[test]
    fn out_of_range_names_the_quantity() {
        let cam = paper();
        let what = |r: Result<CameraAt>| match r {
            Err(Error::OutOfRange { what, .. }) => what,
            other => panic!("{other:?}"),
        };
        assert_eq!(what(cam.at(150.0, 80.0)), "temperature_c");
        assert_eq!(what(cam.at(300.0, 80.0)), "temperature_c");
        assert_eq!(what(cam.at(250.0, 30.0)), "e_in_ma");
        // E_in = 60 mA is inside the thermal range (40..240) but E_com ~ 60 is below 80 - 5.
        assert_eq!(what(cam.at(60.0, 30.0)), "e_com_ma");
        // Just inside the margins.
        assert!(cam.at(150.0, 37.9).is_ok());
        assert!(cam.at(150.0, 38.1).is_err());
        assert!(matches!(cam.at(f64::NAN, 30.0), Err(Error::NotFinite { .. })));
    }

    #[test]
    fn extrapolation_is_explicit_and_marked() {
        let cam = paper();
        let at = cam.at_with(60.0, 40.0, Trust::Extrapolate).unwrap();
        assert_eq!(at.flags(), Extrapolated { temperature: true, e_in: false, e_com: true, focal_power: false });
        // The operating domain still binds: 300 degC is not a lens temperature.
        assert!(matches!(cam.at_with(150.0, 300.0, Trust::Extrapolate), Err(Error::OutOfRange { .. })));
        let inside = cam.at_with(150.0, 30.0, Trust::Extrapolate).unwrap();
        assert!(!inside.extrapolated());
    }

    #[test]
    fn unknown_ranges_and_missing_thermal() {
        let t = ThermalTrust { surface: ThermalSurface::PAPER, t_range_c: None, e_in_range_ma: None };
        let cam = Camera::new(CameraModel::paper_rig(), Some(t), [80.0, 225.0]).unwrap();
        assert!(matches!(cam.at(150.0, 30.0), Err(Error::InvalidArgument { .. })));
        assert!(cam.at_with(150.0, 30.0, Trust::Extrapolate).unwrap().flags().temperature);
        let bare = Camera::new(CameraModel::paper_rig(), None, [80.0, 225.0]).unwrap();
        assert!(matches!(bare.at(150.0, 30.0), Err(Error::InvalidArgument { .. })));
        let at = bare.at_e_com(150.0, Trust::Refuse).unwrap();
        assert_eq!(at.e_com_ma(), 150.0);
        assert!(bare.at_e_com(400.0, Trust::Refuse).is_err());
    }

    #[test]
    fn the_constructor_checks_its_invariants() {
        let mut m = CameraModel::paper_rig();
        assert!(Camera::new(m, None, [225.0, 80.0]).is_err());
        assert!(Camera::new(m, None, [f64::NAN, 80.0]).is_err());
        m.kf_x.coefficients_mut()[0] = f64::NAN;
        assert!(Camera::new(m, None, [80.0, 225.0]).is_err());
        let bad = ThermalTrust {
            t_range_c: Some([37.0, 27.0]),
            ..ThermalTrust::from_calibration(&ThermalCalibration::PAPER)
        };
        assert!(Camera::new(CameraModel::paper_rig(), Some(bad), [80.0, 225.0]).is_err());
    }

    /// The run-time camera of an opencv-family model is that model at the setting.
    #[test]
    fn the_opencv_family_at_a_setting_is_its_model() {
        let model = CameraModel::strong_distortion_rig();
        let cam = Camera::new(model, Some(ThermalTrust::from_calibration(&ThermalCalibration::PAPER)), [80.0, 225.0])
            .unwrap();
        let at = cam.at(150.0, 32.0).unwrap();
        let e = at.e_com_ma();
        assert_eq!(*at.distortion(), model.distortion(e).unwrap());
        let w = [30.0, -20.0, 10.0];
        let px = at.project(w).unwrap();
        assert_eq!(px, model.project(w, e).unwrap());
        let back = at.undistort_point(px).unwrap();
        assert_eq!(back, model.undistort(px, e).unwrap());
        let ray = at.ray(px).unwrap();
        let s = (0..3).map(|i| (w[i] - ray.origin_mm[i]).powi(2)).sum::<f64>().sqrt();
        assert!((0..3).all(|i| (ray.at(s)[i] - w[i]).abs() < 1e-6));
    }

    /// A focal-power camera is the model at the power; the temperature range of its views
    /// and its power range are checked (temperature first); a current is refused on it and
    /// a power on a current camera, each naming the other way in.
    #[test]
    fn a_focal_power_camera_at_a_power() {
        let model = CameraModel::paper_rig();
        let cam = Camera::new_focal_power(model, [10.0, 17.0], Some([25.0, 35.0])).unwrap();
        assert_eq!(cam.setting_kind(), SettingKind::FocalPower);
        let at = cam.at_focal_power(12.5, 30.0).unwrap();
        assert_eq!((at.focal_power_dpt(), at.setting_kind()), (12.5, SettingKind::FocalPower));
        assert!(at.e_com_ma().is_nan() && at.e_in_ma().is_nan() && at.temperature_c() == 30.0);
        let w = [4.5, 6.0, 22.0];
        assert_eq!(at.project(w).unwrap(), model.project(w, 12.5).unwrap());
        let what = |r: Result<CameraAt>| match r {
            Err(Error::OutOfRange { what, .. }) => what,
            other => panic!("{other:?}"),
        };
        assert_eq!(what(cam.at_focal_power(12.5, 37.0)), "temperature_c");
        assert_eq!(what(cam.at_focal_power(30.0, 37.0)), "temperature_c");
        assert_eq!(what(cam.at_focal_power(17.3, 30.0)), "focal_power_dpt");
        assert!(cam.at_focal_power(17.2, 35.9).is_ok());
        let flags = cam.at_focal_power_with(18.0, 36.5, Trust::Extrapolate).unwrap().flags();
        assert!(flags.focal_power && flags.temperature && !flags.e_com);
        assert!(matches!(cam.at_focal_power_with(12.0, 300.0, Trust::Extrapolate), Err(Error::OutOfRange { .. })));
        assert!(matches!(cam.at(150.0, 30.0), Err(Error::InvalidArgument { .. })));
        assert!(matches!(cam.at_e_com(150.0, Trust::Extrapolate), Err(Error::InvalidArgument { .. })));
        assert!(matches!(paper().at_focal_power(12.0, 30.0), Err(Error::InvalidArgument { .. })));
        let unknown = Camera::new_focal_power(model, [10.0, 17.0], None).unwrap();
        assert!(unknown.at_focal_power(12.0, 30.0).is_err());
        assert!(unknown.at_focal_power_with(12.0, 30.0, Trust::Extrapolate).unwrap().flags().temperature);
        assert!(Camera::new_focal_power(model, [17.0, 10.0], None).is_err());
        assert!(Camera::new_focal_power(model, [10.0, 17.0], Some([f64::NAN, 30.0])).is_err());
    }

    #[test]
    fn camera_is_send_sync_copy() {
        fn assert_bounds<T: Send + Sync + Copy>() {}
        assert_bounds::<Camera>();
        assert_bounds::<CameraAt>();
    }
}
