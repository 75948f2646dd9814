//! `genicam:NAME[,feature=F][,unit=dpt|ma][,temperature=F]`: the lens a GenICam camera
//! drives (cargo feature `aravis`), as Basler-style cameras expose an Optotune lens
//! through their own features: etl-core's `Lens` over the camera's float features.
//!
//! - `feature` (default `FocalPower`) is the lens's command. With `unit=dpt` (the default)
//!   it is a focal power, dpt: a current E is commanded as the power the paper's EL-10-30
//!   has at E (etl-core's `LensPhysics::paper().power_dpt`, Eq. 8, 10), and the power read
//!   back is turned into the current with that power (`current_for_power_ma` over
//!   [`POWER_CURRENT_RANGE_MA`]): the currents the rig records are the paper lens's for
//!   those powers. With `unit=ma` the feature is the current itself, mA.
//! - `temperature` names the lens's temperature feature, degC (the camera's own
//!   `DeviceTemperature` is not the lens's: there is no default). Without it a temperature
//!   read is refused in one line, so a capture, which reads the temperature of every view,
//!   needs it.
//!
//! The current commanded is the feature's bounds' clamp of the value asked (as a driver
//! clamps to its limits), and the value read back after writing is the one returned.
//! NAME is aravis's id (an IP address for a GigE Vision camera); a camera grabbing frames
//! under the same id (`--camera aravis:NAME`) shares its connection with the lens.

use aravis::prelude::*;
use aravis::Camera as ArvCamera;
use etl_core::lens::Lens;
use etl_core::physics::LensPhysics;

use crate::error::{Error, ErrorKind, Result};
use crate::spec::{GenicamLensSpec, LensUnit};

/// The currents a focal power is looked for in, mA (the paper lens's power rises with the
/// current over it).
pub const POWER_CURRENT_RANGE_MA: [f64; 2] = [0.0, 292.84];

/// A lens driven through a GenICam camera's features.
pub struct GenicamLens {
    name: String,
    camera: ArvCamera,
    spec: GenicamLensSpec,
    physics: LensPhysics,
}

impl GenicamLens {
    /// The lens of `spec` on `camera` (an open aravis camera: the frames' camera when it
    /// is the same id); checks that its features are there.
    ///
    /// Errors: a feature the camera does not have (named).
    pub fn on_camera(camera: ArvCamera, spec: &GenicamLensSpec) -> Result<GenicamLens> {
        let name = format!("lens {}", crate::spec::LensSpec::Genicam(spec.clone()));
        let lens = GenicamLens { name, camera, spec: spec.clone(), physics: LensPhysics::paper() };
        let features = std::iter::once(&lens.spec.feature).chain(lens.spec.temperature.as_ref());
        for f in features {
            let here = lens.camera.is_feature_available(f).map_err(|e| lens.err(ErrorKind::Protocol, e))?;
            if !here {
                let message =
                    format!("the camera has no feature {f} (arv-tool-0.8 features lists a camera's features)");
                return Err(Error::device(&lens.name, ErrorKind::InvalidInput, message));
            }
        }
        Ok(lens)
    }

    /// Opens camera `spec.id` through aravis and its lens.
    pub fn open(spec: &GenicamLensSpec) -> Result<GenicamLens> {
        let camera = crate::camera::aravis::open_arv_camera(&spec.id).map_err(|e| {
            Error::device(format!("lens {}", crate::spec::LensSpec::Genicam(spec.clone())), e.kind(), strip(&e))
        })?;
        GenicamLens::on_camera(camera, spec)
    }

    /// The device's name in errors: `lens genicam:NAME,...`.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The feature's bounds as current limits, mA.
    pub fn limits_ma(&self) -> Result<[f64; 2]> {
        let (lo, hi) = self.camera.float_bounds(&self.spec.feature).map_err(|e| self.err(ErrorKind::Protocol, e))?;
        Ok(match self.spec.unit {
            LensUnit::Ma => [lo, hi],
            LensUnit::Dpt => [
                self.current_of(lo).unwrap_or(POWER_CURRENT_RANGE_MA[0]),
                self.current_of(hi).unwrap_or(POWER_CURRENT_RANGE_MA[1]),
            ],
        })
    }

    fn err(&self, kind: ErrorKind, e: aravis::glib::Error) -> Error {
        Error::device(&self.name, kind, e.to_string())
    }

    /// The paper lens's current at `dpt`, mA.
    fn current_of(&self, dpt: f64) -> Option<f64> {
        self.physics.current_for_power_ma(dpt, POWER_CURRENT_RANGE_MA)
    }

    /// The feature's value of current `e_in_ma`.
    fn value_of(&self, e_in_ma: f64) -> Result<f64> {
        match self.spec.unit {
            LensUnit::Ma => Ok(e_in_ma),
            LensUnit::Dpt => {
                let dpt = self.physics.power_dpt(e_in_ma);
                if dpt.is_finite() {
                    return Ok(dpt);
                }
                let message = format!("{e_in_ma} mA has no focal power in the paper lens's model (its range {POWER_CURRENT_RANGE_MA:?} mA)");
                Err(Error::device(&self.name, ErrorKind::InvalidInput, message))
            }
        }
    }

    /// The current of the feature's value.
    fn current_of_value(&self, value: f64) -> Result<f64> {
        match self.spec.unit {
            LensUnit::Ma => Ok(value),
            LensUnit::Dpt => self.current_of(value).ok_or_else(|| {
                let message = format!("the camera reports {value} dpt, a power the paper lens does not reach over {POWER_CURRENT_RANGE_MA:?} mA");
                Error::device(&self.name, ErrorKind::Protocol, message)
            }),
        }
    }
}

/// A device error's message without its device.
fn strip(e: &Error) -> String {
    match e {
        Error::Device { message, .. } => message.clone(),
        other => other.to_string(),
    }
}

impl Lens for GenicamLens {
    type Error = Error;

    fn set_current_ma(&mut self, e_in_ma: f64) -> Result<f64> {
        if !e_in_ma.is_finite() {
            return Err(Error::device(
                &self.name,
                ErrorKind::InvalidInput,
                format!("current {e_in_ma} mA is not finite"),
            ));
        }
        let (lo, hi) = self.camera.float_bounds(&self.spec.feature).map_err(|e| self.err(ErrorKind::Protocol, e))?;
        let value = self.value_of(e_in_ma)?.clamp(lo, hi);
        self.camera.set_float(&self.spec.feature, value).map_err(|e| self.err(ErrorKind::Refused, e))?;
        self.current_ma()
    }

    fn current_ma(&mut self) -> Result<f64> {
        let value = self.camera.float(&self.spec.feature).map_err(|e| self.err(ErrorKind::LinkLost, e))?;
        self.current_of_value(value)
    }

    fn temperature_c(&mut self) -> Result<f64> {
        let Some(f) = &self.spec.temperature else {
            let message = "no temperature feature: give the lens's, genicam:NAME,temperature=FEATURE";
            return Err(Error::device(&self.name, ErrorKind::InvalidInput, message));
        };
        self.camera.float(f).map_err(|e| self.err(ErrorKind::LinkLost, e))
    }
}
