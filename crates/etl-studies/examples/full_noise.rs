//! The paper rig under the paper's full noise model (NOTES.md), N seeded trials (default
//! 100): the errors of the plain (paper) and the errors-in-variables bundle adjustment.
//! Prints a markdown table: mean and 95th percentile of the max relative error of fx(E),
//! fy(E) over 80..225 mA, the principal-point error, and the mean relative errors of
//! kf1..kf3 (x, y), om and T (the paper's Fig. 6 measure).
//!
//! `cargo run --release -p etl-calib --example full_noise [-- TRIALS]`
use etl_calib::pipeline::{calibrate, CalibrateOptions};
use etl_core::calib::Estimator;
use etl_core::model::CameraModel;
use etl_core::thermal::ThermalCalibration;
use etl_sim::simulate::{paper_rig, NoiseModel};
use etl_studies::common::curve_errors;
use rayon::prelude::*;

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// [fx curve, fy curve, pp, kf1x, kf2x, kf3x, kf1y, kf2y, kf3y, om, T]
fn errors(m: &CameraModel, t: &CameraModel) -> [f64; 11] {
    let (ex, ey) = curve_errors(m, t, [80.0, 225.0]);
    let pp = (m.principal_point[0] - t.principal_point[0]).hypot(m.principal_point[1] - t.principal_point[1]);
    let d = |a: [f64; 3], b: [f64; 3]| norm([a[0] - b[0], a[1] - b[1], a[2] - b[2]]) / norm(b);
    [
        ex,
        ey,
        pp,
        rel(m.kf_x[1], t.kf_x[1]),
        rel(m.kf_x[2], t.kf_x[2]),
        rel(m.kf_x[3], t.kf_x[3]),
        rel(m.kf_y[1], t.kf_y[1]),
        rel(m.kf_y[2], t.kf_y[2]),
        rel(m.kf_y[3], t.kf_y[3]),
        d(m.rotation_rodrigues, t.rotation_rodrigues),
        d(m.translation_mm, t.translation_mm),
    ]
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
            let th = ThermalCalibration::PAPER;
            let paper = CalibrateOptions { estimator: Estimator::Paper, ..Default::default() };
            let p = calibrate(&sim.observations, &sim.a0, &th, &paper).expect("paper BA");
            let eiv = CalibrateOptions { estimator: Estimator::EIV_PAPER, ..Default::default() };
            let e = calibrate(&sim.observations, &sim.a0, &th, &eiv).expect("eiv BA");
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
