//! [`stereo_calibrate`]: the pair's inputs checked, each camera by Zhang's method, the
//! start, the solve and the result (module docs of [`super`]).

use etl_core::model::rotation::{mat_vec, matrix_to_rodrigues, rodrigues_to_matrix};
use etl_formats::calibration::Outlier;
use etl_formats::{Error, Result};

use super::covariance::with_intrinsics;
use super::init::{relative_pose_median, relative_poses, rotation_angle_between};
use super::options::{StereoMode, StereoOptions, StereoPair, MIN_JOINT_PAIRS};
use super::problem::{PairPoints, StereoProblem};
use super::result::StereoResult;
use super::solve::{distances_at, solve, Solved};
use crate::zhang::{free_numbers, in_list, zhang_with, PlanarView, Shared, ZhangOptions, ZhangResult};

/// The name of a side in messages.
const SIDES: [&str; 2] = ["left", "right"];

/// One camera's Zhang calibration from the views it saw, with their pairs' indices.
/// Errors: fewer than 3 views (naming the side), Zhang's own (its `views[k]` renamed
/// `{side}[pair]`).
fn camera(
    pairs: &[StereoPair],
    side: usize,
    image_size: [u32; 2],
    options: &ZhangOptions,
) -> Result<(ZhangResult, Vec<usize>)> {
    let view = |p: &StereoPair| if side == 0 { p.left.clone() } else { p.right.clone() };
    let (index, views): (Vec<usize>, Vec<PlanarView>) =
        pairs.iter().enumerate().filter_map(|(j, p)| view(p).map(|v| (j, v))).unzip();
    let name = SIDES[side];
    if views.len() < 3 {
        return Err(Error::invalid(
            name,
            format!(
                "the {name} camera sees the board in {} of {} pairs; each camera needs at least 3 views",
                views.len(),
                pairs.len()
            ),
        ));
    }
    let z = zhang_with(&views, image_size, options).map_err(|e| in_list(e, name, Some(&index)))?;
    Ok((z, index))
}

/// The points of view `k` of a camera's Zhang result `z` that it kept (its outliers
/// left out).
fn inliers(view: &PlanarView, z: &ZhangResult, k: usize) -> PlanarView {
    let out: Vec<usize> = z.outliers.iter().filter(|o| o.view == k).map(|o| o.point).collect();
    let keep = |i: &usize| !out.contains(i);
    let (board_mm, pixels) = (0..view.pixels.len()).filter(keep).map(|i| (view.board_mm[i], view.pixels[i])).unzip();
    PlanarView { board_mm, pixels }
}

/// The largest angle, rad, by which a pair's own relative rotation may differ from the
/// median before the pair is taken for one whose board the two cameras numbered
/// differently (60 degrees: noise and a bad pose stay far below it; a board numbered from
/// another corner in one image turns the pair's rotation by 90 or 180 degrees).
const MAX_PAIR_ROTATION_RAD: f64 = std::f64::consts::FRAC_PI_3;

/// Refuses pairs whose own relative rotation lies more than [`MAX_PAIR_ROTATION_RAD`]
/// from the median `rt`: the two cameras numbered the board's corners from different
/// corners (a checkerboard whose colouring is symmetric under a half turn), which would
/// otherwise bias R, T silently. `paired` holds each pair's input index first.
fn check_board_numbering(own: &[[f64; 6]], rt: &[f64; 6], paired: &[(usize, usize, usize)]) -> Result<()> {
    for (p, &(j, _, _)) in own.iter().zip(paired) {
        let angle = rotation_angle_between([p[0], p[1], p[2]], [rt[0], rt[1], rt[2]]);
        if angle > MAX_PAIR_ROTATION_RAD {
            return Err(Error::invalid(
                format!("pairs[{j}]"),
                format!(
                    "pair {j}: the two cameras' board poses disagree by {:.0} degrees with the other pairs: the board's \
                     corners were numbered from different corners (use a checkerboard whose colouring is not symmetric \
                     under a half turn, cols + rows odd, or a ChArUco board), or the pair is not synchronised",
                    angle.to_degrees()
                ),
            ));
        }
    }
    Ok(())
}

