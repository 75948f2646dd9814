//! `etlcal study fig6`: the three studies of the paper's section 5.1.2 (Fig. 6) under the
//! paper's noise model (docs/METHOD.md), each for the plain bundle adjustment (Eq. 24) and the
//! errors-in-variables one, side by side:
//!
//! - (a) pixel noise 0..1.6 px by 0.2 (the other noises at the paper's levels);
//! - (b) current noise 0..1.6 mA by 0.2;
//! - (c) 3..15 images, drawn at random from the 15 views for every trial (as the paper).
//!
//! Per level: the mean relative error of kf1..kf3 (x, y), om and T (the paper's measure),
//! and the errors users feel: the max relative error of fx(E), fy(E) over 80..225 mA, the
//! principal-point error, and the PnP error of a 2 mm stage move at 225 mA (fresh views with
//! the paper's 0.2 px and 1 um noise, the same for both estimators). Each trial is a full
//! calibration from the linear initialisation with the noisy A0 of the noise model.
//!
//! Next to them, the Cramer-Rao bound at the level: "pixel only" treats the recorded Z_W and
//! E as exact (the model of Eq. 24), "full" gives every view unknown dZ_j, dE_j with the
//! level's priors (the stated noise model). Coefficient bounds are given as the mean
//! absolute relative error they imply for Gaussian errors (sqrt(2/pi) std / |truth|), the
//! curve bound as the max over E of std(fx(E)) / fx(E). For (c) the bound is at evenly spaced
//! views.

use etl_core::calib::crlb::crlb_covariance_eiv;
use etl_core::calib::params::{Layout, MAX_PARAMS};
use etl_core::calib::View;
use etl_core::model::CameraModel;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde_json::{json, Value};

use super::common::{
    calibrate_pair, fx_curve_rel_std, md_table, model_errors, move_observations, pct, pct_se, pnp_move_error_um,
    run_jobs, stat, Chart, Figure, ModelErrors, Series, StudyOptions, StudyOutput, KF_NAMES, MEAN_ABS_OF_STD,
};
use etl_formats::Result;
use etl_sim::simulate::{core_points, paper_rig, NoiseModel, PAPER_E_COM_MA};

/// Default trials per level (the paper's 100).
pub const DEFAULT_TRIALS: usize = 100;
/// Current of the PnP measurement, mA.
pub const PNP_E_MA: f64 = 225.0;

/// Which of the three studies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Fig6Study {
    /// (a) pixel noise, px.
    PixelNoise,
    /// (b) current noise, mA.
    CurrentNoise,
    /// (c) number of images.
    Images,
}

impl Fig6Study {
    /// All three, in the paper's order.
    pub const ALL: [Fig6Study; 3] = [Fig6Study::PixelNoise, Fig6Study::CurrentNoise, Fig6Study::Images];

    /// The levels of the study.
    pub fn levels(self) -> Vec<f64> {
        match self {
            Fig6Study::PixelNoise | Fig6Study::CurrentNoise => (0..=8).map(|k| 0.2 * k as f64).collect(),
            Fig6Study::Images => (3..=15).map(|n| n as f64).collect(),
        }
    }

    fn label(self) -> &'static str {
        match self {
            Fig6Study::PixelNoise => "(a) pixel noise (px)",
            Fig6Study::CurrentNoise => "(b) current noise (mA)",
            Fig6Study::Images => "(c) images",
        }
    }

    fn key(self) -> &'static str {
        match self {
            Fig6Study::PixelNoise => "pixel_noise",
            Fig6Study::CurrentNoise => "current_noise",
            Fig6Study::Images => "images",
        }
    }

    /// The noise model at `level`.
    pub fn noise(self, level: f64) -> NoiseModel {
        let mut n = NoiseModel::PAPER;
        match self {
            Fig6Study::PixelNoise => n.px = level,
            Fig6Study::CurrentNoise => n.e_ma = level,
            Fig6Study::Images => {}
        }
        n
    }
}

