//! The pipeline bench's loop (observations.json -> calibration.json, paper rig, seed 1) as
//! a plain program, for a profiler: `valgrind --tool=callgrind target/release/examples/pipeline_profile eiv 20`.
//! Arguments: the estimator (`paper` or `eiv`, default `eiv`) and the number of runs
//! (default 20). Prints the mean time per run.
use std::time::Instant;

use etl_calib::pipeline::{calibrate, CalibrateOptions};
use etl_core::calib::Estimator;
use etl_formats::observations::Observations;
use etl_formats::ThermalRef;
use etl_sim::simulate::{paper_rig, NoiseModel};

fn main() {
    let mut args = std::env::args().skip(1);
    let estimator = match args.next().as_deref() {
        None | Some("eiv") => Estimator::EIV_PAPER,
        Some("paper") => Estimator::Paper,
        Some(other) => {
            eprintln!("estimator must be paper or eiv, got {other}");
            std::process::exit(2)
        }
    };
    let runs: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(20);
    let sim = paper_rig(&NoiseModel::PAPER, 1);
    let dir = tempfile::tempdir().expect("temp dir");
    let (obs_path, cal_path) = (dir.path().join("observations.json"), dir.path().join("calibration.json"));
    sim.observations.save(&obs_path).expect("write observations");
    let options = CalibrateOptions { estimator, ..CalibrateOptions::default() };
    let start = Instant::now();
    for _ in 0..runs {
        let obs = Observations::load(&obs_path).expect("read observations");
        let r = calibrate(&obs, &sim.a0, Some(&ThermalRef::paper()), &options).expect("calibrate");
        r.calibration.save(&cal_path).expect("write calibration");
    }
    let per_run_ms = start.elapsed().as_secs_f64() * 1e3 / runs.max(1) as f64;
    println!("{per_run_ms:.3} ms per run ({runs} runs)");
}
