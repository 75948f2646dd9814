//! The temperature-calibration procedure of the paper's section 4.1 (Fig. 4): for each
//! driver current E_in on a grid, with the board in focus at the first temperature, raise
//! the lens temperature step by step, refocus by maximising image sharpness at every step,
//! and record E_T = refocused E_in - the E_in in focus at the first temperature; then fit
//! the cubic surface E_T(T, E_in) (Eq. 7).
//!
//! The procedure talks to hardware through three traits, so that the real rig and the
//! virtual one (`etl_sim::virtual_rig`) run the same code: a [`Lens`] (set the current, read the
//! temperature), a [`Camera`] (grab a frame; place the board in focus for a grid current),
//! and a [`Climate`] (bring the lens to a temperature and wait until it is there).
//!
//! Choices (the paper is silent):
//! - E_T is referenced to the refocus at the first temperature of each grid current (not to
//!   the commanded grid current), so that the sharpness measure's own small bias cancels;
//!   E_T(T_first, E_in) = 0 by construction. The samples are recorded at the *refocused*
//!   current (E_com = E_in - E_T holds at the E_in the driver is actually given).
//! - The sharpness measure defaults to Tenengrad, not the paper's CPBD: on a checkerboard
//!   CPBD falls to 0 beyond about 1 px of blur (`sharpness::cpbd`), so its capture range is
//!   too narrow for a search of +-20 mA; of the gradient measures Tenengrad is the least
//!   sensitive to sensor noise (on the virtual rig the variance of the Laplacian left
//!   0.4 mA of surface error where Tenengrad leaves 0.1 mA). CPBD remains selectable.
//! - Each frame follows a read-back of the current (a round trip: the driver has applied
//!   it); a real rig adds the lens's settling time (a few ms) in [`Camera::capture`].
//! - The temperature recorded is the mean of the sensor readings before and after the
//!   refocus.

use etl_core::focus::{autofocus, AutofocusOptions};
use etl_core::lens::Lens;
use etl_core::progress::Progress;
use etl_core::thermal::{ThermalCalibration, ThermalFit};
use image::GrayImage;

use etl_formats::thermal::ThermalSample;
use etl_formats::{Error, Result};
use etl_image::sharpness::{sharpness, Metric};

/// A camera for the procedure.
pub trait Camera {
    /// Grabs a frame at the lens's present state (8-bit grayscale).
    fn capture(&mut self) -> Result<GrayImage>;
    /// Places the board in focus for the lens's present state, before the temperature
    /// series of a grid current (a motorised stage, or the operator; the virtual rig does it
    /// exactly).
    fn place_board_in_focus(&mut self) -> Result<()>;
}

/// Temperature control of the lens (a heated mount, a climate chamber).
pub trait Climate {
    /// Brings the lens to `t_c` and returns once it is there.
    fn set_temperature_c(&mut self, t_c: f64) -> Result<()>;
}

/// What the procedure does.
#[derive(Debug, Clone, PartialEq)]
pub struct ProcedureOptions {
    /// The grid of driver currents, mA (paper: 40..240 by 20).
    pub e_in_grid_ma: Vec<f64>,
    /// The temperature steps, degC, first = reference (paper: 27..37 by 1).
    pub temperatures_c: Vec<f64>,
    /// Half width of the refocus search around the previous step's current, mA.
    pub search_half_width_ma: f64,
    /// Sharpness measure.
    pub metric: Metric,
    /// Coarse points and total frames of each refocus.
    pub coarse_points: usize,
    /// Total frames of each refocus (coarse scan included).
    pub max_frames: usize,
    /// Refocus tolerance, mA.
    pub tolerance_ma: f64,
}

impl Default for ProcedureOptions {
    fn default() -> Self {
        ProcedureOptions {
            e_in_grid_ma: (0..=10).map(|k| 40.0 + 20.0 * k as f64).collect(),
            temperatures_c: (0..=10).map(|k| 27.0 + k as f64).collect(),
            search_half_width_ma: 20.0,
            metric: Metric::Tenengrad,
            coarse_points: 9,
            max_frames: 22,
            tolerance_ma: 0.05,
        }
    }
}

