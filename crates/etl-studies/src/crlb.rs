//! `etlcal study crlb`: statistical efficiency at the paper rig (docs/METHOD.md: 15 views, 2311
//! points, all 25 numbers refined).
//!
//! - Pixel noise alone (0.2 px): the Cramer-Rao bound of every parameter and of fx(E) from
//!   the Fisher information J^T J / sigma^2 at the truth
//!   ([`etl_core::calib::crlb::crlb_covariance`]) against the Monte Carlo spread of the
//!   paper's bundle adjustment; efficiency = bound / observed std (1: no unbiased
//!   estimator does better).
//! - The full noise model's per-view errors (10 um on Z_W, 0.4 mA on E, with 0.2 px): the
//!   bound with every view's dZ_j, dE_j unknown under their Gaussian priors
//!   ([`etl_core::calib::crlb::crlb_covariance_eiv`]) against the spread of the
//!   errors-in-variables estimator.
//!
//! Every trial is a full calibration from the linear initialisation, with the A0 error of the
//! noise model (it moves the start, not the optimum). The observed std is uncertain by
//! about 1 / sqrt(2 (trials - 1)) relative (4 % at 300 trials) for Gaussian estimates; each
//! is given with its own standard error ([`crate::common::Stat::std_se`], from the estimates' fourth
//! moment), and each efficiency with the one that implies.

use etl_core::calib::crlb::{crlb_covariance, crlb_covariance_eiv};
use etl_core::calib::View;
use etl_core::model::CameraModel;
use serde_json::json;

use super::common::{
    calibrate_pair, calibrate_paper, cov_std, fx_std_px, md_table, paper_params, param_name, run_jobs, sci, stat,
    truth_params, Chart, Figure, Series, StudyOptions, StudyOutput, TrialCounts, PARAMS,
};
use etl_formats::{Error, Result};
use etl_sim::simulate::{core_points, paper_rig, NoiseModel, PAPER_E_COM_MA};

/// Default trials per estimator.
pub const DEFAULT_TRIALS: usize = 300;
/// Pixel noise, px.
pub const SIGMA_PX: f64 = 0.2;
/// Currents at which fx(E) is compared, mA.
pub const CURVE_E_MA: [f64; 6] = [80.0, 110.0, 140.0, 170.0, 200.0, 225.0];

/// The noise of the pixel-only study: 0.2 px, the A0 error of the paper (start only).
pub const PIXEL_ONLY: NoiseModel =
    NoiseModel { xy_mm: 0.0, z_mm: 0.0, e_ma: 0.0, px: SIGMA_PX, kf0_rel: 0.003, pp_px: 1.0 };
/// The noise of the errors-in-variables study: the paper's per-view errors with 0.2 px.
pub const PER_VIEW: NoiseModel =
    NoiseModel { xy_mm: 0.0, z_mm: 0.010, e_ma: 0.4, px: SIGMA_PX, kf0_rel: 0.003, pp_px: 1.0 };

/// One parameter's row.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ParamRow {
    /// Name ([`super::common::param_name`]).
    pub name: &'static str,
    /// True value.
    pub truth: f64,
    /// CRLB std, pixel noise alone.
    pub crlb_std: f64,
    /// Observed std of the paper's BA, pixel noise alone.
    pub mc_std: f64,
    /// Standard error of `mc_std` (over the trials).
    pub mc_std_se: f64,
    /// crlb_std / mc_std.
    pub efficiency: f64,
    /// Standard error of `efficiency`: efficiency x mc_std_se / mc_std.
    pub efficiency_se: f64,
    /// Mean error of the paper's BA (bias), pixel noise alone.
    pub mc_bias: f64,
    /// CRLB std with the per-view unknowns.
    pub eiv_crlb_std: f64,
    /// Observed std of the errors-in-variables BA under the per-view errors.
    pub eiv_mc_std: f64,
    /// Standard error of `eiv_mc_std`.
    pub eiv_mc_std_se: f64,
    /// eiv_crlb_std / eiv_mc_std.
    pub eiv_efficiency: f64,
    /// Standard error of `eiv_efficiency`.
    pub eiv_efficiency_se: f64,
}

