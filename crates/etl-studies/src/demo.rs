//! The demo (`etlcal demo`): the main job on the simulated paper rig ([`run_demo`]) and its
//! validation ([`validate`]): errors users feel of a calibration of the simulated paper rig
//! against its truth, on fresh views not used in the calibration.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use etl_core::calib::{Estimator, A0};
use etl_core::model::CameraModel;
use etl_core::pnp::{displacement_mm, solve_pnp};
use etl_core::progress::Progress;
use etl_formats::ThermalRef;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde_json::json;

use etl_calib::pipeline::dataset::{default_detector, observations_from_dataset};
use etl_calib::pipeline::{a0_from_offstate, calibrate, CalibrateOptions, CalibrationResult};
use etl_formats::dataset::Dataset;
use etl_formats::observations::Observations;
use etl_formats::{Error, Result};
use etl_sim::simulate::images::{dataset_truth, render_rig, ImageOptions, RigBoard};
use etl_sim::simulate::{focused_z_mm, noise_from, observe_board, paper_rig, Simulation};

use crate::common::{curve_errors, paper_params, param_name, PARAMS};

/// Currents of the validation measurements, mA.
pub const VALIDATION_E_MA: [f64; 5] = [80.0, 120.0, 150.0, 190.0, 225.0];

/// Errors users feel, for one calibrated model.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Validation {
    /// Max relative error of fx(E) over the calibrated range.
    pub fx_curve_max_rel_err: f64,
    /// Max relative error of fy(E) over the calibrated range.
    pub fy_curve_max_rel_err: f64,
    /// Distance of the principal point from the truth, px.
    pub principal_point_err_px: f64,
    /// RMS reprojection error of the calibration, px.
    pub rms_reprojection_px: f64,
    /// PnP error of a 2 mm stage move, per current.
    pub pnp_displacement_err_um: Vec<serde_json::Value>,
}

/// What the demo does: the simulation's seed and stage noise, and whether the corners come
/// from rendered images.
#[derive(Debug, Clone, Copy)]
pub struct DemoOptions {
    /// Random seed of the simulation and of the validation.
    pub seed: u64,
    /// Stage-position noise per view, um (the paper's: 10).
    pub stage_noise_um: f64,
    /// Render every view and detect its corners (else the simulated corners, with the
    /// paper's pixel noise, go straight to the calibration, as in the paper's simulations).
    pub images: bool,
    /// The boards of the rendered views (`etlcal demo`: ChArUco, the default; the
    /// checkerboards with per-view hints for comparison). The validation renders the
    /// ChArUco board either way (its figures do not depend on the board's frame).
    pub board: RigBoard,
}

/// The demo's outcome: the data, both calibrations, their validations and the summary.
pub struct Demo {
    /// The simulated rig (truth, A0, simulated observations: the paper board's frame).
    pub sim: Simulation,
    /// The true camera in the world frame of the observations calibrated from: with
    /// `images` the ChArUco board's ([`dataset_truth`]), else the simulation's.
    pub truth: CameraModel,
    /// The rendered views (with `images`), to be saved as `dataset.json` in the image
    /// directory.
    pub dataset: Option<Dataset>,
    /// The observations calibrated from (detected with `images`, else simulated).
    pub observations: Observations,
    /// Views whose board was found (all views without `images`).
    pub views_detected: usize,
    /// A0 by Zhang's method on the lens-off views of `observations`: where both
    /// calibrations start (`etlcal demo` writes it as `a0.json`).
    pub a0: A0,
    /// The paper's estimator (Eq. 24).
    pub paper: CalibrationResult,
    /// Errors-in-variables.
    pub eiv: CalibrationResult,
    /// The estimator (with its priors) `eiv` was calibrated with.
    pub eiv_estimator: Estimator,
    /// Validation of `paper` on fresh views.
    pub paper_validation: Validation,
    /// Validation of `eiv` on the same fresh views.
    pub eiv_validation: Validation,
    /// Wall time of the demo, s.
    pub seconds: f64,
    /// The markdown summary: errors users feel, then every parameter against the truth.
    pub summary_md: String,
}

