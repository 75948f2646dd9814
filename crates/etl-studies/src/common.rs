//! What every study shares: seeded Monte Carlo trials in parallel (rayon) with a progress
//! bar (indicatif), the errors of an estimate against the truth (the paper's measure and
//! the errors users feel), the full calibration of one simulated data set with both
//! estimators, statistics, plots (drawn by etl-report) and markdown tables.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use etl_core::calib::jacobian::to_params;
use etl_core::calib::params::{Layout, MAX_PARAMS};
use etl_core::calib::{
    bundle_adjust, bundle_adjust_scratch, initialise, initialise_model, BundleAdjustOptions, BundleAdjustReport,
    Estimator, View, ViewScratch, A0,
};
use etl_core::model::{CameraModel, OpenCvFlags};
use etl_core::pnp::{displacement_mm, solve_pnp};
use etl_core::progress::{NoProgress, Progress};
use etl_formats::ThermalRef;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use etl_formats::observations::Observations;
use etl_formats::output::write_bytes_set;
use etl_formats::{Error, Result};
pub use etl_report::figure::{render_figure, write_figure, Chart, Figure, Series};
use etl_sim::simulate::{focused_z_mm, observe_board, NoiseModel};

/// The most Monte Carlo trials a study runs (per level): each trial keeps its result in
/// memory (up to a few hundred bytes, a few ms to seconds of CPU), so 100 000 trials stay
/// within tens of MB while 10^8 would need about 24 GB. Callers (the CLI's `--trials`,
/// Python's `study(trials=)`) refuse more.
pub const MAX_TRIALS: usize = 100_000;

/// What a Cramer-Rao study of a rig reports beside its numbers (both rigs' studies): how
/// many trials calibrated, which failed, and how many corners the rig has.
#[derive(Debug, Clone)]
pub struct TrialCounts {
    /// Trials that calibrated, per estimator (paper rig) or family (strong rig).
    pub trials: [usize; 2],
    /// Failed trials.
    pub failures: Vec<String>,
    /// Corners of the rig.
    pub points: usize,
}

impl TrialCounts {
    /// How uncertain a std observed over the first estimator's trials is, % (for Gaussian
    /// estimates 1 / sqrt(2 (n - 1)) relative): what the markdown tells the reader an
    /// efficiency is good to.
    pub fn std_uncertainty_pct(&self) -> f64 {
        100.0 / (2.0 * (self.trials[0].max(2) - 1) as f64).sqrt()
    }

    /// The JSON keys the Cramer-Rao studies share: these counts, the pixel noise
    /// `sigma_px`, the parameter rows and the smallest efficiency with its check against
    /// 0.9; `own` adds the study's own keys (an object).
    pub fn efficiency_json(
        &self,
        sigma_px: f64,
        parameters: &impl serde::Serialize,
        min_efficiency: f64,
        own: serde_json::Value,
    ) -> serde_json::Value {
        let mut j = serde_json::json!({
            "points": self.points,
            "sigma_px": sigma_px,
            "trials": self.trials,
            "failures": self.failures,
            "parameters": parameters,
            "min_efficiency": min_efficiency,
            "checks": {"efficiency_at_least_0_9": min_efficiency >= 0.9},
        });
        if let (Some(shared), serde_json::Value::Object(own)) = (j.as_object_mut(), own) {
            shared.extend(own);
        }
        j
    }
}

/// How a study runs: Monte Carlo trials, the base seed, where its progress goes.
#[derive(Clone, Copy)]
pub struct StudyOptions<'p> {
    /// Trials (per level, for studies with levels); 0: the study's default.
    pub trials: usize,
    /// Base seed; trial `i` of every level uses the same derived seed (common random
    /// numbers make the curves over the levels smooth).
    pub seed: u64,
    /// Where the trials' progress is reported.
    pub progress: &'p dyn Progress,
    /// Whether the outputs carry the run's wall time (a study's "seconds"). The front ends
    /// set it false when `SOURCE_DATE_EPOCH` is set, so that two runs write the same bytes.
    pub wall_time: bool,
}

impl Default for StudyOptions<'_> {
    fn default() -> Self {
        StudyOptions { trials: 0, seed: 1, progress: &NoProgress, wall_time: true }
    }
}

