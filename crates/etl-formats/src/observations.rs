//! `etlcal.observations/1`: corners of the calibration views (docs/FORMATS.md).
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
//! `e_in_ma` and `temperature_c` through the thermal surface. A view taken in the lens
//! driver's focal-power mode gives `"focal_power_dpt"` instead of `e_in_ma` (and no
//! `e_com_ma`); every view of a file has the same kind of setting ([`crate::lens_setting`]).

use std::path::Path;

use crate::calibration::ThermalRef;
use etl_core::calib::Point;
use etl_core::thermal::{E_IN_DOMAIN_MA, T_DOMAIN_C};
use serde::{Deserialize, Serialize};

use super::{read_json, write_json};
pub use crate::checks::{check_image_size, MAX_IMAGE_PIXELS, MAX_IMAGE_SIDE_PX};
use crate::lens_setting::{self, SettingKind};
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

/// One ETL view, at a current or at a focal power ([`crate::lens_setting`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViewObs {
    /// Commanded lens current, mA (absent, NaN here, in a focal-power view).
    #[serde(default = "lens_setting::absent", skip_serializing_if = "lens_setting::is_absent")]
    pub e_in_ma: f64,
    /// Commanded focal power, dpt (a focal-power view, instead of `e_in_ma`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focal_power_dpt: Option<f64>,
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

/// World coordinates of a board point, mm: within +-10 m of the rig's origin.
pub const WORLD_RANGE_MM: [f64; 2] = [-10_000.0, 10_000.0];
/// How far outside the image an observed pixel may be, in image sizes: a corner is seen
/// in the image, and one image size around it covers any distortion model's overshoot.
pub const PIXEL_MARGIN_IMAGES: f64 = 1.0;

/// One view of a list of the file, as messages and errors name it: `"view 3"` in words,
/// `"views[3]"` as the key path of a field.
#[derive(Clone, Copy)]
struct ViewRef<'a> {
    /// The view in words: "view", "setting view", "lens-off view".
    name: &'a str,
    /// The file's key of its list: "views", "setting_views", "offstate_views".
    key: &'a str,
    /// Its index in the list.
    i: usize,
}

impl ViewRef<'_> {
    /// The key path of `field` of this view: `views[3].points`.
    fn field(&self, field: &str) -> String {
        format!("{}[{}].{field}", self.key, self.i)
    }
}

impl std::fmt::Display for ViewRef<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} {}", self.name, self.i)
    }
}

