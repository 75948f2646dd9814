//! `etlcal study crlb --rig strong`: the strong-distortion rig (etl-sim's `strong_rig`: a
//! short prime behind the ETL, k1 about -0.3 and k2 about 0.15 in OpenCV's normalised
//! units, varying with focus; 15 views, 4085 corners), pixel noise only (0.2 px; the A0
//! error of the noise model moves the start only), every trial calibrated twice from the
//! linear initialisation by the paper's estimator (Eq. 24, the maximum-likelihood estimator
//! under pixel noise):
//!
//! - in the opencv family (the truth's: 31 numbers, cubic focal polynomials): its Monte
//!   Carlo spread against its Cramer-Rao bound, every number (efficiency = bound / spread,
//!   the spread uncertain by about 1 / sqrt(2 (trials - 1)), 4 % at 300 trials);
//! - in the paper's family (Eq. 17: k1, p1, p2 in centred pixels; 25 numbers), which
//!   cannot describe k2: its bias in the principal point and in fx(E) (mean error over
//!   the trials, with its standard error), beside the opencv family's.

use etl_core::calib::crlb::crlb_covariance;
use etl_core::calib::jacobian::to_params;
use etl_core::calib::params::{Layout, MAX_PARAMS};
use etl_core::calib::{View, A0};
use etl_core::model::{CameraModel, DistortionModel, OpenCvFlags};
use serde_json::json;

use super::common::{
    calibrate_layout, fx_std_px_in, md_table, run_jobs, sci, stat, Chart, Figure, Series, StudyOptions, StudyOutput,
    TrialCounts,
};
use super::crlb::{CURVE_E_MA, PIXEL_ONLY, SIGMA_PX};
use etl_formats::{Error, Result};
use etl_sim::simulate::{core_points, strong_rig, NoiseModel, STRONG_E_COM_MA};

/// Default trials.
pub const DEFAULT_TRIALS: usize = 300;

/// One number of the opencv family's model.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct StrongRow {
    /// Name ([`Layout::name`]).
    pub name: &'static str,
    /// True value.
    pub truth: f64,
    /// Cramer-Rao std (0.2 px).
    pub crlb_std: f64,
    /// Monte Carlo std.
    pub mc_std: f64,
    /// crlb_std / mc_std.
    pub efficiency: f64,
    /// Mean error (bias), and its standard error.
    pub mc_bias: f64,
}

/// The error of one family's estimate of a quantity: mean over the trials (its bias) with
/// its standard error, and the spread.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Bias {
    /// Mean error.
    pub mean: f64,
    /// Standard error of the mean.
    pub se: f64,
    /// Standard deviation over the trials.
    pub std: f64,
}

impl Bias {
    fn of(errors: &[f64]) -> Self {
        let s = stat(errors);
        Bias { mean: s.mean, se: s.std / (errors.len().max(1) as f64).sqrt(), std: s.std }
    }
}

/// Both families' errors in one quantity.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct BiasRow {
    /// What (`u0 (px)`, `fx(150 mA) (px)`, ...).
    pub quantity: String,
    /// The current, mA (fx rows; None for the principal point).
    pub e_com_ma: Option<f64>,
    /// The Cramer-Rao std of the quantity in the opencv family (0.2 px).
    pub crlb_std: f64,
    /// The opencv family's.
    pub opencv: Bias,
    /// The paper family's.
    pub paper: Bias,
}

/// The result of the strong-rig study.
#[derive(Debug, Clone)]
pub struct StrongCrlb {
    /// Trials that calibrated per family (opencv, paper), the failed ones, the rig's
    /// corners.
    pub counts: TrialCounts,
    /// The opencv family's numbers.
    pub parameters: Vec<StrongRow>,
    /// Principal point and fx(E): both families' bias.
    pub bias: Vec<BiasRow>,
    /// Mean RMS reprojection error per family (opencv, paper), px.
    pub rms_px: [f64; 2],
}

/// One trial's estimates: the opencv family's model and RMS, the paper family's.
type Trial = (CameraModel, f64, CameraModel, f64);

