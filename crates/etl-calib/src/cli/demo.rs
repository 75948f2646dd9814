//! `etlcal demo [--out DIR] [--seed N] [--stage-noise-um X] [--json]`: the main job on the
//! built-in simulated rig (the paper rig, NOTES.md).
//!
//! Simulates the paper rig's 15 views and 10 lens-off views with the paper's noise model,
//! renders every view with the synthetic camera ([`crate::simulate::images`]), detects the
//! corners, takes A0 from the lens-off views by Zhang's method, calibrates with the paper's
//! estimator and with errors-in-variables, validates on freshly rendered views not used in
//! calibration (the fx(E), fy(E) curves against the truth, the principal point, and a PnP
//! measurement of a 2 mm stage move at several currents, from detected corners), prints a
//! table of every parameter against the truth, and writes the images, dataset.json,
//! observations.json (the detected corners), a0.json (the simulation's), truth.json,
//! calibration.json (paper), calibration-eiv.json, summary.md and the reports into DIR.
//!
//! `--no-images` skips rendering and detection: the simulated corner observations (with
//! the paper's pixel noise) go straight to the calibration, as in the paper's own
//! simulations.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use etl_core::calib::jacobian::{to_params, PARAM_NAMES};
use etl_core::calib::Estimator;
use etl_core::model::CameraModel;
use etl_core::pnp::{displacement_mm, solve_pnp};
use etl_core::thermal::ThermalCalibration;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde_json::json;

use super::print_json;
use super::simulate::{noise_from, write_simulation};
use crate::error::{Error, Result};
use crate::formats::write_atomic;
use crate::pipeline::dataset::{default_detector, observations_from_dataset};
use crate::pipeline::{calibrate, CalibrateOptions, CalibrationResult};
use crate::simulate::images::{render_rig, ImageOptions};
use crate::simulate::{focused_z_mm, observe_board, paper_rig};

/// Currents of the validation measurements, mA.
pub const VALIDATION_E_MA: [f64; 5] = [80.0, 120.0, 150.0, 190.0, 225.0];

/// Arguments of `etlcal demo`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR", default_value = "etlcal-demo")]
    pub out: PathBuf,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Stage-position noise per view, um (paper: 10).
    #[arg(long, default_value_t = 10.0)]
    pub stage_noise_um: f64,
    /// Print one JSON object with the validation figures.
    #[arg(long)]
    pub json: bool,
    /// Calibrate from simulated corner observations instead of rendered images.
    #[arg(long)]
    pub no_images: bool,
}

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

pub use crate::study::common::curve_errors;

/// Validates `result` against `truth` with fresh PnP measurements (same seed for every
/// model, so estimators are compared on the same views). With `images`, each measurement
/// renders the board before and after the move and detects its corners; otherwise the
/// corners are simulated with the paper's noise model.
pub fn validate(result: &CalibrationResult, truth: &CameraModel, seed: u64, images: bool) -> Result<Validation> {
    let m = result.calibration.model();
    let (ex, ey) = curve_errors(&m, truth, result.calibration.e_com_range_ma);
    let pp = (m.principal_point[0] - truth.principal_point[0]).hypot(m.principal_point[1] - truth.principal_point[1]);
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5e_ed0f_9a11);
    let noise = crate::simulate::NoiseModel::PAPER;
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