/// The main job on the simulated paper rig: simulates its 15 views and 10 lens-off views
/// with the paper's noise model (current noise 0.4 mA, pixel noise 0.2 px); with `images`,
/// renders every view into `image_dir` (`views/`, `offstate/`) and detects the corners;
/// takes A0 from the lens-off views by Zhang's method (section 4.2); calibrates with the
/// paper's estimator and with errors-in-variables; validates both on fresh views.
///
/// Writes only the rendered images (into `image_dir`, which must exist); the caller saves
/// the rest of [`Demo`].
pub fn run_demo(options: &DemoOptions, image_dir: &Path, progress: &dyn Progress) -> Result<Demo> {
    let start = Instant::now();
    let noise = noise_from(options.stage_noise_um, 0.4, 0.2)?;
    let sim = paper_rig(&noise, options.seed);
    let (dataset, observations, views_detected, truth) = if options.images {
        // Render, record, detect: the user's chain from images.
        let image_options = ImageOptions { board: options.board, ..ImageOptions::default() };
        let dataset = render_rig(&sim, image_dir, &image_options, options.seed, progress)?;
        let dataset_path = image_dir.join("dataset.json");
        let (obs, summary) = observations_from_dataset(&dataset, &dataset_path, &default_detector(), progress)?;
        (Some(dataset), obs, summary.views_detected, dataset_truth(&sim.truth, &image_options))
    } else {
        (None, sim.observations.clone(), sim.observations.views.len(), sim.truth)
    };
    // The simulated lens follows the paper's surface: the demo chooses it, and the
    // calibrations record that choice ("source": "paper").
    let thermal = ThermalRef::paper();
    let a0 = a0_from_offstate(&observations)?.a0();
    let paper_options = CalibrateOptions { estimator: Estimator::Paper, ..Default::default() };
    let paper = calibrate(&observations, &a0, Some(&thermal), &paper_options)?;
    let eiv_est = Estimator::Eiv { sigma_z_mm: noise.z_mm.max(1e-4), sigma_e_ma: 0.4, sigma_px: None };
    let eiv =
        calibrate(&observations, &a0, Some(&thermal), &CalibrateOptions { estimator: eiv_est, ..Default::default() })?;
    let paper_validation = validate(&paper, &truth, options.seed, options.images)?;
    let eiv_validation = validate(&eiv, &truth, options.seed, options.images)?;
    let mut demo = Demo {
        sim,
        truth,
        dataset,
        observations,
        views_detected,
        a0,
        paper,
        eiv,
        eiv_estimator: eiv_est,
        paper_validation,
        eiv_validation,
        seconds: 0.0,
        summary_md: String::new(),
    };
    demo.seconds = start.elapsed().as_secs_f64();
    demo.summary_md = summary_markdown(&demo, options);
    Ok(demo)
}

/// The demo's summary: a heading, the figures of [`figures_table`] and the parameters of
/// [`parameter_table`].
pub fn summary_markdown(demo: &Demo, options: &DemoOptions) -> String {
    let figures = figures_table(&demo.paper_validation, &demo.eiv_validation);
    let table = parameter_table(&demo.truth, &demo.paper, &demo.eiv);
    format!(
        "# etlcal demo (seed {}, stage noise {} um)\n\nThe paper rig (docs/METHOD.md, \"The paper rig\"), {} views, {} points{}, the paper's noise model; \
         A0 by Zhang's method from {} lens-off views.\n\n## Errors users feel (validated on fresh views)\n\n{figures}\n## Every parameter\n\n{table}",
        options.seed,
        options.stage_noise_um,
        demo.views_detected,
        demo.observations.views.iter().map(|v| v.points.len()).sum::<usize>(),
        if options.images { " detected in rendered images" } else { " simulated" },
        demo.observations.offstate_views.len(),
    )
}

/// The markdown table of every parameter: truth, both estimates and their standard
/// deviations (square roots of the covariance's diagonal).
pub fn parameter_table(truth: &CameraModel, paper: &CalibrationResult, eiv: &CalibrationResult) -> String {
    let truth = paper_params(truth);
    let (xp, xe) = (paper_params(&paper.report.model), paper_params(&eiv.report.model));
    let mut table = String::new();
    let _ = writeln!(table, "| parameter | truth | paper BA | std | eiv BA | std |");
    let _ = writeln!(table, "|---|---|---|---|---|---|");
    let rows = (0..PARAMS).map(param_name).zip(truth).zip(xp).zip(xe).zip(paper.report.std.iter().zip(&eiv.report.std));
    for ((((name, t), p), e), (sp, se)) in rows {
        let _ = writeln!(table, "| {name} | {t:.6e} | {p:.6e} | {sp:.1e} | {e:.6e} | {se:.1e} |");
    }
    table
}

