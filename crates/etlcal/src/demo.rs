//! `etlcal demo [--out DIR] [--seed N] [--stage-noise-um X] [--json]`: the main job on the
//! built-in simulated rig (the paper rig, docs/METHOD.md).
//!
//! Simulates the paper rig's 15 views and 10 lens-off views with the paper's noise model,
//! renders every view with the synthetic camera ([`etl_sim::simulate::images`]), detects the
//! corners, takes A0 from the lens-off views by Zhang's method, calibrates with the paper's
//! estimator and with errors-in-variables, validates on freshly rendered views not used in
//! calibration (the fx(E), fy(E) curves against the truth, the principal point, and a PnP
//! measurement of a 2 mm stage move at several currents, from detected corners), prints a
//! table of every parameter against the truth, and writes into DIR: the images,
//! dataset.json, observations.json (the detected corners), a0.json (A0 by Zhang's method on
//! the lens-off views, where both calibrations start), truth.json (the true model: its
//! `kf_x[0]`, `kf_y[0]` and `principal_point` are the true A0), calibration.json (the
//! recommended estimator's, errors-in-variables), calibration-paper.json (the paper's
//! estimator, Eq. 24), summary.md, the reports of both (report/, report-paper/) and
//! index.html, the page to open first: the figures and a link to each of these files.
//!
//! `--no-images` skips rendering and detection: the simulated corner observations (with
//! the paper's pixel noise) go straight to the calibration, as in the paper's own
//! simulations.

use std::path::PathBuf;

use serde_json::json;

use super::print_json;
use crate::output::write_dir_set;
use etl_core::calib::Estimator;
use etl_formats::output::Output;
use etl_formats::write_atomic;
use etl_formats::A0File;

/// The names `demo` writes into its directory.
const DEMO_FILES: &[&str] = &[
    "views",
    "offstate",
    "dataset.json",
    "observations.json",
    "a0.json",
    "truth.json",
    "calibration.json",
    "calibration-paper.json",
    "summary.md",
    "index.html",
    "report",
    "report-paper",
];
use etl_formats::{Error, Result};
use etl_report::Provenance;
use etl_sim::simulate::images::RigBoard;
use etl_sim::simulate::write_truth;
use etl_studies::demo::{index_html, run_demo, DemoOptions};

/// Arguments of `etlcal demo`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Output directory (created with its missing parents).
    #[arg(long, value_name = "DIR", default_value = "etlcal-demo")]
    pub out: PathBuf,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Stage-position noise per view, um (paper: 10).
    #[arg(long, default_value_t = 10.0)]
    pub stage_noise_um: f64,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
    /// Calibrate from simulated corner observations instead of rendered images.
    #[arg(long)]
    pub no_images: bool,
}

/// Runs `etlcal demo`: [`run_demo`], then writes its files and prints its summary.
pub fn run(args: Args) -> Result<()> {
    crate::output::check([], &[Output::Dir(&args.out)])?;
    // Read before the run: a malformed SOURCE_DATE_EPOCH is refused before any work.
    let written_unix_s = crate::output::source_date_epoch()?;
    let options = DemoOptions {
        seed: args.seed,
        stage_noise_um: args.stage_noise_um,
        images: !args.no_images,
        board: RigBoard::Charuco,
    };
    let inputs = |file: &str| {
        let obs = if options.images { "detected in the rendered views/*.png" } else { "simulated corners" };
        vec![
            ("calibration".to_string(), file.to_string()),
            ("observations".to_string(), format!("observations.json ({obs}; seed {})", args.seed)),
        ]
    };
    // Everything of one run in a temporary sibling directory, swapped in whole.
    let demo = write_dir_set(&args.out, DEMO_FILES, |out| {
        let demo = run_demo(&options, out, &crate::progress::Bar::new(!args.json))?;
        // The true model in the frame of the observations calibrated from (with images,
        // the ChArUco board's as well); the A0 calibrated from, not the simulation's.
        write_truth(&demo.sim, demo.dataset.as_ref().map(|_| &demo.truth), out)?;
        if let Some(dataset) = &demo.dataset {
            dataset.save(&out.join("dataset.json"))?;
        }
        demo.observations.save(&out.join("observations.json"))?;
        A0File::new(&demo.a0).save(&out.join("a0.json"))?;
        demo.eiv.calibration.save(&out.join("calibration.json"))?;
        demo.paper.calibration.save(&out.join("calibration-paper.json"))?;
        write_atomic(&out.join("summary.md"), demo.summary_md.as_bytes())?;
        write_atomic(&out.join("index.html"), index_html(&demo, &options).as_bytes())?;
        for (name, file, r, estimator) in [
            ("report", "calibration.json", &demo.eiv, demo.eiv_estimator),
            ("report-paper", "calibration-paper.json", &demo.paper, Estimator::Paper),
        ] {
            let dir = out.join(name);
            crate::output::create_dir(&dir)?;
            let provenance =
                Provenance { inputs: inputs(file), priors: Some(Provenance::priors_of(&estimator)), written_unix_s };
            let thermal = r.calibration.thermal.as_ref();
            etl_report::write_report(&r.calibration, Some(&demo.observations), thermal, &provenance, &dir)?;
        }
        Ok(demo)
    })?;
    if args.json {
        let to_json = |v| serde_json::to_value(v).map_err(|e| Error::invalid("--json", e.to_string()));
        let mut j = to_json(&demo.paper_validation)?;
        j["views_detected"] = json!(demo.views_detected);
        j["seconds"] = json!(demo.seconds);
        j["estimator"] = json!("paper");
        j["eiv"] = to_json(&demo.eiv_validation)?;
        j["out"] = json!(args.out);
        print_json(&j);
    } else {
        outln!("{}", demo.summary_md);
        outln!(
            "wrote {}observations.json, a0.json (Zhang's), truth.json, calibration.json (errors-in-variables), \
             calibration-paper.json, summary.md, index.html, report/index.html, report-paper/index.html to {} \
             in {:.1} s",
            if options.images { "views/*.png, offstate/*.png, dataset.json, " } else { "" },
            args.out.display(),
            demo.seconds
        );
    }
    Ok(())
}
