//! `etlcal demo [--out DIR] [--seed N] [--stage-noise-um X] [--json]`: the main job on the
//! built-in simulated rig (the paper rig, NOTES.md).
//!
//! Simulates the paper rig's 15 views and 10 lens-off views with the paper's noise model,
//! renders every view with the synthetic camera ([`etl_sim::simulate::images`]), detects the
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

use etl_core::calib::jacobian::to_params;
use etl_core::calib::params::PARAM_NAMES;
use etl_core::calib::Estimator;
use etl_core::thermal::ThermalCalibration;
use serde_json::json;

use super::print_json;
use etl_calib::pipeline::dataset::{default_detector, observations_from_dataset};
use etl_calib::pipeline::{calibrate, CalibrateOptions};
use etl_formats::write_atomic;
use etl_formats::{Error, Result};
use etl_sim::simulate::images::{render_rig, ImageOptions};
use etl_sim::simulate::{noise_from, paper_rig, write_simulation};
use etl_studies::demo::validate;

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

/// Runs `etlcal demo`.
pub fn run(args: Args) -> Result<()> {
    let start = Instant::now();
    std::fs::create_dir_all(&args.out).map_err(|source| Error::Io { path: args.out.clone(), source })?;
    let noise = noise_from(args.stage_noise_um, 0.4, 0.2)?;
    let sim = paper_rig(&noise, args.seed);
    write_simulation(&sim, &args.out)?;
    let images = !args.no_images;
    let progress = crate::progress::Bar::new(!args.json);
    let (observations, views_detected) = if images {
        // Render, record, detect: the user's chain from images.
        let dataset = render_rig(&sim, &args.out, &ImageOptions::default(), args.seed, &progress)?;
        let dataset_path = args.out.join("dataset.json");
        dataset.save(&dataset_path)?;
        let (obs, summary) = observations_from_dataset(&dataset, &dataset_path, &default_detector(), &progress)?;
        obs.save(&args.out.join("observations.json"))?;
        (obs, summary.views_detected)
    } else {
        (sim.observations.clone(), sim.observations.views.len())
    };
    let thermal = ThermalCalibration::PAPER;
    // A0 from the lens-off views by Zhang's method (section 4.2).
    let a0 = etl_calib::pipeline::a0_from_offstate(&observations)?.a0();
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
        etl_report::write_report(&r.calibration, Some(&observations), &thermal, &dir)?;
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
