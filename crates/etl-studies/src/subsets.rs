//! `etlcal study subsets`: the analogue of the paper's Tables 1-2 and Fig. 11. From 9 views
//! of the paper rig (evenly spaced over the 15, the paper's noise model), calibrate (the
//! paper's estimator, from the linear initialisation) with the first 6, 7, 8 and 9 views and
//! with every one of the 84 six-view subsets; per parameter the values and the mean and
//! standard deviation over the subsets; BA iterations; reprojection error before and after
//! BA. Each trial is a fresh data set; the tables show the first.
//!
//! Every subset is calibrated by the paper's estimator and by errors-in-variables (the
//! plain BA leaves the per-view Z_W and E errors in its residuals, so only the latter's
//! reprojection error can equal the pixel noise). "Converged within 5 iterations": the
//! paper's BA stopped after 5 LM iterations is within 0.05 standard deviations (its own
//! formal std) of its minimum in every parameter, and its RMS within 1e-4 relative.
//!
//! The figure shows k1, p1, p2 against the current: the truth, the first 6..9 views of the
//! first data set and, over every data set, the mean of the 84 six-view subsets with its
//! standard error over the data sets (error bars) and the subsets' spread (± 1 std within a
//! data set, root mean square over the data sets: a band).
//!
//! Reprojection error is given per point (sqrt(mean |e|^2), what `etlcal calibrate`
//! reports) and per coordinate (that divided by sqrt 2: the estimate of the pixel noise's
//! standard deviation, comparable to the noise level).

use etl_core::model::CameraModel;
use serde_json::{json, Value};

use super::common::{
    calibrate_pair, calibrate_paper_capped, md_table, paper_params, param_name, run_jobs, sci, stat, truth_params,
    Chart, Figure, Series, StudyOptions, StudyOutput, PARAMS,
};
use etl_formats::Result;
use etl_sim::simulate::{paper_rig, NoiseModel, PAPER_E_COM_MA};

/// Default trials (data sets).
pub const DEFAULT_TRIALS: usize = 5;
/// The 9 views of the study, as indices into the paper rig's 15.
pub const NINE_VIEWS: [usize; 9] = [0, 2, 4, 5, 7, 9, 10, 12, 14];

/// One calibration of a subset.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SubsetFit {
    /// Bit k set: the k-th of the 9 views is used.
    pub mask: u16,
    /// The 25 numbers (paper's BA).
    #[serde(skip)]
    pub params: [f64; PARAMS],
    /// LM iterations of the paper's BA to its stop (ftol 1e-10).
    pub iterations: usize,
    /// RMS reprojection error per point before BA (the linear initialisation), px.
    pub initial_rms_px: f64,
    /// RMS reprojection error per point after the paper's BA, px.
    pub rms_px: f64,
    /// After 5 iterations of the paper's BA: largest |parameter - converged| / formal std.
    pub shift_after_5_std: f64,
    /// After 5 iterations: RMS / converged RMS - 1.
    pub rms_excess_after_5: f64,
    /// LM iterations of the errors-in-variables stage.
    pub eiv_iterations: usize,
    /// RMS reprojection error per point after errors-in-variables (corrections applied), px.
    pub eiv_rms_px: f64,
}

/// Most parameter shift (in formal std) and relative RMS excess after 5 iterations that
/// count as converged.
pub const CONVERGED_WITHIN: (f64, f64) = (0.05, 1e-4);

impl SubsetFit {
    /// The views used (1-based, in the 9).
    pub fn label(&self) -> String {
        (0..9).filter(|k| self.mask & (1 << k) != 0).map(|k| (k + 1).to_string()).collect()
    }
}

/// The result of `etlcal study subsets`.
#[derive(Debug, Clone)]
pub struct Subsets {
    /// Data sets.
    pub trials: usize,
    /// Pixel noise of the data, px.
    pub noise_px: f64,
    /// Per data set: the first 6, 7, 8, 9 views, then the 84 six-view subsets.
    pub fits: Vec<Vec<SubsetFit>>,
    /// Calibrations that failed (with the reason).
    pub failures: Vec<String>,
}

