//! nalgebra against the hand-written code it replaced, in one run:
//! Rodrigues -> matrix (kept hand-written; nalgebra's Rotation3 as the alternative),
//! matrix * vector and the nearest rotation (nalgebra's products now, the `hand` module's
//! loops before), and the closed form of Zhang's method (the right singular vector of the
//! smallest singular value of the stacked 2n x 6 constraints: etl-core's Jacobi SVD of
//! V^T V, kept; faer's thin SVD of V, the alternative that moved the golden outputs, was
//! measured here and is recorded in docs/PERFORMANCE-HISTORY.md, "nalgebra and faer").
//! The `hand` module is the code of before, kept here only as the reference of the bench.
use criterion::{criterion_group, criterion_main, Criterion};
use etl_core::linalg::svd::Svd;
use etl_core::model::rotation::{mat_vec, nearest_rotation, rodrigues_to_matrix, Mat3};
use etl_core::model::CameraModel;
use etl_core::pnp::{homography, zhang_constraints};
use std::hint::black_box;

mod hand {
    use super::{Mat3, Svd};

    pub fn mat_vec(m: &Mat3, x: [f64; 3]) -> [f64; 3] {
        [
            m[0][0] * x[0] + m[0][1] * x[1] + m[0][2] * x[2],
            m[1][0] * x[0] + m[1][1] * x[1] + m[1][2] * x[2],
            m[2][0] * x[0] + m[2][1] * x[1] + m[2][2] * x[2],
        ]
    }

    pub fn nearest_rotation(m: &Mat3) -> Mat3 {
        let svd = Svd::of_rows(m);
        let mut r = [[0.0; 3]; 3];
        for k in 0..3 {
            for i in 0..3 {
                for j in 0..3 {
                    r[i][j] += svd.u[k][i] * svd.v[k][j];
                }
            }
        }
        let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1]) - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
            + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
        if det < 0.0 {
            let kmin = (0..3).min_by(|&a, &b| svd.s[a].total_cmp(&svd.s[b])).unwrap_or(0);
            for i in 0..3 {
                for j in 0..3 {
                    r[i][j] -= 2.0 * svd.u[kmin][i] * svd.v[kmin][j];
                }
            }
        }
        r
    }

    /// b of Zhang's closed form from the 6 x 6 normal matrix V^T V (Jacobi SVD).
    pub fn zhang_b(rows: &[[f64; 6]]) -> [f64; 6] {
        let mut vtv = [[0.0; 6]; 6];
        for row in rows {
            for i in 0..6 {
                for j in 0..6 {
                    vtv[i][j] += row[i] * row[j];
                }
            }
        }
        let svd = Svd::of_rows(&vtv);
        let kmin = (0..6).min_by(|&a, &b| svd.s[a].total_cmp(&svd.s[b])).unwrap_or(0);
        svd.v[kmin]
    }
}

/// 1000 Rodrigues vectors with angles up to ~2.5 rad.
fn rodrigues_vectors() -> Vec<[f64; 3]> {
    (0..1000).map(|i| [0.3 + 0.001 * i as f64, -0.5 + 0.0007 * i as f64, 0.1 + 0.0012 * i as f64]).collect()
}

/// The two constraint rows of Zhang's method per view of an 11 x 8 board, `n` views tilted
/// about both axes in the pixel frame centred on the image and scaled by its size.
fn zhang_rows(n: usize) -> Vec<[f64; 6]> {
    let board: Vec<[f64; 2]> = (0..88).map(|i| [4.0 * (i % 11) as f64, 4.0 * (i / 11) as f64]).collect();
    let mut rows = vec![];
    for k in 0..n {
        let a = 0.4 * (k as f64 / n as f64 - 0.5);
        let cam = CameraModel {
            rotation_rodrigues: [a, -0.8 * a + 0.05 * (k % 3) as f64, 0.1 * k as f64],
            translation_mm: [-20.0, -14.0, 300.0 + 5.0 * k as f64],
            distortion_a: etl_core::model::DistortionA::paper([0.0; 9]),
            ..CameraModel::paper_rig()
        };
        let img: Vec<[f64; 2]> = board
            .iter()
            .map(|b| {
                let p = cam.project([b[0], b[1], 0.0], 0.0).unwrap();
                [(p[0] - 968.0) / 968.0, (p[1] - 729.0) / 968.0]
            })
            .collect();
        let h = homography(&board, &img).unwrap();
        rows.extend(zhang_constraints(&h));
    }
    rows
}

/// fx of Zhang's Appendix B from b, px (the frame's scale is 968 px).
fn fx_px(b: &[f64; 6]) -> f64 {
    let (b11, b12, b22, b13, b23, b33) = (b[0], b[1], b[2], b[3], b[4], b[5]);
    let den = b11 * b22 - b12 * b12;
    let v0 = (b12 * b13 - b11 * b23) / den;
    let lambda = b33 - (b13 * b13 + v0 * (b12 * b13 - b11 * b23)) / b11;
    (lambda / b11).sqrt() * 968.0
}

fn bench_rotation(c: &mut Criterion) {
    let oms = rodrigues_vectors();
    // The library's rodrigues_to_matrix is the hand-written one (kept, see its docs).
    c.bench_function("rodrigues_to_matrix_1000/hand", |b| {
        b.iter(|| black_box(&oms).iter().map(|om| rodrigues_to_matrix(*om)[2][1]).sum::<f64>())
    });
    c.bench_function("rodrigues_to_matrix_1000/nalgebra_rotation3", |b| {
        b.iter(|| {
            black_box(&oms)
                .iter()
                .map(|om| nalgebra::Rotation3::from_scaled_axis(nalgebra::Vector3::from(*om))[(2, 1)])
                .sum::<f64>()
        })
    });
    let r = rodrigues_to_matrix([0.2, 0.2, 0.2]);
    c.bench_function("mat_vec_1000/hand", |b| {
        b.iter(|| black_box(&oms).iter().map(|x| hand::mat_vec(black_box(&r), *x)[2]).sum::<f64>())
    });
    c.bench_function("mat_vec_1000/nalgebra", |b| {
        b.iter(|| black_box(&oms).iter().map(|x| mat_vec(black_box(&r), *x)[2]).sum::<f64>())
    });
    // Near-rotations as a homography gives them: a rotation with its columns scaled.
    let ms: Vec<Mat3> = oms
        .iter()
        .take(100)
        .map(|om| rodrigues_to_matrix(*om).map(|row| [row[0] * 1.01, row[1] * 0.99, row[2]]))
        .collect();
    c.bench_function("nearest_rotation_100/hand", |b| {
        b.iter(|| black_box(&ms).iter().map(|m| hand::nearest_rotation(m)[0][0]).sum::<f64>())
    });
    c.bench_function("nearest_rotation_100/nalgebra_products", |b| {
        b.iter(|| black_box(&ms).iter().map(|m| nearest_rotation(m)[0][0]).sum::<f64>())
    });
}

fn bench_zhang(c: &mut Criterion) {
    for n in [10, 50] {
        let rows = zhang_rows(n);
        let bh = hand::zhang_b(&rows);
        // Noise-free undistorted views of the paper rig at E = 0: the truth is fx = 5380 px.
        eprintln!(
            "zhang closed form, {n} views: fx error (V^T V, Jacobi) {:.3e} (relative)",
            fx_px(&bh) / 5380.0 - 1.0
        );
        c.bench_function(&format!("zhang_closed_form_{n}_views/hand"), |b| b.iter(|| hand::zhang_b(black_box(&rows))));
    }
}

criterion_group!(benches, bench_rotation, bench_zhang);
criterion_main!(benches);
