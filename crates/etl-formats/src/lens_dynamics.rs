//! `etlcal.lens-dynamics/1`: the lens's step response, creep, hysteresis and self-heating
//! ([`etl_core::physics::dynamics`] says what each number means).

use std::path::Path;

use etl_core::physics::dynamics::LensDynamics;
use serde::{Deserialize, Serialize};

use super::{read_json, write_json};
use crate::{Error, Result};

/// The format tag.
pub const FORMAT: &str = "etlcal.lens-dynamics/1";

/// `{"format": "etlcal.lens-dynamics/1", "natural_frequency_hz", "damping",
/// "creep_fraction", "creep_tau_s", "hysteresis_ma", "thermal_tau_s",
/// "self_heating_c_per_ma"}`, every number required (a default would change a result
/// unseen); `"source"` optionally says where the numbers come from (a measurement, a
/// datasheet).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LensDynamicsFile {
    /// `"etlcal.lens-dynamics/1"`.
    pub format: String,
    /// Natural frequency of the membrane's second-order response, Hz.
    pub natural_frequency_hz: f64,
    /// Its damping ratio.
    pub damping: f64,
    /// Fraction of a step that arrives by creep.
    pub creep_fraction: f64,
    /// Time constant of the creep, s.
    pub creep_tau_s: f64,
    /// Width of the hysteresis loop, mA.
    pub hysteresis_ma: f64,
    /// Time constant of the lens's temperature, s.
    pub thermal_tau_s: f64,
    /// Rise of the equilibrium temperature per mA of coil current, degC / mA.
    pub self_heating_c_per_ma: f64,
    /// Where the numbers come from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
}

impl LensDynamicsFile {
    /// The file for `d`, with its `source`.
    pub fn new(d: &LensDynamics, source: Option<String>) -> Self {
        LensDynamicsFile {
            format: FORMAT.into(),
            natural_frequency_hz: d.natural_frequency_hz,
            damping: d.damping,
            creep_fraction: d.creep_fraction,
            creep_tau_s: d.creep_tau_s,
            hysteresis_ma: d.hysteresis_ma,
            thermal_tau_s: d.thermal_tau_s,
            self_heating_c_per_ma: d.self_heating_c_per_ma,
            source,
        }
    }

    /// The core value, unchecked ([`LensDynamicsFile::validate`] checks it).
    pub fn dynamics(&self) -> LensDynamics {
        LensDynamics {
            natural_frequency_hz: self.natural_frequency_hz,
            damping: self.damping,
            creep_fraction: self.creep_fraction,
            creep_tau_s: self.creep_tau_s,
            hysteresis_ma: self.hysteresis_ma,
            thermal_tau_s: self.thermal_tau_s,
            self_heating_c_per_ma: self.self_heating_c_per_ma,
        }
    }

    /// The one check of the format ([`LensDynamics::validate`]: each number in its range),
    /// made by the reader and the writer; the error names the field and `path` the file.
    pub fn validate(&self, path: &Path) -> Result<()> {
        self.dynamics().validate().map_err(|e| {
            let (what, value) = Error::core_input(&e);
            let what = what.unwrap_or("lens dynamics");
            let message = format!("{}: {e}", path.display());
            match value {
                Some(v) => Error::invalid_value(what, v, message),
                None => Error::invalid(what, message),
            }
        })
    }

    /// Reads and checks a file.
    pub fn load(path: &Path) -> Result<Self> {
        let r: LensDynamicsFile = read_json(path, FORMAT)?;
        r.validate(path)?;
        Ok(r)
    }

    /// Checks and writes the file atomically.
    pub fn save(&self, path: &Path) -> Result<()> {
        self.validate(path)?;
        write_json(path, self)
    }
}