/// The first k views for k = 6..9, then every six-view subset of the 9, as masks.
pub fn masks() -> Vec<u16> {
    let mut m: Vec<u16> = (6..=9).map(|k| (1u16 << k) - 1).collect();
    m.extend((0u16..512).filter(|x| x.count_ones() == 6));
    m
}

/// Runs the study (`opts.trials` data sets, default 5).
pub fn subsets(opts: &StudyOptions) -> Result<Subsets> {
    let trials = opts.trials_or(DEFAULT_TRIALS);
    let noise = NoiseModel::PAPER;
    let sims: Vec<_> = (0..trials).map(|t| paper_rig(&noise, opts.trial_seed(t))).collect();
    let masks = masks();
    let jobs: Vec<(usize, u16)> = (0..trials).flat_map(|t| masks.iter().map(move |&m| (t, m))).collect();
    let outs = run_jobs("subsets", &jobs, opts.progress, |&(t, mask)| {
        let sim = &sims[t];
        let mut obs = sim.observations.clone();
        obs.views = NINE_VIEWS
            .iter()
            .enumerate()
            .filter(|(k, _)| mask & (1 << k) != 0)
            .filter_map(|(_, &i)| sim.observations.views.get(i).cloned())
            .collect();
        let pair = calibrate_pair(&obs, &sim.a0, noise.z_mm, noise.e_ma)?;
        let r = &pair.paper;
        let five = calibrate_paper_capped(&obs, &sim.a0, 5)?;
        let (x, x5) = (paper_params(&r.model), paper_params(&five.model));
        let shift = (0..PARAMS).map(|i| (x5[i] - x[i]).abs() / r.std[i].max(1e-300)).fold(0.0, f64::max);
        Ok(SubsetFit {
            mask,
            params: x,
            iterations: r.iterations,
            initial_rms_px: r.initial_rms_px,
            rms_px: r.rms_px,
            shift_after_5_std: shift,
            rms_excess_after_5: five.rms_px / r.rms_px - 1.0,
            eiv_iterations: pair.eiv.iterations,
            eiv_rms_px: pair.eiv.rms_px,
        })
    });
    let mut fits = vec![vec![]; trials];
    let mut failures = vec![];
    for ((t, mask), o) in jobs.iter().zip(outs) {
        match o {
            Ok(f) => fits[*t].push(f),
            Err(e) => failures.push(format!("data set {t}, views {mask:09b}: {e}")),
        }
    }
    Ok(Subsets { trials, noise_px: noise.px, fits, failures })
}

impl Subsets {
    fn all(&self) -> impl Iterator<Item = &SubsetFit> {
        self.fits.iter().flatten()
    }

    /// Most BA iterations over every calibration (paper's BA to its stop).
    pub fn max_iterations(&self) -> usize {
        self.all().map(|f| f.iterations).max().unwrap_or(0)
    }

    /// Whether every calibration's paper BA is converged after 5 iterations
    /// ([`CONVERGED_WITHIN`]).
    pub fn converged_within_5(&self) -> bool {
        self.all().all(|f| f.shift_after_5_std <= CONVERGED_WITHIN.0 && f.rms_excess_after_5 <= CONVERGED_WITHIN.1)
    }

    /// Largest parameter shift (formal std) and RMS excess after 5 iterations.
    pub fn worst_after_5(&self) -> (f64, f64) {
        self.all().fold((0.0f64, 0.0f64), |(a, b), f| (a.max(f.shift_after_5_std), b.max(f.rms_excess_after_5)))
    }

    /// Smallest and largest per-coordinate RMS after BA over every calibration, px:
    /// (paper's BA, errors-in-variables).
    pub fn per_coordinate_rms_range_px(&self) -> [(f64, f64); 2] {
        let range = |f: &dyn Fn(&SubsetFit) -> f64| {
            self.all()
                .map(|s| f(s) / std::f64::consts::SQRT_2)
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
        };
        [range(&|s| s.rms_px), range(&|s| s.eiv_rms_px)]
    }

