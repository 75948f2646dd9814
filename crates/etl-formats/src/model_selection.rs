//! `"model_selection"` of `etlcal.calibration/1` (optional): how `calibrate --distortion
//! auto` / `--focal-degree auto` chose the model, as the table it chose from.
//!
//! ```json
//! "model_selection": {"method": "leave-one-view-out", "rule": "one-standard-error",
//!   "candidates": [{"distortion_model": "paper", "focal_degree": 3, "parameters": 25,
//!                   "fit_rms_px": 0.29, "prediction_rms_px": 0.41, "excess_mse_px2": 0.0,
//!                   "excess_se_px2": 0.0, "chosen": true}, ...]}
//! ```
//!
//! Each candidate: its family and focal degree, its number of model parameters, the RMS of
//! its fit to every view, the RMS with which it predicts each view held out (fitted to the
//! others), its held-out mean squared error above the best candidate's and the standard
//! error of that excess (the larger of its spread over the views and its noise model's);
//! or `"error"`, why it could not be fitted.
//! The chosen candidate is the simplest whose excess is within one standard error
//! (etl_calib::pipeline::select documents the method and why).

use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// One candidate model of the comparison.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelCandidate {
    /// `"paper"` or `"opencv"`.
    pub distortion_model: String,
    /// Degree of fx(E), fy(E), 1..=5.
    pub focal_degree: usize,
    /// `"moving"` for a candidate with the moving centre (Eq. C1-C3); absent for the fixed
    /// centre (and in files written before the centre was a candidate).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub centre: Option<String>,
    /// Model parameters (pose, focal polynomials, principal point, a_i, the centre's).
    pub parameters: usize,
    /// RMS reprojection error of the fit to every view, px.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fit_rms_px: Option<f64>,
    /// RMS error of each view's pixels predicted by the model fitted without it, px.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prediction_rms_px: Option<f64>,
    /// Held-out mean squared error above the best candidate's, px^2 (0 for the best).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub excess_mse_px2: Option<f64>,
    /// Standard error of that excess, px^2: the larger of its paired spread over the
    /// held-out views and its value from the views' noise model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub excess_se_px2: Option<f64>,
    /// Whether this is the model of the calibration.
    pub chosen: bool,
    /// Why the candidate could not be fitted (its numbers are then absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// The comparison a model choice was made by.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelSelection {
    /// How the prediction error was measured: `"leave-one-view-out"`.
    pub method: String,
    /// How the choice follows from it: `"one-standard-error"`.
    pub rule: String,
    /// Every candidate, in the order they were tried.
    pub candidates: Vec<ModelCandidate>,
}

impl ModelSelection {
    /// The chosen candidate (the first marked so).
    pub fn chosen(&self) -> Option<&ModelCandidate> {
        self.candidates.iter().find(|c| c.chosen)
    }

    /// Checks the table: exactly one candidate chosen, and it fitted; families known,
    /// degrees 1..=5; every number finite and not negative (the excess is never below the
    /// best's). Errors name the entry and the field.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::invalid("model_selection", format!("model_selection: {m}")));
        let chosen = self.candidates.iter().filter(|c| c.chosen).count();
        if chosen != 1 {
            return bad(format!("{chosen} candidates are marked chosen, expected 1"));
        }
        for (i, c) in self.candidates.iter().enumerate() {
            if etl_core::model::DistortionModel::from_name(&c.distortion_model).is_none() {
                return bad(format!(
                    "candidates[{i}].distortion_model = {:?} is not \"paper\" or \"opencv\"",
                    c.distortion_model
                ));
            }
            if !(1..=etl_core::model::MAX_FOCAL_DEGREE).contains(&c.focal_degree) {
                return bad(format!("candidates[{i}].focal_degree = {} is outside 1..=5", c.focal_degree));
            }
            if let Some(centre) = c.centre.as_deref().filter(|&w| w != "moving") {
                return bad(format!("candidates[{i}].centre = {centre:?} is not \"moving\" (absent: fixed)"));
            }
            let numbers = [
                ("fit_rms_px", c.fit_rms_px),
                ("prediction_rms_px", c.prediction_rms_px),
                ("excess_mse_px2", c.excess_mse_px2),
                ("excess_se_px2", c.excess_se_px2),
            ];
            if let Some((name, v)) = numbers.iter().find(|(_, v)| v.is_some_and(|v| !(v.is_finite() && v >= 0.0))) {
                return bad(format!("candidates[{i}].{name} = {v:?} must be a finite number >= 0"));
            }
            if c.chosen && (c.error.is_some() || c.prediction_rms_px.is_none()) {
                return bad(format!("candidates[{i}] is chosen but was not fitted"));
            }
        }
        Ok(())
    }
}
