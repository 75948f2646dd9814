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

mod setting;
mod trust;

pub use setting::{CameraAt, Extrapolated};
pub use trust::{ThermalTrust, Trust, E_COM_MARGIN_MA, E_IN_MARGIN_MA, T_MARGIN_C};

use crate::error::{Error, Result};
use crate::model::CameraModel;

/// A calibrated ETL camera with the ranges its calibration can be trusted over.
///
/// Invariants (checked by [`Camera::new`], the one constructor): the model's numbers are
/// finite; the E_com range is finite and ordered; the thermal part, if any, is valid. The
/// fields are private so that a `Camera` is always one that passed these checks.
/// `Camera` is `Copy`, `Send` and `Sync` and holds no reference: share it between threads
/// freely.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    model: CameraModel,
    thermal: Option<ThermalTrust>,
    e_com_range_ma: [f64; 2],
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
        Ok(Camera { model, thermal, e_com_range_ma })
    }

    /// The camera model (the numbers of Eq. 13-18, in its layout).
    pub fn model(&self) -> &CameraModel {
        &self.model
    }

    /// The temperature compensation and its calibrated ranges, if the calibration has one.
    pub fn thermal(&self) -> Option<&ThermalTrust> {
        self.thermal.as_ref()
    }

    /// The calibrated E_com range, [min, max] mA.
    pub fn e_com_range_ma(&self) -> [f64; 2] {
        self.e_com_range_ma
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
        let Some(thermal) = &self.thermal else {
            return Err(Error::InvalidArgument {
                what: "this calibration has no temperature compensation: use at_e_com with a known E_com",
            });
        };
        let (e_t_ma, mut flags) = thermal.e_t_ma(e_in_ma, temperature_c, trust)?;
        let e_com_ma = crate::error::finite(e_in_ma - e_t_ma, "e_com_ma")?;
        flags.e_com = self.check_e_com(e_com_ma, trust)?;
        CameraAt::new(&self.model, e_in_ma, temperature_c, e_com_ma, flags)
    }

    /// The camera at a known compensated current `e_com_ma` (temperature unknown or
    /// already compensated): the E_com range is checked as in [`Self::at_with`].
    pub fn at_e_com(&self, e_com_ma: f64, trust: Trust) -> Result<CameraAt> {
        crate::error::finite(e_com_ma, "e_com_ma")?;
        let flags = Extrapolated { e_com: self.check_e_com(e_com_ma, trust)?, ..Extrapolated::NONE };
        CameraAt::new(&self.model, f64::NAN, f64::NAN, e_com_ma, flags)
    }

    /// Whether `e_com_ma` is outside the calibrated range widened by [`E_COM_MARGIN_MA`];
    /// an error if it is and `trust` refuses.
    fn check_e_com(&self, e_com_ma: f64, trust: Trust) -> Result<bool> {
        let [lo, hi] = self.e_com_range_ma;
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
        assert_eq!(at.flags(), Extrapolated { temperature: true, e_in: false, e_com: true });
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

    #[test]
    fn camera_is_send_sync_copy() {
        fn assert_bounds<T: Send + Sync + Copy>() {}
        assert_bounds::<Camera>();
        assert_bounds::<CameraAt>();
    }
}
