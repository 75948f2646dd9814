//! Zhang's monofocal calibration (Zhang 2000): the lens-off intrinsics A0 (paper section
//! 4.2) from views of a planar board, and the building block of the per-setting baseline.
//!
//! 1. A homography per view ([`etl_core::pnp::homography`], normalised DLT), computed in
//!    a pixel frame centred on the image and scaled by its size, for conditioning.
//! 2. The closed form: each H gives two linear constraints v12^T b = 0,
//!    (v11 - v22)^T b = 0 on b = (B11, B12, B22, B13, B23, B33), B = K^-T K^-1; b is the
//!    right singular vector of the smallest singular value; K follows (Zhang's Appendix B),
//!    skew dropped. Each view's pose from K^-1 H, then the nearest rotation.
//! 3. Levenberg-Marquardt over the 7 shared numbers (fx, fy, u0, v0 and the paper's
//!    distortion k1, p1, p2 in centred pixels) and the 6 pose numbers of every view,
//!    by the Schur-block solver of etl-core. The projection and its Jacobian are the ETL
//!    model's at E = 0 with kf_x = [fx, 0, 0, 0], kf_y = [fy, 0, 0, 0] and
//!    a = [0, 0, k1, 0, 0, p1, 0, 0, p2]: one camera model in the project.
//!
//! Needs at least 3 views of the board in distinct orientations (each view gives two
//! constraints on the 5 unknowns of B up to scale).

use etl_core::calib::jacobian::Projector;
use etl_core::calib::A0;
use etl_core::linalg::svd::Svd;
use etl_core::lm::{solve_blocks, BlockProblem, BlockReport, BlockRowSink, BlockScratch, Options, StopReason};
use etl_core::model::rotation::{matrix_to_rodrigues, rotation_from_two_columns};
use etl_core::model::{CameraModel, DistortionA, FocalPoly};
use etl_core::pnp::homography;

use etl_formats::calibration::Outlier;
use etl_formats::{Error, Result};

use crate::pipeline::robust::{homography_inliers, outlier_limit_px};

/// One view: board points (mm, on Z = 0) and their observed pixels.
#[derive(Debug, Clone, Default)]
pub struct PlanarView {
    /// Board (X, Y), mm.
    pub board_mm: Vec<[f64; 2]>,
    /// Observed pixels.
    pub pixels: Vec<[f64; 2]>,
}

/// The result of [`zhang`].
#[derive(Debug, Clone)]
pub struct ZhangResult {
    /// Focal length along u, px.
    pub fx: f64,
    /// Focal length along v, px.
    pub fy: f64,
    /// Principal point u0, px.
    pub u0: f64,
    /// Principal point v0, px.
    pub v0: f64,
    /// The paper's radial coefficient, 1/px^2.
    pub k1: f64,
    /// The paper's decentering coefficient p1, 1/px.
    pub p1: f64,
    /// The paper's decentering coefficient p2, 1/px.
    pub p2: f64,
    /// One standard deviation of (fx, fy, u0, v0, k1, p1, p2).
    pub std: [f64; 7],
    /// RMS reprojection error, px.
    pub rms_px: f64,
    /// Each view's pose (Rodrigues, translation mm).
    pub poses: Vec<([f64; 3], [f64; 3])>,
    /// LM iterations.
    pub iterations: usize,
    /// Views used.
    pub views_used: usize,
    /// The points left out as gross outliers (view and point indices into the input),
    /// with their distances under the result; empty when there are none.
    pub outliers: Vec<Outlier>,
}

impl ZhangResult {
    /// The lens-off intrinsics A0.
    pub fn a0(&self) -> A0 {
        A0 { kf0x: self.fx, kf0y: self.fy, u0: self.u0, v0: self.v0 }
    }
}