/// Summary of one estimator at one level: means over the trials that calibrated.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct LevelSummary {
    /// Trials that calibrated.
    pub trials: usize,
    /// Trials whose calibration failed (reported, not hidden).
    pub failures: usize,
    /// Mean errors (every field of [`ModelErrors`]).
    pub mean: ModelErrors,
    /// Standard error of each mean: the trials' sample std / sqrt(trials).
    pub se: ModelErrors,
    /// 95th percentile of the max relative error of fx(E).
    pub fx_curve_max_rel_p95: f64,
    /// Mean PnP error of the 2 mm move at [`PNP_E_MA`], um.
    pub pnp_um: f64,
    /// Standard error of `pnp_um`, um.
    pub pnp_um_se: f64,
    /// Mean LM iterations.
    pub iterations: f64,
}

/// The Cramer-Rao bound at one level.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct LevelBound {
    /// Mean-absolute-equivalent relative bound of kf1x..kf3y, recorded Z_W and E exact
    /// (NaN without pixel noise).
    pub kf_rel_pixel_only: [f64; 6],
    /// The same with the per-view unknowns of the stated noise model.
    pub kf_rel_full: [f64; 6],
    /// Max relative std of fx(E), pixel noise only.
    pub fx_curve_rel_pixel_only: f64,
    /// Max relative std of fx(E), full model.
    pub fx_curve_rel_full: f64,
}

/// One level of one study.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Fig6Level {
    /// The level (px, mA or images).
    pub level: f64,
    /// The paper's estimator.
    pub paper: LevelSummary,
    /// Errors-in-variables.
    pub eiv: LevelSummary,
    /// The bound.
    pub bound: LevelBound,
}

/// The result of `etlcal study fig6`.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Fig6 {
    /// Trials per level.
    pub trials: usize,
    /// Per study, its levels.
    pub studies: Vec<(Fig6Study, Vec<Fig6Level>)>,
    /// Wall time, s; `None` when the options ask for outputs without it
    /// ([`StudyOptions::wall_time`]): the JSON's "seconds" is then null.
    pub seconds: Option<f64>,
}

struct TrialOut {
    paper: ModelErrors,
    eiv: ModelErrors,
    pnp_um: [f64; 2],
    iterations: [usize; 2],
}

fn trial(study: Fig6Study, level: f64, seed: u64) -> Result<TrialOut> {
    let noise = study.noise(level);
    let mut sim = paper_rig(&noise, seed);
    if study == Fig6Study::Images {
        let n = level as usize;
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x1a9e_5000 ^ n as u64);
        let mut keep = rand::seq::index::sample(&mut rng, sim.observations.views.len(), n).into_vec();
        keep.sort_unstable();
        let views = std::mem::take(&mut sim.observations.views);
        sim.observations.views = keep.into_iter().filter_map(|i| views.get(i).cloned()).collect();
    }
    let fit = calibrate_pair(&sim.observations, &sim.a0, noise.z_mm.max(1e-4), noise.e_ma.max(0.01))?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x9a11_2250);
    let mv = move_observations(&sim.truth, PNP_E_MA, &NoiseModel::PAPER, &mut rng);
    Ok(TrialOut {
        paper: model_errors(&fit.paper.model, &sim.truth),
        eiv: model_errors(&fit.eiv.model, &sim.truth),
        pnp_um: [
            pnp_move_error_um(&fit.paper.model, PNP_E_MA, &mv)?,
            pnp_move_error_um(&fit.eiv.model, PNP_E_MA, &mv)?,
        ],
        iterations: [fit.paper.iterations, fit.eiv.iterations],
    })
}

fn summarise(outs: &[&Result<TrialOut>], pick: impl Fn(&TrialOut) -> (ModelErrors, f64, usize)) -> LevelSummary {
    let ok: Vec<(ModelErrors, f64, usize)> = outs.iter().filter_map(|r| r.as_ref().ok()).map(&pick).collect();
    let n = ok.len().max(1) as f64;
    // Each field's mean, or its standard error (sample std / sqrt(n)) with `se`.
    let moment = |f: &dyn Fn(&ModelErrors) -> f64, se: bool| {
        let values: Vec<f64> = ok.iter().map(|o| f(&o.0)).collect();
        let s = stat(&values);
        if se {
            s.std / n.sqrt()
        } else {
            s.mean
        }
    };
    let errors = |se: bool| ModelErrors {
        kf_rel: core::array::from_fn(|k| moment(&|m| m.kf_rel[k], se)),
        om_rel: moment(&|m| m.om_rel, se),
        t_rel: moment(&|m| m.t_rel, se),
        fx_curve_max_rel: moment(&|m| m.fx_curve_max_rel, se),
        fy_curve_max_rel: moment(&|m| m.fy_curve_max_rel, se),
        principal_point_px: moment(&|m| m.principal_point_px, se),
    };
    let (mean, se) = (errors(false), errors(true));
    let pnp = stat(&ok.iter().map(|o| o.1).collect::<Vec<_>>());
    let fx: Vec<f64> = ok.iter().map(|o| o.0.fx_curve_max_rel).collect();
    LevelSummary {
        trials: ok.len(),
        failures: outs.len() - ok.len(),
        mean,
        se,
        fx_curve_max_rel_p95: stat(&fx).p95,
        pnp_um: pnp.mean,
        pnp_um_se: pnp.std / n.sqrt(),
        iterations: ok.iter().map(|o| o.2 as f64).sum::<f64>() / n,
    }
}