/// Calibrates a fixed-focus pair from synchronised views (module docs of [`super`]):
/// each camera by Zhang's method on every view it saw (`image_size`: left, right, px),
/// then R, T (and in [`StereoMode::Joint`] both cameras' intrinsics) over the pairs seen
/// by both, with Zhang's outliers left out.
///
/// Errors (one line, naming the input): a camera that sees the board in fewer than 3
/// views (`"left"`, `"right"`); fewer pairs seen by both than the mode needs (`"pairs"`:
/// 1, or [`MIN_JOINT_PAIRS`]); a pair whose relative rotation lies more than 60 degrees
/// from the others' median (`"pairs[j]"`: the board numbered differently in its two
/// images); an OpenCV flag with the paper family; Zhang's errors; a rank-deficient solve.
///
/// ```
/// use etl_calib::stereo::{stereo_calibrate, StereoMode, StereoOptions, StereoPair};
/// use etl_calib::zhang::{PlanarView, ZhangOptions};
/// // Two views only: refused before any solve, naming the camera.
/// let v = PlanarView { board_mm: vec![[0.0, 0.0]; 4], pixels: vec![[0.0, 0.0]; 4] };
/// let pairs = vec![StereoPair { left: Some(v.clone()), right: Some(v) }; 2];
/// let options = StereoOptions { zhang: ZhangOptions::default(), mode: StereoMode::FixedIntrinsics };
/// let err = stereo_calibrate(&pairs, [[640, 480]; 2], &options).unwrap_err();
/// assert!(err.to_string().contains("the left camera sees the board in 2 of 2 pairs"));
/// ```
pub fn stereo_calibrate(
    pairs: &[StereoPair],
    image_size: [[u32; 2]; 2],
    options: &StereoOptions,
) -> Result<StereoResult> {
    options.zhang.flags.check(options.zhang.model).map_err(Error::Core)?;
    let (zl, left_index) = camera(pairs, 0, image_size[0], &options.zhang)?;
    let (zr, right_index) = camera(pairs, 1, image_size[1], &options.zhang)?;
    let paired: Vec<(usize, usize, usize)> = (0..pairs.len())
        .filter_map(|j| Some((j, left_index.binary_search(&j).ok()?, right_index.binary_search(&j).ok()?)))
        .collect();
    let min = if options.mode == StereoMode::Joint { MIN_JOINT_PAIRS } else { 1 };
    if paired.len() < min {
        return Err(Error::invalid(
            "pairs",
            format!(
                "both cameras see the board in {} of {} pairs; the {} mode needs at least {min}",
                paired.len(),
                pairs.len(),
                if options.mode == StereoMode::Joint { "joint" } else { "fixed-intrinsics" }
            ),
        ));
    }
    let points: Vec<PairPoints> = paired
        .iter()
        .map(|&(j, kl, kr)| PairPoints {
            left: pairs[j].left.as_ref().map(|v| inliers(v, &zl, kl)).unwrap_or_default(),
            right: pairs[j].right.as_ref().map(|v| inliers(v, &zr, kr)).unwrap_or_default(),
        })
        .collect();
    let lp: Vec<_> = paired.iter().map(|&(_, kl, _)| zl.poses[kl]).collect();
    let rp: Vec<_> = paired.iter().map(|&(_, _, kr)| zr.poses[kr]).collect();
    let rt = relative_pose_median(&lp, &rp);
    check_board_numbering(&relative_poses(&lp, &rp), &rt, &paired)?;
    let free = match options.mode {
        StereoMode::FixedIntrinsics => vec![],
        StereoMode::Joint => free_numbers(&options.zhang),
    };
    let (sl, sr) = (zl.shared(), zr.shared());
    let x0: Vec<f64> =
        rt.iter().chain(free.iter().map(|&i| &sl[i])).chain(free.iter().map(|&i| &sr[i])).copied().collect();
    let mut problem = StereoProblem {
        pairs: &points,
        model: options.zhang.model,
        left: sl,
        right: sr,
        left_free: &free,
        right_free: &free,
    };
    let start: Vec<[f64; 6]> = lp.iter().map(|(om, t)| [om[0], om[1], om[2], t[0], t[1], t[2]]).collect();
    let mut solved = solve(&mut problem, &x0, &start)?;
    let d = distances_at(&problem, &solved);
    if options.mode == StereoMode::FixedIntrinsics {
        let free = free_numbers(&options.zhang);
        let x: Vec<f64> =
            solved.x.iter().chain(free.iter().map(|&i| &sl[i])).chain(free.iter().map(|&i| &sr[i])).copied().collect();
        let mut joint = StereoProblem { left_free: &free, right_free: &free, ..problem };
        let cov = with_intrinsics(&mut joint, (&x, &solved.poses), &solved.covariance, (&zl, &zr, &free))?;
        for (row, c) in solved.covariance.iter_mut().zip(cov) {
            row[..6].copy_from_slice(&c);
        }
    }
    let used: Vec<usize> = paired.iter().map(|p| p.0).collect();
    let cameras = match options.mode {
        StereoMode::FixedIntrinsics => [(zl, left_index), (zr, right_index)],
        StereoMode::Joint => {
            let (_, _, l, r) =
                problem.unpack(&core::array::from_fn::<f64, 24, _>(|k| solved.x.get(k).copied().unwrap_or(0.0)));
            let joint = |side: usize, base: &ZhangResult, z: Shared| {
                let index: Vec<usize> = paired.iter().map(|p| if side == 0 { p.1 } else { p.2 }).collect();
                joint_camera(base, z, JointSide { side, free: &free, solved: &solved, distances: &d, index: &index })
            };
            [(joint(0, &zl, l), used.clone()), (joint(1, &zr, r), used.clone())]
        }
    };
    Ok(summarise(cameras, used, &solved, &d, options.mode))
}