impl std::fmt::Debug for StudyOptions<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StudyOptions").field("trials", &self.trials).field("seed", &self.seed).finish_non_exhaustive()
    }
}

impl StudyOptions<'_> {
    /// The trial count, or `default` when none was asked for.
    pub fn trials_or(&self, default: usize) -> usize {
        if self.trials == 0 {
            default
        } else {
            self.trials
        }
    }

    /// The seed of trial `trial` (independent of the level).
    pub fn trial_seed(&self, trial: usize) -> u64 {
        self.seed.wrapping_mul(0x9e37_79b9_7f4a_7c15).wrapping_add(1_000_003 * trial as u64 + 17)
    }
}

/// Runs `f` on every job in parallel (rayon), reporting to `progress` under `label`. Each
/// job's own result is kept (a failed calibration is a result too).
pub fn run_jobs<J, T, F>(label: &str, jobs: &[J], progress: &dyn Progress, f: F) -> Vec<Result<T>>
where
    J: Sync,
    T: Send,
    F: Fn(&J) -> Result<T> + Sync + Send,
{
    progress.start(jobs.len(), label);
    let out = jobs
        .par_iter()
        .map(|j| {
            let r = f(j);
            progress.advance(1);
            r
        })
        .collect();
    progress.finish();
    out
}

/// Max relative curve errors of fx(E), fy(E) of `est` against `truth` over [lo, hi] mA
/// (1 mA steps, both ends included).
pub fn curve_errors(est: &CameraModel, truth: &CameraModel, range_ma: [f64; 2]) -> (f64, f64) {
    let (mut ex, mut ey) = (0.0f64, 0.0f64);
    let steps = ((range_ma[1] - range_ma[0]).max(0.0)).ceil() as usize;
    for k in 0..=steps {
        let e = (range_ma[0] + k as f64).min(range_ma[1]);
        let (fx, fy) = truth.focal_lengths(e);
        let (gx, gy) = est.focal_lengths(e);
        ex = ex.max(((gx - fx) / fx).abs());
        ey = ey.max(((gy - fy) / fy).abs());
    }
    (ex, ey)
}

/// The range of the paper rig's currents, mA: where curve errors are measured.
pub const RIG_RANGE_MA: [f64; 2] = [80.0, 225.0];

/// Names of the paper's coefficient measures (Fig. 6), in [`ModelErrors::kf_rel`] order.
pub const KF_NAMES: [&str; 6] = ["kf1x", "kf2x", "kf3x", "kf1y", "kf2y", "kf3y"];

/// Errors of an estimated model against the truth.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct ModelErrors {
    /// Relative errors of kf1x, kf2x, kf3x, kf1y, kf2y, kf3y (the paper's Fig. 6 measure).
    pub kf_rel: [f64; 6],
    /// |om - om_true| / |om_true|.
    pub om_rel: f64,
    /// |T - T_true| / |T_true|.
    pub t_rel: f64,
    /// Max relative error of fx(E) over [`RIG_RANGE_MA`].
    pub fx_curve_max_rel: f64,
    /// Max relative error of fy(E) over [`RIG_RANGE_MA`].
    pub fy_curve_max_rel: f64,
    /// Distance of the principal point from the truth, px.
    pub principal_point_px: f64,
}

