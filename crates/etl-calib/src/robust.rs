//! Robustness against gross corner outliers (a corner detected on the wrong feature, a
//! pixel swapped with another view's): they would break the linear initialisation
//! (Zhang's homographies, RAC, the focal polynomial are plain least squares, and RAC takes
//! the sign of ty from the point farthest from the centre, which a random pixel often is)
//! before a robust loss in the bundle adjustment could help.
//!
//! Two stages:
//! 1. Before the linear initialisation, each planar view's points are screened against a
//!    homography fitted robustly ([`homography_inliers`]): least median of squares over
//!    deterministic 6-point samples, then iterated least-squares refits on the points
//!    within [`INIT_SIGMAS`] robust sigmas (MAD-style, from the median residual). LMedS
//!    is chosen over a thresholded RANSAC because it needs no pixel threshold (the
//!    homography's residuals on clean corners include the lens distortion, whose size
//!    is not known before calibration) and tolerates up to half the points of a view
//!    being wrong; the refits then use all good points. The screen only decides which
//!    points the initialisation and the first solve see; it does not decide what is an
//!    outlier.
//! 2. After the bundle adjustment, a corner whose reprojection distance exceeds
//!    [`outlier_limit_px`] (the larger of [`OUTLIER_SIGMAS`] robust sigmas of all
//!    distances and [`OUTLIER_FLOOR_PX`]) is an outlier; the solve is repeated without the
//!    outliers until the set no longer changes.

use etl_core::pnp::homography;

/// Robust sigmas beyond which the initialisation's homography screen sets a point aside.
pub const INIT_SIGMAS: f64 = 5.0;

/// The least distance, px, the homography screen ever sets aside. A homography ignores the
/// lens distortion, which on the paper rig's clean views leaves residuals up to 3.2 px at
/// the board's edges (median 0.25-0.77 px, view 13 at 200 mA); a point less than 10 px off
/// cannot break the linear initialisation (to it, it is noise that the bundle adjustment
/// then removes), while a gross outlier (a random pixel, a neighbouring corner) is off
/// by tens to hundreds of px. Clean data thus go through the initialisation whole, as
/// before the screen existed (the golden outputs are unchanged).
pub const INIT_FLOOR_PX: f64 = 10.0;

/// Robust sigmas of the reprojection distance beyond which a corner is an outlier after
/// the bundle adjustment. For Gaussian pixel noise the distance is Rayleigh distributed:
/// P(d > 5 sigma) = exp(-12.5) = 3.7e-6, i.e. 0.009 false outliers expected among the
/// paper rig's 2311 corners.
pub const OUTLIER_SIGMAS: f64 = 5.0;

/// The least distance, px, that makes an outlier. Without it, model misfit would be taken
/// for outliers whenever the corner noise is far below the misfit: the paper's estimator
/// leaves residuals up to 1 px (10 um stage errors it cannot absorb) on the demo's
/// rendered images, whose corners are good to 0.01 px (robust sigma 0.09 px), and a pure
/// sigma rule set 8 % of those corners aside. Gross outliers (a neighbouring corner, a
/// stray detection, a random pixel) are off by a square: tens of px.
pub const OUTLIER_FLOOR_PX: f64 = 2.0;

/// The distance, px, beyond which a point is an outlier given all points' distances
/// `d_px`: max([`OUTLIER_SIGMAS`] [`robust_sigma_px`](d_px), [`OUTLIER_FLOOR_PX`]).
pub fn outlier_limit_px(d_px: &[f64]) -> f64 {
    (OUTLIER_SIGMAS * robust_sigma_px(d_px)).max(OUTLIER_FLOOR_PX)
}

/// The least robust sigma, px, [`robust_sigma_px`] returns: noise-free data (simulations)
/// would otherwise make round-off an outlier. Far below any real corner detector's noise
/// (etlcal's: 0.01 px on rendered boards).
pub const SIGMA_FLOOR_PX: f64 = 1e-3;

/// The pixel noise sigma of 2-D distances `d_px`, robustly: median(d) / sqrt(2 ln 2) (the
/// median of a Rayleigh distribution is sigma sqrt(2 ln 2) = 1.1774 sigma), at least
/// [`SIGMA_FLOOR_PX`]. Non-finite distances count as large. Empty input gives the floor.
pub fn robust_sigma_px(d_px: &[f64]) -> f64 {
    let mut d: Vec<f64> = d_px.iter().map(|&x| if x.is_nan() { f64::INFINITY } else { x }).collect();
    if d.is_empty() {
        return SIGMA_FLOOR_PX;
    }
    let mid = d.len() / 2;
    let (_, m, _) = d.select_nth_unstable_by(mid, f64::total_cmp);
    (*m / (2.0 * core::f64::consts::LN_2).sqrt()).max(SIGMA_FLOOR_PX)
}