    /// Mean and std over the six-view subsets of data set `t`, per parameter.
    pub fn six_view_stats(&self, t: usize) -> Vec<(f64, f64)> {
        let six: Vec<&SubsetFit> = self.fits.get(t).into_iter().flatten().skip(4).collect();
        (0..PARAMS)
            .map(|i| {
                let s = stat(&six.iter().map(|f| f.params[i]).collect::<Vec<_>>());
                (s.mean, s.std)
            })
            .collect()
    }

    /// JSON, markdown and plots.
    pub fn output(&self) -> StudyOutput {
        let truth = truth_params();
        let first: &[SubsetFit] = self.fits.first().map_or(&[], |v| v.as_slice());
        let numbers: Vec<&SubsetFit> = first.iter().take(4).collect();
        let six: Vec<&SubsetFit> = first.iter().skip(4).collect();
        let stats = self.six_view_stats(0);
        let mut rows = vec![];
        for i in 0..PARAMS {
            let mut r = vec![param_name(i).to_string(), sci(truth[i])];
            r.extend(numbers.iter().map(|f| sci(f.params[i])));
            r.push(sci(stats[i].0));
            r.push(sci(stats[i].1));
            rows.push(r);
        }
        let six_stat = |f: &dyn Fn(&SubsetFit) -> f64| stat(&six.iter().map(|s| f(s)).collect::<Vec<_>>());
        let mut extra = |name: &str, f: &dyn Fn(&SubsetFit) -> f64, fmt: &dyn Fn(f64) -> String| {
            let mut r = vec![name.to_string(), "".into()];
            r.extend(numbers.iter().map(|s| fmt(f(s))));
            let st = six_stat(f);
            r.push(fmt(st.mean));
            r.push(fmt(st.std));
            rows.push(r);
        };
        extra("RMS before BA (px/point)", &|s| s.initial_rms_px, &|v| format!("{v:.4}"));
        extra("RMS after BA (px/point)", &|s| s.rms_px, &|v| format!("{v:.4}"));
        extra("RMS after BA (px/coordinate)", &|s| s.rms_px / std::f64::consts::SQRT_2, &|v| format!("{v:.4}"));
        extra("RMS after eiv BA (px/coordinate)", &|s| s.eiv_rms_px / std::f64::consts::SQRT_2, &|v| format!("{v:.4}"));
        extra("BA iterations to ftol 1e-10", &|s| s.iterations as f64, &|v| format!("{v:.1}"));
        extra("after 5 iterations: max shift (std)", &|s| s.shift_after_5_std, &|v| format!("{v:.2e}"));
        let [(lo, hi), (elo, ehi)] = self.per_coordinate_rms_range_px();
        let (shift5, excess5) = self.worst_after_5();
        let n_all = self.all().count();
        let iters_ok = self.converged_within_5();
        let rms_ok = elo >= 0.9 * self.noise_px && ehi <= 1.1 * self.noise_px;
        let md = format!(
            "# Tables 1-2, Fig. 11: calibrating with 6..9 of 9 views and with all 84 six-view subsets\n\n\
             The paper rig's views {} (of 15), the paper's noise model, the paper's estimator from the linear \
             initialisation. {} data sets, {} calibrations ({} failed). Columns 6..9: the first k views of data set 1; \
             last two: mean and std over its 84 six-view subsets.\n\n{}\n\
             Over all {} calibrations: the paper's BA stops (ftol 1e-10) after at most {} iterations; after 5 iterations \
             it is within {:.2e} formal std of its minimum in every parameter and {:.1e} of its RMS (converged within 5 \
             iterations by the criterion above, as the acceptance asks: {}). Per-coordinate RMS after BA: paper's BA {:.4} .. {:.4} \
             px (the per-view Z_W and E errors stay in its residuals), errors-in-variables {:.4} .. {:.4} px, against \
             the pixel noise {} px (within 10 %: {}). The paper: 2-3 iterations (its Table 1 shows 5), 0.4 px -> 0.23 px.\n\n\
             Figure `subsets_distortion` (the paper's Fig. 11): k1, p1, p2 against E_com; the truth, the first 6..9 views \
             of data set 1, and over the {} data sets the mean of the 84 six-view subsets ± one standard error over the \
             data sets (bars) with the subsets' spread, ± 1 std within a data set (band; `distortion_band` in \
             subsets.json).\n",
            NINE_VIEWS.iter().map(|i| (i + 1).to_string()).collect::<Vec<_>>().join(", "),
            self.trials,
            n_all + self.failures.len(),
            self.failures.len(),
            md_table(&["parameter", "truth", "6 views", "7 views", "8 views", "9 views", "84 x 6: mean", "84 x 6: std"], &rows),
            n_all,
            self.max_iterations(),
            shift5,
            excess5,
            if iters_ok { "yes" } else { "**no**" },
            lo,
            hi,
            elo,
            ehi,
            self.noise_px,
            if rms_ok { "yes" } else { "**no**" },
            self.fits.iter().filter(|f| f.len() > 4).count(),
        );
        let param_obj = |p: &[f64; PARAMS]| -> Value {
            Value::Object((0..PARAMS).map(param_name).zip(p).map(|(n, v)| (n.to_string(), json!(v))).collect())
        };
        let j = json!({
            "views_of_15": NINE_VIEWS,
            "trials": self.trials,
            "numbers_of_views": numbers.iter().zip(6..).map(|(f, k)| json!({
                "views": k, "iterations": f.iterations, "initial_rms_px": f.initial_rms_px, "rms_px": f.rms_px,
                "parameters": param_obj(&f.params)})).collect::<Vec<_>>(),
            "six_view_subsets": {
                "count": six.len(),
                "parameters": (0..PARAMS).map(|i| json!({"name": param_name(i), "truth": truth[i],
                    "mean": stats[i].0, "std": stats[i].1})).collect::<Vec<_>>(),
                "subsets": six.iter().map(|f| json!({"views": f.label(), "iterations": f.iterations,
                    "initial_rms_px": f.initial_rms_px, "rms_px": f.rms_px, "eiv_rms_px": f.eiv_rms_px,
                    "shift_after_5_iterations_std": f.shift_after_5_std})).collect::<Vec<_>>(),
            },
            "all_calibrations": {"count": n_all, "failures": self.failures, "max_iterations": self.max_iterations(),
                "max_shift_after_5_iterations_std": shift5, "max_rms_excess_after_5_iterations": excess5,
                "rms_per_coordinate_px_min": lo, "rms_per_coordinate_px_max": hi,
                "eiv_rms_per_coordinate_px_min": elo, "eiv_rms_per_coordinate_px_max": ehi, "noise_px": self.noise_px},
            "checks": {"converged_within_5_iterations": iters_ok, "eiv_rms_within_10_percent_of_noise": rms_ok},
            "distortion_band": self.band_json(),
        });
        StudyOutput { name: "subsets".into(), json: j, markdown: md, figures: vec![self.figure(&numbers)] }
    }