fn norm3(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// The errors of `est` against `truth` (see [`ModelErrors`]).
pub fn model_errors(est: &CameraModel, truth: &CameraModel) -> ModelErrors {
    let rel = |a: f64, b: f64| ((a - b) / b).abs();
    let d = |a: [f64; 3], b: [f64; 3]| norm3([a[0] - b[0], a[1] - b[1], a[2] - b[2]]) / norm3(b);
    let (fx, fy) = curve_errors(est, truth, RIG_RANGE_MA);
    ModelErrors {
        kf_rel: [
            rel(est.kf_x.coefficients()[1], truth.kf_x.coefficients()[1]),
            rel(est.kf_x.coefficients()[2], truth.kf_x.coefficients()[2]),
            rel(est.kf_x.coefficients()[3], truth.kf_x.coefficients()[3]),
            rel(est.kf_y.coefficients()[1], truth.kf_y.coefficients()[1]),
            rel(est.kf_y.coefficients()[2], truth.kf_y.coefficients()[2]),
            rel(est.kf_y.coefficients()[3], truth.kf_y.coefficients()[3]),
        ],
        om_rel: d(est.rotation_rodrigues, truth.rotation_rodrigues),
        t_rel: d(est.translation_mm, truth.translation_mm),
        fx_curve_max_rel: fx,
        fy_curve_max_rel: fy,
        principal_point_px: (est.principal_point[0] - truth.principal_point[0])
            .hypot(est.principal_point[1] - truth.principal_point[1]),
    }
}

/// Board observations (board X, Y; pixel) before and after a 2 mm stage move.
pub type MoveObservations = (Vec<([f64; 2], [f64; 2])>, Vec<([f64; 2], [f64; 2])>);

/// Length of the simulated stage move, mm.
pub const MOVE_MM: f64 = 2.0;

/// The paper board seen through `truth` at the stage position in focus at `e_ma` and
/// [`MOVE_MM`] further, with the corner and pixel noise of `noise`.
pub fn move_observations(truth: &CameraModel, e_ma: f64, noise: &NoiseModel, rng: &mut ChaCha8Rng) -> MoveObservations {
    let z = focused_z_mm(e_ma);
    let a = observe_board(truth, z, e_ma, noise, rng);
    let b = observe_board(truth, z + MOVE_MM, e_ma, noise, rng);
    (a, b)
}

/// |measured - true| length of the move of `obs` by plane-based PnP through `model` at
/// `e_ma`, um (the paper's section 5.2.3 measurement).
///
/// Errors: those of [`solve_pnp`] (e.g. fewer than 4 visible corners).
pub fn pnp_move_error_um(model: &CameraModel, e_ma: f64, obs: &MoveObservations) -> Result<f64> {
    let pose = |o: &[([f64; 2], [f64; 2])]| {
        let board: Vec<[f64; 3]> = o.iter().map(|(w, _)| [w[0], w[1], 0.0]).collect();
        let px: Vec<[f64; 2]> = o.iter().map(|(_, p)| *p).collect();
        solve_pnp(model, e_ma, &board, &px)
    };
    let d = displacement_mm(&pose(&obs.0)?, &pose(&obs.1)?);
    Ok(1000.0 * (norm3(d) - MOVE_MM).abs())
}

/// One data set calibrated by the paper's bundle adjustment and by errors-in-variables.
#[derive(Debug, Clone)]
pub struct PairFit {
    /// The paper's estimator (Eq. 24) from the linear initialisation.
    pub paper: BundleAdjustReport,
    /// Errors-in-variables.
    pub eiv: BundleAdjustReport,
}

/// Initial damping of the errors-in-variables stage in the studies. The block solver's
/// default (1e-3, relative) is made for starts far from the minimum; started from the plain
/// solution it costs about 17 iterations where 1e-8 takes about 6, and the estimates agree
/// to about 1e-5 px of focal length (measured over the paper rig; their spread is ~1 px).
pub const EIV_INITIAL_DAMPING: f64 = 1e-8;

/// The views of `obs` (E_com through the paper's thermal surface) as core points.
fn core_views(obs: &Observations) -> Result<(Vec<Vec<etl_core::calib::Point>>, Vec<f64>)> {
    obs.validate()?;
    Ok((obs.core_points(), obs.e_com_ma(Some(&ThermalRef::paper()))?))
}

/// The paper's calibration of `obs` with `a0`: the linear initialisation (RAC, focal
/// polynomial, distortion) then the bundle adjustment of Eq. 24, with the options of
/// `etl_calib::pipeline::calibrate` (the per-view summaries it adds for reports are skipped).
pub fn calibrate_paper(obs: &Observations, a0: &A0) -> Result<BundleAdjustReport> {
    calibrate_paper_capped(obs, a0, BundleAdjustOptions::default().lm.max_iterations)
}

/// [`calibrate_paper`] with the bundle adjustment stopped after at most `max_iterations`
/// LM iterations (to see how far it is from its minimum then).
pub fn calibrate_paper_capped(obs: &Observations, a0: &A0, max_iterations: usize) -> Result<BundleAdjustReport> {
    let (pts, e_com) = core_views(obs)?;
    let views: Vec<View<'_>> = pts.iter().zip(&e_com).map(|(p, &e)| View { e_com_ma: e, points: p }).collect();
    let initial = initialise(&views, a0)?;
    let mut scratch = vec![ViewScratch::ZERO; bundle_adjust_scratch(views.len())];
    let mut options = BundleAdjustOptions::default();
    options.lm.max_iterations = max_iterations;
    Ok(bundle_adjust(&views, &initial, &options, &mut scratch)?)
}

/// The calibration of `obs` with `a0` in `layout` (distortion family, focal degree; the
/// numbers OpenCV's `flags` hold held): the linear initialisation then the paper's
/// bundle adjustment (Eq. 24), as [`calibrate_paper`] for the paper's layout.
pub fn calibrate_layout(obs: &Observations, a0: &A0, layout: Layout, flags: OpenCvFlags) -> Result<BundleAdjustReport> {
    let (pts, e_com) = core_views(obs)?;
    let views: Vec<View<'_>> = pts.iter().zip(&e_com).map(|(p, &e)| View { e_com_ma: e, points: p }).collect();
    let initial = initialise_model(&views, a0, layout, flags)?;
    let mut scratch = vec![ViewScratch::ZERO; bundle_adjust_scratch(views.len())];
    let options = BundleAdjustOptions { hold: layout.opencv_mask(flags)?, ..BundleAdjustOptions::default() };
    Ok(bundle_adjust(&views, &initial, &options, &mut scratch)?)
}

/// Calibrates `obs` with `a0` by the paper's estimator ([`calibrate_paper`]), then by
/// errors-in-variables with priors `sigma_z_mm`, `sigma_e_ma` (pixel noise estimated from
/// the plain solution).
///
/// Both are full calibrations from the linear initialisation: the errors-in-variables
/// bundle adjustment always starts with the plain solve, so it is started here from the
/// plain result of the same data (its plain stage then converges at once) instead of
/// repeating that solve, with [`EIV_INITIAL_DAMPING`].
pub fn calibrate_pair(obs: &Observations, a0: &A0, sigma_z_mm: f64, sigma_e_ma: f64) -> Result<PairFit> {
    let (pts, e_com) = core_views(obs)?;
    let views: Vec<View<'_>> = pts.iter().zip(&e_com).map(|(p, &e)| View { e_com_ma: e, points: p }).collect();
    let initial = initialise(&views, a0)?;
    let mut scratch = vec![ViewScratch::ZERO; bundle_adjust_scratch(views.len())];
    let paper = bundle_adjust(&views, &initial, &BundleAdjustOptions::default(), &mut scratch)?;
    let estimator = Estimator::Eiv { sigma_z_mm, sigma_e_ma, sigma_px: None };
    let mut options = BundleAdjustOptions { estimator, ..BundleAdjustOptions::default() };
    options.lm.initial_damping = EIV_INITIAL_DAMPING;
    let eiv = bundle_adjust(&views, &paper.model, &options, &mut scratch)?;
    Ok(PairFit { paper, eiv })
}

/// Mean, standard deviation and 95th percentile of a sample, with the standard errors of
/// the mean and of the standard deviation.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Stat {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (n - 1).
    pub std: f64,
    /// 95th percentile (nearest rank).
    pub p95: f64,
    /// Standard error of the mean: std / sqrt(n) (NaN below 2 values).
    pub mean_se: f64,
    /// Standard error of the standard deviation (NaN below 4 values): by the delta method,
    /// se(s) = sqrt(var(s^2)) / (2 s) with var(s^2) = (m4 - s^4 (n - 3) / (n - 1)) / n and
    /// m4 the sample's fourth central moment; for Gaussian values about
    /// s / sqrt(2 (n - 1)), larger for heavy tails.
    pub std_se: f64,
}