/// Checks the points of view `i` (`name`: "view", "lens-off view", ...): at least one,
/// world coordinates in [`WORLD_RANGE_MM`], pixels within [`PIXEL_MARGIN_IMAGES`] of the
/// image, and with `planar` every Z = 0. The message names the view and the point.
fn check_points(points: &[PointObs], view: ViewRef<'_>, image_size: [u32; 2], planar: bool) -> Result<()> {
    if points.is_empty() {
        return Err(Error::invalid(view.field("points"), format!("{view} has no points")));
    }
    let coordinates = |p: &PointObs| {
        let world = p.world_mm.into_iter().map(|x| ("world_mm", x));
        world.chain(p.pixel.into_iter().map(|x| ("pixel", x))).collect::<Vec<_>>()
    };
    for (j, p) in points.iter().enumerate() {
        if let Some((field, x)) = coordinates(p).into_iter().find(|(_, x)| !x.is_finite()) {
            let what = view.field(&format!("points[{j}].{field}"));
            return Err(Error::invalid_value(what, x, format!("{view}: a point is not finite")));
        }
    }
    let [wr0, wr1] = WORLD_RANGE_MM;
    for (j, p) in points.iter().enumerate() {
        let bad = |field: &str, x: f64, what: String| {
            Error::invalid_value(view.field(&format!("points[{j}].{field}")), x, format!("{view} point {j}: {what}"))
        };
        if let Some(&x) = p.world_mm.iter().find(|x| !(wr0..=wr1).contains(*x)) {
            return Err(bad(
                "world_mm",
                x,
                format!("world_mm coordinate {} mm is outside [{wr0}, {wr1}] mm", crate::compact(x)),
            ));
        }
        for (&x, side) in p.pixel.iter().zip(image_size) {
            let margin = PIXEL_MARGIN_IMAGES * f64::from(side);
            if !(-margin..=f64::from(side) + margin).contains(&x) {
                return Err(bad(
                    "pixel",
                    x,
                    format!(
                        "pixel coordinate {} px is outside [{}, {}] px (the image and one image size around it)",
                        crate::compact(x),
                        -margin,
                        f64::from(side) + margin
                    ),
                ));
            }
        }
        if planar && p.world_mm[2] != 0.0 {
            let z = p.world_mm[2];
            return Err(bad(
                "world_mm",
                z,
                format!("world_mm Z = {} mm, but this board is planar: its points must have Z = 0", crate::compact(z)),
            ));
        }
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
        self.validate().map_err(|e| e.within(path.display(), None))?;
        write_json(path, self)
    }

    /// Checks the documented ranges (docs/RELIABILITY.md): at least one ETL view or one
    /// setting view; `image_size` within [`check_image_size`]; currents (`e_in_ma`,
    /// `e_com_ma`) within the driver's [`E_IN_DOMAIN_MA`] and temperatures within
    /// [`T_DOMAIN_C`]; points as `check_points` (lens-off and setting boards planar).
    pub fn validate(&self) -> Result<()> {
        if self.views.is_empty() && self.setting_views.is_empty() {
            return Err(Error::invalid("views", "observations hold no views"));
        }
        check_image_size(self.image_size, "image_size")?;
        for (list, name, key, planar) in
            [(&self.views, "view", "views", false), (&self.setting_views, "setting view", "setting_views", true)]
        {
            for (i, v) in list.iter().enumerate() {
                let view = ViewRef { name, key, i };
                check_view_setting(v, view)?;
                check_points(&v.points, view, self.image_size, planar)?;
            }
        }
        self.setting_kind()?;
        for (i, v) in self.offstate_views.iter().enumerate() {
            check_points(
                &v.points,
                ViewRef { name: "lens-off view", key: "offstate_views", i },
                self.image_size,
                true,
            )?;
        }
        Ok(())
    }

    /// E_com of every setting view: as recorded, or compensated through `thermal` (`view_e_com_ma`).
    pub fn setting_e_com_ma(&self, thermal: Option<&ThermalRef>) -> Result<Vec<f64>> {
        let view = |i| ViewRef { name: "setting view", key: "setting_views", i };
        self.setting_views.iter().enumerate().map(|(i, v)| view_e_com_ma(v, view(i), thermal)).collect()
    }

    /// E_com of every view: as recorded, or compensated through `thermal` (`view_e_com_ma`); the focal
    /// power (dpt) of focal-power views, the setting their calibration is in.
    pub fn e_com_ma(&self, thermal: Option<&ThermalRef>) -> Result<Vec<f64>> {
        let view = |i| ViewRef { name: "view", key: "views", i };
        self.views.iter().enumerate().map(|(i, v)| view_e_com_ma(v, view(i), thermal)).collect()
    }

    /// Whether some ETL or setting view has a current but no recorded E_com (so a thermal
    /// calibration must be chosen to calibrate it); never for focal-power views.
    pub fn needs_thermal(&self) -> bool {
        self.views.iter().chain(&self.setting_views).any(|v| v.e_com_ma.is_none() && v.focal_power_dpt.is_none())
    }

    /// The one kind of setting of the ETL and setting views (a current when there are
    /// none); an error naming the first view of another kind.
    pub fn setting_kind(&self) -> Result<SettingKind> {
        let views = self.views.iter().enumerate().map(|(i, v)| (v.kind(), format!("views[{i}]")));
        let settings = self.setting_views.iter().enumerate().map(|(i, v)| (v.kind(), format!("setting_views[{i}]")));
        Ok(lens_setting::common_kind(views.chain(settings))?.unwrap_or_default())
    }

    /// The points of every view as core [`Point`]s.
    pub fn core_points(&self) -> Vec<Vec<Point>> {
        self.views
            .iter()
            .map(|v| v.points.iter().map(|p| Point { world_mm: p.world_mm, pixel: p.pixel }).collect())
            .collect()
    }
}

