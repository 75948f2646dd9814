//! `etlcal.plan/1`: what a capture takes (docs/FORMATS.md, docs/RIG.md, "Capture").
//!
//! ```json
//! {"format": "etlcal.plan/1",
//!  "board": {"type": "charuco", "squares": [15, 13], "square_mm": 1.5, "marker_mm": 1.1,
//!            "dictionary": "DICT_5X5_100"},
//!  "stage_mm": [75.0, 60.0, 48.0],
//!  "frames": 2,
//!  "focus": "current",
//!  "currents_ma": [80.0, 90.0, 100.0],
//!  "offstate_views": 10,
//!  "offstate_board": {"type": "charuco", "squares": [12, 9], "square_mm": 4.0,
//!                     "marker_mm": 3.0, "dictionary": "DICT_5X5_100"}}
//! ```
//!
//! - `board`: the `etlcal.board/1` object on the stage (its `"format"` may be left out).
//! - `stage_mm`: one ETL view per stage position, mm, in this order (at least one).
//! - `frames`: frames averaged into each image (1..=[`MAX_FRAMES`]).
//! - `focus`: `"autofocus"` (the sharpest current at each position) or `"current"` (the
//!   currents of `currents_ma`, one per position, mA).
//! - `offstate_views` (optional): that many lens-off views (lens at 0 mA) are taken first,
//!   so that one plan gives a dataset that calibrates on its own.
//! - `offstate_board` (optional, default `board`): the lens-off views' board, as the
//!   dataset's key of the same name.
//! - `thermal` (optional; `etlcal capture thermal` needs it): the temperature procedure's
//!   grid ([`ThermalPlan`]). Its currents are the plan's `currents_ma` (focus
//!   `"current"`), each with its stage position in `stage_mm`: where the board is in focus
//!   at that current, the series' first temperature.
//!
//! Any other key is refused. The stage's limits are checked against `stage_mm` when the
//! capture opens the stage (they are the stage's, not the plan's).

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::board::Board;
use crate::{read_json, Error, Result};

/// The format tag.
pub const FORMAT: &str = "etlcal.plan/1";

/// The most frames a view may average.
pub const MAX_FRAMES: u32 = 1000;

/// The most views (ETL or lens-off) a plan may ask for.
pub const MAX_VIEWS: usize = 10_000;

/// The temperature procedure's keys (`"thermal"` in a plan), e.g.
/// `{"temperatures_c": [27, 30, 33, 36], "temperature_tolerance_c": 0.25,
/// "temperature_timeout_s": 1800}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalPlan {
    /// The temperature steps of each current's series, degC, in order; the first is the
    /// series' reference (E_T = 0 there).
    pub temperatures_c: Vec<f64>,
    /// A step begins once the lens reads within this of its temperature, degC.
    pub temperature_tolerance_c: f64,
    /// The longest wait for the lens to reach a temperature, s.
    pub temperature_timeout_s: f64,
    /// Half width of each refocus search around the previous step's current, mA
    /// (default [`THERMAL_SEARCH_HALF_WIDTH_MA`], the procedure's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub search_half_width_ma: Option<f64>,
    /// Frames (sharpness evaluations) of each refocus, coarse scan included (default
    /// [`THERMAL_MAX_FRAMES`], the procedure's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refocus_frames: Option<usize>,
}

/// The default half width of a refocus search, mA (etl-calib's procedure's).
pub const THERMAL_SEARCH_HALF_WIDTH_MA: f64 = 20.0;
/// The default frames of a refocus (etl-calib's procedure's).
pub const THERMAL_MAX_FRAMES: usize = 22;
/// The fewest frames of a refocus: its coarse scan ([`THERMAL_COARSE_POINTS`]) and two
/// refinements.
pub const THERMAL_MIN_FRAMES: usize = THERMAL_COARSE_POINTS + 2;
/// The points of a refocus's coarse scan (etl-calib's procedure's).
pub const THERMAL_COARSE_POINTS: usize = 9;
/// The distinct temperatures and currents a cubic surface needs.
pub const THERMAL_DISTINCT_NEEDED: usize = 4;
/// The longest wait for a temperature a plan may ask, s (a day).
pub const MAX_TEMPERATURE_TIMEOUT_S: f64 = 86_400.0;