/// The errors users feel, one row each: (figure, paper's estimator, errors-in-variables),
/// as [`figures_table`] and [`index_html`] print them.
fn figure_rows(vp: &Validation, ve: &Validation) -> Vec<[String; 3]> {
    let pct = |x: f64| format!("{:.3} %", 100.0 * x);
    let mut rows = vec![
        ["max rel. error of fx(E)".to_owned(), pct(vp.fx_curve_max_rel_err), pct(ve.fx_curve_max_rel_err)],
        ["max rel. error of fy(E)".to_owned(), pct(vp.fy_curve_max_rel_err), pct(ve.fy_curve_max_rel_err)],
        [
            "principal point error".to_owned(),
            format!("{:.2} px", vp.principal_point_err_px),
            format!("{:.2} px", ve.principal_point_err_px),
        ],
        [
            "RMS reprojection".to_owned(),
            format!("{:.3} px", vp.rms_reprojection_px),
            format!("{:.3} px", ve.rms_reprojection_px),
        ],
    ];
    let um = |v: &serde_json::Value| format!("{:.1} um", v["err_um"].as_f64().unwrap_or(f64::NAN));
    for (a, b) in vp.pnp_displacement_err_um.iter().zip(&ve.pnp_displacement_err_um) {
        rows.push([format!("2 mm move at {} mA", a["e_com_ma"]), um(a), um(b)]);
    }
    rows
}

/// The markdown table of the errors users feel, paper's estimator against
/// errors-in-variables.
pub fn figures_table(vp: &Validation, ve: &Validation) -> String {
    let mut figures = String::new();
    let _ = writeln!(figures, "| figure | paper BA | eiv BA |\n|---|---|---|");
    for [figure, paper, eiv] in figure_rows(vp, ve) {
        let _ = writeln!(figures, "| {figure} | {paper} | {eiv} |");
    }
    figures
}

/// The demo directory's `index.html`: what was done, the errors users feel, and a link to
/// every file the demo writes (the names `etlcal demo` gives them).
pub fn index_html(demo: &Demo, options: &DemoOptions) -> String {
    let mut rows = String::new();
    for [figure, paper, eiv] in figure_rows(&demo.paper_validation, &demo.eiv_validation) {
        let _ = writeln!(rows, "<tr><td>{figure}</td><td>{eiv}</td><td>{paper}</td></tr>");
    }
    let link = |file: &str, what: &str| format!("<li><a href=\"{file}\">{file}</a>: {what}</li>\n");
    let mut files = link("report/index.html", "the report of calibration.json: plots, parameters, views")
        + &link("report-paper/index.html", "the report of calibration-paper.json")
        + &link("summary.md", "every parameter against the truth, with its standard deviation")
        + &link("calibration.json", "the calibration by the recommended estimator, errors-in-variables")
        + &link("calibration-paper.json", "the calibration by the paper's estimator (Eq. 24)")
        + &link("a0.json", "the lens-off intrinsics A0 Zhang's method found, where both calibrations start")
        + &link("truth.json", "the simulated rig's true model and each view's true stage and current errors")
        + &link("observations.json", "the corners calibrated from");
    if options.images {
        files += &link("dataset.json", "the rendered images (views/, offstate/) and what was recorded with each");
    }
    let points: usize = demo.observations.views.iter().map(|v| v.points.len()).sum();
    let source = if options.images { "detected in rendered images" } else { "simulated" };
    format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>etlcal demo</title></head><body>\n\
         <h1>etlcal demo (seed {}, stage noise {} um)</h1>\n\
         <p>The paper's rig simulated with its noise model: {} views, {points} corners {source}; A0 by Zhang's \
         method from {} lens-off views; calibrated with the errors-in-variables estimator and with the paper's, \
         then validated on fresh views against the truth.</p>\n\
         <table>\n<tr><th>figure</th><th>errors-in-variables BA</th><th>paper BA</th></tr>\n{rows}</table>\n\
         <h2>Files</h2>\n<ul>\n{files}</ul>\n</body></html>\n",
        options.seed,
        options.stage_noise_um,
        demo.views_detected,
        demo.observations.offstate_views.len(),
    )
}

