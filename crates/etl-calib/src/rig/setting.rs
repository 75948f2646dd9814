//! [`RigSetting`]: one camera's lens setting as a rig is given it.

use std::str::FromStr;

use etl_formats::{Camera, CameraAt, Error, Result, SettingKind, Trust};

/// One camera's setting: a number in its calibration's own unit (the driver current E_in,
/// mA, for a current calibration; the commanded focal power, dpt, for a focal-power one),
/// optionally with the unit it was given in, which is checked against the calibration's.
///
/// Parsed from `"150"` (the calibration's unit), `"150mA"` or `"12.5dpt"`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigSetting {
    /// The number.
    pub value: f64,
    /// The kind it was given as, if said: refused on a calibration of the other kind.
    pub kind: Option<SettingKind>,
}

impl RigSetting {
    /// A number in the calibration's own unit.
    pub fn of(value: f64) -> Self {
        RigSetting { value, kind: None }
    }

    /// The camera at this setting and the lens temperature `temperature_c`: E_in and T
    /// through the thermal part (Eq. 7) for a current calibration, the focal power for a
    /// focal-power one. Errors: a setting of the other kind, and the camera's own.
    pub fn camera_at(&self, camera: &Camera, temperature_c: f64, trust: Trust) -> Result<CameraAt> {
        let kind = camera.setting_kind();
        if let Some(given) = self.kind.filter(|&k| k != kind) {
            return Err(Error::invalid_value(
                "settings",
                format!("{}{}", etl_formats::compact(self.value), given.unit()),
                format!(
                    "a {} setting ({}) for a calibration whose setting is {} ({})",
                    given.name(),
                    given.unit(),
                    kind.name(),
                    kind.unit()
                ),
            ));
        }
        Ok(match kind {
            SettingKind::Current => camera.at_with(self.value, temperature_c, trust)?,
            SettingKind::FocalPower => camera.at_focal_power_with(self.value, temperature_c, trust)?,
        })
    }
}

impl FromStr for RigSetting {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        let t = s.trim();
        let (number, kind) = if let Some(n) = t.strip_suffix("mA") {
            (n, Some(SettingKind::Current))
        } else if let Some(n) = t.strip_suffix("dpt") {
            (n, Some(SettingKind::FocalPower))
        } else {
            (t, None)
        };
        match number.trim().parse::<f64>() {
            Ok(value) if value.is_finite() => Ok(RigSetting { value, kind }),
            _ => Err(Error::invalid_value(
                "settings",
                s,
                format!("setting {s:?} is not a number, optionally with its unit (150mA, 12.5dpt)"),
            )),
        }
    }
}