/// The board at stage positions `z_mm` and `z_mm + 2` at current `e_ma`, rendered and
/// detected: (board X, Y; detected pixel) of the block of corners visible in both.
fn rendered_move(truth: &CameraModel, e_ma: f64, z_mm: f64, seed: u64) -> Result<(BoardPixelPairs, BoardPixelPairs)> {
    use crate::render::{render, Optics, RenderOptions, Scene};
    use crate::simulate::images::{visible_block, ImageOptions};
    let (inner_corners, square_mm) = crate::simulate::PAPER_BOARD;
    let board = crate::formats::dataset::Board { inner_corners, square_mm };
    let size = CameraModel::PAPER_IMAGE_SIZE;
    let options = ImageOptions::default();
    let blocks: Vec<_> = [z_mm, z_mm + 2.0]
        .iter()
        .map(|&z| visible_block(truth, e_ma, board, z, size, options.margin_px))
        .collect::<Option<Vec<_>>>()
        .ok_or_else(|| Error::InvalidInput(format!("validation at {e_ma} mA: the board does not fit the image")))?;
    // The block visible at both positions.
    let i0 = blocks[0].1[0].max(blocks[1].1[0]);
    let j0 = blocks[0].1[1].max(blocks[1].1[1]);
    let i1 = (blocks[0].1[0] + blocks[0].0.inner_corners[0]).min(blocks[1].1[0] + blocks[1].0.inner_corners[0]);
    let j1 = (blocks[0].1[1] + blocks[0].0.inner_corners[1]).min(blocks[1].1[1] + blocks[1].0.inner_corners[1]);
    let block =
        crate::formats::dataset::Board { inner_corners: [i1.saturating_sub(i0), j1.saturating_sub(j0)], square_mm };
    let first = [i0, j0];
    let mut out = vec![];
    for (n, z) in [z_mm, z_mm + 2.0].into_iter().enumerate() {
        let scene = Scene::new(crate::simulate::images::shifted(truth, first, square_mm), e_ma, block, z, size);
        let opts = RenderOptions {
            optics: Optics::paper_focus(truth, e_ma, options.aperture_mm),
            photometry: options.photometry,
            seed: seed.wrapping_add(n as u64 * 104_729),
            ..RenderOptions::default()
        };
        let image = render(&scene, &opts)?.image.to_dynamic();
        let det = crate::detect::detect_dynamic(
            &image,
            crate::detect::Pattern::new(block.inner_corners[0], block.inner_corners[1])?,
        )?;
        out.push(
            det.indexed()
                .map(|([i, j], p)| ([(i0 + i) as f64 * square_mm, (j0 + j) as f64 * square_mm], p))
                .collect::<Vec<_>>(),
        );
    }
    let b = out.pop().unwrap_or_default();
    let a = out.pop().unwrap_or_default();
    Ok((a, b))
}

