//! `etlcal.a0/1`: the lens-off intrinsics when they come from elsewhere.

use std::path::Path;

use etl_core::calib::A0;
use serde::{Deserialize, Serialize};

use super::{read_json, write_json};
use crate::{Error, Result};

/// The format tag.
pub const FORMAT: &str = "etlcal.a0/1";

/// `{"format": "etlcal.a0/1", "kf0x", "kf0y", "u0", "v0"}` (px).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct A0File {
    /// `"etlcal.a0/1"`.
    pub format: String,
    /// fx at E = 0, px.
    pub kf0x: f64,
    /// fy at E = 0, px.
    pub kf0y: f64,
    /// u0, px.
    pub u0: f64,
    /// v0, px.
    pub v0: f64,
}

impl A0File {
    /// The file for `a0`.
    pub fn new(a0: &A0) -> Self {
        A0File { format: FORMAT.into(), kf0x: a0.kf0x, kf0y: a0.kf0y, u0: a0.u0, v0: a0.v0 }
    }

    /// The core value.
    pub fn a0(&self) -> A0 {
        A0 { kf0x: self.kf0x, kf0y: self.kf0y, u0: self.u0, v0: self.v0 }
    }

    /// The one check of the format (positive focal lengths, finite numbers), made by the
    /// reader and the writer; `path` names the file in the message.
    pub fn validate(&self, path: &Path) -> Result<()> {
        let r = self;
        if !([r.kf0x, r.kf0y, r.u0, r.v0].iter().all(|x| x.is_finite()) && r.kf0x > 0.0 && r.kf0y > 0.0) {
            return Err(Error::Parse {
                path: path.to_owned(),
                message: "kf0x, kf0y must be positive and u0, v0 finite".into(),
            });
        }
        Ok(())
    }

    /// Reads and checks a file.
    pub fn load(path: &Path) -> Result<Self> {
        let r: A0File = read_json(path, FORMAT)?;
        r.validate(path)?;
        Ok(r)
    }

    /// Checks and writes the file atomically.
    pub fn save(&self, path: &Path) -> Result<()> {
        self.validate(path)?;
        write_json(path, self)
    }
}
