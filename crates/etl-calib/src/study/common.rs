//! What every study shares: seeded Monte Carlo trials in parallel (rayon) with a progress
//! bar (indicatif), the errors of an estimate against the truth (the paper's measure and
//! the errors users feel), the full calibration of one simulated data set with both
//! estimators, statistics, plots (plotters) and markdown tables.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use etl_core::calib::jacobian::{to_params, PARAMS};
use etl_core::calib::{
    bundle_adjust, bundle_adjust_scratch, initialise, BundleAdjustOptions, BundleAdjustReport, Estimator, View,
    ViewCorrection, A0,
};
use etl_core::lm::BlockScratch;
use etl_core::model::CameraModel;
use etl_core::pnp::{displacement_mm, solve_pnp};
use etl_core::thermal::ThermalCalibration;
use indicatif::{ProgressBar, ProgressStyle};
use plotters::coord::Shift;
use plotters::prelude::*;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::formats::observations::Observations;
use crate::formats::write_atomic;
use crate::simulate::{focused_z_mm, observe_board, NoiseModel};

/// How a study runs: Monte Carlo trials, the base seed, whether to draw a progress bar.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StudyOptions {
    /// Trials (per level, for studies with levels); 0: the study's default.
    pub trials: usize,
    /// Base seed; trial `i` of every level uses the same derived seed (common random
    /// numbers make the curves over the levels smooth).
    pub seed: u64,
    /// Draw a progress bar on stderr.
    pub progress: bool,
}

impl Default for StudyOptions {
    fn default() -> Self {
        StudyOptions { trials: 0, seed: 1, progress: false }
    }
}

impl StudyOptions {
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

/// Runs `f` on every job in parallel (rayon), with a progress bar labelled `label` when
/// `progress`. Each job's own result is kept (a failed calibration is a result too).
pub fn run_jobs<J, T, F>(label: &str, jobs: &[J], progress: bool, f: F) -> Vec<Result<T>>
where
    J: Sync,
    T: Send,
    F: Fn(&J) -> Result<T> + Sync + Send,
{
    let bar = if progress { ProgressBar::new(jobs.len() as u64) } else { ProgressBar::hidden() };
    if let Ok(style) = ProgressStyle::with_template("{msg:>8} [{elapsed_precise}] {wide_bar} {pos}/{len} (eta {eta})") {
        bar.set_style(style);
    }
    bar.set_message(label.to_string());
    let out = jobs
        .par_iter()
        .map(|j| {
            let r = f(j);
            bar.inc(1);
            r
        })
        .collect();
    bar.finish_and_clear();
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
            rel(est.kf_x[1], truth.kf_x[1]),
            rel(est.kf_x[2], truth.kf_x[2]),
            rel(est.kf_x[3], truth.kf_x[3]),
            rel(est.kf_y[1], truth.kf_y[1]),
            rel(est.kf_y[2], truth.kf_y[2]),
            rel(est.kf_y[3], truth.kf_y[3]),
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
    Ok((obs.core_points(), obs.e_com_ma(&ThermalCalibration::PAPER)?))
}

/// The paper's calibration of `obs` with `a0`: the linear initialisation (RAC, focal
/// polynomial, distortion) then the bundle adjustment of Eq. 24, with the options of
/// `crate::pipeline::calibrate` (the per-view summaries it adds for reports are skipped).
pub fn calibrate_paper(obs: &Observations, a0: &A0) -> Result<BundleAdjustReport> {
    calibrate_paper_capped(obs, a0, BundleAdjustOptions::default().lm.max_iterations)
}

/// [`calibrate_paper`] with the bundle adjustment stopped after at most `max_iterations`
/// LM iterations (to see how far it is from its minimum then).
pub fn calibrate_paper_capped(obs: &Observations, a0: &A0, max_iterations: usize) -> Result<BundleAdjustReport> {
    let (pts, e_com) = core_views(obs)?;
    let views: Vec<View<'_>> = pts.iter().zip(&e_com).map(|(p, &e)| View { e_com_ma: e, points: p }).collect();
    let initial = initialise(&views, a0)?;
    let mut corrections = vec![ViewCorrection::default(); views.len()];
    let mut options = BundleAdjustOptions::default();
    options.lm.max_iterations = max_iterations;
    Ok(bundle_adjust(&views, &initial, &options, &mut corrections, &mut [])?)
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
    let mut corrections = vec![ViewCorrection::default(); views.len()];
    let paper = bundle_adjust(&views, &initial, &BundleAdjustOptions::default(), &mut corrections, &mut [])?;
    let estimator = Estimator::Eiv { sigma_z_mm, sigma_e_ma, sigma_px: None };
    let mut options = BundleAdjustOptions { estimator, ..BundleAdjustOptions::default() };
    options.lm.initial_damping = EIV_INITIAL_DAMPING;
    let mut scratch = vec![BlockScratch::ZERO; bundle_adjust_scratch(views.len(), &estimator)];
    let eiv = bundle_adjust(&views, &paper.model, &options, &mut corrections, &mut scratch)?;
    Ok(PairFit { paper, eiv })
}

/// Mean, standard deviation and 95th percentile of a sample.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Stat {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (n - 1).
    pub std: f64,
    /// 95th percentile (nearest rank).
    pub p95: f64,
}

