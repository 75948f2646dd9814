//! `etlcal.observations/1`: corners of the calibration views (DESIGN.md).
//!
//! ```json
//! {"format": "etlcal.observations/1", "image_size": [1936, 1458],
//!  "views": [{"e_in_ma": 100.0, "temperature_c": 27.0, "e_com_ma": 100.0,
//!             "points": [{"world_mm": [0, 0, 48], "pixel": [812.3, 402.1]}]}],
//!  "offstate_views": [{"points": [...]}],
//!  "setting_views": [{"e_in_ma": 150.0, "temperature_c": 27.0, "points": [...]}]}
//! ```
//!
//! `e_com_ma` is optional: if present it is used as is, else E_com is computed from
//! `e_in_ma` and `temperature_c` through the thermal surface.

use std::path::Path;

use crate::calibration::ThermalRef;
use etl_core::calib::Point;
use serde::{Deserialize, Serialize};

use super::{read_json, write_json};
use crate::{Error, Result};

/// The format tag this module reads and writes.
pub const FORMAT: &str = "etlcal.observations/1";

/// One observed point (world mm, observed pixel).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointObs {
    /// World coordinates, mm.
    pub world_mm: [f64; 3],
    /// Observed pixel.
    pub pixel: [f64; 2],
}

/// One ETL view.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViewObs {
    /// Commanded lens current, mA.
    pub e_in_ma: f64,
    /// Lens temperature, degC.
    pub temperature_c: f64,
    /// Compensated current, mA (optional; used as is when present).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub e_com_ma: Option<f64>,
    /// The view's points.
    pub points: Vec<PointObs>,
}

/// A lens-off view of a planar board (Z = 0), for A0.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OffstateView {
    /// The view's points.
    pub points: Vec<PointObs>,
}

fn check_points(points: &[PointObs], name: &str, i: usize) -> Result<()> {
    if points.is_empty() {
        return Err(Error::InvalidInput(format!("{name} {i} has no points")));
    }
    if points.iter().any(|p| p.world_mm.iter().chain(&p.pixel).any(|x| !x.is_finite())) {
        return Err(Error::InvalidInput(format!("{name} {i}: a point is not finite")));
    }
    Ok(())
}

/// The whole file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Observations {
    /// `"etlcal.observations/1"`.
    pub format: String,
    /// Image width and height, px.
    pub image_size: [u32; 2],
    /// The ETL views.
    pub views: Vec<ViewObs>,
    /// Lens-off views (optional).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub offstate_views: Vec<OffstateView>,
    /// Views for the per-setting baseline (optional): a planar board (points with Z = 0 in
    /// the board's own frame) in a free pose per view, several views at each current;
    /// views whose E_com agree within [`SETTING_TOLERANCE_MA`] form one setting.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub setting_views: Vec<ViewObs>,
}

/// Views of `setting_views` whose E_com differ by less than this are one setting, mA.
pub const SETTING_TOLERANCE_MA: f64 = 0.5;

impl Observations {
    /// An empty set of observations for an image of `image_size`.
    pub fn new(image_size: [u32; 2]) -> Self {
        Observations { format: FORMAT.into(), image_size, views: vec![], offstate_views: vec![], setting_views: vec![] }
    }

    /// Reads and checks a file.
    pub fn load(path: &Path) -> Result<Self> {
        let o: Observations = read_json(path, FORMAT)?;
        o.validate().map_err(|e| Error::Parse { path: path.to_owned(), message: e.to_string() })?;
        Ok(o)
    }

    /// Checks and writes the file atomically.
    pub fn save(&self, path: &Path) -> Result<()> {
        self.validate().map_err(|e| Error::InvalidInput(format!("{}: {e}", path.display())))?;
        write_json(path, self)
    }

    /// Checks finiteness and non-empty views: at least one ETL view or one setting view.
    pub fn validate(&self) -> Result<()> {
        if self.views.is_empty() && self.setting_views.is_empty() {
            return Err(Error::InvalidInput("observations hold no views".into()));
        }
        for (list, name) in [(&self.views, "view"), (&self.setting_views, "setting view")] {
            for (i, v) in list.iter().enumerate() {
                if !(v.e_in_ma.is_finite() && v.temperature_c.is_finite() && v.e_com_ma.is_none_or(f64::is_finite)) {
                    return Err(Error::InvalidInput(format!("{name} {i}: current or temperature is not finite")));
                }
                check_points(&v.points, name, i)?;
            }
        }
        for (i, v) in self.offstate_views.iter().enumerate() {
            check_points(&v.points, "lens-off view", i)?;
        }
        Ok(())
    }

    /// E_com of every setting view: as recorded, or compensated ([`view_e_com_ma`]).
    pub fn setting_e_com_ma(&self, thermal: Option<&ThermalRef>) -> Result<Vec<f64>> {
        self.setting_views.iter().enumerate().map(|(i, v)| view_e_com_ma(v, "setting view", i, thermal)).collect()
    }

    /// E_com of every view: as recorded, or compensated ([`view_e_com_ma`]).
    pub fn e_com_ma(&self, thermal: Option<&ThermalRef>) -> Result<Vec<f64>> {
        self.views.iter().enumerate().map(|(i, v)| view_e_com_ma(v, "view", i, thermal)).collect()
    }

    /// Whether some ETL or setting view has no recorded E_com (so a thermal calibration
    /// must be chosen to calibrate it).
    pub fn needs_thermal(&self) -> bool {
        self.views.iter().chain(&self.setting_views).any(|v| v.e_com_ma.is_none())
    }

    /// The points of every view as core [`Point`]s.
    pub fn core_points(&self) -> Vec<Vec<Point>> {
        self.views
            .iter()
            .map(|v| v.points.iter().map(|p| Point { world_mm: p.world_mm, pixel: p.pixel }).collect())
            .collect()
    }
}

/// E_com of one view: its recorded `e_com_ma`, or E_in - E_T(T, E_in) through `thermal`,
/// refused outside the thermal calibration's ranges. No surface is assumed: a view without
/// E_com and no thermal calibration chosen is an error naming the view.
fn view_e_com_ma(v: &ViewObs, name: &str, i: usize, thermal: Option<&ThermalRef>) -> Result<f64> {
    if let Some(e) = v.e_com_ma {
        return Ok(e);
    }
    let Some(t) = thermal else {
        return Err(Error::InvalidInput(format!(
            "{name} {i} has no e_com_ma and no thermal calibration was chosen: give one (--thermal FILE, or \
             --thermal paper for the paper's surface)"
        )));
    };
    t.e_com_ma(v.e_in_ma, v.temperature_c).map_err(|e| Error::InvalidInput(format!("{name} {i}: {e}")))
}
