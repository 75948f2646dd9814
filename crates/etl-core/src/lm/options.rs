//! Solver options and stop reasons.

/// Options of [`super::solve`] and [`super::solve_blocks`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Cap on the number of iterations (Jacobian evaluations).
    pub max_iterations: usize,
    /// Cap on the number of cost evaluations (trial steps included).
    pub max_evaluations: usize,
    /// Stop when both the actual and the predicted relative reduction of the cost are
    /// below `ftol` (MINPACK's ftol).
    pub ftol: f64,
    /// Stop when the (scaled) step is below `xtol` times the (scaled) parameter norm.
    pub xtol: f64,
    /// Stop when the largest cosine between the residual vector and a Jacobian column is
    /// below `gtol` (MINPACK's gtol).
    pub gtol: f64,
    /// Initial trust radius as a multiple of the scaled norm of the start (MINPACK's
    /// `factor`; dense solver), or the initial relative damping (block solver uses
    /// `initial_damping`).
    pub step_factor: f64,
    /// Initial relative (Marquardt) damping of the block solver.
    pub initial_damping: f64,
    /// Relative singular-value threshold below which a direction counts as unidentified
    /// (rank deficiency), relative to the largest singular value of the scaled Jacobian.
    pub rank_tolerance: f64,
    /// How the dense solver reduces the Jacobian rows (the block solver always forms the
    /// normal equations).
    pub accumulation: Accumulation,
}

/// How [`super::solve`] folds the streamed rows into the triangular factor R.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Accumulation {
    /// Givens rotations row by row: the conditioning of J itself (default; the choice for
    /// hard problems such as NIST StRD's).
    Qr,
    /// J^T J and J^T r, then a scaled Cholesky factorisation: about 3 times fewer
    /// operations per row and vectorisable, at the price of squaring the condition number
    /// of the scaled Jacobian. For well-posed problems with many residuals (bundle
    /// adjustment).
    NormalEquations,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            max_iterations: 200,
            max_evaluations: 2000,
            ftol: 1e-15,
            xtol: 1e-15,
            gtol: 1e-15,
            step_factor: 1.0,
            initial_damping: 1e-3,
            rank_tolerance: 1e-13,
            accumulation: Accumulation::Qr,
        }
    }
}

/// Why the solver stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// The relative cost reduction (actual and predicted) fell below `ftol`, or the cost
    /// reached zero.
    CostTolerance,
    /// The scaled step fell below `xtol` times the scaled parameter norm.
    StepTolerance,
    /// The residual vector is orthogonal to the Jacobian columns within `gtol`.
    GradientTolerance,
    /// `max_iterations` or `max_evaluations` reached.
    MaxIterations,
    /// The Jacobian lost rank: some parameter combination is not determined by the data.
    /// The report's `rank` says how many directions are; the estimate is the
    /// minimum-norm one in the scaled parameters and its covariance is not meaningful.
    RankDeficient,
    /// No trial step reduces the cost although none of the tolerances is met (the
    /// trust region collapsed): the cost is at a minimum to machine precision.
    NoProgress,
}

impl StopReason {
    /// True for the reasons that mean "converged".
    pub fn converged(&self) -> bool {
        matches!(
            self,
            StopReason::CostTolerance
                | StopReason::StepTolerance
                | StopReason::GradientTolerance
                | StopReason::NoProgress
        )
    }
}

/// What one trial step of either solver showed, each test measured in that solver's own
/// terms (the dense solver's trust radius, the block solver's damped step).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct TrialOutcome {
    /// The actual and the predicted relative reduction of the cost are both within `ftol`.
    pub cost_converged: bool,
    /// The scaled step is within `xtol` of the scaled parameters.
    pub step_converged: bool,
    /// No smaller step can be tried (read only when the step was rejected).
    pub stalled: bool,
    /// The step was accepted.
    pub accepted: bool,
}

/// The stop test shared by [`super::solve`] and [`super::solve_blocks`], in MINPACK's
/// order of precedence: cost tolerance, step tolerance, the evaluation cap, no progress
/// (a rejected step that cannot shrink further), then the iteration cap after an accepted
/// step. `evaluations` and `iterations` are the counts after this trial (an accepted step
/// counted). `None`: go on.
pub(crate) fn stop_reason(
    trial: &TrialOutcome,
    evaluations: usize,
    iterations: usize,
    options: &Options,
) -> Option<StopReason> {
    if trial.cost_converged {
        Some(StopReason::CostTolerance)
    } else if trial.step_converged {
        Some(StopReason::StepTolerance)
    } else if evaluations >= options.max_evaluations {
        Some(StopReason::MaxIterations)
    } else if !trial.accepted && trial.stalled {
        Some(StopReason::NoProgress)
    } else if trial.accepted && iterations >= options.max_iterations {
        Some(StopReason::MaxIterations)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trial(cost: bool, step: bool, stalled: bool, accepted: bool) -> TrialOutcome {
        TrialOutcome { cost_converged: cost, step_converged: step, stalled, accepted }
    }

    #[test]
    fn stop_reasons_follow_minpack_precedence() {
        let o = Options { max_iterations: 5, max_evaluations: 10, ..Options::default() };
        assert_eq!(stop_reason(&trial(true, true, true, true), 10, 5, &o), Some(StopReason::CostTolerance));
        assert_eq!(stop_reason(&trial(false, true, true, false), 10, 5, &o), Some(StopReason::StepTolerance));
        assert_eq!(stop_reason(&trial(false, false, true, false), 10, 1, &o), Some(StopReason::MaxIterations));
        assert_eq!(stop_reason(&trial(false, false, true, false), 9, 1, &o), Some(StopReason::NoProgress));
        // A stalled flag means nothing once the step was accepted.
        assert_eq!(stop_reason(&trial(false, false, true, true), 9, 4, &o), None);
        assert_eq!(stop_reason(&trial(false, false, false, true), 9, 5, &o), Some(StopReason::MaxIterations));
        // The iteration cap counts accepted steps only.
        assert_eq!(stop_reason(&trial(false, false, false, false), 9, 5, &o), None);
    }
}