/// [`Stat`] of `values` (NaN fields when empty).
pub fn stat(values: &[f64]) -> Stat {
    let n = values.len();
    if n == 0 {
        return Stat { mean: f64::NAN, std: f64::NAN, p95: f64::NAN };
    }
    let mean = values.iter().sum::<f64>() / n as f64;
    let var = if n > 1 { values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64 } else { 0.0 };
    let mut s = values.to_vec();
    s.sort_by(f64::total_cmp);
    let k = ((0.95 * n as f64).ceil() as usize).clamp(1, n) - 1;
    Stat { mean, std: var.sqrt(), p95: s[k] }
}

/// Relative std of every parameter and the max relative std of fx(E) over
/// [`RIG_RANGE_MA`] from a covariance of the 25 numbers.
pub fn cov_std(cov: &[[f64; PARAMS]; PARAMS]) -> [f64; PARAMS] {
    core::array::from_fn(|i| cov[i][i].max(0.0).sqrt())
}

/// The standard deviation of fx(E) (px) at `e_ma` from a covariance of the 25 numbers
/// (fx is linear in kf0x..kf3x: var = g^T C g with g = [1, E, E^2, E^3]).
pub fn fx_std_px(cov: &[[f64; PARAMS]; PARAMS], e_ma: f64) -> f64 {
    let g = [1.0, e_ma, e_ma * e_ma, e_ma * e_ma * e_ma];
    let k = etl_core::calib::jacobian::KF0X;
    let mut v = 0.0;
    for i in 0..4 {
        for j in 0..4 {
            v += g[i] * cov[k + i][k + j] * g[j];
        }
    }
    v.max(0.0).sqrt()
}

/// Max over [`RIG_RANGE_MA`] (1 mA steps) of std(fx(E)) / fx(E).
pub fn fx_curve_rel_std(cov: &[[f64; PARAMS]; PARAMS], truth: &CameraModel) -> f64 {
    (RIG_RANGE_MA[0] as usize..=RIG_RANGE_MA[1] as usize)
        .map(|e| fx_std_px(cov, e as f64) / truth.focal_lengths(e as f64).0)
        .fold(0.0, f64::max)
}

/// sqrt(2 / pi): the mean absolute value of a standard normal variable, turning a
/// Cramer-Rao standard deviation into the mean absolute error it implies (Gaussian errors).
pub const MEAN_ABS_OF_STD: f64 = 0.797_884_560_802_865_4;

/// The truth as a parameter vector (order of `PARAM_NAMES`).
pub fn truth_params() -> [f64; PARAMS] {
    to_params(&CameraModel::paper_rig())
}

// ---------------------------------------------------------------- plots

/// One curve of a chart.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// (x, y) points; non-finite y are skipped.
    pub points: Vec<(f64, f64)>,
    /// Index into the palette.
    pub colour: usize,
    /// A thin line without markers (bounds, references) instead of a line with markers.
    pub reference: bool,
    /// Markers only, no line (scatter).
    pub scatter: bool,
}

impl Series {
    /// A line with markers.
    pub fn line(name: impl Into<String>, colour: usize, points: Vec<(f64, f64)>) -> Self {
        Series { name: name.into(), points, colour, reference: false, scatter: false }
    }
    /// A thin reference line (a bound, the paper's value).
    pub fn reference(name: impl Into<String>, colour: usize, points: Vec<(f64, f64)>) -> Self {
        Series { name: name.into(), points, colour, reference: true, scatter: false }
    }
    /// Markers only.
    pub fn scatter(name: impl Into<String>, colour: usize, points: Vec<(f64, f64)>) -> Self {
        Series { name: name.into(), points, colour, reference: false, scatter: true }
    }
}

/// One panel.
#[derive(Debug, Clone)]
pub struct Chart {
    /// Caption.
    pub title: String,
    /// Axis descriptions.
    pub x_label: String,
    /// Axis descriptions.
    pub y_label: String,
    /// Plot log10(y) (positive y only).
    pub log_y: bool,
    /// Curves.
    pub series: Vec<Series>,
}

/// A figure of panels on a grid, written as `name.png` and `name.svg`.
#[derive(Debug, Clone)]
pub struct Figure {
    /// File stem.
    pub name: String,
    /// (rows, columns) of panels.
    pub grid: (usize, usize),
    /// Panels, row by row.
    pub panels: Vec<Chart>,
}

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(90, 90, 90),
];