/// The result: every sample, the fitted surface and its RMS residual.
#[derive(Debug, Clone, PartialEq)]
pub struct ProcedureResult {
    /// (T, refocused E_in, E_T) per grid current and temperature.
    pub samples: Vec<ThermalSample>,
    /// The fitted surface (Eq. 7) with its domain.
    pub calibration: ThermalCalibration,
    /// RMS residual of the fit, mA.
    pub rms_ma: f64,
    /// Frames grabbed in all.
    pub frames: usize,
}

/// Fits the cubic surface to samples, scaled by their own ranges (`etlcal thermal fit`).
///
/// Errors: a sample outside the surface's domain, or too few / degenerate samples (named).
pub fn fit_samples(samples: &[ThermalSample]) -> Result<(ThermalCalibration, f64)> {
    let (mut t, mut e) = ([f64::INFINITY, f64::NEG_INFINITY], [f64::INFINITY, f64::NEG_INFINITY]);
    for r in samples {
        t = [t[0].min(r.temperature_c), t[1].max(r.temperature_c)];
        e = [e[0].min(r.e_in_ma), e[1].max(r.e_in_ma)];
    }
    let mut fit = ThermalFit::with_ranges(e, t).unwrap_or_default();
    for (i, r) in samples.iter().enumerate() {
        fit.add(r.e_in_ma, r.temperature_c, r.e_t_ma)
            .map_err(|err| Error::Core(err).within(format_args!("data row {}", i + 1), Some(&format!("rows[{i}]"))))?;
    }
    fit.solve_calibration().map_err(|err| Error::Core(err).within("cannot fit the surface", Some("rows")))
}

impl ProcedureOptions {
    /// Checks the options, naming the first bad one: at least one current and two
    /// temperatures, a positive search half width and tolerance.
    pub fn validate(&self) -> Result<()> {
        if self.e_in_grid_ma.is_empty() || self.temperatures_c.len() < 2 {
            let what = if self.e_in_grid_ma.is_empty() { "e_in_grid_ma" } else { "temperatures_c" };
            return Err(Error::invalid(what, "the procedure needs at least one current and two temperatures"));
        }
        let widths = [("search_half_width_ma", self.search_half_width_ma), ("tolerance_ma", self.tolerance_ma)];
        if let Some((what, x)) = widths.into_iter().find(|(_, x)| !(*x > 0.0)) {
            return Err(Error::invalid_value(what, x, "search half width and tolerance must be positive"));
        }
        Ok(())
    }
}

/// Where the temperature series of one grid current stands: the grid current, the
/// refocused current at the series' first temperature (its E_T reference, once measured)
/// and the last refocused current (the centre of the next search).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Series {
    /// The grid current, mA.
    pub e0_ma: f64,
    /// The refocused current at the first temperature, mA (None before it is measured).
    pub reference_ma: Option<f64>,
    /// The last refocused current, mA (the grid current before the first step).
    pub last_ma: f64,
}

impl Series {
    /// A series not begun.
    pub fn new(e0_ma: f64) -> Series {
        Series { e0_ma, reference_ma: None, last_ma: e0_ma }
    }

    /// A series that `samples` (its first steps, in order) began: a capture resumed
    /// between two steps goes on exactly as an uninterrupted one would.
    pub fn resume(e0_ma: f64, samples: &[ThermalSample]) -> Series {
        Series {
            e0_ma,
            reference_ma: samples.first().map(|s| s.e_in_ma),
            last_ma: samples.last().map_or(e0_ma, |s| s.e_in_ma),
        }
    }
}

