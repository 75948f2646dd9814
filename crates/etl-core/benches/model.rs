//! Projection and undistortion of a paper-rig view (issue 2's targets: < 2 us for 168
//! projections on one core).
use criterion::{criterion_group, criterion_main, Criterion};
use etl_core::model::CameraModel;
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

criterion_group!(benches, bench);
criterion_main!(benches);
