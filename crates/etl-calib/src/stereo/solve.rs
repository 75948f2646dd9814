//! The Levenberg-Marquardt solve of [`super::problem::StereoProblem`] for its number of
//! shared numbers, and the covariance of the result.

use etl_core::lm::{solve_blocks, BlockScratch, Options, StopReason};
use etl_formats::{Error, Result};

use super::problem::StereoProblem;

/// What one solve gives: the shared numbers x (om, T, the free intrinsics), their
/// covariance with OpenCV's scaling, the pairs' left poses and the iterations.
#[derive(Debug, Clone)]
pub(super) struct Solved {
    pub x: Vec<f64>,
    pub covariance: Vec<Vec<f64>>,
    pub poses: Vec<[f64; 6]>,
    pub iterations: usize,
}

/// The solve for `N` shared numbers from `x0` and the pairs' starting poses.
fn solve_n<const N: usize>(problem: &mut StereoProblem<'_>, x0: &[f64], poses: &[[f64; 6]]) -> Result<Solved> {
    let x0: [f64; N] = core::array::from_fn(|k| x0.get(k).copied().unwrap_or(0.0));
    let mut scratch: Vec<BlockScratch<N, 6>> = poses.iter().map(|&p| BlockScratch::starting_at(p)).collect();
    let opts = Options { max_iterations: 200, ftol: 1e-14, xtol: 1e-14, gtol: 1e-14, ..Options::default() };
    let r = solve_blocks(problem, x0, &opts, &mut scratch)?;
    if r.stop == StopReason::RankDeficient {
        return Err(Error::Core(etl_core::Error::Degenerate {
            what: "the stereo refinement is rank deficient (too few pairs, or pairs too alike)",
        }));
    }
    // OpenCV's degrees of freedom: every pose number is a parameter too.
    let dof = r.residuals.saturating_sub(N + 6 * poses.len()).max(1) as f64;
    let scale = if r.sigma2 > 0.0 { r.cost / dof / r.sigma2 } else { 0.0 };
    Ok(Solved {
        x: r.x.to_vec(),
        covariance: r.covariance.iter().map(|row| row.iter().map(|v| v * scale).collect()).collect(),
        poses: scratch.iter().map(|b| *b.y()).collect(),
        iterations: r.iterations,
    })
}

/// Solves `problem` from the shared numbers `x0` (6 + both cameras' free numbers) and the
/// pairs' starting left poses. Errors: a count of shared numbers no mode gives (6 with the
/// intrinsics held; 18, 20, 22, 24 with both cameras' free), a rank-deficient or failed
/// solve.
pub(super) fn solve(problem: &mut StereoProblem<'_>, x0: &[f64], poses: &[[f64; 6]]) -> Result<Solved> {
    match x0.len() {
        6 => solve_n::<6>(problem, x0, poses),
        18 => solve_n::<18>(problem, x0, poses),
        20 => solve_n::<20>(problem, x0, poses),
        22 => solve_n::<22>(problem, x0, poses),
        24 => solve_n::<24>(problem, x0, poses),
        n => Err(Error::invalid("options", format!("the stereo refinement: {n} free numbers"))),
    }
}

/// [`super::problem::distances`] at a solve's numbers.
pub(super) fn distances_at(problem: &StereoProblem<'_>, s: &Solved) -> Vec<[Vec<f64>; 2]> {
    let x: [f64; 24] = core::array::from_fn(|k| s.x.get(k).copied().unwrap_or(0.0));
    super::problem::distances(problem, &x, &s.poses)
}