/// One temperature step of a series, the lens already at `t_c` (the caller's climate
/// brought it there): at the series' first step the lens goes to the grid current and
/// the board is placed in focus; then the refocus by sharpness over
/// `series.last_ma +- search_half_width_ma`. Returns the sample (the temperature the mean
/// of the readings before and after the refocus; E_T = refocused current - the series'
/// reference) and the frames grabbed.
///
/// Errors: the lens's and the camera's; a refocus ending at the edge of its window
/// (`search_half_width_ma`, named with the temperature and the grid current).
pub fn refocus_step<L: Lens, C: Camera>(
    lens: &mut L,
    camera: &mut C,
    series: &mut Series,
    t_c: f64,
    options: &ProcedureOptions,
) -> Result<(ThermalSample, usize)> {
    let e0 = series.e0_ma;
    if series.reference_ma.is_none() {
        lens.set_current_ma(e0).and_then(|_| lens.current_ma()).map_err(Error::lens)?;
        camera.place_board_in_focus()?;
    }
    let t_before = lens.temperature_c().map_err(Error::lens)?;
    let window = [series.last_ma - options.search_half_width_ma, series.last_ma + options.search_half_width_ma];
    let af = AutofocusOptions {
        range_ma: window,
        coarse_points: options.coarse_points,
        max_evaluations: options.max_frames,
        tolerance_ma: options.tolerance_ma,
    };
    let mut failure: Option<Error> = None;
    let found = autofocus(
        |e| {
            // The read-back is a round trip: the driver has applied the current before
            // the frame is grabbed (real rigs add the lens's settling time, a few ms, in
            // `Camera::capture`).
            let measured = lens
                .set_current_ma(e)
                .and_then(|_| lens.current_ma())
                .map_err(Error::lens)
                .and_then(|_| camera.capture())
                .and_then(|img| sharpness(&img, options.metric));
            measured.map_err(|err| {
                failure = Some(err);
                etl_core::Error::InvalidArgument { what: "frame failed" }
            })
        },
        &af,
    );
    let found = match (found, failure) {
        (_, Some(err)) => return Err(err),
        (r, None) => r.map_err(Error::Core)?,
    };
    let edge = 0.02 * options.search_half_width_ma;
    if (found.best_ma - window[0]).abs() < edge || (window[1] - found.best_ma).abs() < edge {
        return Err(Error::invalid_value(
            "search_half_width_ma",
            options.search_half_width_ma,
            format!(
                "refocus at {t_c} degC for E_in {e0} mA ended at the edge of its window {window:?} mA: \
                 widen the search (search_half_width_ma)"
            ),
        ));
    }
    // The current the driver actually holds (clamped and quantised) is the one recorded.
    let e_set = lens.set_current_ma(found.best_ma).map_err(Error::lens)?;
    let t_after = lens.temperature_c().map_err(Error::lens)?;
    let e_ref = *series.reference_ma.get_or_insert(e_set);
    series.last_ma = e_set;
    let sample = ThermalSample { temperature_c: 0.5 * (t_before + t_after), e_in_ma: e_set, e_t_ma: e_set - e_ref };
    Ok((sample, found.evaluations))
}

/// Runs the procedure (see the module documentation); `progress` draws a bar.
///
/// Errors: bad options (named); any error of the lens, camera or climate; a refocus that
/// finds its best current at the edge of its search window (the lens moved more than
/// `search_half_width_ma` in one temperature step: widen it); the fit's errors.
pub fn run_procedure<L: Lens, C: Camera, K: Climate>(
    lens: &mut L,
    camera: &mut C,
    climate: &mut K,
    options: &ProcedureOptions,
    progress: &dyn Progress,
) -> Result<ProcedureResult> {
    options.validate()?;
    let steps = options.e_in_grid_ma.len() * options.temperatures_c.len();
    progress.start(steps, "thermal");
    let mut samples = vec![];
    let mut frames = 0usize;
    for &e0 in &options.e_in_grid_ma {
        let mut series = Series::new(e0);
        for &t in &options.temperatures_c {
            climate.set_temperature_c(t)?;
            let (sample, n) = refocus_step(lens, camera, &mut series, t, options)?;
            samples.push(sample);
            frames += n;
            progress.advance(1);
        }
    }
    progress.finish();
    let (calibration, rms_ma) = fit_samples(&samples)?;
    Ok(ProcedureResult { samples, calibration, rms_ma, frames })
}