fn vij(h: &[[f64; 3]; 3], i: usize, j: usize) -> [f64; 6] {
    // Columns of H: h_i = (H[0][i], H[1][i], H[2][i]).
    let (a, b) = ([h[0][i], h[1][i], h[2][i]], [h[0][j], h[1][j], h[2][j]]);
    [
        a[0] * b[0],
        a[0] * b[1] + a[1] * b[0],
        a[1] * b[1],
        a[2] * b[0] + a[0] * b[2],
        a[2] * b[1] + a[1] * b[2],
        a[2] * b[2],
    ]
}

/// The camera model Zhang's parameters stand for (E = 0).
fn model(x: &[f64; 7], pose: &[f64; 6]) -> CameraModel {
    CameraModel {
        rotation_rodrigues: [pose[0], pose[1], pose[2]],
        translation_mm: [pose[3], pose[4], pose[5]],
        kf_x: FocalPoly::cubic([x[0], 0.0, 0.0, 0.0]),
        kf_y: FocalPoly::cubic([x[1], 0.0, 0.0, 0.0]),
        principal_point: [x[2], x[3]],
        distortion_a: DistortionA::paper([0.0, 0.0, x[4], 0.0, 0.0, x[5], 0.0, 0.0, x[6]]),
    }
}

/// Indices of fx, fy, u0, v0, k1 (a3), p1 (a6), p2 (a9) in the 25-number vector.
const SHARED: [usize; 7] = [6, 10, 14, 15, 18, 21, 24];

struct Refine<'a> {
    views: &'a [PlanarView],
}

impl BlockProblem<7, 6> for Refine<'_> {
    fn block_count(&self) -> usize {
        self.views.len()
    }

    fn eval_block(
        &mut self,
        b: usize,
        x: &[f64; 7],
        y: &[f64; 6],
        jacobian: bool,
        sink: &mut dyn BlockRowSink<7, 6>,
    ) -> etl_core::Result<()> {
        let v = self.views.get(b).ok_or(etl_core::Error::InvalidArgument { what: "view index" })?;
        let proj = Projector::new(&model(x, y));
        for (w, px) in v.board_mm.iter().zip(&v.pixels) {
            let p = proj.project([w[0], w[1], 0.0], 0.0, jacobian)?;
            for row in 0..2 {
                let d = &p.d_params[row];
                let jx: [f64; 7] = core::array::from_fn(|k| d[SHARED[k]]);
                let jy: [f64; 6] = core::array::from_fn(|k| d[k]);
                sink.push(p.pixel[row] - px[row], &jx, &jy);
            }
        }
        Ok(())
    }
}