/// Validates `result` against `truth` with fresh PnP measurements (same seed for every
/// model, so estimators are compared on the same views). With `images`, each measurement
/// renders the board before and after the move and detects its corners; otherwise the
/// corners are simulated with the paper's noise model.
pub fn validate(result: &CalibrationResult, truth: &CameraModel, seed: u64, images: bool) -> Result<Validation> {
    let m = result.calibration.model()?;
    let (ex, ey) = curve_errors(&m, truth, result.calibration.e_com_range_ma);
    let pp = (m.principal_point[0] - truth.principal_point[0]).hypot(m.principal_point[1] - truth.principal_point[1]);
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5e_ed0f_9a11);
    let noise = etl_sim::simulate::NoiseModel::PAPER;
    let mut pnp = vec![];
    for (k, e) in VALIDATION_E_MA.into_iter().enumerate() {
        let z = focused_z_mm(e);
        let (a, b) = if images {
            rendered_move(truth, e, z, seed.wrapping_mul(7919).wrapping_add(k as u64))?
        } else {
            (observe_board(truth, z, e, &noise, &mut rng), observe_board(truth, z + 2.0, e, &noise, &mut rng))
        };
        let pose = |obs: &[([f64; 2], [f64; 2])]| {
            let board: Vec<[f64; 3]> = obs.iter().map(|(w, _)| [w[0], w[1], 0.0]).collect();
            let px: Vec<[f64; 2]> = obs.iter().map(|(_, p)| *p).collect();
            solve_pnp(&m, e, &board, &px)
        };
        let d = displacement_mm(&pose(&a)?, &pose(&b)?);
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        pnp.push(json!({"e_com_ma": e, "err_um": 1000.0 * (len - 2.0).abs()}));
    }
    Ok(Validation {
        fx_curve_max_rel_err: ex,
        fy_curve_max_rel_err: ey,
        principal_point_err_px: pp,
        rms_reprojection_px: result.calibration.rms_reprojection_px,
        pnp_displacement_err_um: pnp,
    })
}

/// (board X, Y in mm; detected pixel) of each corner of one view.
type BoardPixelPairs = Vec<([f64; 2], [f64; 2])>;

/// The rig's ChArUco board at stage positions `z_mm` and `z_mm + 2` at current `e_ma` seen
/// by `truth` (its world frame taken as the board's: a frame one square off moves the
/// board by a square, which changes no figure), rendered and detected: (board X, Y;
/// detected pixel) of every corner found in each image (each pose from its own corners).
fn rendered_move(truth: &CameraModel, e_ma: f64, z_mm: f64, seed: u64) -> Result<(BoardPixelPairs, BoardPixelPairs)> {
    use etl_sim::render::{render, Optics, RenderOptions, Scene};
    let board = etl_sim::rig::PAPER_CHARUCO.board()?;
    // The demo's fixed validation rig, not an input of the user's: `what` names it.
    let charuco = board.as_charuco().ok_or_else(|| Error::invalid("validation", "the rig's board is not ChArUco"))?;
    let options = ImageOptions::default();
    let mut out = vec![];
    for (n, z) in [z_mm, z_mm + 2.0].into_iter().enumerate() {
        let scene = Scene::new(*truth, e_ma, board, z, CameraModel::PAPER_IMAGE_SIZE);
        let opts = RenderOptions {
            optics: Optics::paper_focus(truth, e_ma, options.aperture_mm),
            photometry: options.photometry,
            seed: seed.wrapping_add(n as u64 * 104_729),
            ..RenderOptions::default()
        };
        let image = render(&scene, &opts)?.image.to_dynamic();
        let det = etl_image::charuco::detect_charuco_dynamic(&image, charuco)?;
        out.push(det.board_points(charuco).map(|(_, xy, p)| (xy, p)).collect::<Vec<_>>());
    }
    let b = out.pop().unwrap_or_default();
    let a = out.pop().unwrap_or_default();
    Ok((a, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn demo_without_images_recovers_the_paper_rig_and_tabulates_it() {
        let dir = tempfile::tempdir().unwrap();
        let options = DemoOptions { seed: 1, stage_noise_um: 10.0, images: false, board: RigBoard::Charuco };
        let d = run_demo(&options, dir.path(), &etl_core::progress::NoProgress).unwrap();
        // Nothing written without images: the caller saves.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        assert!(d.dataset.is_none());
        assert_eq!(d.views_detected, 15);
        assert_eq!(d.observations.offstate_views.len(), 10);
        // The acceptance figures of the paper rig (as `etlcal demo` checks them).
        assert!(d.paper_validation.fx_curve_max_rel_err < 0.01, "{:?}", d.paper_validation);
        assert!(d.eiv_validation.fx_curve_max_rel_err < 0.005, "{:?}", d.eiv_validation);
        assert_eq!(d.paper_validation.pnp_displacement_err_um.len(), VALIDATION_E_MA.len());
        // One table row per parameter, its truth column the true model's parameter.
        let truth = paper_params(&d.sim.truth);
        let rows: Vec<&str> = d
            .summary_md
            .lines()
            .filter(|l| (0..PARAMS).map(param_name).any(|n| l.starts_with(&format!("| {n} |"))))
            .collect();
        assert_eq!(rows.len(), 25);
        for (row, (name, t)) in rows.iter().zip((0..PARAMS).map(param_name).zip(truth)) {
            let cell: f64 = row.split('|').nth(2).unwrap().trim().parse().unwrap();
            assert!((cell - t).abs() <= 1e-6 * t.abs(), "{name}: {cell} vs {t}");
        }
        assert!(d.summary_md.contains(" simulated, the paper's noise model"));
    }
}
