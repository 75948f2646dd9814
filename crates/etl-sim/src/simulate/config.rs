//! `etlcal simulate --config sim.json`: what to simulate, as a file.
//!
//! ```json
//! {"format": "etlcal.simconfig/1", "seed": 1,
//!  "noise": {"xy_mm": 0.001, "z_mm": 0.01, "e_ma": 0.4, "px": 0.2, "kf0_rel": 0.003, "pp_px": 1.0},
//!  "setting_rig": {"e_com_ma": [80, 150, 225], "views_per_setting": 15, "blur_px": 2.0,
//!                  "aperture_mm": 2.5, "max_tilt_deg": 25.0}}
//! ```
//!
//! Every field but `format` is optional (defaults: seed 1, the paper's noise, no setting
//! views). Unknown fields are refused, as in every etlcal file.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{NoiseModel, SettingRig};
use etl_formats::read_json;
use etl_formats::{Error, Result};

/// The format tag.
pub const CONFIG_FORMAT: &str = "etlcal.simconfig/1";

/// A simulation's configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimConfig {
    /// `"etlcal.simconfig/1"`.
    pub format: String,
    /// Random seed.
    #[serde(default = "default_seed")]
    pub seed: u64,
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
        SimConfig { format: CONFIG_FORMAT.into(), seed: 1, noise: NoiseModel::PAPER, setting_rig: None }
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
        let n = &self.noise;
        if ![n.xy_mm, n.z_mm, n.e_ma, n.px, n.kf0_rel, n.pp_px].iter().all(|x| x.is_finite() && *x >= 0.0) {
            return Err(Error::InvalidInput("noise levels must be finite and not negative".into()));
        }
        if let Some(r) = &self.setting_rig {
            if r.e_com_ma.is_empty() || r.views_per_setting == 0 {
                return Err(Error::InvalidInput("setting_rig needs at least one current and one view".into()));
            }
            if !(r.blur_px > 0.0 && r.aperture_mm > 0.0 && r.max_tilt_deg >= 0.0)
                || r.e_com_ma.iter().any(|e| !e.is_finite())
            {
                return Err(Error::InvalidInput(
                    "setting_rig: blur_px and aperture_mm must be positive, currents finite".into(),
                ));
            }
        }
        Ok(())
    }
}
