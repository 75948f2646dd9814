//! Exports the paper-rig bundle-adjustment problem for `benches/ba_scipy.py` and times
//! etlcal's solve of it: prints one JSON object with the observations, the linear start,
//! etlcal's final cost and its mean time per solve (one core).
//!
//! `cargo run --release -p etl-sim --example ba_problem`
use std::time::Instant;

use etl_core::calib::jacobian::to_params;
use etl_core::calib::{bundle_adjust, bundle_adjust_scratch, initialise, BundleAdjustOptions, View, ViewScratch};
use etl_sim::simulate::{paper_rig, NoiseModel};

fn main() {
    let sim = paper_rig(&NoiseModel::PAPER, 1);
    let pts = sim.observations.core_points();
    let e: Vec<f64> = sim.observations.views.iter().map(|v| v.e_com_ma.unwrap_or(v.e_in_ma)).collect();
    let views: Vec<View> = pts.iter().zip(&e).map(|(p, &e)| View { e_com_ma: e, points: p }).collect();
    let init = initialise(&views, &sim.a0).expect("initialise");
    // The solve alone, as scipy's least_squares does it: no covariance with the input errors.
    let opts = BundleAdjustOptions { input_noise: None, ..BundleAdjustOptions::default() };
    let mut scratch = vec![ViewScratch::ZERO; bundle_adjust_scratch(views.len())];
    let runs = 20;
    let t = Instant::now();
    let mut report = None;
    for _ in 0..runs {
        report = Some(bundle_adjust(&views, &init, &opts, &mut scratch).expect("bundle adjustment"));
    }
    let secs = t.elapsed().as_secs_f64() / runs as f64;
    let r = report.expect("at least one run");
    let n: usize = pts.iter().map(Vec::len).sum();
    let cost = r.rms_px * r.rms_px * n as f64;
    let out = serde_json::json!({
        "observations": sim.observations,
        "start": to_params(&init)[..init.layout().len()],
        "etlcal_final": to_params(&r.model)[..r.model.layout().len()],
        "etlcal_cost": cost,
        "etlcal_seconds": secs,
        "etlcal_iterations": r.iterations,
    });
    println!("{out}");
}
