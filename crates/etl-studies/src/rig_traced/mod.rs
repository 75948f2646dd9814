//! The acceptance of a calibrated two-camera ETL rig on ray-traced optics: the study of
//! [`crate::rig_triangulation`] (triangulated points at random settings against their
//! propagated uncertainty, a 2 mm move measured by triangulation) on the traced rig of
//! [`etl_sim::optics::multi_camera`], where every corner is the centroid of a traced spot
//! and no camera model is exact.
//!
//! The rig is traced once ([`trace_multi_camera`]: two cameras of the given optics, 15
//! stage views over the travel both can focus, each camera refocused per view, lens-off
//! views); each trial (its own seed) gives that record its pixel noise
//! ([`TracedMultiCamera::with_pixel_noise`], the procedure's 0.05 px; no stage or current
//! error) and calibrates it with [`calibrate_rig`] ([`RigRequest`]: the default request,
//! `--hold-a0` or `--centre moving`, each with the paper's thermal surface, which the
//! traced procedure records E_in by). Then, with the estimated rig ([`Rig`]) against the
//! traced cameras:
//!
//! - **a random point**: each camera's E_com uniform in its calibrated range, a point
//!   uniform in the stage's volume (X, Y over the board, Z over the travel) that both
//!   traced cameras see there (not necessarily in focus), its traced pixels plus noise,
//!   triangulated by `RigAt::triangulate` with the pixel and joint calibration parts.
//!   Or, [`PointDraw::InFocus`], as an autofocusing rig measures: the point first, each
//!   camera focused on it. Each trial records the point's defocus per camera, and the
//!   result bins both measures by it ([`RigTraced::by_defocus`]).
//! - **a 2 mm move**: the board at Z uniform in the travel (0.5 mm inside either end) and
//!   at Z + 2 mm, both cameras refocused at each position (each at its focus current,
//!   [`TracedMultiCamera::focus_currents_ma`]), every corner both see at both positions
//!   triangulated; the length of the corners' mean displacement against 2 mm
//!   ([`crate::rig_triangulation::moves::measure_move`], beside camera 0's PnP).
//!
//! **Coverage without a true camera frame.** On the paper's model the truth of a
//! triangulated point is exact in camera 0's frame. Traced optics have no such frame: the
//! rays of a non-central camera do not meet in one point, and the calibrated model's
//! centre is wherever the fit puts it (hundreds of um along the axis from the entrance
//! pupil with A0 free: docs/RESULTS.md, "The fixed centre on a ray-traced rig"). The truth
//! is exact in the stage's world frame (the board's corners at known stage positions), so
//! the study maps the triangulated point there through camera 0's *calibrated* pose and
//! propagates the joint calibration covariance through the whole map, camera 0's pose
//! included ([`world`]): W = R_0' (X - t_0(E_0)), Cov_W = R_0' Cov_pixels R_0 + J
//! Sigma_joint J'. Its error against the true world point, per world axis (|e_i| <=
//! sigma_i, 68.3 % if right) and as d^2 = e' Cov_W^-1 e (chi-square, 3 dof: mean 3), is
//! the acceptance's coverage. It depends on no frame the optics do not define, and it
//! keeps what matters to a user: where the point is relative to the stage. The move is
//! frame-independent by construction (a length).
//!
//! Beside it, the paper study's definition where it applies: the error in camera 0's
//! frame at its setting against the covariance `triangulate` returns, the truth taken
//! in camera 0's traced frame with its origin moved to the paraxial entrance pupil at
//! E_0 (the centre a pinhole model of that setting would have).
//!
//! The baseline: [`RigCalibration::baseline_mm`] against the distance between the two
//! cameras' paraxial entrance pupils at their focus currents at the middle of the travel.

pub mod observe;
pub mod world;

use std::path::Path;

use etl_calib::request::{CalibrationRequest, CentreChoice};
use etl_calib::rig::{CalibrationPart, Rig};
use etl_calib::rig_calibration::{calibrate_rig, RigCalibration, RigCalibrationOptions};
use etl_core::model::rotation::Mat3;
use etl_core::model::CameraModel;
use etl_formats::{Error, Result, ThermalRef, Trust};
use etl_sim::optics::multi_camera::{trace_multi_camera, TracedMultiCamera};
use nalgebra::DMatrix;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::common::{stat, Stat};
use crate::rig_triangulation::moves::{measure_move, MOVE_MM};
use crate::rig_triangulation::point::mahalanobis2;
use crate::rig_triangulation::{move_stat, settings_of, MoveStat};

