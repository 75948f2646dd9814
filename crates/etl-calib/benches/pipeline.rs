//! From observations to calibration file for the paper rig (target: under 10 ms, process
//! start excluded): read `observations.json`, compensate E, initialise, bundle-adjust,
//! write `calibration.json` atomically; with errors-in-variables (the default estimator)
//! and with the paper's Eq. 24.
use criterion::{criterion_group, criterion_main, Criterion};
use etl_calib::pipeline::{calibrate, CalibrateOptions};
use etl_core::calib::Estimator;
use etl_formats::observations::Observations;
use etl_formats::ThermalRef;
use etl_sim::simulate::{paper_rig, NoiseModel};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let sim = paper_rig(&NoiseModel::PAPER, 1);
    let dir = tempfile::tempdir().unwrap();
    let (obs_path, cal_path) = (dir.path().join("observations.json"), dir.path().join("calibration.json"));
    sim.observations.save(&obs_path).unwrap();
    for (name, estimator) in [("paper", Estimator::Paper), ("eiv", Estimator::EIV_PAPER)] {
        let options = CalibrateOptions { estimator, ..CalibrateOptions::default() };
        c.bench_function(&format!("observations_to_calibration_file_{name}"), |b| {
            b.iter(|| {
                let obs = Observations::load(black_box(&obs_path)).unwrap();
                let r = calibrate(&obs, &sim.a0, Some(&ThermalRef::paper()), &options).unwrap();
                r.calibration.save(&cal_path).unwrap();
            })
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