    /// The distortion coefficient `k` (0: k1, 1: p1, 2: p2, in the figure's units: x 1e9,
    /// x 1e6, x 1e6) of a parameter vector at `e_ma` (NaN where the model cannot say).
    fn coefficient(p: &[f64; PARAMS], e_ma: f64, k: usize) -> f64 {
        let m: CameraModel = etl_core::calib::jacobian::from_params(&etl_core::calib::Layout::PAPER, p);
        m.distortion(e_ma).map_or(f64::NAN, |d| d.padded()[k]) * BAND_SCALE[k]
    }

    /// The six-view subsets' band of coefficient `k` (0: k1, 1: p1, 2: p2, in the figure's units) at each of
    /// [`band_currents`]: (mean over the data sets of each data set's subset mean, its
    /// standard error over the data sets (NaN below 2 data sets), the root mean square over
    /// the data sets of the std over a data set's subsets).
    pub fn band(&self, k: usize) -> Vec<(f64, f64, f64)> {
        band_currents()
            .iter()
            .map(|&e| {
                let per_set: Vec<(f64, f64)> = self
                    .fits
                    .iter()
                    .map(|fits| {
                        let s =
                            stat(&fits.iter().skip(4).map(|f| Self::coefficient(&f.params, e, k)).collect::<Vec<_>>());
                        (s.mean, s.std)
                    })
                    .filter(|(m, _)| m.is_finite())
                    .collect();
                let means = stat(&per_set.iter().map(|p| p.0).collect::<Vec<_>>());
                let spread = (per_set.iter().map(|p| p.1 * p.1).sum::<f64>() / per_set.len().max(1) as f64).sqrt();
                (means.mean, means.mean_se, spread)
            })
            .collect()
    }