/// The Cramer-Rao bound of `study` at `level` (see the module docs).
pub fn level_bound(study: Fig6Study, level: f64) -> Result<LevelBound> {
    let truth = CameraModel::paper_rig();
    let sim = paper_rig(&NoiseModel::NONE, 0);
    let pts = core_points(&sim);
    let mut views: Vec<View<'_>> =
        pts.iter().zip(PAPER_E_COM_MA).map(|(p, e)| View { e_com_ma: e, points: p }).collect();
    if study == Fig6Study::Images {
        let n = level as usize;
        let last = (views.len() - 1) as f64;
        let keep: Vec<usize> = (0..n).map(|k| (last * k as f64 / (n - 1).max(1) as f64).round() as usize).collect();
        views = keep.into_iter().filter_map(|i| views.get(i).copied()).collect();
    }
    let noise = study.noise(level);
    let x = super::common::truth_params();
    let rel = |cov: &[[f64; MAX_PARAMS]; MAX_PARAMS]| -> [f64; 6] {
        let (kx, ky) = (Layout::PAPER.kf_x(), Layout::PAPER.kf_y());
        let idx = [kx.at(1), kx.at(2), kx.at(3), ky.at(1), ky.at(2), ky.at(3)];
        core::array::from_fn(|k| MEAN_ABS_OF_STD * cov[idx[k]][idx[k]].max(0.0).sqrt() / x[idx[k]].abs())
    };
    if noise.px <= 0.0 {
        return Ok(LevelBound {
            kf_rel_pixel_only: [f64::NAN; 6],
            kf_rel_full: [f64::NAN; 6],
            fx_curve_rel_pixel_only: f64::NAN,
            fx_curve_rel_full: f64::NAN,
        });
    }
    let plain = crlb_covariance_eiv(&views, &truth, noise.px, None)?;
    let full = crlb_covariance_eiv(&views, &truth, noise.px, Some((noise.z_mm.max(1e-6), noise.e_ma.max(1e-6))))?;
    Ok(LevelBound {
        kf_rel_pixel_only: rel(&plain),
        kf_rel_full: rel(&full),
        fx_curve_rel_pixel_only: fx_curve_rel_std(&plain, &truth),
        fx_curve_rel_full: fx_curve_rel_std(&full, &truth),
    })
}

/// Runs the three studies with `opts.trials` trials per level (default 100).
pub fn fig6(opts: &StudyOptions) -> Result<Fig6> {
    fig6_of(&Fig6Study::ALL, opts)
}

