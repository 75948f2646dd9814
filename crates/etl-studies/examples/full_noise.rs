//! The paper rig under the paper's full noise model (docs/METHOD.md), N seeded trials (default
//! 100): the errors of the plain (paper) and the errors-in-variables bundle adjustment.
//! Prints a markdown table: mean and 95th percentile of the max relative error of fx(E),
//! fy(E) over 80..225 mA, the principal-point error, and the mean relative errors of
//! kf1..kf3 (x, y), om and T (the paper's Fig. 6 measure).
//!
//! `cargo run --release -p etl-studies --example full_noise [-- TRIALS]`
use etl_calib::pipeline::{calibrate, CalibrateOptions};
use etl_core::calib::Estimator;
use etl_core::model::CameraModel;
use etl_formats::ThermalRef;
use etl_sim::simulate::{paper_rig, NoiseModel};
use etl_studies::common::model_errors;
use rayon::prelude::*;

/// [fx curve, fy curve, pp, kf1x, kf2x, kf3x, kf1y, kf2y, kf3y, om, T]
fn errors(m: &CameraModel, t: &CameraModel) -> [f64; 11] {
    let e = model_errors(m, t);
    let [k0, k1, k2, k3, k4, k5] = e.kf_rel;
    [e.fx_curve_max_rel, e.fy_curve_max_rel, e.principal_point_px, k0, k1, k2, k3, k4, k5, e.om_rel, e.t_rel]
}

/// One trial's 11 errors: (paper BA, eiv BA).
type TrialErrors = ([f64; 11], [f64; 11]);

fn main() {
    let trials: u64 = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(100);
    let start = std::time::Instant::now();
    let rows: Vec<([f64; 11], [f64; 11])> = (0..trials)
        .into_par_iter()
        .map(|seed| {
            let sim = paper_rig(&NoiseModel::PAPER, 50_000 + seed);
            let th = ThermalRef::paper();
            let paper = CalibrateOptions { estimator: Estimator::Paper, ..Default::default() };
            let p = calibrate(&sim.observations, &sim.a0, Some(&th), &paper).expect("paper BA");
            let eiv = CalibrateOptions { estimator: Estimator::EIV_PAPER, ..Default::default() };
            let e = calibrate(&sim.observations, &sim.a0, Some(&th), &eiv).expect("eiv BA");
            (errors(&p.report.model, &sim.truth), errors(&e.report.model, &sim.truth))
        })
        .collect();
    let names = [
        "max rel err fx(E)",
        "max rel err fy(E)",
        "principal point (px)",
        "kf1x",
        "kf2x",
        "kf3x",
        "kf1y",
        "kf2y",
        "kf3y",
        "om",
        "T",
    ];
    println!(
        "{trials} trials of the paper rig with the paper's noise model ({:.1} s)\n",
        start.elapsed().as_secs_f64()
    );
    println!("| error | paper BA mean | paper BA p95 | eiv BA mean | eiv BA p95 |\n|---|---|---|---|---|");
    for (k, name) in names.iter().enumerate() {
        let stats = |pick: &dyn Fn(&TrialErrors) -> f64| {
            let mut v: Vec<f64> = rows.iter().map(pick).collect();
            v.sort_by(f64::total_cmp);
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            let p95 = v[((v.len() as f64 * 0.95) as usize).min(v.len() - 1)];
            (mean, p95)
        };
        let (pm, pp) = stats(&|r| r.0[k]);
        let (em, ep) = stats(&|r| r.1[k]);
        if k == 2 {
            println!("| {name} | {pm:.2} | {pp:.2} | {em:.2} | {ep:.2} |");
        } else {
            println!(
                "| {name} | {:.3} % | {:.3} % | {:.3} % | {:.3} % |",
                100.0 * pm,
                100.0 * pp,
                100.0 * em,
                100.0 * ep
            );
        }
    }
}