/// fx(E) at one current.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CurveRow {
    /// Current, mA.
    pub e_com_ma: f64,
    /// True fx, px.
    pub fx_px: f64,
    /// CRLB std of fx(E), px (pixel noise alone).
    pub crlb_std_px: f64,
    /// Observed std, px.
    pub mc_std_px: f64,
    /// Standard error of `mc_std_px`, px.
    pub mc_std_se_px: f64,
    /// With the per-view unknowns: bound, px.
    pub eiv_crlb_std_px: f64,
    /// With the per-view unknowns: observed std of the errors-in-variables BA, px.
    pub eiv_mc_std_px: f64,
    /// Standard error of `eiv_mc_std_px`, px.
    pub eiv_mc_std_se_px: f64,
}

/// The result of `etlcal study crlb`.
#[derive(Debug, Clone)]
pub struct Crlb {
    /// Trials per estimator (pixel-only, per-view) that calibrated, the failed ones, the
    /// rig's points.
    pub counts: TrialCounts,
    /// Per parameter.
    pub parameters: Vec<ParamRow>,
    /// fx(E).
    pub curve: Vec<CurveRow>,
}

/// Runs the study (`opts.trials` per estimator, default 300).
pub fn crlb(opts: &StudyOptions) -> Result<Crlb> {
    let n = opts.trials_or(DEFAULT_TRIALS);
    let truth = CameraModel::paper_rig();
    let sim = paper_rig(&NoiseModel::NONE, 0);
    let pts = core_points(&sim);
    let views: Vec<View<'_>> = pts.iter().zip(PAPER_E_COM_MA).map(|(p, e)| View { e_com_ma: e, points: p }).collect();
    let points = pts.iter().map(|p| p.len()).sum();
    let plain = crlb_covariance(&views, &truth, SIGMA_PX)?;
    let full = crlb_covariance_eiv(&views, &truth, SIGMA_PX, Some((PER_VIEW.z_mm, PER_VIEW.e_ma)))?;
    let jobs: Vec<(usize, usize)> = (0..2).flat_map(|k| (0..n).map(move |t| (k, t))).collect();
    let outs = run_jobs("crlb", &jobs, opts.progress, |&(k, t)| {
        let seed = opts.trial_seed(t);
        if k == 0 {
            let s = paper_rig(&PIXEL_ONLY, seed);
            Ok(calibrate_paper(&s.observations, &s.a0)?.model)
        } else {
            let s = paper_rig(&PER_VIEW, seed);
            Ok(calibrate_pair(&s.observations, &s.a0, PER_VIEW.z_mm, PER_VIEW.e_ma)?.eiv.model)
        }
    });
    let mut est: [Vec<CameraModel>; 2] = [vec![], vec![]];
    let mut failures = vec![];
    for ((k, t), o) in jobs.iter().zip(outs) {
        match o {
            Ok(m) => est[*k].push(m),
            Err(e) => failures.push(format!("{} trial {t}: {e}", ["pixel-only", "per-view"][*k])),
        }
    }
    if est.iter().any(|e| e.len() < 2) {
        return Err(Error::invalid("trials", "the CRLB study needs at least 2 trials that calibrate"));
    }
    let x = truth_params();
    let p: [Vec<[f64; PARAMS]>; 2] =
        [est[0].iter().map(paper_params).collect(), est[1].iter().map(paper_params).collect()];
    let (cs, fs) = (cov_std(&plain), cov_std(&full));
    let parameters = (0..PARAMS)
        .map(|i| {
            let s0 = stat(&p[0].iter().map(|v| v[i]).collect::<Vec<_>>());
            let s1 = stat(&p[1].iter().map(|v| v[i]).collect::<Vec<_>>());
            ParamRow {
                name: param_name(i),
                truth: x[i],
                crlb_std: cs[i],
                mc_std: s0.std,
                mc_std_se: s0.std_se,
                efficiency: cs[i] / s0.std,
                efficiency_se: cs[i] / s0.std * s0.std_se / s0.std,
                mc_bias: s0.mean - x[i],
                eiv_crlb_std: fs[i],
                eiv_mc_std: s1.std,
                eiv_mc_std_se: s1.std_se,
                eiv_efficiency: fs[i] / s1.std,
                eiv_efficiency_se: fs[i] / s1.std * s1.std_se / s1.std,
            }
        })
        .collect();
    let curve = CURVE_E_MA
        .iter()
        .map(|&e| {
            let fx = |k: usize| stat(&est[k].iter().map(|m| m.focal_lengths(e).0).collect::<Vec<_>>());
            let (s0, s1) = (fx(0), fx(1));
            CurveRow {
                e_com_ma: e,
                fx_px: truth.focal_lengths(e).0,
                crlb_std_px: fx_std_px(&plain, e),
                mc_std_px: s0.std,
                mc_std_se_px: s0.std_se,
                eiv_crlb_std_px: fx_std_px(&full, e),
                eiv_mc_std_px: s1.std,
                eiv_mc_std_se_px: s1.std_se,
            }
        })
        .collect();
    Ok(Crlb { counts: TrialCounts { trials: [est[0].len(), est[1].len()], failures, points }, parameters, curve })
}