    /// The figure's band ([`Self::band`]) of k1, p1, p2 as JSON: per coefficient its name,
    /// unit, the currents and the means, their standard errors and the spreads.
    fn band_json(&self) -> Value {
        let bands = (0..3).map(|k| {
            let band = self.band(k);
            json!({"coefficient": BAND_NAMES[k], "unit": BAND_UNITS[k], "e_com_ma": band_currents(),
                "mean": band.iter().map(|b| b.0).collect::<Vec<_>>(),
                "mean_se": band.iter().map(|b| b.1).collect::<Vec<_>>(),
                "spread_std": band.iter().map(|b| b.2).collect::<Vec<_>>()})
        });
        Value::Array(bands.collect())
    }

    /// The paper's Fig. 11: k1, p1, p2 against the current, one panel each (the module
    /// doc says what is drawn); `numbers`: the first 6..9 views of data set 1.
    fn figure(&self, numbers: &[&SubsetFit]) -> Figure {
        let es = band_currents();
        let truth = truth_params();
        let sets = self.fits.iter().filter(|f| f.len() > 4).count();
        let panels = (0..3)
            .map(|k| {
                let band = self.band(k);
                let mean: Vec<(f64, f64)> = es.iter().zip(&band).map(|(e, b)| (*e, b.0)).collect();
                let mut series = vec![
                    Series::band("subsets: ± 1 std (spread)", 4, mean.clone(), band.iter().map(|b| b.2).collect()),
                    Series::reference("truth", 7, es.iter().map(|&e| (e, Self::coefficient(&truth, e, k))).collect()),
                ];
                for (f, n) in numbers.iter().zip(6..) {
                    series.push(Series::reference(
                        format!("first {n} views (set 1)"),
                        n - 6,
                        es.iter().map(|&e| (e, Self::coefficient(&f.params, e, k))).collect(),
                    ));
                }
                series.push(
                    Series::line(format!("subsets: mean ± 1 s.e. ({sets} sets)"), 4, mean)
                        .with_se(band.iter().map(|b| b.1).collect()),
                );
                Chart {
                    title: format!("{}(E): 84 six-view subsets of 9 views, the first 6..9, the truth", BAND_NAMES[k]),
                    x_label: "E_com (mA)".into(),
                    y_label: BAND_UNITS[k].into(),
                    log_y: false,
                    series,
                    x_names: vec![],
                }
            })
            .collect();
        Figure { name: "subsets_distortion".into(), grid: (3, 1), panels }
    }
}

/// The currents of the figure and of the JSON's band, mA: the rig's 80..225 by 5.
pub fn band_currents() -> Vec<f64> {
    (0..=29).map(|k| PAPER_E_COM_MA[0] + 5.0 * k as f64).collect()
}

/// The band's coefficients: names, units (as scaled) and scales.
const BAND_NAMES: [&str; 3] = ["k1", "p1", "p2"];
const BAND_UNITS: [&str; 3] = ["k1 (1e-9 / px^2)", "p1 (1e-6 / px)", "p2 (1e-6 / px)"];
const BAND_SCALE: [f64; 3] = [1e9, 1e6, 1e6];