type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;

fn y_of(c: &Chart, y: f64) -> f64 {
    if c.log_y {
        if y > 0.0 {
            y.log10()
        } else {
            f64::NAN
        }
    } else {
        y
    }
}

fn draw_chart<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, c: &Chart, text: bool) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let pts: Vec<Vec<(f64, f64)>> = c
        .series
        .iter()
        .map(|s| {
            s.points.iter().map(|&(x, y)| (x, y_of(c, y))).filter(|p| p.0.is_finite() && p.1.is_finite()).collect()
        })
        .collect();
    let (mut xl, mut xh, mut yl, mut yh) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for p in pts.iter().flatten() {
        xl = xl.min(p.0);
        xh = xh.max(p.0);
        yl = yl.min(p.1);
        yh = yh.max(p.1);
    }
    if !(xl.is_finite() && yl.is_finite()) {
        (xl, xh, yl, yh) = (0.0, 1.0, 0.0, 1.0);
    }
    let (px, py) = (((xh - xl) * 0.05).max(1e-9), ((yh - yl) * 0.08).max(1e-9 * yh.abs().max(1e-12)));
    let mut b = ChartBuilder::on(area);
    b.margin(10);
    if text {
        b.caption(&c.title, ("sans-serif", 18)).x_label_area_size(40).y_label_area_size(65);
    }
    let mut chart = b.build_cartesian_2d(xl - px..xh + px, yl - py..yh + py)?;
    if text {
        let y_desc = if c.log_y { format!("log10 {}", c.y_label) } else { c.y_label.clone() };
        chart.configure_mesh().x_desc(c.x_label.as_str()).y_desc(y_desc).light_line_style(WHITE).draw()?;
    }
    for (s, p) in c.series.iter().zip(pts) {
        let col = PALETTE[s.colour % PALETTE.len()];
        let legend = move |(x, y): (i32, i32)| PathElement::new(vec![(x, y), (x + 20, y)], col.stroke_width(2));
        if s.scatter {
            chart
                .draw_series(p.iter().map(|q| Circle::new(*q, 3, col.filled())))?
                .label(s.name.as_str())
                .legend(legend);
        } else if s.reference {
            chart.draw_series(LineSeries::new(p, col.mix(0.7).stroke_width(1)))?.label(s.name.as_str()).legend(legend);
        } else {
            chart.draw_series(LineSeries::new(p.clone(), col.stroke_width(2)))?.label(s.name.as_str()).legend(legend);
            chart.draw_series(p.iter().map(|q| Circle::new(*q, 3, col.filled())))?;
        }
    }
    if text {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font(("sans-serif", 12))
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
    }
    Ok(())
}

fn draw_figure<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, f: &Figure, text: bool) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let areas = root.split_evenly(f.grid);
    for (area, c) in areas.iter().zip(&f.panels) {
        draw_chart(area, c, text)?;
    }
    root.present()?;
    Ok(())
}

/// Writes `f` as `dir/name.svg` and `dir/name.png` (atomic writes); returns the paths.
pub fn write_figure(dir: &Path, f: &Figure) -> Result<Vec<PathBuf>> {
    let size = (560 * f.grid.1 as u32, 400 * f.grid.0 as u32);
    let text = crate::report::font_available();
    let fail = |e: Box<dyn std::error::Error>| Error::InvalidInput(format!("plot {}: {e}", f.name));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw_figure(&root, f, text).map_err(fail)?;
    }
    let mut buf = vec![0u8; (size.0 * size.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        draw_figure(&root, f, text).map_err(fail)?;
    }
    let img = image::RgbImage::from_raw(size.0, size.1, buf)
        .ok_or_else(|| Error::InvalidInput(format!("plot {}: bitmap size mismatch", f.name)))?;
    let mut png = std::io::Cursor::new(vec![]);
    img.write_to(&mut png, image::ImageFormat::Png)
        .map_err(|e| Error::InvalidInput(format!("plot {}: PNG encoding: {e}", f.name)))?;
    let (p, s) = (dir.join(format!("{}.png", f.name)), dir.join(format!("{}.svg", f.name)));
    write_atomic(&p, png.get_ref())?;
    write_atomic(&s, svg.as_bytes())?;
    Ok(vec![p, s])
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
    /// Writes `name.json`, `name.md` and every figure into the existing directory `dir`.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let mut files = vec![];
        let j = dir.join(format!("{}.json", self.name));
        let text = serde_json::to_string_pretty(&self.json).map_err(|e| Error::InvalidInput(e.to_string()))?;
        write_atomic(&j, text.as_bytes())?;
        files.push(j);
        let m = dir.join(format!("{}.md", self.name));
        write_atomic(&m, self.markdown.as_bytes())?;
        files.push(m);
        for f in &self.figures {
            files.extend(write_figure(dir, f)?);
        }
        Ok(files)
    }
}