/// What [`joint_camera`] needs of the joint solve about one side.
struct JointSide<'a> {
    side: usize,
    free: &'a [usize],
    solved: &'a Solved,
    distances: &'a [[Vec<f64>; 2]],
    /// The Zhang view index of each pair used.
    index: &'a [usize],
}

/// One camera of the joint solve as a [`ZhangResult`]: its shared numbers `z`, their
/// standard deviations from the joint covariance (0 for a held one), its RMS over the
/// pairs, its board poses (the right camera's composed: R R_j, R t_j + T), Zhang's
/// outliers of the pairs used (their `view` the pair's position among them).
fn joint_camera(base: &ZhangResult, z: Shared, s: JointSide<'_>) -> ZhangResult {
    let first = 6 + s.side * s.free.len();
    let count = 4 + base.options.model.coefficient_count();
    let mut std = vec![0.0; count];
    for (k, &i) in s.free.iter().enumerate() {
        if let Some(slot) = std.get_mut(i) {
            *slot = s.solved.covariance[first + k][first + k].max(0.0).sqrt();
        }
    }
    let rms = |d: &[f64]| (d.iter().map(|x| x * x).sum::<f64>() / d.len().max(1) as f64).sqrt();
    let all: Vec<f64> = s.distances.iter().flat_map(|p| p[s.side].iter().copied()).collect();
    let (om, t) = ([s.solved.x[0], s.solved.x[1], s.solved.x[2]], [s.solved.x[3], s.solved.x[4], s.solved.x[5]]);
    let r = rodrigues_to_matrix(om);
    let poses = s
        .solved
        .poses
        .iter()
        .map(|y| {
            let (omj, tj) = ([y[0], y[1], y[2]], [y[3], y[4], y[5]]);
            if s.side == 0 {
                return (omj, tj);
            }
            let rj = rodrigues_to_matrix(omj);
            let rr: [[f64; 3]; 3] =
                core::array::from_fn(|i| core::array::from_fn(|j| (0..3).map(|k| r[i][k] * rj[k][j]).sum()));
            let q = mat_vec(&r, tj);
            (matrix_to_rodrigues(&rr), [q[0] + t[0], q[1] + t[1], q[2] + t[2]])
        })
        .collect();
    let outliers = base
        .outliers
        .iter()
        .filter_map(|o| Some(Outlier { view: s.index.iter().position(|&k| k == o.view)?, ..*o }))
        .collect();
    let mut coefficients = base.coefficients;
    coefficients.copy_from_slice(&z[4..]);
    ZhangResult {
        fx: z[0],
        fy: z[1],
        u0: z[2],
        v0: z[3],
        options: base.options,
        coefficients,
        std,
        rms_px: rms(&all),
        per_view_rms_px: s.distances.iter().map(|p| rms(&p[s.side])).collect(),
        poses,
        iterations: s.solved.iterations,
        views_used: s.index.len(),
        outliers,
        uncertainty: None,
    }
}

/// The result from both cameras (with their views' pair indices), the pairs used, the
/// solve and its distances.
fn summarise(
    [(left, left_pairs), (right, right_pairs)]: [(ZhangResult, Vec<usize>); 2],
    pairs_used: Vec<usize>,
    solved: &Solved,
    d: &[[Vec<f64>; 2]],
    mode: StereoMode,
) -> StereoResult {
    let ss = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>();
    let (total, n) = d.iter().fold((0.0, 0usize), |(s, n), p| (s + ss(&p[0]) + ss(&p[1]), n + p[0].len() + p[1].len()));
    let per_view_rms_px = d.iter().map(|p| [0, 1].map(|c| (ss(&p[c]) / p[c].len().max(1) as f64).sqrt())).collect();
    StereoResult {
        left,
        right,
        left_pairs,
        right_pairs,
        rotation_rodrigues: [solved.x[0], solved.x[1], solved.x[2]],
        translation_mm: [solved.x[3], solved.x[4], solved.x[5]],
        covariance: core::array::from_fn(|i| core::array::from_fn(|j| solved.covariance[i][j])),
        rms_px: (total / n.max(1) as f64).sqrt(),
        per_view_rms_px,
        pairs_used,
        poses: solved.poses.iter().map(|y| ([y[0], y[1], y[2]], [y[3], y[4], y[5]])).collect(),
        mode,
        iterations: solved.iterations,
    }
}
