//! The joint Levenberg-Marquardt loop: etl-core's damping logic (Marquardt's diagonal
//! scaling, Nielsen's update of lambda from the gain ratio) over the reduced steps of
//! [`super::reduced`]. A step whose damped system cannot be factored is rejected like a
//! step that raises the cost (more damping), not an error.

use etl_formats::Result;
use nalgebra::DVector;

use super::normal::{JointProblem, Normal, State};
use super::reduced::{dense_step, is_not_positive, sparse_step, SparsePattern};

/// What the loop gives: the state, the iterations and the cost before and after.
pub(super) struct Solved {
    pub state: State,
    pub iterations: usize,
    pub initial_cost: f64,
    pub cost: f64,
}

/// The damping the loop starts with: the start is each camera's converged solution, where
/// a Gauss-Newton-like step is right (etl-core's bundle adjustment starts its
/// errors-in-variables stage the same way).
const INITIAL_DAMPING: f64 = 1e-8;
/// The relative decrease of the cost below which an accepted step ends the loop.
const COST_RTOL: f64 = 1e-14;
/// The relative change of every number below which an accepted step ends the loop.
const XTOL: f64 = 1e-12;
/// The damping beyond which no step can be found (the loop ends at the current state).
const MAX_DAMPING: f64 = 1e16;

/// The predicted decrease of the cost by the damped step (dx, dy): for the cost
/// sum |r|^2, 2 d'g + d'Hd = -d'g + lambda d'diag(H)d when (H + lambda diag(H)) d = -g.
fn predicted(n: &Normal, sizes: &[usize], (dx, dy): (&DVector<f64>, &[DVector<f64>]), lambda: f64) -> f64 {
    let mut at = 0;
    let mut p = 0.0;
    for (k, &pk) in sizes.iter().enumerate() {
        let d = dx.rows(at, pk);
        p -= d.dot(&n.g[k]);
        p += lambda * (0..pk).map(|i| n.u[k][(i, i)].max(1e-12) * d[i] * d[i]).sum::<f64>();
        at += pk;
    }
    for (j, d) in dy.iter().enumerate().filter(|(_, d)| !d.is_empty()) {
        p -= d.dot(&n.gy[j]);
        p += lambda * (0..d.len()).map(|i| n.v[j][(i, i)].max(1e-12) * d[i] * d[i]).sum::<f64>();
    }
    p
}

/// Whether every number's change `dx` is below [`XTOL`] of the number (internal numbers
/// of the state `s`): the fit has reached the rounding of the data.
fn step_is_small(s: &State, dx: &DVector<f64>, sizes: &[usize]) -> bool {
    let mut at = 0;
    for (z, &p) in s.z.iter().zip(sizes) {
        if (0..p).any(|i| dx[at + i].abs() > XTOL * z[i].abs().max(1e-12)) {
            return false;
        }
        at += p;
    }
    true
}

/// Runs the loop from the problem's start, each step by the sparse path if `sparse`.
pub(super) fn solve(problem: &JointProblem<'_>, sparse: bool, max_iterations: usize) -> Result<Solved> {
    let sizes = problem.sizes();
    let mut state = problem.start();
    let mut normal = problem.normal(&state)?;
    let initial_cost = normal.cost;
    let (mut lambda, mut nu, mut iterations) = (INITIAL_DAMPING, 2.0, 0);
    let pattern = SparsePattern::new();
    while iterations < max_iterations && normal.cost > 0.0 && lambda < MAX_DAMPING {
        iterations += 1;
        let step = if sparse {
            sparse_step(&normal, &sizes, &problem.present, lambda, &pattern)
        } else {
            dense_step(&normal, &sizes, &problem.present, lambda)
        };
        // A damped system that rounding leaves indefinite (a direction the data barely
        // fix, such as a centre sliding along the axis) is a rejected step: more damping
        // makes it definite, as any other failed step.
        let (dx, dy) = match step {
            Ok(d) => d,
            Err(e) if is_not_positive(&e) => {
                lambda *= nu;
                nu *= 2.0;
                continue;
            }
            Err(e) => return Err(e),
        };
        let next = problem.moved(&state, &dx, &dy);
        let cost = problem.cost(&next).unwrap_or(f64::INFINITY);
        if !(cost < normal.cost) {
            lambda *= nu;
            nu *= 2.0;
            continue;
        }
        let rho = (normal.cost - cost) / predicted(&normal, &sizes, (&dx, &dy), lambda).max(f64::MIN_POSITIVE);
        lambda *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
        nu = 2.0;
        let decrease = normal.cost - cost;
        let done = decrease <= COST_RTOL * normal.cost || step_is_small(&state, &dx, &sizes);
        state = next;
        normal = problem.normal(&state)?;
        if done {
            break;
        }
    }
    Ok(Solved { cost: normal.cost, state, iterations, initial_cost })
}
