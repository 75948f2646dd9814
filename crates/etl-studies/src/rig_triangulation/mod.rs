//! The acceptance of a calibrated two-camera ETL rig: triangulated points at random
//! settings against their propagated uncertainty, and a 2 mm move measured by
//! triangulation, on the simulated rig of [`etl_sim::multi_camera`] (the paper's model per
//! camera, fixed or moving centres).
//!
//! Each trial (its own seed) simulates the rig ([`simulate_multi_camera`], 15 stage views,
//! 60 mm baseline) and calibrates it jointly ([`calibrate_rig`]) with the default request
//! (errors-in-variables with the paper's priors; sigma_px from the residuals), the paper's
//! thermal surface ([`options`]) and, for a moving-centre rig, `centre = moving`. Then, with the estimated rig ([`Rig`]) against the
//! simulation's true cameras:
//!
//! - **a random point** ([`point`]): each camera's E_com uniform in its calibrated range
//!   (given to the rig as E_in at the views' temperature, through the paper's thermal
//!   surface, as the simulation records it), a point uniform in the stage's volume (X, Y
//!   over the board, Z over the travel) that both true cameras see at those settings
//!   (not necessarily in focus), its true pixels plus pixel noise of the simulation's
//!   sigma, triangulated with the pixel and calibration parts of the covariance
//!   ([`etl_calib::rig::CalibrationPart::Include`], the calibration's part from the rig file's joint
//!   covariance; beside it, the same rig without it: independent groups); per axis of camera 0's frame, whether
//!   |error| <= 1 sigma, and the Mahalanobis distance d^2 (chi-square with 3 dof: mean 3,
//!   P(d^2 <= 1) = 19.9 %);
//! - **a 2 mm move** ([`moves`]): the board at Z uniform in the travel and at Z + 2 mm,
//!   refocused or at fixed settings, the length of the triangulated corners' mean
//!   displacement against 2 mm, beside camera 0's PnP.
//!
//! The pixels at run time are those of the true lens at exactly the commanded setting
//! (no current error at run time): the calibration's current errors are in the
//! calibration's covariance, a run-time current error is not in the triangulation's.

pub mod moves;
pub mod point;

use std::path::Path;

use etl_calib::request::{CalibrationRequest, CentreChoice};
use etl_calib::rig::{Rig, RigSetting};
use etl_calib::rig_calibration::{calibrate_rig, RigCalibrationOptions};
use etl_core::model::CameraModel;
use etl_core::thermal::ThermalSurface;
use etl_formats::rig::RigFile;
use etl_formats::{Result, ThermalRef};
use etl_sim::multi_camera::{simulate_multi_camera, MultiCameraDesign, STAGE_TRAVEL_MM};
use etl_sim::rig::PAPER_TEMPERATURE_C;
use etl_sim::simulate::{gauss, NoiseModel};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::common::{stat, Stat};
pub use moves::{MoveErrors, MOVE_MM};
pub use point::PointError;

/// The study's noise: the paper's without the corner-position noise (the errors the
/// joint solve models: 0.2 px, 10 um of stage per view, 0.4 mA per camera and view).
pub const NOISE: NoiseModel = crate::rig_efficiency::NOISE;

/// What the trials simulate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigTriangulationDesign {
    /// Whether the cameras' centres move with the setting (and are calibrated so).
    pub moving_centre: bool,
    /// The simulation's noise.
    pub noise: NoiseModel,
}

/// One trial's results.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Trial {
    /// Its seed.
    pub seed: u64,
    /// The random point.
    pub point: PointError,
    /// The 2 mm move.
    pub moves: MoveErrors,
}

/// Whether a pixel falls in the simulated cameras' image.
pub(crate) fn in_image(p: [f64; 2]) -> bool {
    let [w, h] = CameraModel::PAPER_IMAGE_SIZE.map(|s| f64::from(s) - 1.0);
    (0.0..=w).contains(&p[0]) && (0.0..=h).contains(&p[1])
}

/// The rig's settings for compensated currents `e_com_ma`: E_in at `temperature_c` by the
/// paper's thermal surface (what the simulation records).
pub(crate) fn settings_of(e_com_ma: &[f64], temperature_c: f64) -> Result<Vec<RigSetting>> {
    e_com_ma.iter().map(|&e| Ok(RigSetting::of(ThermalSurface::PAPER.e_in_for_e_com(e, temperature_c)?))).collect()
}