impl ThermalPlan {
    /// The half width of each refocus search, mA.
    pub fn search_half_width_ma(&self) -> f64 {
        self.search_half_width_ma.unwrap_or(THERMAL_SEARCH_HALF_WIDTH_MA)
    }

    /// The frames of each refocus.
    pub fn refocus_frames(&self) -> usize {
        self.refocus_frames.unwrap_or(THERMAL_MAX_FRAMES)
    }

    /// Checks every key (named `thermal.KEY`): at least [`THERMAL_DISTINCT_NEEDED`]
    /// distinct temperatures in the lens's operating range (-40..=125 degC), a tolerance
    /// in (0, 10] degC, a time-out in (0, [`MAX_TEMPERATURE_TIMEOUT_S`]] s, a search
    /// half width in (0, 100] mA, [`THERMAL_MIN_FRAMES`]..=200 frames per refocus.
    pub fn validate(&self) -> Result<()> {
        let t = &self.temperatures_c;
        if let Some((i, x)) = t.iter().enumerate().find(|(_, x)| !(x.is_finite() && (-40.0..=125.0).contains(*x))) {
            let message = format!("thermal.temperatures_c[{i}] {x} degC is outside the lens's -40..=125 degC");
            return Err(Error::invalid_value(format!("thermal.temperatures_c[{i}]"), *x, message));
        }
        if distinct(t) < THERMAL_DISTINCT_NEEDED {
            let message = format!(
                "thermal.temperatures_c: {} distinct temperatures; the cubic surface needs at least {THERMAL_DISTINCT_NEEDED}",
                distinct(t)
            );
            return Err(Error::invalid("thermal.temperatures_c", message));
        }
        let ranges = [
            ("temperature_tolerance_c", self.temperature_tolerance_c, 10.0, "degC"),
            ("temperature_timeout_s", self.temperature_timeout_s, MAX_TEMPERATURE_TIMEOUT_S, "s"),
            ("search_half_width_ma", self.search_half_width_ma(), 100.0, "mA"),
        ];
        if let Some((key, x, hi, unit)) = ranges.into_iter().find(|(_, x, hi, _)| !(*x > 0.0 && *x <= *hi)) {
            let message = format!("thermal.{key} {x} must lie in (0, {hi}] {unit}");
            return Err(Error::invalid_value(format!("thermal.{key}"), x, message));
        }
        let n = self.refocus_frames();
        if !(THERMAL_MIN_FRAMES..=200).contains(&n) {
            let message = format!("thermal.refocus_frames: {n} frames; give {THERMAL_MIN_FRAMES}..=200");
            return Err(Error::invalid_value("thermal.refocus_frames", n, message));
        }
        Ok(())
    }
}

/// The number of distinct values of `x`.
fn distinct(x: &[f64]) -> usize {
    let mut v = x.to_vec();
    v.sort_by(f64::total_cmp);
    v.dedup();
    v.len()
}

/// How each ETL view is focused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Focus {
    /// The sharpest current at each stage position (a sharpness search).
    Autofocus,
    /// The plan's `currents_ma`, one per stage position.
    Current,
}

/// A capture plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plan {
    /// `"etlcal.plan/1"`.
    pub format: String,
    /// The board on the stage.
    pub board: Board,
    /// Stage positions of the ETL views, mm.
    pub stage_mm: Vec<f64>,
    /// Frames averaged per image.
    pub frames: u32,
    /// How the ETL views are focused.
    pub focus: Focus,
    /// Driver currents per stage position, mA (with `focus: "current"` only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub currents_ma: Option<Vec<f64>>,
    /// Lens-off views taken first (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub offstate_views: Option<u32>,
    /// The lens-off views' board (optional, default `board`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub offstate_board: Option<Board>,
    /// The temperature procedure's keys (optional; `etlcal capture thermal` needs them).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thermal: Option<ThermalPlan>,
}

