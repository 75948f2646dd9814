//! One Levenberg-Marquardt step of the joint rig calibration (errors-in-variables) at
//! 2, 4, 8, 12 and 16 cameras with 200 stage views of the simulated rig
//! (`etl_sim::multi_camera`): the reduced system formed, factored and solved, and the
//! corrections back-substituted, by the dense path (every correction eliminated,
//! nalgebra's Cholesky of the (sum p_k) square Schur complement) and by the sparse path
//! (the stage corrections kept, faer's sparse Cholesky of the bordered system). Both start
//! from the same normal equations (formed once, outside the timing).
use criterion::{criterion_group, criterion_main, Criterion};
use etl_calib::rig_calibration::{JointSystem, LinearSolver};
use etl_core::model::CameraModel;
use etl_sim::multi_camera::{simulate_multi_camera, MultiCameraDesign};
use etl_sim::simulate::NoiseModel;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let noise = NoiseModel { xy_mm: 0.0, ..NoiseModel::PAPER };
    for cameras in [2, 4, 8, 12, 16] {
        let design = MultiCameraDesign { views: 200, ..MultiCameraDesign::new(cameras) };
        let sim = simulate_multi_camera(&design, &noise, 1).unwrap();
        let models: Vec<CameraModel> = sim.truths.clone();
        let system = JointSystem::new(&sim.dataset, &models, 0.2, (0.01, 0.4)).unwrap();
        for (name, solver) in [("dense", LinearSolver::Dense), ("sparse", LinearSolver::Sparse)] {
            c.bench_function(&format!("rig_step_{name}_{cameras}_cameras"), |b| {
                b.iter(|| black_box(system.step(solver, black_box(1e-3)).unwrap()))
            });
        }
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench
}
criterion_main!(benches);