/// The calibration request of the study: the default, with the paper's thermal surface
/// (the simulation's: without a thermal part a calibration takes no E_in and temperature,
/// and a rig takes no other setting) and `centre = moving` for a moving-centre rig.
pub fn options(design: &RigTriangulationDesign) -> RigCalibrationOptions {
    let centre = design.moving_centre.then_some(CentreChoice::Moving);
    let request = CalibrationRequest { centre, thermal: Some(ThermalRef::paper()), ..Default::default() };
    RigCalibrationOptions { request, ..Default::default() }
}

/// One trial (module docs) of seed `seed`.
pub fn trial(design: &RigTriangulationDesign, seed: u64) -> Result<Trial> {
    let rig_design = MultiCameraDesign { moving_centre: design.moving_centre, ..MultiCameraDesign::new(2) };
    let sim = simulate_multi_camera(&rig_design, &design.noise, seed)?;
    let calibrated = calibrate_rig(&sim.dataset, &options(design))?;
    let file = calibrated.rig_file();
    let rig = Rig::from_file(file.clone(), Path::new("."))?;
    let independent = Rig::from_file(RigFile { joint_covariance: None, ..file }, Path::new("."))?;
    let ranges = [0, 1].map(|k| calibrated.cameras[k].calibration.e_com_range_ma);
    // The run-time draws from their own stream, apart from the simulation's.
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_ac0e);
    let t = PAPER_TEMPERATURE_C;
    let point = point::point_error((&rig, &independent), &sim.truths, (ranges, t), design.noise.px, &mut rng)?;
    let [z0, z1] = STAGE_TRAVEL_MM;
    // Half a millimetre inside the travel: the focus currents stay inside the ranges.
    let z = rng.random_range(z0 + 0.5..=z1 - MOVE_MM - 0.5);
    let moves = moves::move_errors(&rig, &sim.truths, t, z, design.noise.px, &mut rng)?;
    Ok(Trial { seed, point, moves })
}

/// Root mean square, max |x| and mean of a measurement's errors, um.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MoveStat {
    /// sqrt(mean x^2).
    pub rms_um: f64,
    /// max |x|.
    pub max_um: f64,
    /// mean x (the bias).
    pub mean_um: f64,
}

pub(crate) fn move_stat(x: &[f64]) -> MoveStat {
    let n = x.len().max(1) as f64;
    MoveStat {
        rms_um: (x.iter().map(|v| v * v).sum::<f64>() / n).sqrt(),
        max_um: x.iter().fold(0.0, |m, v| v.abs().max(m)),
        mean_um: x.iter().sum::<f64>() / n,
    }
}

/// The study's result.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RigTriangulation {
    /// The design.
    pub moving_centre: bool,
    /// Trials run.
    pub trials: usize,
    /// Trials that failed (left out), with their seed and error.
    pub failed: Vec<(u64, String)>,
    /// Fraction of the 1-sigma intervals covering the truth, per axis of camera 0's frame.
    pub coverage_per_axis: [f64; 3],
    /// The same over all axes (3 per trial).
    pub coverage: f64,
    /// The z-scores error / sigma per axis: mean and standard deviation (1 if the
    /// propagated sigma is right).
    pub z_scores: [Stat; 3],
    /// Mean d^2 (3 if the covariance is right) with its standard error.
    pub d2: Stat,
    /// Fraction with d^2 <= 1 (19.9 % if right).
    pub within_ellipsoid: f64,
    /// Coverage per axis with the calibration part from independent groups (the rig
    /// file without its `joint_covariance`).
    pub coverage_independent_per_axis: [f64; 3],
    /// The z-scores with that covariance.
    pub z_scores_independent: [Stat; 3],
    /// Mean d^2 with that covariance.
    pub d2_independent: Stat,
    /// Mean d^2 with the pixel part of the covariance alone.
    pub d2_pixels_only: Stat,
    /// Mean share of the calibration part in the covariance's trace.
    pub calibration_share: f64,
    /// Mean propagated sigma per axis, um.
    pub mean_std_um: [f64; 3],
    /// The move by triangulation, refocused and at fixed settings; by camera 0's PnP,
    /// refocused and fixed.
    pub moves: [MoveStat; 4],
    /// Every trial that succeeded.
    pub results: Vec<Trial>,
}

/// Runs `trials` trials from `seed` (trial t seeded `seed + t`), in parallel.
pub fn rig_triangulation(design: &RigTriangulationDesign, trials: usize, seed: u64) -> RigTriangulation {
    let runs: Vec<(u64, Result<Trial>)> =
        (0..trials as u64).into_par_iter().map(|t| (seed + t, trial(design, seed + t))).collect();
    let mut results = vec![];
    let mut failed = vec![];
    for (s, r) in runs {
        match r {
            Ok(t) => results.push(t),
            Err(e) => failed.push((s, e.to_string())),
        }
    }
    summarise(design, trials, results, failed)
}