/// Runs `etlcal demo`.
pub fn run(args: Args) -> Result<()> {
    let start = Instant::now();
    std::fs::create_dir_all(&args.out).map_err(|source| Error::Io { path: args.out.clone(), source })?;
    let noise = noise_from(args.stage_noise_um, 0.4, 0.2)?;
    let sim = paper_rig(&noise, args.seed);
    write_simulation(&sim, &args.out)?;
    let images = !args.no_images;
    let progress = !args.json;
    let (observations, views_detected) = if images {
        // Render, record, detect: the user's chain from images.
        let dataset = render_rig(&sim, &args.out, &ImageOptions::default(), args.seed, progress)?;
        let dataset_path = args.out.join("dataset.json");
        dataset.save(&dataset_path)?;
        let (obs, summary) = observations_from_dataset(&dataset, &dataset_path, &default_detector(), progress)?;
        obs.save(&args.out.join("observations.json"))?;
        (obs, summary.views_detected)
    } else {
        (sim.observations.clone(), sim.observations.views.len())
    };
    let thermal = ThermalCalibration::PAPER;
    // A0 from the lens-off views by Zhang's method (section 4.2).
    let a0 = crate::pipeline::a0_from_offstate(&observations)?.a0();
    let paper_options = CalibrateOptions { estimator: Estimator::Paper, ..Default::default() };
    let paper = calibrate(&observations, &a0, &thermal, &paper_options)?;
    let eiv_est = Estimator::Eiv { sigma_z_mm: noise.z_mm.max(1e-4), sigma_e_ma: 0.4, sigma_px: None };
    let eiv = calibrate(&observations, &a0, &thermal, &CalibrateOptions { estimator: eiv_est, ..Default::default() })?;
    paper.calibration.save(&args.out.join("calibration.json"))?;
    eiv.calibration.save(&args.out.join("calibration-eiv.json"))?;
    let vp = validate(&paper, &sim.truth, args.seed, images)?;
    let ve = validate(&eiv, &sim.truth, args.seed, images)?;
    let views = views_detected;

    // The table of every parameter against the truth.
    let truth = to_params(&sim.truth);
    let (xp, xe) = (to_params(&paper.report.model), to_params(&eiv.report.model));
    let mut table = String::new();
    let _ = writeln!(table, "| parameter | truth | paper BA | std | eiv BA | std |");
    let _ = writeln!(table, "|---|---|---|---|---|---|");
    for i in 0..25 {
        let _ = writeln!(
            table,
            "| {} | {:.6e} | {:.6e} | {:.1e} | {:.6e} | {:.1e} |",
            PARAM_NAMES[i], truth[i], xp[i], paper.report.std[i], xe[i], eiv.report.std[i]
        );
    }
    let mut figures = String::new();
    let _ = writeln!(figures, "| figure | paper BA | eiv BA |\n|---|---|---|");
    let _ = writeln!(
        figures,
        "| max rel. error of fx(E) | {:.3} % | {:.3} % |",
        100.0 * vp.fx_curve_max_rel_err,
        100.0 * ve.fx_curve_max_rel_err
    );
    let _ = writeln!(
        figures,
        "| max rel. error of fy(E) | {:.3} % | {:.3} % |",
        100.0 * vp.fy_curve_max_rel_err,
        100.0 * ve.fy_curve_max_rel_err
    );
    let _ = writeln!(
        figures,
        "| principal point error | {:.2} px | {:.2} px |",
        vp.principal_point_err_px, ve.principal_point_err_px
    );
    let _ =
        writeln!(figures, "| RMS reprojection | {:.3} px | {:.3} px |", vp.rms_reprojection_px, ve.rms_reprojection_px);
    for (a, b) in vp.pnp_displacement_err_um.iter().zip(&ve.pnp_displacement_err_um) {
        let _ = writeln!(
            figures,
            "| 2 mm move at {} mA | {:.1} um | {:.1} um |",
            a["e_com_ma"],
            a["err_um"].as_f64().unwrap_or(f64::NAN),
            b["err_um"].as_f64().unwrap_or(f64::NAN)
        );
    }
    let seconds = start.elapsed().as_secs_f64();
    let summary = format!(
        "# etlcal demo (seed {}, stage noise {} um)\n\nThe paper rig (NOTES.md), {views} views, {} points{}, the paper's noise model; \
         A0 by Zhang's method from {} lens-off views.\n\n## Errors users feel (validated on fresh views)\n\n{figures}\n## Every parameter\n\n{table}\n({seconds:.2} s)\n",
        args.seed,
        args.stage_noise_um,
        observations.views.iter().map(|v| v.points.len()).sum::<usize>(),
        if images { " detected in rendered images" } else { " simulated" },
        observations.offstate_views.len(),
    );
    write_atomic(&args.out.join("summary.md"), summary.as_bytes())?;
    for (name, r) in [("report", &paper), ("report-eiv", &eiv)] {
        let dir = args.out.join(name);
        super::report::ensure_out_dir(&dir)?;
        crate::report::write_report(&r.calibration, Some(&observations), &thermal, &dir)?;
    }
    if args.json {
        let mut j = serde_json::to_value(&vp).map_err(|e| Error::InvalidInput(e.to_string()))?;
        j["views_detected"] = json!(views);
        j["seconds"] = json!(seconds);
        j["estimator"] = json!("paper");
        j["eiv"] = serde_json::to_value(&ve).map_err(|e| Error::InvalidInput(e.to_string()))?;
        j["out"] = json!(args.out);
        print_json(&j);
    } else {
        outln!("{summary}");
        outln!(
            "wrote {}observations.json, a0.json, truth.json, calibration.json, calibration-eiv.json, summary.md, \
             report/index.html, report-eiv/index.html to {}",
            if images { "views/*.png, offstate/*.png, dataset.json, " } else { "" },
            args.out.display()
        );
    }
    Ok(())
}