impl Crlb {
    /// Smallest efficiency over the parameters (pixel noise alone).
    pub fn min_efficiency(&self) -> f64 {
        self.parameters.iter().map(|p| p.efficiency).fold(f64::INFINITY, f64::min)
    }

    /// JSON, markdown and plots.
    pub fn output(&self) -> StudyOutput {
        let min = self.min_efficiency();
        let md = self.markdown(min);
        let j = self.counts.efficiency_json(SIGMA_PX, &self.parameters, min, json!({"fx_curve": self.curve}));
        let fig = self.figure();
        StudyOutput { name: "crlb".into(), json: j, markdown: md, figures: vec![fig] }
    }

    /// The markdown summary: every parameter's bound, Monte Carlo spread and efficiency,
    /// the smallest efficiency `min` against the target 0.9, and the same for fx(E).
    fn markdown(&self, min: f64) -> String {
        let rows: Vec<Vec<String>> = self
            .parameters
            .iter()
            .map(|p| {
                vec![
                    p.name.into(),
                    format!("{:+.4e}", p.truth),
                    sci(p.crlb_std),
                    sci(p.mc_std),
                    format!("{:.3} ± {:.3}", p.efficiency, p.efficiency_se),
                    sci(p.eiv_crlb_std),
                    sci(p.eiv_mc_std),
                    format!("{:.3} ± {:.3}", p.eiv_efficiency, p.eiv_efficiency_se),
                ]
            })
            .collect();
        let crows: Vec<Vec<String>> = self
            .curve
            .iter()
            .map(|c| {
                vec![
                    format!("{}", c.e_com_ma),
                    format!("{:.3}", c.crlb_std_px),
                    format!("{:.3} ± {:.3}", c.mc_std_px, c.mc_std_se_px),
                    format!("{:.3}", c.crlb_std_px / c.mc_std_px),
                    format!("{:.3}", c.eiv_crlb_std_px),
                    format!("{:.3} ± {:.3}", c.eiv_mc_std_px, c.eiv_mc_std_se_px),
                    format!("{:.3}", c.eiv_crlb_std_px / c.eiv_mc_std_px),
                ]
            })
            .collect();
        format!(
            "# Cramer-Rao bound and statistical efficiency at the paper rig\n\n{} points, all 25 numbers refined, \
             {} + {} trials ({} failed). Pixel only: 0.2 px, the paper's BA. Per-view errors: 10 um on Z_W and 0.4 mA \
             on E per view with 0.2 px, the errors-in-variables BA and the bound with dZ_j, dE_j unknown under their \
             priors. Efficiency = bound / observed std, ± one standard error from the trials (the observed std is \
             uncertain by about {:.0} % for Gaussian estimates).\n\n{}\n\
             Smallest efficiency (pixel only): {:.3} (the acceptance asks at least 0.9: {}).\n\n## fx(E) (px)\n\n{}",
            self.counts.points,
            self.counts.trials[0],
            self.counts.trials[1],
            self.counts.failures.len(),
            self.counts.std_uncertainty_pct(),
            md_table(
                &[
                    "parameter",
                    "truth",
                    "CRLB std",
                    "MC std",
                    "efficiency",
                    "CRLB std (per-view)",
                    "eiv MC std",
                    "eiv efficiency"
                ],
                &rows
            ),
            min,
            if min >= 0.9 { "yes" } else { "**no**" },
            md_table(
                &["E (mA)", "CRLB std", "MC std", "efficiency", "CRLB std (per-view)", "eiv MC std", "eiv efficiency"],
                &crows
            )
        )
    }