/// [`Stat`] of `values` (NaN fields when empty).
pub fn stat(values: &[f64]) -> Stat {
    let n = values.len();
    if n == 0 {
        return Stat { mean: f64::NAN, std: f64::NAN, p95: f64::NAN, mean_se: f64::NAN, std_se: f64::NAN };
    }
    let mean = values.iter().sum::<f64>() / n as f64;
    let var = if n > 1 { values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64 } else { 0.0 };
    let mut s = values.to_vec();
    s.sort_by(f64::total_cmp);
    let k = ((0.95 * n as f64).ceil() as usize).clamp(1, n) - 1;
    let nf = n as f64;
    let mean_se = if n > 1 { (var / nf).sqrt() } else { f64::NAN };
    let std_se = if n > 3 && var > 0.0 {
        let m4 = values.iter().map(|v| (v - mean).powi(4)).sum::<f64>() / nf;
        let var_of_var = (m4 - var * var * (nf - 3.0) / (nf - 1.0)) / nf;
        var_of_var.max(0.0).sqrt() / (2.0 * var.sqrt())
    } else {
        f64::NAN
    };
    Stat { mean, std: var.sqrt(), p95: s[k], mean_se, std_se }
}

/// The number of numbers of the paper's model, which the studies calibrate
/// ([`Layout::PAPER`]).
pub const PARAMS: usize = Layout::PAPER.len();

