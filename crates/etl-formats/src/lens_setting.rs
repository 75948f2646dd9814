//! The lens setting of a view (`etlcal.observations/1` and `etlcal.dataset/1`): the driver
//! current `"e_in_ma"` (with the lens temperature, and E_com optionally), or the focal
//! power `"focal_power_dpt"` commanded in the Lens Driver 4's focal-power mode (with the
//! lens temperature, and no E_com: the driver's firmware compensated the temperature).
//!
//! ```json
//! {"e_in_ma": 150.0, "temperature_c": 30.0, "e_com_ma": 148.9, ...}
//! {"focal_power_dpt": 12.5, "temperature_c": 30.0, ...}
//! ```
//!
//! A file's ETL and setting views all have the same kind of setting: the calibration's
//! polynomials are in one of them ([`SettingKind`]).

pub use etl_core::runtime::SettingKind;

use crate::{Error, Result};

/// Focal powers a view may record, dpt: Optotune's lenses span about -13..+20 dpt; a number
/// beyond +-50 dpt is not a focal power (typically a focal length in mm, or a current).
pub const FOCAL_POWER_DOMAIN_DPT: [f64; 2] = [-50.0, 50.0];

/// The value of an absent `e_in_ma` (a focal-power view): NaN, as [`crate::CameraAt::e_in_ma`]
/// has it when no current is known.
pub fn absent() -> f64 {
    f64::NAN
}

/// Whether an `e_in_ma` is absent (NaN): the field is then not written.
pub fn is_absent(x: &f64) -> bool {
    x.is_nan()
}

/// The kind of one view's setting, its fields checked against each other: a focal power
/// (`focal_power_dpt`, finite and within [`FOCAL_POWER_DOMAIN_DPT`], with neither `e_in_ma`
/// nor `e_com_ma`) or a current (`e_in_ma`). `field` gives a field's key path
/// (`views[3].e_in_ma`), `view` names the view in the message ("view 3").
pub fn view_setting_kind(
    e_in_ma: f64,
    focal_power_dpt: Option<f64>,
    e_com_ma: Option<f64>,
    field: impl Fn(&str) -> String,
    view: &str,
) -> Result<SettingKind> {
    let Some(p) = focal_power_dpt else {
        if is_absent(&e_in_ma) {
            // Absent and NaN are one here (a NaN current is no setting): the value is shown.
            let message = format!("{view} has no lens setting: give e_in_ma (mA) or focal_power_dpt (dpt)");
            return Err(Error::invalid_value(field("e_in_ma"), e_in_ma, message));
        }
        return Ok(SettingKind::Current);
    };
    if !is_absent(&e_in_ma) {
        let message = format!("{view} gives both e_in_ma and focal_power_dpt: a view has one setting, give one");
        return Err(Error::invalid(field("focal_power_dpt"), message));
    }
    if e_com_ma.is_some() {
        let message = format!(
            "{view} gives e_com_ma with a focal power: the driver compensates the temperature in focal-power \
             mode, so a focal-power view has no E_com; remove it"
        );
        return Err(Error::invalid(field("e_com_ma"), message));
    }
    let [lo, hi] = FOCAL_POWER_DOMAIN_DPT;
    if !(lo..=hi).contains(&p) {
        let message =
            format!("{view}: focal_power_dpt {} dpt is outside [{lo}, {hi}] dpt (a focal power)", crate::compact(p));
        return Err(Error::invalid_value(field("focal_power_dpt"), p, message));
    }
    Ok(SettingKind::FocalPower)
}

/// The one kind of setting of a list of views (`kinds`: each view's kind with its key
/// path, `"views[3]"`), or an error naming the first view that differs from the first;
/// None for no views.
pub fn common_kind(kinds: impl IntoIterator<Item = (SettingKind, String)>) -> Result<Option<SettingKind>> {
    let mut first: Option<(SettingKind, String)> = None;
    for (kind, key) in kinds {
        match &first {
            None => first = Some((kind, key)),
            Some((k, first_key)) if *k != kind => {
                let name = |k: SettingKind| match k {
                    SettingKind::Current => "a current (e_in_ma)",
                    SettingKind::FocalPower => "a focal power (focal_power_dpt)",
                };
                let message = format!(
                    "{key} is set by {} but {first_key} by {}: every view of a calibration has the same kind of \
                     setting",
                    name(kind),
                    name(*k)
                );
                return Err(Error::invalid(key, message));
            }
            Some(_) => {}
        }
    }
    Ok(first.map(|(k, _)| k))
}