/// Runs the given studies (see [`fig6`]).
///
/// ```
/// use etl_studies::fig6::{fig6_of, Fig6Study};
/// use etl_studies::StudyOptions;
/// let opts = StudyOptions { trials: 2, seed: 1, ..Default::default() };
/// let r = fig6_of(&[Fig6Study::CurrentNoise], &opts).unwrap();
/// let levels = &r.studies[0].1;
/// assert_eq!(levels.len(), 9); // 0..1.6 mA by 0.2
/// // At 1.6 mA of current noise errors-in-variables keeps the fx(E) curve far closer.
/// let top = &levels[8];
/// assert!(top.eiv.mean.fx_curve_max_rel < top.paper.mean.fx_curve_max_rel);
/// ```
pub fn fig6_of(studies: &[Fig6Study], opts: &StudyOptions) -> Result<Fig6> {
    let start = std::time::Instant::now();
    let trials = opts.trials_or(DEFAULT_TRIALS);
    let mut jobs = vec![];
    for (s, study) in studies.iter().enumerate() {
        for (l, level) in study.levels().into_iter().enumerate() {
            for t in 0..trials {
                jobs.push((s, l, *study, level, t));
            }
        }
    }
    let outs =
        run_jobs("fig6", &jobs, opts.progress, |&(_, _, study, level, t)| trial(study, level, opts.trial_seed(t)));
    // The bounds are independent of the trials: computed in parallel too.
    let at_levels: Vec<(Fig6Study, f64)> =
        studies.iter().flat_map(|s| s.levels().into_iter().map(move |l| (*s, l))).collect();
    let mut bounds = at_levels.par_iter().map(|&(s, l)| level_bound(s, l)).collect::<Result<Vec<_>>>()?.into_iter();
    let mut result = vec![];
    for (s, study) in studies.iter().enumerate() {
        let mut levels = vec![];
        for (l, level) in study.levels().into_iter().enumerate() {
            let at: Vec<&Result<TrialOut>> =
                jobs.iter().zip(&outs).filter(|(j, _)| j.0 == s && j.1 == l).map(|(_, o)| o).collect();
            levels.push(Fig6Level {
                level,
                paper: summarise(&at, |o| (o.paper, o.pnp_um[0], o.iterations[0])),
                eiv: summarise(&at, |o| (o.eiv, o.pnp_um[1], o.iterations[1])),
                bound: bounds.next().ok_or_else(|| etl_formats::Error::invalid("fig6", "fig6: missing bound"))?,
            });
        }
        result.push((*study, levels));
    }
    let seconds = opts.wall_time.then(|| start.elapsed().as_secs_f64());
    Ok(Fig6 { trials, studies: result, seconds })
}

fn summary_json(s: &LevelSummary) -> Value {
    let mut j = json!({
        "trials": s.trials, "failures": s.failures,
        "om_rel": s.mean.om_rel, "t_rel": s.mean.t_rel,
        "fx_curve_max_rel": s.mean.fx_curve_max_rel, "fx_curve_max_rel_p95": s.fx_curve_max_rel_p95,
        "fy_curve_max_rel": s.mean.fy_curve_max_rel, "principal_point_px": s.mean.principal_point_px,
        "pnp_225ma_um": s.pnp_um, "iterations": s.iterations,
    });
    for (k, name) in KF_NAMES.iter().enumerate() {
        j[format!("{name}_rel")] = json!(s.mean.kf_rel[k]);
        j[format!("{name}_rel_se")] = json!(s.se.kf_rel[k]);
    }
    // The standard error of every mean, as `<key>_se`.
    for (key, se) in [
        ("om_rel_se", s.se.om_rel),
        ("t_rel_se", s.se.t_rel),
        ("fx_curve_max_rel_se", s.se.fx_curve_max_rel),
        ("fy_curve_max_rel_se", s.se.fy_curve_max_rel),
        ("principal_point_px_se", s.se.principal_point_px),
        ("pnp_225ma_um_se", s.pnp_um_se),
    ] {
        j[key] = json!(se);
    }
    j
}

impl Fig6 {
    /// Whether errors-in-variables has a lower mean fx(E) and fy(E) curve error than the plain
    /// estimator at every level of study (b) above 0.4 mA (the acceptance); None when
    /// study (b) was not run.
    pub fn eiv_lowers_current_noise_curves(&self) -> Option<bool> {
        let (_, levels) = self.studies.iter().find(|(s, _)| *s == Fig6Study::CurrentNoise)?;
        Some(levels.iter().filter(|l| l.level > 0.4 + 1e-9).all(|l| {
            l.eiv.mean.fx_curve_max_rel < l.paper.mean.fx_curve_max_rel
                && l.eiv.mean.fy_curve_max_rel < l.paper.mean.fy_curve_max_rel
        }))
    }