/// The name of number `i` of the paper's model.
pub fn param_name(i: usize) -> &'static str {
    Layout::PAPER.name(i)
}

/// The paper model's numbers of `m` (the first [`PARAMS`] of its parameter vector).
pub fn paper_params(m: &CameraModel) -> [f64; PARAMS] {
    let x = to_params(m);
    core::array::from_fn(|i| x[i])
}

/// Relative std of every parameter and the max relative std of fx(E) over
/// [`RIG_RANGE_MA`] from a covariance of the 25 numbers.
pub fn cov_std(cov: &[[f64; MAX_PARAMS]; MAX_PARAMS]) -> [f64; PARAMS] {
    core::array::from_fn(|i| cov[i][i].max(0.0).sqrt())
}

/// The standard deviation of fx(E) (px) at `e_ma` from a covariance of the 25 numbers
/// (fx is linear in kf0x..kf3x: var = g^T C g with g = [1, E, E^2, E^3]).
pub fn fx_std_px(cov: &[[f64; MAX_PARAMS]; MAX_PARAMS], e_ma: f64) -> f64 {
    fx_std_px_in(cov, &Layout::PAPER, e_ma)
}

/// [`fx_std_px`] for a covariance in `layout` (any focal degree d: g = [1, E, .., E^d]).
pub fn fx_std_px_in(cov: &[[f64; MAX_PARAMS]; MAX_PARAMS], layout: &Layout, e_ma: f64) -> f64 {
    let kf_x = layout.kf_x();
    let mut g = [1.0; etl_core::model::MAX_FOCAL_DEGREE + 1];
    for i in 1..kf_x.len {
        g[i] = g[i - 1] * e_ma;
    }
    let mut v = 0.0;
    for i in 0..kf_x.len {
        for j in 0..kf_x.len {
            v += g[i] * cov[kf_x.at(i)][kf_x.at(j)] * g[j];
        }
    }
    v.max(0.0).sqrt()
}

/// Max over [`RIG_RANGE_MA`] (1 mA steps) of std(fx(E)) / fx(E).
pub fn fx_curve_rel_std(cov: &[[f64; MAX_PARAMS]; MAX_PARAMS], truth: &CameraModel) -> f64 {
    (RIG_RANGE_MA[0] as usize..=RIG_RANGE_MA[1] as usize)
        .map(|e| fx_std_px(cov, e as f64) / truth.focal_lengths(e as f64).0)
        .fold(0.0, f64::max)
}

/// sqrt(2 / pi): the mean absolute value of a standard normal variable, turning a
/// Cramer-Rao standard deviation into the mean absolute error it implies (Gaussian errors).
pub const MEAN_ABS_OF_STD: f64 = 0.797_884_560_802_865_4;

/// The truth as a parameter vector (order of [`param_name`]).
pub fn truth_params() -> [f64; PARAMS] {
    paper_params(&CameraModel::paper_rig())
}

// ---------------------------------------------------------------- markdown

/// A markdown table.
pub fn md_table(headers: &[&str], rows: &[Vec<String>]) -> String {
    let mut t = String::new();
    let _ = writeln!(t, "| {} |", headers.join(" | "));
    let _ = writeln!(t, "|{}", "---|".repeat(headers.len()));
    for r in rows {
        let _ = writeln!(t, "| {} |", r.join(" | "));
    }
    t
}

/// A relative error as a percentage with 3 decimals.
pub fn pct(v: f64) -> String {
    if v.is_finite() {
        format!("{:.3} %", 100.0 * v)
    } else {
        "-".into()
    }
}

