//! The statistical efficiency of the joint rig calibration
//! ([`etl_calib::rig_calibration`]) on the simulated 2-camera rig
//! ([`etl_sim::multi_camera`]): the Monte Carlo variance of the extrinsics and of each
//! camera's fx(E) against the Cramer-Rao bound of the joint problem.
//!
//! Each trial simulates the rig under the paper's noise model without the corner-position
//! noise (0.2 px pixel noise, one 10 um stage error per view shared by the cameras, a
//! 0.4 mA current error per camera and view: exactly the errors-in-variables model the
//! joint solve assumes), with its own seed, and calibrates it jointly with the pixel noise
//! given (0.2 px). The bound is the inverse of the joint problem's Fisher information at
//! the truth under that noise, the corrections marginalised out
//! ([`JointSystem::covariance`]); a quantity q(x) gets g' C g, g its gradient. The visible
//! corners and the settings are the same in every trial (the design fixes them), so one
//! bound serves all trials. Efficiency = bound variance / Monte Carlo variance (1: the
//! bound reached; the Monte Carlo variance of 300 trials is itself known to about 8 %).
//! Beside it, the spread of the same quantities from each camera's own calibration (the
//! cameras calibrated apart, the joint solve's start).

use etl_calib::request::{CalibrationRequest, EivPriors};
use etl_calib::rig_calibration::{calibrate_rig, JointSystem, RigCalibrationOptions};
use etl_core::model::CameraModel;
use etl_formats::rig::relative_pose;
use etl_formats::Result;
use etl_sim::multi_camera::{simulate_multi_camera, MultiCameraDesign};
use etl_sim::simulate::NoiseModel;
use nalgebra::DMatrix;
use rayon::prelude::*;

/// The currents at which each camera's fx(E) is compared, mA (inside every camera's range).
pub const FX_CURRENTS_MA: [f64; 3] = [90.0, 150.0, 210.0];

/// The noise of the study (module docs).
pub const NOISE: NoiseModel = NoiseModel { xy_mm: 0.0, ..NoiseModel::PAPER };

/// One compared quantity.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Quantity {
    /// Its name (`"T_x (mm)"`, `"cam1 fx(150 mA) (px)"`).
    pub name: String,
    /// Its true value.
    pub truth: f64,
    /// The mean of the estimates minus the truth.
    pub bias: f64,
    /// The standard deviation of the estimates.
    pub monte_carlo_std: f64,
    /// The Cramer-Rao bound's standard deviation.
    pub crlb_std: f64,
    /// crlb_std^2 / monte_carlo_std^2.
    pub efficiency: f64,
    /// The standard deviation of the same quantity from each camera's own calibration
    /// (the joint solve's start: the cameras calibrated apart, the extrinsics from their
    /// poses).
    pub separate_std: f64,
}

/// The study's result.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RigEfficiency {
    /// Trials run.
    pub trials: usize,
    /// Trials whose calibration failed (left out).
    pub failed: usize,
    /// The quantities: the 6 extrinsics, then each camera's fx at [`FX_CURRENTS_MA`].
    pub quantities: Vec<Quantity>,
}

/// The compared quantities of a rig's models (camera 0 first): the extrinsics of camera
/// 1, then each camera's fx at [`FX_CURRENTS_MA`].
fn quantities(models: &[CameraModel]) -> Vec<f64> {
    let pose = |m: &CameraModel| (m.rotation_rodrigues, m.translation_mm);
    let (om, t) = relative_pose(pose(&models[0]), pose(&models[1]));
    let fx = models.iter().flat_map(|m| FX_CURRENTS_MA.map(|e| m.kf_x.eval(e)));
    om.into_iter().chain(t).chain(fx).collect()
}

/// The names of [`quantities`].
fn names(cameras: usize) -> Vec<String> {
    let pose = ["om_x (rad)", "om_y (rad)", "om_z (rad)", "T_x (mm)", "T_y (mm)", "T_z (mm)"].map(String::from);
    let fx = (0..cameras).flat_map(|k| FX_CURRENTS_MA.map(|e| format!("cam{k} fx({e} mA) (px)")));
    pose.into_iter().chain(fx).collect()
}