pub use etl_sim::optics::multi_camera::TracedRigDesign;

/// The calibration request of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum RigRequest {
    /// The default request (errors-in-variables, A0 by Zhang on the lens-off views, free).
    Default,
    /// `--hold-a0`: A0 held at its Zhang estimate.
    HoldA0,
    /// `--centre moving` (kept when ill-conditioned: on the stage's fronto-parallel
    /// views the centre's move is barely observable).
    MovingCentre,
    /// `--centre moving --setting-views joint`: each camera's own calibration takes the
    /// rig's free views as tilted views (a traced rig with `free_views`), which make the
    /// centre's move observable.
    MovingTilted,
}

impl RigRequest {
    /// The requests the example runs, in order.
    pub const ALL: [RigRequest; 3] = [RigRequest::Default, RigRequest::HoldA0, RigRequest::MovingCentre];

    /// Its name, as `etlcal calibrate-rig` spells it.
    pub fn name(self) -> &'static str {
        match self {
            RigRequest::Default => "default",
            RigRequest::HoldA0 => "--hold-a0",
            RigRequest::MovingCentre => "--centre moving",
            RigRequest::MovingTilted => "--centre moving --setting-views joint",
        }
    }

    /// Its options: the request plus the paper's thermal surface (the traced procedure
    /// records E_in through it; without a thermal part a calibration takes no E_in).
    pub fn options(self) -> RigCalibrationOptions {
        let base = CalibrationRequest { thermal: Some(ThermalRef::paper()), ..Default::default() };
        let request = match self {
            RigRequest::Default => base,
            RigRequest::HoldA0 => CalibrationRequest { hold_a0: true, ..base },
            RigRequest::MovingCentre => {
                CalibrationRequest { centre: Some(CentreChoice::Moving), accept_ill_conditioned: true, ..base }
            }
            RigRequest::MovingTilted => CalibrationRequest {
                centre: Some(CentreChoice::Moving),
                setting_views: Some(etl_calib::pipeline::SettingViews::Joint),
                accept_ill_conditioned: true,
                ..base
            },
        };
        RigCalibrationOptions { request, ..Default::default() }
    }
}

/// A point's error against its covariance.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PointFit {
    /// error_i / sqrt(Cov_ii) per axis.
    pub z_scores: [f64; 3],
    /// e' Cov^-1 e.
    pub d2: f64,
    /// The same with the pixel part alone.
    pub d2_pixels_only: f64,
    /// sqrt(Cov_ii) per axis, mm.
    pub std_mm: [f64; 3],
    /// The error, mm.
    pub error_mm: [f64; 3],
    /// trace(calibration part) / trace(Cov).
    pub calibration_share: f64,
}

fn fit(error_mm: [f64; 3], pixels: &Mat3, calibration: &Mat3) -> Result<PointFit> {
    let cov: Mat3 = std::array::from_fn(|i| std::array::from_fn(|j| pixels[i][j] + calibration[i][j]));
    let std_mm: [f64; 3] = std::array::from_fn(|i| cov[i][i].max(0.0).sqrt());
    let trace = |c: &Mat3| c[0][0] + c[1][1] + c[2][2];
    Ok(PointFit {
        z_scores: std::array::from_fn(|i| error_mm[i] / std_mm[i]),
        d2: mahalanobis2(&cov, error_mm)?,
        d2_pixels_only: mahalanobis2(pixels, error_mm)?,
        std_mm,
        error_mm,
        calibration_share: trace(calibration) / trace(&cov),
    })
}