/// Calibrates trial `t` in both families.
fn trial(opts: &StudyOptions, t: usize) -> Result<Trial> {
    let s = strong_rig(&PIXEL_ONLY, opts.trial_seed(t));
    let a0: A0 = s.a0;
    let opencv = Layout::new(DistortionModel::OpenCv, 3).map_err(Error::Core)?;
    let o = calibrate_layout(&s.observations, &a0, opencv, OpenCvFlags::NONE)?;
    let p = calibrate_layout(&s.observations, &a0, Layout::PAPER, OpenCvFlags::NONE)?;
    Ok((o.model, o.rms_px, p.model, p.rms_px))
}

/// Runs the study (`opts.trials`, default 300).
pub fn strong_crlb(opts: &StudyOptions) -> Result<StrongCrlb> {
    let n = opts.trials_or(DEFAULT_TRIALS);
    let truth = CameraModel::strong_distortion_rig();
    let layout = truth.layout();
    let sim = strong_rig(&NoiseModel::NONE, 0);
    let pts = core_points(&sim);
    let views: Vec<View<'_>> = pts.iter().zip(STRONG_E_COM_MA).map(|(p, e)| View { e_com_ma: e, points: p }).collect();
    let points = pts.iter().map(Vec::len).sum();
    let bound = crlb_covariance(&views, &truth, SIGMA_PX)?;
    let jobs: Vec<usize> = (0..n).collect();
    let outs = run_jobs("crlb strong rig", &jobs, opts.progress, |&t| trial(opts, t));
    let (mut ok, mut failures) = (vec![], vec![]);
    for (t, o) in jobs.iter().zip(outs) {
        match o {
            Ok(r) => ok.push(r),
            Err(e) => failures.push(format!("trial {t}: {e}")),
        }
    }
    if ok.len() < 2 {
        return Err(Error::invalid("trials", "the strong-rig study needs at least 2 trials that calibrate"));
    }
    let x = to_params(&truth);
    let est: Vec<[f64; MAX_PARAMS]> = ok.iter().map(|r| to_params(&r.0)).collect();
    let parameters = (0..layout.len())
        .map(|i| {
            let s = stat(&est.iter().map(|v| v[i]).collect::<Vec<_>>());
            let crlb_std = bound[i][i].max(0.0).sqrt();
            StrongRow {
                name: layout.name(i),
                truth: x[i],
                crlb_std,
                mc_std: s.std,
                efficiency: crlb_std / s.std,
                mc_bias: s.mean - x[i],
            }
        })
        .collect();
    let row = |quantity: String, e_com_ma: Option<f64>, crlb_std: f64, f: &dyn Fn(&CameraModel) -> f64| BiasRow {
        quantity,
        e_com_ma,
        crlb_std,
        opencv: Bias::of(&ok.iter().map(|r| f(&r.0)).collect::<Vec<_>>()),
        paper: Bias::of(&ok.iter().map(|r| f(&r.2)).collect::<Vec<_>>()),
    };
    let [u0, v0] = truth.principal_point;
    let sd = |i: usize| bound[i][i].max(0.0).sqrt();
    let mut bias = vec![
        row("u0 (px)".into(), None, sd(layout.u0()), &|m| m.principal_point[0] - u0),
        row("v0 (px)".into(), None, sd(layout.v0()), &|m| m.principal_point[1] - v0),
    ];
    for e in CURVE_E_MA {
        let fx = truth.focal_lengths(e).0;
        bias.push(row(format!("fx({e} mA) (px)"), Some(e), fx_std_px_in(&bound, &layout, e), &|m| {
            m.focal_lengths(e).0 - fx
        }));
    }
    let mean = |k: usize| ok.iter().map(|r| if k == 0 { r.1 } else { r.3 }).sum::<f64>() / ok.len() as f64;
    let counts = TrialCounts { trials: [ok.len(), ok.len()], failures, points };
    Ok(StrongCrlb { counts, parameters, bias, rms_px: [mean(0), mean(1)] })
}

impl StrongCrlb {
    /// Smallest efficiency over the opencv family's numbers.
    pub fn min_efficiency(&self) -> f64 {
        self.parameters.iter().map(|p| p.efficiency).fold(f64::INFINITY, f64::min)
    }