impl Plan {
    /// Reads and checks a plan file ([`Plan::validate`]).
    pub fn load(path: &Path) -> Result<Plan> {
        let plan: Plan = read_json(path, FORMAT)?;
        plan.validate().map_err(|e| e.within(path.display(), None))?;
        Ok(plan)
    }

    /// Checks every key: boards, at least one finite stage position, 1..=[`MAX_FRAMES`]
    /// frames, one finite current per position with `"current"` focus and none with
    /// `"autofocus"`, at most [`MAX_VIEWS`] views of each kind. The error names the key.
    pub fn validate(&self) -> Result<()> {
        self.board.validate().map_err(|e| e.under("board"))?;
        if let Some(b) = self.offstate_board {
            b.validate().map_err(|e| e.under("offstate_board"))?;
        }
        if self.stage_mm.is_empty() {
            return Err(Error::invalid(
                "stage_mm",
                "stage_mm: the plan has no stage positions (give at least one, mm)",
            ));
        }
        if self.stage_mm.len() > MAX_VIEWS {
            let message =
                format!("stage_mm: {} positions, more than the {MAX_VIEWS} a plan may hold", self.stage_mm.len());
            return Err(Error::invalid("stage_mm", message));
        }
        if let Some((i, z)) = self.stage_mm.iter().enumerate().find(|(_, z)| !z.is_finite()) {
            return Err(Error::invalid_value(format!("stage_mm[{i}]"), *z, format!("stage_mm[{i}] {z} is not finite")));
        }
        if !(1..=MAX_FRAMES).contains(&self.frames) {
            let message = format!("frames: {} frames per view; give 1..={MAX_FRAMES}", self.frames);
            return Err(Error::invalid_value("frames", self.frames, message));
        }
        self.validate_currents()?;
        if let Some(n) = self.offstate_views {
            if n as usize > MAX_VIEWS {
                let message = format!("offstate_views: {n} views, more than the {MAX_VIEWS} a plan may hold");
                return Err(Error::invalid_value("offstate_views", n, message));
            }
        }
        if let Some(t) = &self.thermal {
            t.validate()?;
        }
        Ok(())
    }

    /// The temperature procedure's grid, for `etlcal capture thermal`: the `thermal` keys
    /// and the plan's currents (focus `"current"`, at least [`THERMAL_DISTINCT_NEEDED`]
    /// distinct), each with its stage position. The error names the key.
    pub fn thermal_grid(&self) -> Result<(&ThermalPlan, &[f64])> {
        let Some(t) = &self.thermal else {
            let message = "thermal: the plan has no \"thermal\" keys (temperatures_c, temperature_tolerance_c, \
                           temperature_timeout_s) for the temperature procedure";
            return Err(Error::invalid("thermal", message));
        };
        let (Focus::Current, Some(c)) = (self.focus, &self.currents_ma) else {
            let message = "focus: the temperature procedure starts each series at one of the plan's currents: \
                           give focus \"current\" with currents_ma (the board in focus at stage_mm)";
            return Err(Error::invalid("focus", message));
        };
        if distinct(c) < THERMAL_DISTINCT_NEEDED {
            let message = format!(
                "currents_ma: {} distinct currents; the cubic surface needs at least {THERMAL_DISTINCT_NEEDED}",
                distinct(c)
            );
            return Err(Error::invalid("currents_ma", message));
        }
        Ok((t, c))
    }