/// The closed form (steps 1 and 2): (fx, fy, u0, v0) and each view's pose
/// (Rodrigues, translation) from the views' homographies.
fn closed_form(views: &[PlanarView], image_size: [u32; 2]) -> Result<([f64; 4], Vec<[f64; 6]>)> {
    let (cx, cy) = (image_size[0] as f64 / 2.0, image_size[1] as f64 / 2.0);
    let s = cx.max(cy).max(1.0);
    let mut hs = vec![];
    let mut vtv = [[0.0; 6]; 6];
    for v in views {
        let img: Vec<[f64; 2]> = v.pixels.iter().map(|p| [(p[0] - cx) / s, (p[1] - cy) / s]).collect();
        let h = homography(&v.board_mm, &img)?;
        let v12 = vij(&h, 0, 1);
        let (v11, v22) = (vij(&h, 0, 0), vij(&h, 1, 1));
        let d: [f64; 6] = core::array::from_fn(|i| v11[i] - v22[i]);
        for row in [v12, d] {
            for i in 0..6 {
                for j in 0..6 {
                    vtv[i][j] += row[i] * row[j];
                }
            }
        }
        hs.push(h);
    }
    // etl-core's Jacobi SVD of V^T V, not faer's SVD of V: the latter moves A0 in the last
    // bits and the golden outputs of `calibrate` and `demo` beyond 1e-12 (docs/BENCHMARKS.md).
    let svd = Svd::of_rows(&vtv);
    let kmin = (0..6).min_by(|&a, &b| svd.s[a].total_cmp(&svd.s[b])).unwrap_or(0);
    let b = svd.v[kmin];
    let (b11, b12, b22, b13, b23, b33) = (b[0], b[1], b[2], b[3], b[4], b[5]);
    let den = b11 * b22 - b12 * b12;
    let degenerate = || {
        Error::Core(etl_core::Error::Degenerate {
            what: "Zhang's closed form failed: board views too alike (tilt the board between views)",
        })
    };
    if den.abs() < 1e-300 || b11.abs() < 1e-300 {
        return Err(degenerate());
    }
    let v0n = (b12 * b13 - b11 * b23) / den;
    let lambda = b33 - (b13 * b13 + v0n * (b12 * b13 - b11 * b23)) / b11;
    let alpha2 = lambda / b11;
    let beta2 = lambda * b11 / den;
    if !(alpha2 > 0.0 && beta2 > 0.0) {
        return Err(degenerate());
    }
    let (alpha, beta) = (alpha2.sqrt(), beta2.sqrt());
    let u0n = -b13 * alpha2 / lambda; // skew dropped
                                      // Poses from K^-1 H (H in the normalised frame, K likewise).
    let kinv = |p: [f64; 3]| [(p[0] - u0n * p[2]) / alpha, (p[1] - v0n * p[2]) / beta, p[2]];
    let mut poses: Vec<[f64; 6]> = vec![];
    for h in &hs {
        let r1 = kinv([h[0][0], h[1][0], h[2][0]]);
        let r2 = kinv([h[0][1], h[1][1], h[2][1]]);
        let t = kinv([h[0][2], h[1][2], h[2][2]]);
        let n1 = (r1[0] * r1[0] + r1[1] * r1[1] + r1[2] * r1[2]).sqrt();
        let n2 = (r2[0] * r2[0] + r2[1] * r2[1] + r2[2] * r2[2]).sqrt();
        let mut l = 2.0 / (n1 + n2);
        if t[2] * l < 0.0 {
            l = -l;
        }
        let (r1, r2, t) = (r1.map(|v| v * l), r2.map(|v| v * l), t.map(|v| v * l));
        let om = matrix_to_rodrigues(&rotation_from_two_columns(r1, r2));
        poses.push([om[0], om[1], om[2], t[0], t[1], t[2]]);
    }
    // Back to pixels: the normalised frame is (p - c) / s.
    Ok(([alpha * s, beta * s, u0n * s + cx, v0n * s + cy], poses))
}

/// Step 3: the LM refinement of the 7 shared numbers and every view's pose from `x0`
/// and `poses`.
fn refine(views: &[PlanarView], x0: [f64; 7], poses: &[[f64; 6]]) -> Result<(BlockReport<7>, Vec<[f64; 6]>)> {
    let mut problem = Refine { views };
    let mut scratch: Vec<BlockScratch<7, 6>> = poses.iter().map(|&p| BlockScratch::starting_at(p)).collect();
    let opts = Options { max_iterations: 100, ftol: 1e-12, xtol: 1e-12, gtol: 1e-12, ..Options::default() };
    let r = solve_blocks(&mut problem, x0, &opts, &mut scratch)?;
    if r.stop == StopReason::RankDeficient {
        return Err(Error::Core(etl_core::Error::Degenerate {
            what: "Zhang's refinement is rank deficient (too few or too similar views)",
        }));
    }
    Ok((r, scratch.iter().map(|b| *b.y()).collect()))
}

/// The points of each view that `used` keeps.
fn kept(views: &[PlanarView], used: &[Vec<bool>]) -> Vec<PlanarView> {
    views
        .iter()
        .zip(used)
        .map(|(v, u)| {
            let (board_mm, pixels) =
                v.board_mm.iter().zip(&v.pixels).zip(u).filter(|(_, &k)| k).map(|((b, p), _)| (*b, *p)).unzip();
            PlanarView { board_mm, pixels }
        })
        .collect()
}

