//! Where the bundle adjustment's time goes on the paper rig (pixel noise 0.2 px): iterations,
//! evaluations, time of one Jacobian evaluation and of one cost evaluation, total per solve.
//!
//! `cargo run --release -p etl-core --example ba_profile`
use std::time::Instant;

use etl_core::calib::jacobian::Projector;
use etl_core::calib::{
    bundle_adjust, bundle_adjust_scratch, initialise, BundleAdjustOptions, Point, View, ViewScratch, A0,
};
use etl_core::model::CameraModel;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

const Z_W: [f64; 15] = [75.0, 60.0, 48.0, 43.0, 35.0, 31.0, 28.0, 22.0, 19.0, 16.0, 13.0, 10.0, 8.0, 4.0, 2.0];

/// The paper rig's 15 views with 0.2 px pixel noise: (points per view, current per view).
fn paper_rig_points(cam: &CameraModel) -> (Vec<Vec<Point>>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let n = Normal::new(0.0, 0.2).expect("sigma");
    let (mut pts, mut e) = (vec![], vec![]);
    for (k, &z) in Z_W.iter().enumerate() {
        let cur = if k == 14 { 225.0 } else { 80.0 + 10.0 * k as f64 };
        let mut v = vec![];
        for j in 0..12 {
            for i in 0..14 {
                let w = [1.5 * i as f64, 1.5 * j as f64, z];
                let p = cam.project(w, cur).expect("visible");
                if (0.0..=1935.0).contains(&p[0]) && (0.0..=1457.0).contains(&p[1]) {
                    v.push(Point { world_mm: w, pixel: [p[0] + n.sample(&mut rng), p[1] + n.sample(&mut rng)] });
                }
            }
        }
        pts.push(v);
        e.push(cur);
    }
    (pts, e)
}

fn main() {
    let cam = CameraModel::paper_rig();
    let (pts, e) = paper_rig_points(&cam);
    let views: Vec<View> = pts.iter().zip(&e).map(|(p, &e)| View { e_com_ma: e, points: p }).collect();
    let a0 = A0 { kf0x: 5380.0, kf0y: 5430.0, u0: 900.0, v0: 550.0 };
    let init = initialise(&views, &a0).expect("initialise");
    let opts = if std::env::var_os("BA_EIV").is_some() {
        let mut o = BundleAdjustOptions { estimator: etl_core::calib::Estimator::EIV_PAPER, ..Default::default() };
        if let Some(d) = std::env::var("BA_DAMPING").ok().and_then(|d| d.parse().ok()) {
            o.lm.initial_damping = d;
        }
        o
    } else {
        BundleAdjustOptions::default()
    };
    let mut scratch = vec![ViewScratch::ZERO; bundle_adjust_scratch(views.len())];
    let r = bundle_adjust(&views, &init, &opts, &mut scratch).expect("ba");
    if std::env::var_os("BA_TRACE").is_some() {
        for k in 1..=r.iterations {
            let mut o = opts;
            o.lm.max_iterations = k;
            let rk = bundle_adjust(&views, &init, &o, &mut scratch).expect("ba");
            println!(
                "iterations {k}: rms {:.12} px, fx(225) rel err {:.3e}",
                rk.rms_px,
                rk.model.intrinsics(225.0).map(|i| i.fx / cam.intrinsics(225.0).unwrap().fx - 1.0).unwrap()
            );
        }
    }
    if std::env::var_os("BA_ONCE").is_some() {
        // For instruction counts (valgrind): the solve above, once.
        return;
    }
    // Minimum over batches: the machine may be shared, the minimum is the undisturbed time.
    let min_time = |f: &mut dyn FnMut()| {
        (0..20)
            .map(|_| {
                let t = Instant::now();
                for _ in 0..10 {
                    f();
                }
                t.elapsed().as_secs_f64() / 10.0
            })
            .fold(f64::INFINITY, f64::min)
    };
    let total = min_time(&mut || {
        std::hint::black_box(bundle_adjust(&views, &init, &opts, &mut scratch).expect("ba"));
    });
    if std::env::var_os("BA_ONLY").is_some() {
        println!("solve {:.3} ms", total * 1e3);
        return;
    }
    let runs = 1;
    let proj = Projector::new(&init);
    let mut acc = 0.0;
    let jac = min_time(&mut || {
        for v in &views {
            for p in v.points {
                acc += proj.project_reduced(p.world_mm, v.e_com_ma, true).expect("p").d_reduced[0][3];
            }
        }
    }) / runs as f64;
    let cost = min_time(&mut || {
        for v in &views {
            for p in v.points {
                acc += proj.project_reduced(p.world_mm, v.e_com_ma, false).expect("p").pixel[0];
            }
        }
    });
    std::hint::black_box(acc);
    let mut cols = [[0.0; 25]; 25];
    for j in 0..25 {
        for i in 0..=j {
            cols[j][i] = 1.0 / (1.0 + (i + j) as f64) + if i == j { 1.0 } else { 0.0 };
        }
    }
    let svd = min_time(&mut || {
        std::hint::black_box(etl_core::linalg::svd::Svd::of_columns(std::hint::black_box(cols)));
    });
    println!("svd 25x25 {:.3} ms", svd * 1e3);
    println!(
        "points {} iterations {} stop {:?} rms {:.4} -> {:.4} px\nsolve {:.3} ms, projections with Jacobian {:.3} ms, without {:.3} ms",
        views.iter().map(|v| v.points.len()).sum::<usize>(),
        r.iterations,
        r.stop,
        r.initial_rms_px,
        r.rms_px,
        total * 1e3,
        jac * 1e3,
        cost * 1e3
    );
}