impl ViewObs {
    /// The kind of the view's setting: a focal power when it gives one.
    pub fn kind(&self) -> SettingKind {
        match self.focal_power_dpt {
            Some(_) => SettingKind::FocalPower,
            None => SettingKind::Current,
        }
    }
}

/// Checks a view's setting ([`lens_setting::view_setting_kind`]), its currents and
/// temperature against the lens driver's domain.
fn check_view_setting(v: &ViewObs, view: ViewRef<'_>) -> Result<()> {
    let name = view.to_string();
    let kind = lens_setting::view_setting_kind(v.e_in_ma, v.focal_power_dpt, v.e_com_ma, |f| view.field(f), &name)?;
    let e_in = (kind == SettingKind::Current).then_some(v.e_in_ma);
    let setting = [("e_in_ma", e_in), ("temperature_c", Some(v.temperature_c)), ("e_com_ma", v.e_com_ma)];
    if let Some((key, x)) = crate::first_not_finite(setting) {
        return Err(Error::invalid_value(view.field(key), x, format!("{view}: current or temperature is not finite")));
    }
    let [e0, e1] = E_IN_DOMAIN_MA;
    let [t0, t1] = T_DOMAIN_C;
    for (value, key) in [(e_in, "e_in_ma"), (v.e_com_ma, "e_com_ma")] {
        match value {
            Some(e) if !(e0..=e1).contains(&e) => {
                return Err(Error::invalid_value(
                    view.field(key),
                    e,
                    format!("{view}: {key} {} mA is outside the lens driver's [{e0}, {e1}] mA", crate::compact(e)),
                ));
            }
            _ => {}
        }
    }
    if !(t0..=t1).contains(&v.temperature_c) {
        return Err(Error::invalid_value(
            view.field("temperature_c"),
            v.temperature_c,
            format!("{view}: temperature_c {} degC is outside [{t0}, {t1}] degC", crate::compact(v.temperature_c)),
        ));
    }
    Ok(())
}

/// E_com of one view: its recorded `e_com_ma`, or E_in - E_T(T, E_in) through `thermal`,
/// refused outside the thermal calibration's ranges. No surface is assumed: a view without
/// E_com and no thermal calibration chosen is an error naming the view.
///
/// A focal-power view's setting is its focal power, dpt: the thermal calibration is refused
/// for it (the driver compensated the temperature).
fn view_e_com_ma(v: &ViewObs, view: ViewRef<'_>, thermal: Option<&ThermalRef>) -> Result<f64> {
    if let Some(p) = v.focal_power_dpt {
        if thermal.is_some() {
            return Err(Error::invalid(
                view.field("focal_power_dpt"),
                format!(
                    "{view} is at a focal power, which the lens driver compensates for temperature itself: a \
                     thermal calibration does not apply (leave out --thermal)"
                ),
            ));
        }
        return Ok(p);
    }
    if let Some(e) = v.e_com_ma {
        return Ok(e);
    }
    let Some(t) = thermal else {
        return Err(Error::invalid(
            view.field("e_com_ma"),
            format!(
                "{view} has no e_com_ma and no thermal calibration was chosen: give one (--thermal FILE, or \
                 --thermal paper for the paper's surface)"
            ),
        ));
    };
    // The thermal calibration refuses the view's own current or temperature: name it.
    let prefix = format!("{}[{}]", view.key, view.i);
    t.e_com_ma(v.e_in_ma, v.temperature_c).map_err(|e| e.within(view, Some(&prefix)))
}