/// One trial's results.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Trial {
    /// Its seed.
    pub seed: u64,
    /// The random point's currents, mA.
    pub e_com_ma: [f64; 2],
    /// The random point's defocus in each camera, dioptres: 1000 / depth - 1000 / the
    /// distance in focus at its current (camera z, mm).
    pub defocus_dpt: [f64; 2],
    /// The random point in the world frame (the acceptance's measure).
    pub world: PointFit,
    /// The same point in camera 0's frame, the truth's origin at the entrance pupil.
    pub camera0: PointFit,
    /// The triangulated 2 mm move, refocused, minus 2 mm, um.
    pub move_um: f64,
    /// Camera 0's PnP of the same pixels, minus 2 mm, um.
    pub pnp_um: f64,
    /// The corners of the move.
    pub corners: usize,
    /// The calibrated baseline minus the entrance pupils' distance, mm.
    pub baseline_error_mm: f64,
    /// Each camera's RMS reprojection error in the joint solve, px.
    pub rms_px: [f64; 2],
}

/// How the random point of a trial is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub enum PointDraw {
    /// The acceptance's: each camera's E_com uniform in its calibrated range, the point
    /// uniform in the volume both see there, in focus or not.
    #[default]
    RandomSettings,
    /// The point uniform in the volume, each camera focused on it (an autofocusing rig):
    /// [`observe::draw_focused_point`].
    InFocus,
}

/// What a run asks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigTracedDesign {
    /// The calibration request.
    pub request: RigRequest,
    /// The pixel noise, px (the calibration's data and the run time's).
    pub sigma_px: f64,
    /// How the random point is drawn.
    pub point: PointDraw,
}

/// The distance between the cameras' paraxial entrance pupils at their focus currents at
/// the middle of the travel, mm.
pub fn pupil_baseline_mm(rig: &TracedMultiCamera) -> Result<f64> {
    let z = 0.5 * (rig.stage_travel_mm[0] + rig.stage_travel_mm[1]);
    let e = rig.focus_currents_ma(z)?;
    let p0 = rig.cameras[0].entrance_pupil_world_mm(e[0])?;
    let p1 = rig.cameras[1].entrance_pupil_world_mm(e[1])?;
    Ok((0..3).map(|i| (p1[i] - p0[i]).powi(2)).sum::<f64>().sqrt())
}

/// The calibrated rig of one trial: the run-time rig, both models, the joint covariance.
struct Calibrated {
    rig: Rig,
    models: [CameraModel; 2],
    joint: DMatrix<f64>,
    ranges: [[f64; 2]; 2],
}

impl Calibrated {
    fn of(c: &RigCalibration) -> Result<Self> {
        Ok(Calibrated {
            rig: Rig::from_file(c.rig_file(), Path::new("."))?,
            models: [c.model(0)?, c.model(1)?],
            joint: c.covariance.clone(),
            ranges: [0, 1].map(|k| c.cameras[k].calibration.e_com_range_ma),
        })
    }
}

/// The random point of a trial (module docs): its currents and both fits.
fn point_fits(
    rig: &TracedMultiCamera,
    cal: &Calibrated,
    (temperature_c, sigma_px, point): (f64, f64, PointDraw),
    rng: &mut ChaCha8Rng,
) -> Result<([f64; 2], PointFit, PointFit, [f64; 2])> {
    let none = || Error::invalid("point", "point: no point seen by both cameras at these settings");
    let (e, w, clean) = match point {
        PointDraw::RandomSettings => {
            let e = cal.ranges.map(|[lo, hi]| rng.random_range(lo..=hi));
            let (w, clean) = observe::draw_point(rig, &observe::settings(rig, e)?, rng).ok_or_else(none)?;
            (e, w, clean)
        }
        PointDraw::InFocus => {
            let d = observe::draw_focused_point(rig, cal.ranges, rng).ok_or_else(none)?;
            (d.e_com_ma, d.world_mm, d.pixels)
        }
    };
    let at = observe::settings(rig, e)?;
    let px = clean.map(|p| observe::noisy(p, sigma_px, rng));
    let t = cal.rig.at(&settings_of(&e, temperature_c)?, &[temperature_c; 2], Trust::Refuse)?.triangulate(
        &px.map(Some),
        sigma_px,
        CalibrationPart::Include,
    )?;
    let m0 = &cal.models[0];
    let estimate = world::to_world(m0, e[0], t.point_mm);
    let jac = world::world_jacobian(&cal.models, e, px, &cal.joint)?;
    let pixels_w = world::rotate_to_world(&m0.rotation_matrix(), &t.from_pixels);
    let world_fit = fit(std::array::from_fn(|i| estimate[i] - w[i]), &pixels_w, &world::propagate(&jac, &cal.joint))?;
    let mut truth = rig.cameras[0].world_to_camera(w);
    truth[2] += at[0].pupil.z_mm;
    let from_calibration = t.from_calibration.unwrap_or_default();
    let camera_fit = fit(std::array::from_fn(|i| t.point_mm[i] - truth[i]), &t.from_pixels, &from_calibration)?;
    Ok((e, world_fit, camera_fit, observe::defocus_dpt(rig, e, w)?))
}