    /// JSON, markdown and plots.
    pub fn output(&self) -> StudyOutput {
        let mut j = json!({ "trials_per_level": self.trials, "seconds": self.seconds,
            "eiv_lowers_current_noise_curves_above_0_4ma": self.eiv_lowers_current_noise_curves() });
        let mut md = format!(
            "# Fig. 6: estimation errors against pixel noise, current noise and number of images\n\n\
             {} trials per level, the paper's noise model otherwise (docs/METHOD.md); each trial a full calibration from the \
             linear initialisation. Coefficient columns: mean relative error (the paper's measure); CRLB rows: the mean \
             absolute relative error the Cramer-Rao bound implies (Gaussian), with pixel noise only (Z_W, E exact) and \
             with the full model (per-view dZ, dE unknown). Curve errors: max over 80..225 mA; PnP: a 2 mm move at 225 mA. \
             Uncertainty: every estimator's number is a mean over the trials; the tables of errors users feel give its \
             standard error (± std / sqrt(trials)), and fig6.json gives it for every mean (keys `*_se`).\n",
            self.trials
        );
        let mut figures = vec![];
        for (study, levels) in &self.studies {
            let mut rows = vec![];
            let mut table = vec![];
            for l in levels {
                let mut push = |name: &str, kf: [f64; 6], om: f64, t: f64| {
                    let mut r = vec![format!("{:.1}", l.level), name.to_string()];
                    r.extend(kf.iter().map(|v| pct(*v)));
                    r.push(pct(om));
                    r.push(pct(t));
                    table.push(r);
                };
                push("paper BA", l.paper.mean.kf_rel, l.paper.mean.om_rel, l.paper.mean.t_rel);
                push("eiv BA", l.eiv.mean.kf_rel, l.eiv.mean.om_rel, l.eiv.mean.t_rel);
                push("CRLB pixel only", l.bound.kf_rel_pixel_only, f64::NAN, f64::NAN);
                push("CRLB full", l.bound.kf_rel_full, f64::NAN, f64::NAN);
                let mut jr = json!({ "level": l.level, "paper": summary_json(&l.paper), "eiv": summary_json(&l.eiv),
                    "crlb": { "fx_curve_rel_pixel_only": l.bound.fx_curve_rel_pixel_only,
                              "fx_curve_rel_full": l.bound.fx_curve_rel_full } });
                for (k, name) in KF_NAMES.iter().enumerate() {
                    jr["crlb"][format!("{name}_rel_pixel_only")] = json!(l.bound.kf_rel_pixel_only[k]);
                    jr["crlb"][format!("{name}_rel_full")] = json!(l.bound.kf_rel_full[k]);
                }
                rows.push(jr);
            }
            j[study.key()] = Value::Array(rows);
            let mut hdr = vec!["level", "estimator"];
            hdr.extend(KF_NAMES);
            hdr.extend(["om", "T"]);
            md += &format!("\n## {}\n\n### The paper's measure\n\n{}", study.label(), md_table(&hdr, &table));
            let felt: Vec<Vec<String>> = levels
                .iter()
                .map(|l| {
                    vec![
                        format!("{:.1}", l.level),
                        pct_se(l.paper.mean.fx_curve_max_rel, l.paper.se.fx_curve_max_rel),
                        pct_se(l.eiv.mean.fx_curve_max_rel, l.eiv.se.fx_curve_max_rel),
                        pct(l.bound.fx_curve_rel_full),
                        pct_se(l.paper.mean.fy_curve_max_rel, l.paper.se.fy_curve_max_rel),
                        pct_se(l.eiv.mean.fy_curve_max_rel, l.eiv.se.fy_curve_max_rel),
                        format!(
                            "{:.2} ± {:.2} / {:.2} ± {:.2}",
                            l.paper.mean.principal_point_px,
                            l.paper.se.principal_point_px,
                            l.eiv.mean.principal_point_px,
                            l.eiv.se.principal_point_px
                        ),
                        format!(
                            "{:.1} ± {:.1} / {:.1} ± {:.1}",
                            l.paper.pnp_um, l.paper.pnp_um_se, l.eiv.pnp_um, l.eiv.pnp_um_se
                        ),
                        format!("{} / {}", l.paper.failures, l.eiv.failures),
                    ]
                })
                .collect();
            md += &format!(
                "\n### Errors users feel (paper BA / eiv BA)\n\n{}",
                md_table(
                    &[
                        "level",
                        "fx(E) paper",
                        "fx(E) eiv",
                        "fx(E) CRLB full (1 std)",
                        "fy(E) paper",
                        "fy(E) eiv",
                        "principal point (px)",
                        "PnP 2 mm @225 mA (um)",
                        "failures",
                    ],
                    &felt
                )
            );
            figures.push(self.figure(*study, levels));
        }
        if let Some(ok) = self.eiv_lowers_current_noise_curves() {
            md += &format!(
                "\nErrors-in-variables lowers the fx(E), fy(E) curve errors of study (b) at every level above 0.4 mA: {}.\n",
                if ok { "yes" } else { "**no**" }
            );
        }
        if let Some(s) = self.seconds {
            md += &format!("\n({s:.1} s)\n");
        }
        StudyOutput { name: "fig6".into(), json: j, markdown: md, figures }
    }

