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
/// `d_px`: max([`OUTLIER_SIGMAS`] [`robust_sigma_px`]`(d_px)`, [`OUTLIER_FLOOR_PX`]).
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

/// Squared distance, px^2, of pixel `p` from board point `b`'s image under H.
fn distance_sq(h: &[[f64; 3]; 3], b: [f64; 2], p: [f64; 2]) -> f64 {
    let q = apply(h, b);
    (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)
}

/// Distance, px, of pixel `p` from board point `b`'s image under H (infinite where it is
/// not finite).
fn distance(h: &[[f64; 3]; 3], b: [f64; 2], p: [f64; 2]) -> f64 {
    let d = distance_sq(h, b, p).sqrt();
    if d.is_finite() {
        d
    } else {
        f64::INFINITY
    }
}

/// Distances, px, of every pixel from its board point's image under H.
fn distances(h: &[[f64; 3]; 3], board: &[[f64; 2]], pixels: &[[f64; 2]]) -> Vec<f64> {
    board.iter().zip(pixels).map(|(b, p)| distance(h, *b, *p)).collect()
}

/// The least squared distance t whose distance is not below `m` (>= 0, not NaN): the
/// square root is correctly rounded, hence monotone, so [`distance`] < m exactly when
/// [`distance_sq`] < t (both false for a non-finite square, both true for every finite
/// one when m is infinite). t is m^2 moved by the few ulps its rounding needs; 0 (no
/// square below) when m is not positive.
fn square_bound(m: f64) -> f64 {
    if !(m > 0.0) {
        return 0.0;
    }
    // Neighbouring doubles of a positive t: its bit pattern plus or minus one.
    let (down, up) = (|t: f64| f64::from_bits(t.to_bits() - 1), |t: f64| f64::from_bits(t.to_bits() + 1));
    let mut t = m * m;
    while t > 0.0 && down(t).sqrt() >= m {
        t = down(t);
    }
    while t.sqrt() < m {
        t = up(t);
    }
    t
}

/// The median distance under H (element n / 2 of the ascending order) if it is below
/// `bound` (any when `None`), else `None`; `d` is working storage.
///
/// The median is below the bound exactly when more than n / 2 distances are (they are
/// never NaN, so `<` orders them as `total_cmp` does); that count is taken on the squared
/// distances against [`square_bound`], without a square root, and only a hypothesis that
/// passes has its distances computed and selected: most LMedS samples are no better than
/// the best so far.
fn median_below(
    h: &[[f64; 3]; 3],
    board: &[[f64; 2]],
    pixels: &[[f64; 2]],
    bound: Option<f64>,
    d: &mut Vec<f64>,
) -> Option<f64> {
    let n = board.len();
    if let Some(m) = bound {
        let t = square_bound(m);
        let below = board.iter().zip(pixels).filter(|&(b, p)| distance_sq(h, *b, *p) < t).count();
        if below <= n / 2 {
            return None;
        }
    }
    d.clear();
    d.extend(board.iter().zip(pixels).map(|(b, p)| distance(h, *b, *p)));
    let (_, med, _) = d.select_nth_unstable_by(n / 2, f64::total_cmp);
    Some(*med)
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
/// 2 `SAMPLE_POINTS` points, with board and pixel counts that differ, or where no
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
    let mut d = Vec::with_capacity(n);
    for _ in 0..SAMPLES {
        let mut idx = [0usize; SAMPLE_POINTS];
        for k in 0..SAMPLE_POINTS {
            let mut i = next() % n;
            while idx[..k].contains(&i) {
                i = next() % n;
            }
            idx[k] = i;
        }
        let (b, p) = (idx.map(|i| board[i]), idx.map(|i| pixels[i]));
        let Ok(h) = homography(&b, &p) else { continue };
        if let Some(med) = median_below(&h, board, pixels, best.map(|(m, _)| m), &mut d) {
            best = Some((med, h));
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The squared test of `median_below` decides as the distances themselves would: for
    /// squares within a few ulps of every bound's square, sqrt(s) < m exactly when s < t.
    #[test]
    fn square_bound_splits_the_squares_as_the_square_root_does() {
        // The distance of a square as `distance` gives it: infinite where not finite.
        let root = |s: f64| if s.sqrt().is_finite() { s.sqrt() } else { f64::INFINITY };
        let bounds = [0.0, -1.0, f64::NAN, 1e-300, 0.1, 0.25, 0.6180339887, 1.0, 3.2, 10.0, 1e10, 1e154, f64::INFINITY];
        // And a dense sweep over the distances a screen meets, 1e-3 px to 3e3 px.
        let sweep = (0..2000).map(|k| 1e-3 * 1.0075f64.powi(k));
        for m in bounds.into_iter().chain(sweep) {
            let t = square_bound(m);
            let centre = if (m * m).is_finite() { m * m } else { f64::MAX };
            let near = (-8i64..=8).map(|k| f64::from_bits(centre.to_bits().saturating_add_signed(k)));
            for s in near.chain([0.0, f64::INFINITY, f64::NAN]) {
                assert_eq!(s < t, root(s) < m, "m {m:e}, s {s:e}, t {t:e}");
            }
        }
    }
}
