//! The paper's BA on one six-view subset of the `subsets` study, iteration by iteration:
//! RMS and the largest parameter distance (in formal std) from the converged estimate.
//! `NOISE_NONE=1` runs it on noise-free data.
//!
//! `cargo run --release -p etl-studies --example subset_trace -- [VIEWS] [TRIAL]`, VIEWS as
//! the study labels them (e.g. 135789, 1-based in the nine).
use etl_core::calib::jacobian::to_params;
use etl_sim::simulate::{paper_rig, NoiseModel};
use etl_studies::common::{calibrate_paper_capped, param_name, StudyOptions, PARAMS};
use etl_studies::subsets::NINE_VIEWS;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let label = args.get(1).map_or("135789", String::as_str);
    let trial: usize = args.get(2).and_then(|t| t.parse().ok()).unwrap_or(0);
    let opts = StudyOptions::default();
    let noise = if std::env::var_os("NOISE_NONE").is_some() { NoiseModel::NONE } else { NoiseModel::PAPER };
    let sim = paper_rig(&noise, opts.trial_seed(trial));
    let mut obs = sim.observations.clone();
    obs.views = label
        .chars()
        .filter_map(|c| c.to_digit(10))
        .filter_map(|k| NINE_VIEWS.get(k as usize - 1))
        .filter_map(|&i| sim.observations.views.get(i).cloned())
        .collect();
    let full = calibrate_paper_capped(&obs, &sim.a0, 200).expect("calibrate");
    let x = to_params(&full.model);
    println!("converged: {} iterations, rms {:.6} px, stop {:?}", full.iterations, full.rms_px, full.stop);
    for k in 0..=full.iterations {
        let r = calibrate_paper_capped(&obs, &sim.a0, k).expect("calibrate");
        let xk = to_params(&r.model);
        let (worst, i) = (0..PARAMS)
            .map(|i| ((xk[i] - x[i]).abs() / full.std[i].max(1e-300), i))
            .fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a });
        println!("iter {k:2}: rms {:.6} px, worst shift {worst:9.3} std ({})", r.rms_px, param_name(i));
    }
}