    /// JSON, markdown and the figure.
    pub fn output(&self) -> StudyOutput {
        let min = self.min_efficiency();
        let own = json!({
            "rig": "strong",
            "bias": self.bias,
            "rms_px": {"opencv": self.rms_px[0], "paper": self.rms_px[1]},
        });
        let j = self.counts.efficiency_json(SIGMA_PX, &self.parameters, min, own);
        StudyOutput { name: "crlb-strong".into(), json: j, markdown: self.markdown(min), figures: vec![self.figure()] }
    }

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
                    format!("{:.3}", p.efficiency),
                    sci(p.mc_bias),
                ]
            })
            .collect();
        let b = |x: &Bias| format!("{:+.3} ± {:.3} ({:.3})", x.mean, x.se, x.std);
        let brows: Vec<Vec<String>> = self
            .bias
            .iter()
            .map(|r| vec![r.quantity.clone(), format!("{:.3}", r.crlb_std), b(&r.opencv), b(&r.paper)])
            .collect();
        format!(
            "# The strong-distortion rig: the opencv family against its Cramer-Rao bound, the paper family's bias\n\n\
             {} points, 0.2 px of pixel noise only, {} trials ({} failed), each calibrated from the linear \
             initialisation by the paper's estimator in both families. Efficiency = bound / observed std (the observed \
             std is uncertain by about {:.0} %).\n\n## The opencv family (31 numbers)\n\n{}\nSmallest efficiency: {:.3} \
             (the acceptance asks at least 0.9: {}).\n\n## Principal point and fx(E): mean error ± its standard error \
             (std over the trials)\n\n{}\nMean RMS reprojection error: opencv family {:.4} px, paper family {:.4} px.\n",
            self.counts.points,
            self.counts.trials[0],
            self.counts.failures.len(),
            self.counts.std_uncertainty_pct(),
            md_table(&["number", "truth", "CRLB std", "MC std", "efficiency", "MC bias"], &rows),
            min,
            if min >= 0.9 { "yes" } else { "**no**" },
            md_table(&["quantity", "CRLB std (opencv)", "opencv family", "paper family"], &brows),
            self.rms_px[0],
            self.rms_px[1],
        )
    }

    /// (a) the opencv family's efficiency per number; (b) the bias of fx(E) of both
    /// families, with the opencv family's bound as a band.
    fn figure(&self) -> Figure {
        let fx: Vec<&BiasRow> = self.bias.iter().filter(|r| r.e_com_ma.is_some()).collect();
        let pts =
            |f: &dyn Fn(&BiasRow) -> f64| fx.iter().map(|r| (r.e_com_ma.unwrap_or(0.0), f(r))).collect::<Vec<_>>();
        let last = self.parameters.len().saturating_sub(1) as f64;
        Figure {
            name: "crlb-strong".into(),
            grid: (1, 2),
            panels: vec![
                Chart {
                    title: "opencv family: efficiency = CRLB std / MC std".into(),
                    x_label: "parameter".into(),
                    x_names: self.parameters.iter().map(|p| p.name.to_string()).collect(),
                    y_label: "efficiency".into(),
                    log_y: false,
                    series: vec![
                        Series::line(
                            "opencv family, pixel noise",
                            0,
                            self.parameters.iter().enumerate().map(|(i, p)| (i as f64, p.efficiency)).collect(),
                        ),
                        Series::reference("1", 7, vec![(0.0, 1.0), (last, 1.0)]),
                        Series::reference("0.9", 2, vec![(0.0, 0.9), (last, 0.9)]),
                    ],
                },
                Chart {
                    title: "fx(E) bias: mean error over the trials".into(),
                    x_label: "E_com (mA)".into(),
                    y_label: "mean fx error (px)".into(),
                    x_names: vec![],
                    log_y: false,
                    series: vec![
                        Series::line("paper family", 1, pts(&|r| r.paper.mean))
                            .with_se(fx.iter().map(|r| r.paper.se).collect()),
                        Series::line("opencv family", 0, pts(&|r| r.opencv.mean))
                            .with_se(fx.iter().map(|r| r.opencv.se).collect()),
                        Series::reference("+1 CRLB std (opencv)", 7, pts(&|r| r.crlb_std)),
                        Series::reference("-1 CRLB std (opencv)", 7, pts(&|r| -r.crlb_std)),
                    ],
                },
            ],
        }
    }
}
