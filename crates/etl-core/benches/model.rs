//! Projection and undistortion of a paper-rig view, and the temperature compensation
//! (the targets: < 2 us for 168 projections, < 20 ns per E_com, on one core), and
//! the run-time camera at a setting (target: `Camera::at` under 100 ns).
use criterion::{criterion_group, criterion_main, Criterion};
use etl_core::model::CameraModel;
use etl_core::runtime::{Camera, ThermalTrust};
use etl_core::thermal::{ThermalCalibration, ThermalSurface};
use std::hint::black_box;

fn board(z: f64) -> Vec<[f64; 3]> {
    (0..12).flat_map(|j| (0..14).map(move |i| [1.5 * i as f64, 1.5 * j as f64, z])).collect()
}

fn bench(c: &mut Criterion) {
    let cam = CameraModel::paper_rig();
    let pts = board(48.0);
    let mut out = vec![[0.0; 2]; pts.len()];
    c.bench_function("project_168_points", |b| {
        b.iter(|| cam.project_many(black_box(&pts), black_box(100.0), &mut out).unwrap())
    });
    cam.project_many(&pts, 100.0, &mut out).unwrap();
    let observed = out.clone();
    c.bench_function("undistort_168_points", |b| {
        b.iter(|| {
            for p in &observed {
                black_box(cam.undistort(black_box(*p), 100.0).unwrap());
            }
        })
    });
}

fn bench_camera_at(c: &mut Criterion) {
    let thermal = ThermalTrust::from_calibration(&ThermalCalibration::PAPER);
    let cam = Camera::new(CameraModel::paper_rig(), Some(thermal), [80.0, 225.0]).unwrap();
    // (E_in, T) -> E_com (Eq. 7), range checks, K and distortion (Eq. 16, 18).
    c.bench_function("camera_at", |b| b.iter(|| cam.at(black_box(150.0), black_box(31.7)).unwrap()));
}

fn bench_thermal(c: &mut Criterion) {
    let s = ThermalSurface::PAPER;
    c.bench_function("e_com_one", |b| b.iter(|| s.e_com_ma(black_box(143.2), black_box(31.7)).unwrap()));
    // 1000 distinct (T, E_in) per iteration, so the time per E_com is the time / 1000.
    let inputs: Vec<(f64, f64)> = (0..1000).map(|i| (27.0 + 0.01 * i as f64, 40.0 + 0.2 * i as f64)).collect();
    c.bench_function("e_com_1000", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &(t, e) in black_box(&inputs) {
                acc += s.e_com_ma(e, t).unwrap();
            }
            acc
        })
    });
    let cal = ThermalCalibration::PAPER;
    c.bench_function("compensate_flagged_one", |b| {
        b.iter(|| cal.compensate(black_box(143.2), black_box(31.7)).unwrap())
    });
    c.bench_function("e_in_for_e_com_one", |b| b.iter(|| s.e_in_for_e_com(black_box(143.2), black_box(31.7)).unwrap()));
}

criterion_group!(benches, bench, bench_thermal, bench_camera_at);
criterion_main!(benches);