    /// The figure: (a) the efficiency of every parameter (named on the x axis), (b) the std of fx(E), bound and
    /// Monte Carlo, both estimators; the Monte Carlo numbers with error bars of one
    /// standard error.
    fn figure(&self) -> Figure {
        let idx: Vec<f64> = (0..PARAMS).map(|i| i as f64).collect();
        Figure {
            name: "crlb".into(),
            grid: (1, 2),
            panels: vec![
                Chart {
                    title: "efficiency = CRLB std / MC std, ± 1 s.e.".into(),
                    x_label: "parameter".into(),
                    y_label: "efficiency".into(),
                    log_y: false,
                    series: vec![
                        // Markers only (the parameters are categories), the two estimators
                        // side by side at each.
                        Series::scatter(
                            "paper BA, pixel noise",
                            0,
                            idx.iter().zip(&self.parameters).map(|(i, p)| (*i - 0.15, p.efficiency)).collect(),
                        )
                        .with_se(self.parameters.iter().map(|p| p.efficiency_se).collect()),
                        Series::scatter(
                            "eiv BA, per-view errors",
                            1,
                            idx.iter().zip(&self.parameters).map(|(i, p)| (*i + 0.15, p.eiv_efficiency)).collect(),
                        )
                        .with_se(self.parameters.iter().map(|p| p.eiv_efficiency_se).collect()),
                        Series::reference("1: efficient", 7, vec![(0.0, 1.0), (24.0, 1.0)]),
                        Series::reference("0.9: the acceptance", 2, vec![(0.0, 0.9), (24.0, 0.9)]),
                    ],
                    x_names: (0..PARAMS).map(|i| param_name(i).to_string()).collect(),
                },
                Chart {
                    title: "std of fx(E): bound and Monte Carlo ± 1 s.e.".into(),
                    x_label: "E_com (mA)".into(),
                    y_label: "std (px)".into(),
                    log_y: false,
                    series: vec![
                        Series::reference(
                            "CRLB, pixel noise",
                            0,
                            self.curve.iter().map(|c| (c.e_com_ma, c.crlb_std_px)).collect(),
                        ),
                        Series::line("paper BA", 0, self.curve.iter().map(|c| (c.e_com_ma, c.mc_std_px)).collect())
                            .with_se(self.curve.iter().map(|c| c.mc_std_se_px).collect()),
                        Series::reference(
                            "CRLB, per-view errors",
                            1,
                            self.curve.iter().map(|c| (c.e_com_ma, c.eiv_crlb_std_px)).collect(),
                        ),
                        Series::line("eiv BA", 1, self.curve.iter().map(|c| (c.e_com_ma, c.eiv_mc_std_px)).collect())
                            .with_se(self.curve.iter().map(|c| c.eiv_mc_std_se_px).collect()),
                    ],
                    x_names: vec![],
                },
            ],
        }
    }
}