/// The bound's variance of every quantity: the extrinsics' from the system's 6 x 6, fx's
/// from the gradient (1, E, E^2, ...) over the kf_x coefficients.
fn crlb_variances(system: &JointSystem, truths: &[CameraModel]) -> Result<Vec<f64>> {
    let c = system.covariance()?;
    let e = system.extrinsics_covariance(1, &c);
    let off = system.offsets();
    let mut out: Vec<f64> = (0..6).map(|i| e[i][i]).collect();
    for (k, m) in truths.iter().enumerate() {
        let span = m.layout().kf_x();
        for e_ma in FX_CURRENTS_MA {
            let g: Vec<(usize, f64)> = (0..span.len).map(|i| (off[k] + span.at(i), e_ma.powi(i as i32))).collect();
            out.push(g.iter().map(|&(a, ga)| g.iter().map(|&(b, gb)| ga * c[(a, b)] * gb).sum::<f64>()).sum());
        }
    }
    Ok(out)
}

/// Runs `trials` trials from `seed` (trial t seeded `seed + t`) on the 2-camera rig.
pub fn rig_efficiency(trials: usize, seed: u64) -> Result<RigEfficiency> {
    let design = MultiCameraDesign::new(2);
    let first = simulate_multi_camera(&design, &NOISE, seed)?;
    let system = JointSystem::new(&first.dataset, &first.truths, NOISE.px, (NOISE.z_mm, NOISE.e_ma))?;
    let bound = crlb_variances(&system, &first.truths)?;
    let truth = quantities(&first.truths);
    let priors = EivPriors { sigma_px: Some(NOISE.px), ..EivPriors::default() };
    let options =
        RigCalibrationOptions { request: CalibrationRequest { priors, ..Default::default() }, ..Default::default() };
    let estimates: Vec<Option<[Vec<f64>; 2]>> = (0..trials as u64)
        .into_par_iter()
        .map(|t| {
            let sim = simulate_multi_camera(&design, &NOISE, seed + t).ok()?;
            let rig = calibrate_rig(&sim.dataset, &options).ok()?;
            let models: Vec<CameraModel> = (0..2).filter_map(|k| rig.model(k).ok()).collect();
            let own: Vec<CameraModel> = rig.cameras.iter().filter_map(|c| c.own.model().ok()).collect();
            (models.len() == 2 && own.len() == 2).then(|| [quantities(&models), quantities(&own)])
        })
        .collect();
    let ok: Vec<&[Vec<f64>; 2]> = estimates.iter().flatten().collect();
    let n = ok.len().max(2) as f64;
    let spread = |which: usize, j: usize| {
        let x = DMatrix::from_fn(ok.len(), 1, |i, _| ok[i][which][j]);
        let mean = x.sum() / n;
        (mean, x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0))
    };
    let quantities = names(2)
        .into_iter()
        .enumerate()
        .map(|(j, name)| {
            let ((mean, var), (_, separate)) = (spread(0, j), spread(1, j));
            Quantity {
                name,
                truth: truth[j],
                bias: mean - truth[j],
                monte_carlo_std: var.sqrt(),
                crlb_std: bound[j].max(0.0).sqrt(),
                efficiency: bound[j] / var,
                separate_std: separate.sqrt(),
            }
        })
        .collect();
    Ok(RigEfficiency { trials, failed: trials - ok.len(), quantities })
}

impl RigEfficiency {
    /// The result as a markdown table.
    pub fn markdown(&self) -> String {
        let mut s = format!(
            "{} trials ({} failed)\n\n| quantity | truth | bias | Monte Carlo std | CRLB std | efficiency | std, cameras apart |\n|---|---|---|---|---|---|---|\n",
            self.trials, self.failed
        );
        for q in &self.quantities {
            s += &format!(
                "| {} | {:.6} | {:.2e} | {:.3e} | {:.3e} | {:.3} | {:.3e} |\n",
                q.name, q.truth, q.bias, q.monte_carlo_std, q.crlb_std, q.efficiency, q.separate_std
            );
        }
        s
    }
}
