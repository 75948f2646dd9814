//! `etlcal simulate --config sim.json`: what to simulate, as a file.
//!
//! ```json
//! {"format": "etlcal.simconfig/1", "seed": 1, "rig": "paper",
//!  "noise": {"xy_mm": 0.001, "z_mm": 0.01, "e_ma": 0.4, "px": 0.2, "kf0_rel": 0.003, "pp_px": 1.0},
//!  "setting_rig": {"e_com_ma": [80, 150, 225], "views_per_setting": 15, "blur_px": 2.0,
//!                  "aperture_mm": 2.5, "max_tilt_deg": 25.0}}
//! ```
//!
//! Every field but `format` is optional (defaults: seed 1, the paper rig, the paper's noise,
//! no setting views). `"rig": "strong"` simulates the strong-distortion rig instead
//! ([`super::strong_rig`]; corners only, no setting views). Unknown fields are refused, as
//! in every etlcal file.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{NoiseModel, SettingRig};
use etl_formats::read_json;
use etl_formats::{Error, Result};

/// The format tag.
pub const CONFIG_FORMAT: &str = "etlcal.simconfig/1";

/// The most views per setting a configuration may ask for (the paper's rig has 15).
pub const MAX_VIEWS_PER_SETTING: usize = 1000;
/// The most currents of a setting rig (the paper's has 7).
pub const MAX_SETTINGS: usize = 1000;

/// The peak memory one view of the setting rig costs a simulation, bytes (measured 42 kB,
/// rounded up): the estimate [`SimConfig::validate`] checks against the memory budget.
pub const SETTING_VIEW_BYTES: u64 = 48 * 1024;

/// Which simulated rig.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SimRig {
    /// The paper's rig (docs/METHOD.md).
    #[default]
    Paper,
    /// The strong-distortion rig ([`super::strong_rig`]).
    Strong,
}

impl SimRig {
    fn is_paper(&self) -> bool {
        *self == SimRig::Paper
    }
}

/// A simulation's configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimConfig {
    /// `"etlcal.simconfig/1"`.
    pub format: String,
    /// Random seed.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// The rig (default: the paper's).
    #[serde(default, skip_serializing_if = "SimRig::is_paper")]
    pub rig: SimRig,
    /// The noise model.
    #[serde(default = "default_noise")]
    pub noise: NoiseModel,
    /// Views for the per-setting baseline (none when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub setting_rig: Option<SettingRig>,
}

fn default_seed() -> u64 {
    1
}

fn default_noise() -> NoiseModel {
    NoiseModel::PAPER
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            format: CONFIG_FORMAT.into(),
            seed: 1,
            rig: SimRig::Paper,
            noise: NoiseModel::PAPER,
            setting_rig: None,
        }
    }
}

impl SimConfig {
    /// Reads and checks a file: noise levels finite and not negative; a setting rig with
    /// at least one current and view, positive blur and aperture.
    pub fn load(path: &Path) -> Result<Self> {
        let c: SimConfig = read_json(path, CONFIG_FORMAT)?;
        c.validate().map_err(|e| Error::Parse { path: path.to_owned(), message: e.to_string() })?;
        Ok(c)
    }

    /// See [`Self::load`].
    pub fn validate(&self) -> Result<()> {
        self.noise.validate(|key| format!("noise.{key}"))?;
        if let Some(r) = &self.setting_rig {
            if self.rig != SimRig::Paper {
                return Err(Error::invalid(
                    "setting_rig",
                    "setting_rig: the per-setting baseline's views are the paper rig's, not with \"rig\": \"strong\"",
                ));
            }
            let message = "setting_rig needs at least one current and one view";
            if r.e_com_ma.is_empty() {
                return Err(Error::invalid("setting_rig.e_com_ma", message));
            }
            if r.views_per_setting == 0 {
                return Err(Error::invalid_value("setting_rig.views_per_setting", 0_usize, message));
            }
            if r.views_per_setting > MAX_VIEWS_PER_SETTING || r.e_com_ma.len() > MAX_SETTINGS {
                let message = format!(
                    "setting_rig: {} currents x {} views_per_setting: at most {MAX_SETTINGS} currents and \
                     {MAX_VIEWS_PER_SETTING} views per setting",
                    r.e_com_ma.len(),
                    r.views_per_setting
                );
                return Err(if r.views_per_setting > MAX_VIEWS_PER_SETTING {
                    Error::invalid_value("setting_rig.views_per_setting", r.views_per_setting, message)
                } else {
                    Error::invalid("setting_rig.e_com_ma", message)
                });
            }
            // Measured: 42 kB of peak memory per setting view (`simulate --observations-only`,
            // 400 and 3600 views); the caps alone allow a million views, 42 GB.
            let views = (r.e_com_ma.len() * r.views_per_setting) as u64;
            etl_formats::memory::check_memory("setting_rig.views_per_setting", views * SETTING_VIEW_BYTES)?;
            for e in &r.e_com_ma {
                etl_formats::check_range("setting_rig.e_com_ma", *e, etl_core::thermal::E_IN_DOMAIN_MA, "mA")?;
            }
            let positive = [("blur_px", r.blur_px), ("aperture_mm", r.aperture_mm)];
            let bad = positive.into_iter().find(|(_, x)| !(*x > 0.0));
            let bad = bad.or(Some(("max_tilt_deg", r.max_tilt_deg)).filter(|(_, x)| !(*x >= 0.0)));
            if let Some((key, x)) = bad {
                let message = "setting_rig: blur_px and aperture_mm must be positive, currents finite";
                return Err(Error::invalid_value(format!("setting_rig.{key}"), x, message));
            }
        }
        Ok(())
    }
}
