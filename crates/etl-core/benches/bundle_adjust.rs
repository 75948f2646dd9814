//! Bundle adjustment of the paper rig (15 views, 2311 points) from the linear
//! initialisation, and the initialisation itself (target < 2 ms on one core).
use criterion::{criterion_group, criterion_main, Criterion};
use etl_core::calib::{
    bundle_adjust, bundle_adjust_scratch, initialise, BundleAdjustOptions, Estimator, Point, View, ViewScratch, A0,
};
use etl_core::model::CameraModel;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::hint::black_box;

const Z_W: [f64; 15] = [75.0, 60.0, 48.0, 43.0, 35.0, 31.0, 28.0, 22.0, 19.0, 16.0, 13.0, 10.0, 8.0, 4.0, 2.0];

fn paper_rig() -> (Vec<Vec<Point>>, Vec<f64>) {
    let cam = CameraModel::paper_rig();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let n = Normal::new(0.0, 0.2).unwrap();
    let mut views = vec![];
    let mut e = vec![];
    for (k, &z) in Z_W.iter().enumerate() {
        let cur = if k == 14 { 225.0 } else { 80.0 + 10.0 * k as f64 };
        let mut pts = vec![];
        for j in 0..12 {
            for i in 0..14 {
                let w = [1.5 * i as f64, 1.5 * j as f64, z];
                let p = cam.project(w, cur).unwrap();
                if (0.0..=1935.0).contains(&p[0]) && (0.0..=1457.0).contains(&p[1]) {
                    pts.push(Point { world_mm: w, pixel: [p[0] + n.sample(&mut rng), p[1] + n.sample(&mut rng)] });
                }
            }
        }
        views.push(pts);
        e.push(cur);
    }
    (views, e)
}

fn bench(c: &mut Criterion) {
    let (pts, e) = paper_rig();
    let views: Vec<View> = pts.iter().zip(&e).map(|(p, &e)| View { e_com_ma: e, points: p }).collect();
    let a0 = A0 { kf0x: 5380.0, kf0y: 5430.0, u0: 900.0, v0: 550.0 };
    let init = initialise(&views, &a0).unwrap();
    c.bench_function("initialise_paper_rig", |b| b.iter(|| initialise(black_box(&views), &a0).unwrap()));
    let mut scratch = vec![ViewScratch::ZERO; bundle_adjust_scratch(views.len())];
    let paper = BundleAdjustOptions::default();
    c.bench_function("bundle_adjust_paper_rig", |b| {
        b.iter(|| bundle_adjust(black_box(&views), &init, &paper, &mut scratch).unwrap())
    });
    let eiv = BundleAdjustOptions { estimator: Estimator::EIV_PAPER, ..Default::default() };
    c.bench_function("bundle_adjust_eiv_paper_rig", |b| {
        b.iter(|| bundle_adjust(black_box(&views), &init, &eiv, &mut scratch).unwrap())
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