/// One trial (module docs) of seed `seed` on the traced `rig`; `pupil_baseline_mm` its
/// true baseline ([`pupil_baseline_mm`]).
pub fn trial(rig: &TracedMultiCamera, design: &RigTracedDesign, pupil_baseline: f64, seed: u64) -> Result<Trial> {
    let calibrated = calibrate_rig(&rig.with_pixel_noise(design.sigma_px, seed), &design.request.options())?;
    let cal = Calibrated::of(&calibrated)?;
    // The run-time draws from their own stream, apart from the record's noise.
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_ac0e);
    let temperature_c = rig.cameras[0].optics.file.procedure.temperature_c;
    let (e_com_ma, world, camera0, defocus_dpt) =
        point_fits(rig, &cal, (temperature_c, design.sigma_px, design.point), &mut rng)?;
    let [z0, z1] = rig.stage_travel_mm;
    let z = rng.random_range(z0 + 0.5..=z1 - MOVE_MM - 0.5);
    let focus = |z: f64| -> Result<[f64; 2]> {
        let e = rig.focus_currents_ma(z)?;
        Ok([e[0], e[1]])
    };
    let (ea, eb) = (focus(z)?, focus(z + MOVE_MM)?);
    let a = observe::board_pixels(rig, z, ea, design.sigma_px, &mut rng)?;
    let b = observe::board_pixels(rig, z + MOVE_MM, eb, design.sigma_px, &mut rng)?;
    let corners_mm = observe::corners_mm(rig);
    let (move_um, pnp_um, corners) =
        measure_move(&cal.rig, (temperature_c, &corners_mm), [(ea, &a), (eb, &b)], design.sigma_px)?;
    let baseline = calibrated.baseline_mm(1).ok_or_else(|| Error::invalid("extrinsics", "no camera 1"))?;
    Ok(Trial {
        seed,
        e_com_ma,
        defocus_dpt,
        world,
        camera0,
        move_um,
        pnp_um,
        corners,
        baseline_error_mm: baseline - pupil_baseline,
        rms_px: [calibrated.cameras[0].rms_px, calibrated.cameras[1].rms_px],
    })
}

/// Coverage and d^2 of one measure of the point.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Coverage {
    /// Fraction of the 1-sigma intervals covering the truth, per axis.
    pub per_axis: [f64; 3],
    /// Over all axes.
    pub all: f64,
    /// The z-scores per axis: mean and standard deviation (1 if right).
    pub z_scores: [Stat; 3],
    /// Mean d^2 (3 if right).
    pub d2: Stat,
    /// Mean d^2 with the pixel part alone.
    pub d2_pixels_only: Stat,
    /// Mean propagated sigma per axis, um.
    pub mean_std_um: [f64; 3],
    /// RMS error per axis, um.
    pub rms_error_um: [f64; 3],
    /// Mean share of the calibration part in the covariance's trace.
    pub calibration_share: f64,
}

fn coverage(fits: &[PointFit]) -> Coverage {
    let n = fits.len().max(1) as f64;
    let col = |f: &dyn Fn(&PointFit) -> f64| fits.iter().map(f).collect::<Vec<f64>>();
    let mean = |v: Vec<f64>| v.iter().sum::<f64>() / n;
    let per_axis = [0, 1, 2].map(|i| fits.iter().filter(|f| f.z_scores[i].abs() <= 1.0).count() as f64 / n);
    Coverage {
        per_axis,
        all: per_axis.iter().sum::<f64>() / 3.0,
        z_scores: [0, 1, 2].map(|i| stat(&col(&|f| f.z_scores[i]))),
        d2: stat(&col(&|f| f.d2)),
        d2_pixels_only: stat(&col(&|f| f.d2_pixels_only)),
        mean_std_um: [0, 1, 2].map(|i| 1000.0 * mean(col(&|f| f.std_mm[i]))),
        rms_error_um: [0, 1, 2].map(|i| 1000.0 * mean(col(&|f| f.error_mm[i].powi(2))).sqrt()),
        calibration_share: mean(col(&|f| f.calibration_share)),
    }
}