/// The image of board point `b` under H (row-major, (x, y, 1) ~ H (X, Y, 1)); NaN at
/// infinity.
fn apply(h: &[[f64; 3]; 3], b: [f64; 2]) -> [f64; 2] {
    let w = h[2][0] * b[0] + h[2][1] * b[1] + h[2][2];
    [(h[0][0] * b[0] + h[0][1] * b[1] + h[0][2]) / w, (h[1][0] * b[0] + h[1][1] * b[1] + h[1][2]) / w]
}

/// Distances, px, of every pixel from its board point's image under H.
fn distances(h: &[[f64; 3]; 3], board: &[[f64; 2]], pixels: &[[f64; 2]]) -> Vec<f64> {
    board
        .iter()
        .zip(pixels)
        .map(|(b, p)| {
            let q = apply(h, *b);
            let d = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
            if d.is_finite() {
                d
            } else {
                f64::INFINITY
            }
        })
        .collect()
}

/// LMedS hypotheses drawn per view: with 6 points a sample, the chance that none of 100
/// samples is outlier-free is 1e-9 at 15 % outliers in a view (0.38 % at 40 %).
const SAMPLES: usize = 100;
/// Points per LMedS sample (more than the minimal 4: a least-squares fit through 6 spread
/// points is far better conditioned on a distorted, noisy grid).
const SAMPLE_POINTS: usize = 6;

/// Which points of one planar view agree with a robustly fitted homography (`true`:
/// inlier), by least median of squares then iterated refits (see the module docs): a
/// point is set aside when its distance exceeds max([`INIT_SIGMAS`] sigma,
/// [`INIT_FLOOR_PX`]), sigma from [`robust_sigma_px`] of the current fit's distances.
///
/// Deterministic (the samples come from a fixed-seed generator). Views with fewer than
/// 2 [`SAMPLE_POINTS`] points, with board and pixel counts that differ, or where no
/// homography can be fitted (collinear points) are returned all `true`: the solvers
/// after it then report their own precondition.
pub fn homography_inliers(board: &[[f64; 2]], pixels: &[[f64; 2]]) -> Vec<bool> {
    let n = board.len();
    let all = vec![true; n];
    if n < 2 * SAMPLE_POINTS || pixels.len() != n {
        return all;
    }
    // xorshift64*: a fixed, dependency-free sequence, so a calibration is reproducible.
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15 ^ n as u64;
    let mut next = move || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as usize
    };
    let mut best: Option<(f64, [[f64; 3]; 3])> = None;
    for _ in 0..SAMPLES {
        let mut idx = [0usize; SAMPLE_POINTS];
        for k in 0..SAMPLE_POINTS {
            let mut i = next() % n;
            while idx[..k].contains(&i) {
                i = next() % n;
            }
            idx[k] = i;
        }
        let (b, p): (Vec<[f64; 2]>, Vec<[f64; 2]>) = idx.iter().map(|&i| (board[i], pixels[i])).unzip();
        let Ok(h) = homography(&b, &p) else { continue };
        let mut d = distances(&h, board, pixels);
        let (_, med, _) = d.select_nth_unstable_by(n / 2, f64::total_cmp);
        if best.is_none_or(|(m, _)| *med < m) {
            best = Some((*med, h));
        }
    }
    let Some((_, mut h)) = best else { return all };
    let mut inliers = all.clone();
    for _ in 0..10 {
        let d = distances(&h, board, pixels);
        let limit = (INIT_SIGMAS * robust_sigma_px(&d)).max(INIT_FLOOR_PX);
        let next_inliers: Vec<bool> = d.iter().map(|&x| x <= limit).collect();
        let stable = next_inliers == inliers;
        inliers = next_inliers;
        if stable {
            break;
        }
        let (b, p): (Vec<[f64; 2]>, Vec<[f64; 2]>) =
            (0..n).filter(|&i| inliers[i]).map(|i| (board[i], pixels[i])).unzip();
        match homography(&b, &p) {
            Ok(next_h) => h = next_h,
            Err(_) => break,
        }
    }
    inliers
}