fn summarise(
    design: &RigTriangulationDesign,
    trials: usize,
    results: Vec<Trial>,
    failed: Vec<(u64, String)>,
) -> RigTriangulation {
    let n = results.len().max(1) as f64;
    let covered = |i: usize| results.iter().filter(|t| t.point.z_scores[i].abs() <= 1.0).count() as f64 / n;
    let coverage_per_axis = [0, 1, 2].map(covered);
    let covered_independent =
        |i: usize| results.iter().filter(|t| t.point.z_scores_independent[i].abs() <= 1.0).count() as f64 / n;
    let column = |f: &dyn Fn(&Trial) -> f64| results.iter().map(f).collect::<Vec<f64>>();
    let m = |f: &dyn Fn(&MoveErrors) -> f64| move_stat(&column(&|t| f(&t.moves)));
    RigTriangulation {
        moving_centre: design.moving_centre,
        trials,
        coverage_per_axis,
        coverage: coverage_per_axis.iter().sum::<f64>() / 3.0,
        z_scores: [0, 1, 2].map(|i| stat(&column(&|t| t.point.z_scores[i]))),
        d2: stat(&column(&|t| t.point.d2)),
        coverage_independent_per_axis: [0, 1, 2].map(covered_independent),
        z_scores_independent: [0, 1, 2].map(|i| stat(&column(&|t| t.point.z_scores_independent[i]))),
        d2_independent: stat(&column(&|t| t.point.d2_independent)),
        within_ellipsoid: results.iter().filter(|t| t.point.d2 <= 1.0).count() as f64 / n,
        d2_pixels_only: stat(&column(&|t| t.point.d2_pixels_only)),
        calibration_share: column(&|t| t.point.calibration_share).iter().sum::<f64>() / n,
        mean_std_um: [0, 1, 2].map(|i| 1000.0 * column(&|t| t.point.std_mm[i]).iter().sum::<f64>() / n),
        moves: [
            m(&|e| e.triangulated_refocused_um),
            m(&|e| e.triangulated_fixed_um),
            m(&|e| e.pnp_refocused_um),
            m(&|e| e.pnp_fixed_um),
        ],
        results,
        failed,
    }
}

impl RigTriangulation {
    /// The result as markdown: the coverage table and the move table.
    pub fn markdown(&self) -> String {
        let centre = if self.moving_centre { "moving" } else { "fixed" };
        let mut s = format!(
            "{} trials, {} centres ({} failed)\n\n| axis | coverage of 1 sigma | z-score mean | z-score std | mean sigma (um) | coverage, independent groups | z-score std, independent |\n|---|---|---|---|---|---|---|\n",
            self.trials,
            centre,
            self.failed.len()
        );
        for (i, axis) in ["X", "Y", "Z"].iter().enumerate() {
            let z = &self.z_scores[i];
            let zi = &self.z_scores_independent[i];
            s += &format!(
                "| {axis} | {:.1} % | {:+.3} | {:.3} ± {:.3} | {:.2} | {:.1} % | {:.3} ± {:.3} |\n",
                100.0 * self.coverage_per_axis[i],
                z.mean,
                z.std,
                z.std_se,
                self.mean_std_um[i],
                100.0 * self.coverage_independent_per_axis[i],
                zi.std,
                zi.std_se
            );
        }
        s += &format!(
            "\nall axes: {:.1} % (target 68 ± 5 %); mean d^2 {:.2} ± {:.2} (3 if right); P(d^2 <= 1) {:.1} % (19.9 %); pixel part alone: mean d^2 {:.1}; calibration's share of the trace {:.1} %; independent groups instead of the joint covariance: all axes {:.1} %, mean d^2 {:.2} ± {:.2}\n",
            100.0 * self.coverage,
            self.d2.mean,
            self.d2.mean_se,
            100.0 * self.within_ellipsoid,
            self.d2_pixels_only.mean,
            100.0 * self.calibration_share,
            100.0 * self.coverage_independent_per_axis.iter().sum::<f64>() / 3.0,
            self.d2_independent.mean,
            self.d2_independent.mean_se
        );
        s += "\n| 2 mm move | RMS (um) | max (um) | mean (um) |\n|---|---|---|---|\n";
        let names = [
            "triangulated, refocused",
            "triangulated, fixed settings",
            "camera 0 PnP, refocused",
            "camera 0 PnP, fixed settings",
        ];
        for (name, m) in names.iter().zip(&self.moves) {
            s += &format!("| {name} | {:.3} | {:.3} | {:+.3} |\n", m.rms_um, m.max_um, m.mean_um);
        }
        for (seed, e) in &self.failed {
            s += &format!("\nfailed: seed {seed}: {e}");
        }
        s
    }
}