/// The upper ends of the defocus bins of [`RigTraced::by_defocus`], dioptres (the last
/// bin is open).
pub const DEFOCUS_BINS_DPT: [f64; 4] = [0.25, 0.5, 1.0, 2.0];

/// The coverage of the trials whose larger defocus (of the two cameras) falls in one bin.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DefocusBin {
    /// The bin, [lo, hi) of max |defocus| over the cameras, dioptres (hi infinite: open).
    pub range_dpt: [f64; 2],
    /// The trials in it.
    pub trials: usize,
    /// The world measure over them.
    pub world: Coverage,
    /// The camera-0 measure over them.
    pub camera0: Coverage,
}

/// The trials binned by their larger defocus ([`DEFOCUS_BINS_DPT`]); empty bins left out.
fn by_defocus(results: &[Trial]) -> Vec<DefocusBin> {
    let edges: Vec<f64> = std::iter::once(0.0).chain(DEFOCUS_BINS_DPT).chain(std::iter::once(f64::INFINITY)).collect();
    edges
        .windows(2)
        .filter_map(|w| {
            let inside: Vec<&Trial> = results
                .iter()
                .filter(|t| (w[0]..w[1]).contains(&t.defocus_dpt[0].abs().max(t.defocus_dpt[1].abs())))
                .collect();
            (!inside.is_empty()).then(|| DefocusBin {
                range_dpt: [w[0], w[1]],
                trials: inside.len(),
                world: coverage(&inside.iter().map(|t| t.world).collect::<Vec<_>>()),
                camera0: coverage(&inside.iter().map(|t| t.camera0).collect::<Vec<_>>()),
            })
        })
        .collect()
}

/// The study's result on one rig and request.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RigTraced {
    /// The request.
    pub request: RigRequest,
    /// How the random point was drawn.
    pub point: PointDraw,
    /// Trials run.
    pub trials: usize,
    /// Trials that failed (left out), with their seed and error.
    pub failed: Vec<(u64, String)>,
    /// The point in the world frame (the acceptance's coverage).
    pub world: Coverage,
    /// The point in camera 0's frame, the truth at the entrance pupil.
    pub camera0: Coverage,
    /// Both measures by the point's defocus.
    pub by_defocus: Vec<DefocusBin>,
    /// The triangulated move and camera 0's PnP of it, refocused.
    pub moves: [MoveStat; 2],
    /// The baseline's error against the entrance pupils' distance, mean and std, mm.
    pub baseline_error_mm: Stat,
    /// The true baseline (entrance pupils), mm.
    pub pupil_baseline_mm: f64,
    /// Mean RMS reprojection error per camera, px.
    pub rms_px: [f64; 2],
    /// Every trial that succeeded.
    pub results: Vec<Trial>,
}

/// Runs `trials` trials from `seed` (trial t seeded `seed + t`) on the traced `rig`, in
/// parallel. Errors: the true baseline's trace.
pub fn rig_traced(rig: &TracedMultiCamera, design: &RigTracedDesign, trials: usize, seed: u64) -> Result<RigTraced> {
    let pupil = pupil_baseline_mm(rig)?;
    let runs: Vec<(u64, Result<Trial>)> =
        (0..trials as u64).into_par_iter().map(|t| (seed + t, trial(rig, design, pupil, seed + t))).collect();
    let (mut results, mut failed) = (vec![], vec![]);
    for (s, r) in runs {
        match r {
            Ok(t) => results.push(t),
            Err(e) => failed.push((s, e.to_string())),
        }
    }
    let n = results.len().max(1) as f64;
    let col = |f: &dyn Fn(&Trial) -> f64| results.iter().map(f).collect::<Vec<f64>>();
    Ok(RigTraced {
        request: design.request,
        point: design.point,
        trials,
        failed,
        world: coverage(&results.iter().map(|t| t.world).collect::<Vec<_>>()),
        camera0: coverage(&results.iter().map(|t| t.camera0).collect::<Vec<_>>()),
        by_defocus: by_defocus(&results),
        moves: [move_stat(&col(&|t| t.move_um)), move_stat(&col(&|t| t.pnp_um))],
        baseline_error_mm: stat(&col(&|t| t.baseline_error_mm)),
        pupil_baseline_mm: pupil,
        rms_px: [0, 1].map(|k| col(&|t| t.rms_px[k]).iter().sum::<f64>() / n),
        results,
    })
}