/// A mean and its standard error as percentages, "0.750 ± 0.031 %" ("-" when not finite).
pub fn pct_se(mean: f64, se: f64) -> String {
    if mean.is_finite() && se.is_finite() {
        format!("{:.3} ± {:.3} %", 100.0 * mean, 100.0 * se)
    } else {
        pct(mean)
    }
}

/// A number in scientific notation with 3 decimals ("-" when not finite).
pub fn sci(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.3e}")
    } else {
        "-".into()
    }
}

/// What a study produces.
#[derive(Debug, Clone)]
pub struct StudyOutput {
    /// The study's name (file stem).
    pub name: String,
    /// The `--json` object.
    pub json: serde_json::Value,
    /// The markdown summary.
    pub markdown: String,
    /// The plots.
    pub figures: Vec<Figure>,
}

impl StudyOutput {
    /// Writes `name.json`, `name.md` and every figure (PNG and SVG) into the existing
    /// directory `dir` as one set (etl_formats::output::write_bytes_set): a kill or a full
    /// disk leaves the earlier files of this study or the new ones, never a mix. Returns
    /// the paths.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let text = serde_json::to_string_pretty(&self.json).map_err(|e| Error::invalid(&self.name, e.to_string()))?;
        let mut files = vec![
            (dir.join(format!("{}.json", self.name)), text.into_bytes()),
            (dir.join(format!("{}.md", self.name)), self.markdown.clone().into_bytes()),
        ];
        for f in &self.figures {
            files.extend(render_figure(f)?.into_iter().map(|(name, bytes)| (dir.join(name), bytes)));
        }
        write_bytes_set(&files)?;
        Ok(files.into_iter().map(|(p, _)| p).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Exp1, StandardNormal};

    /// The standard errors against their definition: the spread, over many samples, of the
    /// sample mean and of the sample std (Gaussian values, and exponential ones whose
    /// heavy tail makes the std about twice as uncertain as for Gaussian values).
    #[test]
    fn standard_errors_are_the_spread_of_the_estimates_over_samples() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        // Samples of 300, the CRLB study's default trials; s / sqrt(2 (n - 1)) at s = 1.
        let gaussian_formula = 1.0 / 598f64.sqrt();
        for heavy in [false, true] {
            let (mut means, mut stds, mut mean_ses, mut std_ses) = (vec![], vec![], vec![], vec![]);
            for _ in 0..3000 {
                let x: Vec<f64> = (0..300)
                    .map(|_| if heavy { Exp1.sample(&mut rng) } else { StandardNormal.sample(&mut rng) })
                    .collect();
                let s = stat(&x);
                means.push(s.mean);
                stds.push(s.std);
                mean_ses.push(s.mean_se);
                std_ses.push(s.std_se);
            }
            let (spread_of_mean, spread_of_std) = (stat(&means).std, stat(&stds).std);
            let (mean_se, std_se) = (stat(&mean_ses).mean, stat(&std_ses).mean);
            // Unit variance: the mean's spread is 1 / sqrt(300) for both.
            assert!((spread_of_mean * 300f64.sqrt() - 1.0).abs() < 0.05, "{heavy}: {spread_of_mean}");
            assert!((mean_se / spread_of_mean - 1.0).abs() < 0.05, "{heavy}: {mean_se} vs {spread_of_mean}");
            if heavy {
                // The exponential's std spreads twice as far as the Gaussian formula says;
                // the estimate follows it to within 15 % (measured: 6 % low, as the
                // sample's fourth moment is itself low for such tails).
                assert!(spread_of_std > 1.7 * gaussian_formula, "{spread_of_std}");
                assert!(std_se / spread_of_std > 0.85 && std_se / spread_of_std < 1.05, "{std_se} vs {spread_of_std}");
            } else {
                assert!((spread_of_std / gaussian_formula - 1.0).abs() < 0.05, "{spread_of_std}");
                assert!((std_se / spread_of_std - 1.0).abs() < 0.05, "{std_se} vs {spread_of_std}");
            }
        }
        let few = stat(&[1.0, 2.0, 4.0]);
        assert!(few.std_se.is_nan() && few.mean_se > 0.0 && stat(&[1.0]).mean_se.is_nan());
    }
}