    fn figure(&self, study: Fig6Study, levels: &[Fig6Level]) -> Figure {
        let x_label = study.label().trim_start_matches(|c: char| c != ' ').trim().to_string();
        let coef = |pick: &dyn Fn(&Fig6Level) -> &LevelSummary, title: &str| -> Chart {
            let mut series: Vec<Series> = (0..6)
                .map(|k| {
                    Series::line(KF_NAMES[k], k, levels.iter().map(|l| (l.level, pick(l).mean.kf_rel[k])).collect())
                        .with_se(levels.iter().map(|l| pick(l).se.kf_rel[k]).collect())
                })
                .collect();
            series.push(
                Series::line("om", 6, levels.iter().map(|l| (l.level, pick(l).mean.om_rel)).collect())
                    .with_se(levels.iter().map(|l| pick(l).se.om_rel).collect()),
            );
            series.push(
                Series::line("T", 7, levels.iter().map(|l| (l.level, pick(l).mean.t_rel)).collect())
                    .with_se(levels.iter().map(|l| pick(l).se.t_rel).collect()),
            );
            // Its own colour (dashed): kf3x's would make it look like a tenth curve of kf3x.
            series.push(Series::reference(
                "CRLB kf3x (full model)",
                8,
                levels.iter().map(|l| (l.level, l.bound.kf_rel_full[2])).collect(),
            ));
            Chart {
                title: title.into(),
                x_label: x_label.clone(),
                y_label: "mean relative error".into(),
                log_y: true,
                series,
                x_names: vec![],
            }
        };
        let curve = Chart {
            title: "max relative error of fx(E), mean ± 1 s.e.".into(),
            x_label: x_label.clone(),
            y_label: "relative error".into(),
            log_y: true,
            series: vec![
                Series::line("paper BA", 0, levels.iter().map(|l| (l.level, l.paper.mean.fx_curve_max_rel)).collect())
                    .with_se(levels.iter().map(|l| l.paper.se.fx_curve_max_rel).collect()),
                Series::line("eiv BA", 1, levels.iter().map(|l| (l.level, l.eiv.mean.fx_curve_max_rel)).collect())
                    .with_se(levels.iter().map(|l| l.eiv.se.fx_curve_max_rel).collect()),
                Series::reference(
                    "CRLB full (1 std)",
                    2,
                    levels.iter().map(|l| (l.level, l.bound.fx_curve_rel_full)).collect(),
                ),
                Series::reference(
                    "CRLB pixel only (1 std)",
                    3,
                    levels.iter().map(|l| (l.level, l.bound.fx_curve_rel_pixel_only)).collect(),
                ),
            ],
            x_names: vec![],
        };
        let pnp = Chart {
            title: "PnP error of a 2 mm move at 225 mA, mean ± 1 s.e.".into(),
            x_label: x_label.clone(),
            y_label: "error (um)".into(),
            log_y: false,
            series: vec![
                Series::line("paper BA", 0, levels.iter().map(|l| (l.level, l.paper.pnp_um)).collect())
                    .with_se(levels.iter().map(|l| l.paper.pnp_um_se).collect()),
                Series::line("eiv BA", 1, levels.iter().map(|l| (l.level, l.eiv.pnp_um)).collect())
                    .with_se(levels.iter().map(|l| l.eiv.pnp_um_se).collect()),
            ],
            x_names: vec![],
        };
        Figure {
            name: format!("fig6_{}", study.key()),
            grid: (2, 2),
            panels: vec![
                coef(&|l| &l.paper, &format!("{}: paper BA", study.label())),
                coef(&|l| &l.eiv, &format!("{}: eiv BA", study.label())),
                curve,
                pnp,
            ],
        }
    }
}