/// Traces the two-camera rig of `optics` (camera 0 first) by `design`
/// ([`trace_multi_camera`]), for [`rig_traced`].
pub fn trace(optics: &[etl_sim::optics::OpticalRig], design: &TracedRigDesign) -> Result<TracedMultiCamera> {
    if optics.len() != 2 {
        let message = format!("cameras: the study takes 2 cameras, got {}", optics.len());
        return Err(Error::invalid_value("cameras", optics.len() as f64, message));
    }
    trace_multi_camera(optics, design)
}

impl RigTraced {
    /// The result as markdown: the coverage table (both measures), the move, the baseline;
    /// the first failures (alone when every trial failed).
    pub fn markdown(&self) -> String {
        let mut s = format!(
            "{}{}: {} trials ({} failed); RMS reprojection {:.4} / {:.4} px; baseline {:+.3} ± {:.3} mm off the entrance pupils' {:.3} mm\n\n",
            self.request.name(),
            if self.point == PointDraw::InFocus { ", each camera focused on the point" } else { "" },
            self.trials,
            self.failed.len(),
            self.rms_px[0],
            self.rms_px[1],
            self.baseline_error_mm.mean,
            self.baseline_error_mm.std,
            self.pupil_baseline_mm
        );
        if self.results.is_empty() {
            return s + &self.failures();
        }
        s += "| measure | axis | coverage of 1 sigma | z-score mean | z-score std | mean sigma (um) | RMS error (um) |\n|---|---|---|---|---|---|---|\n";
        for (name, c) in [("world", &self.world), ("camera 0, truth at the pupil", &self.camera0)] {
            for (i, axis) in ["X", "Y", "Z"].iter().enumerate() {
                let z = &c.z_scores[i];
                s += &format!(
                    "| {name} | {axis} | {:.1} % | {:+.3} | {:.3} ± {:.3} | {:.2} | {:.2} |\n",
                    100.0 * c.per_axis[i],
                    z.mean,
                    z.std,
                    z.std_se,
                    c.mean_std_um[i],
                    c.rms_error_um[i]
                );
            }
        }
        for (name, c) in [("world", &self.world), ("camera 0", &self.camera0)] {
            s += &format!(
                "\n{name}: all axes {:.1} % (target 68 ± 5 %); mean d^2 {:.2} ± {:.2} (3 if right); pixel part alone: mean d^2 {:.1}; calibration's share of the trace {:.1} %",
                100.0 * c.all,
                c.d2.mean,
                c.d2.mean_se,
                c.d2_pixels_only.mean,
                100.0 * c.calibration_share
            );
        }
        s += "\n\n| larger defocus of the two cameras (dpt) | trials | world: coverage, mean d^2 | camera 0: coverage, mean d^2 |\n|---|---|---|---|\n";
        for b in &self.by_defocus {
            s += &format!(
                "| {:.2}..{} | {} | {:.1} %, {:.2} | {:.1} %, {:.2} |\n",
                b.range_dpt[0],
                if b.range_dpt[1].is_finite() { format!("{:.2}", b.range_dpt[1]) } else { "".into() },
                b.trials,
                100.0 * b.world.all,
                b.world.d2.mean,
                100.0 * b.camera0.all,
                b.camera0.d2.mean
            );
        }
        s += "\n| 2 mm move, refocused | RMS (um) | max (um) | mean (um) |\n|---|---|---|---|\n";
        for (name, m) in ["triangulated", "camera 0 PnP"].iter().zip(&self.moves) {
            s += &format!("| {name} | {:.3} | {:.3} | {:+.3} |\n", m.rms_um, m.max_um, m.mean_um);
        }
        s + &self.failures()
    }

    /// The first five failures, one line each.
    fn failures(&self) -> String {
        self.failed.iter().take(5).map(|(seed, e)| format!("\nfailed: seed {seed}: {e}")).collect()
    }
}