/// Every point's reprojection distance, px, under the shared numbers `x` and `poses`
/// (infinite where it does not project).
fn distances(views: &[PlanarView], x: &[f64; 7], poses: &[[f64; 6]]) -> Vec<Vec<f64>> {
    views
        .iter()
        .zip(poses)
        .map(|(v, pose)| {
            let m = model(x, pose);
            v.board_mm
                .iter()
                .zip(&v.pixels)
                .map(|(b, px)| match m.project([b[0], b[1], 0.0], 0.0) {
                    Ok(q) => (q[0] - px[0]).hypot(q[1] - px[1]),
                    Err(_) => f64::INFINITY,
                })
                .collect()
        })
        .collect()
}

/// Calibrates a fixed-focus camera from planar views (see the module docs), robustly:
/// each view's points are first screened against a robust homography
/// ([`crate::pipeline::robust::homography_inliers`]); after the refinement a point whose
/// distance exceeds [`outlier_limit_px`] is an outlier, and the refinement is
/// repeated without the outliers until their set no longer changes (at most 4 times).
///
/// `image_size` sets the conditioning frame. Errors: fewer than 3 views or a view with
/// fewer than 4 points ([`Error::InvalidInput`]); degenerate geometry (all views parallel)
/// or a failed solve ([`Error::Core`]).
pub fn zhang(views: &[PlanarView], image_size: [u32; 2]) -> Result<ZhangResult> {
    if views.len() < 3 {
        return Err(Error::InvalidInput(format!(
            "Zhang's method needs at least 3 views of the board, got {}",
            views.len()
        )));
    }
    for (k, v) in views.iter().enumerate() {
        if v.board_mm.len() != v.pixels.len() || v.board_mm.len() < 4 {
            return Err(Error::InvalidInput(format!("view {k}: needs at least 4 points with their pixels")));
        }
    }
    let mut used: Vec<Vec<bool>> = views.iter().map(|v| homography_inliers(&v.board_mm, &v.pixels)).collect();
    let screened = kept(views, &used);
    let (k, poses) = closed_form(&screened, image_size)?;
    let x0 = [k[0], k[1], k[2], k[3], 0.0, 0.0, 0.0];
    let (mut r, mut poses) = refine(&screened, x0, &poses)?;
    let mut d = distances(views, &r.x, &poses);
    for _ in 0..4 {
        let all: Vec<f64> = d.iter().flatten().copied().collect();
        let limit = outlier_limit_px(&all);
        let inliers: Vec<Vec<bool>> = d.iter().map(|v| v.iter().map(|&x| x <= limit).collect()).collect();
        if inliers == used {
            break;
        }
        used = inliers;
        // From the last solution: it is already near, and the closed form is only needed
        // to start.
        (r, poses) = refine(&kept(views, &used), r.x, &poses)?;
        d = distances(views, &r.x, &poses);
    }
    let mut outliers = vec![];
    let (mut ss, mut n) = (0.0, 0usize);
    for (j, (u, dv)) in used.iter().zip(&d).enumerate() {
        for (i, (&k, &x)) in u.iter().zip(dv).enumerate() {
            if k {
                ss += x * x;
                n += 1;
            } else {
                outliers.push(Outlier { view: j, point: i, residual_px: if x.is_finite() { x } else { f64::MAX } });
            }
        }
    }
    let std: [f64; 7] = core::array::from_fn(|i| r.covariance[i][i].max(0.0).sqrt());
    Ok(ZhangResult {
        fx: r.x[0],
        fy: r.x[1],
        u0: r.x[2],
        v0: r.x[3],
        k1: r.x[4],
        p1: r.x[5],
        p2: r.x[6],
        std,
        rms_px: (ss / n.max(1) as f64).sqrt(),
        poses: poses.iter().map(|p| ([p[0], p[1], p[2]], [p[3], p[4], p[5]])).collect(),
        iterations: r.iterations,
        views_used: views.len(),
        outliers,
    })
}