    fn validate_currents(&self) -> Result<()> {
        match (self.focus, &self.currents_ma) {
            (Focus::Current, None) => Err(Error::invalid(
                "currents_ma",
                "currents_ma: focus \"current\" needs one current per stage position, mA",
            )),
            (Focus::Autofocus, Some(_)) => Err(Error::invalid(
                "currents_ma",
                "currents_ma: focus \"autofocus\" finds the currents itself; give currents_ma with focus \"current\" only",
            )),
            (Focus::Current, Some(c)) if c.len() != self.stage_mm.len() => {
                let message = format!(
                    "currents_ma: {} currents for {} stage positions; give one per position",
                    c.len(),
                    self.stage_mm.len()
                );
                Err(Error::invalid("currents_ma", message))
            }
            (Focus::Current, Some(c)) => match c.iter().enumerate().find(|(_, e)| !e.is_finite()) {
                Some((i, e)) => {
                    Err(Error::invalid_value(format!("currents_ma[{i}]"), *e, format!("currents_ma[{i}] {e} is not finite")))
                }
                None => Ok(()),
            },
            (Focus::Autofocus, None) => Ok(()),
        }
    }

    /// The lens-off board (`offstate_board`, or `board`).
    pub fn offstate_board(&self) -> Board {
        self.offstate_board.unwrap_or(self.board)
    }

    /// The number of lens-off views (0 without `offstate_views`).
    pub fn offstate_count(&self) -> usize {
        self.offstate_views.unwrap_or(0) as usize
    }

    /// Checks the stage positions against a stage's travel `[lo, hi]`, mm: the first
    /// position outside is named.
    pub fn check_stage_limits(&self, limits_mm: [f64; 2], stage: &str) -> Result<()> {
        let [lo, hi] = limits_mm;
        match self.stage_mm.iter().enumerate().find(|(_, z)| !(lo..=hi).contains(*z)) {
            Some((i, z)) => Err(Error::invalid_value(
                format!("stage_mm[{i}]"),
                *z,
                format!("stage_mm[{i}] {z} mm is outside the travel of stage {stage}, [{lo}, {hi}] mm"),
            )),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(text: &str) -> Result<Plan> {
        let p: Plan = crate::parse_json(text, Path::new("plan.json"), FORMAT)?;
        p.validate()?;
        Ok(p)
    }

    const BOARD: &str = r#""board": {"type": "checkerboard", "inner_corners": [9, 7], "square_mm": 2.0}"#;

    #[test]
    fn a_plan_reads_and_every_bad_key_is_named() {
        let ok = plan(&format!(
            r#"{{"format": "etlcal.plan/1", {BOARD}, "stage_mm": [10, 20], "frames": 2, "focus": "current", "currents_ma": [100, 150], "offstate_views": 3}}"#
        ))
        .unwrap();
        assert_eq!((ok.stage_mm.len(), ok.frames, ok.offstate_count()), (2, 2, 3));
        let cases = [
            (r#""stage_mm": [], "frames": 1, "focus": "autofocus""#, "stage_mm"),
            (r#""stage_mm": [1], "frames": 0, "focus": "autofocus""#, "frames"),
            (r#""stage_mm": [1], "frames": 1, "focus": "current""#, "currents_ma"),
            (r#""stage_mm": [1], "frames": 1, "focus": "current", "currents_ma": [1, 2]"#, "currents_ma"),
            (r#""stage_mm": [1], "frames": 1, "focus": "autofocus", "speed": 3"#, "speed"),
            (r#""stage_mm": [1], "frames": 1, "focus": "blur""#, "focus"),
        ];
        for (body, key) in cases {
            let e = plan(&format!(r#"{{"format": "etlcal.plan/1", {BOARD}, {body}}}"#)).unwrap_err().to_string();
            assert!(e.contains(key) && !e.contains('\n'), "{body}: {e}");
        }
        let e = ok.check_stage_limits([0.0, 15.0], "sim").unwrap_err().to_string();
        assert!(e.contains("stage_mm[1]") && e.contains("sim"), "{e}");
    }
}
