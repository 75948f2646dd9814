//! The temperature procedure on the rig ([`capture_thermal`]): etl-calib's section 4.1
//! procedure ([`etl_calib::thermal_calibration::refocus_step`]) driven by the rig's lens,
//! camera and stage, one sample at a time, written resumably.
//!
//! The plan's `thermal` keys give the temperatures; its `currents_ma` the grid currents,
//! each with its stage position in `stage_mm` (where the board is in focus at that current,
//! the series' first temperature). For each grid current k (in order), for each
//! temperature j (in order):
//! 1. the stage moves to `stage_mm[k]` (a step resumed in the middle of a series finds the
//!    board where the series had it);
//! 2. the lens is brought to the temperature: the virtual lens's heated mount is set to it
//!    and jumps to equilibrium; a real lens is waited for (its temperature read every
//!    [`TEMPERATURE_POLL_S`] until it is within `temperature_tolerance_c` of the step's,
//!    for at most `temperature_timeout_s`: a heated mount or a climate chamber, driven by
//!    its own controller, brings it there);
//! 3. the refocus: at the series' first temperature the lens goes to the grid current,
//!    then the sharpest current within `search_half_width_ma` of the previous step's is
//!    searched; every current commanded is approached from below
//!    ([`crate::lens::RigLens::approach_ma`]), and each evaluation's frame is the first on
//!    which the sharpness has settled ([`super::settle::settle_on_sharpness`]);
//! 4. a step whose lens temperature moved more than
//!    [`super::CaptureOptions::max_temperature_change_c`] during it is refused;
//! 5. the sample (temperature, refocused current, E_T) is appended to `DIR/thermal.csv`,
//!    the table `etlcal thermal fit` reads, rewritten atomically after every sample.
//!
//! Once the grid is done the cubic surface is fitted and written to `DIR/thermal.json`
//! (`etlcal.thermal/1`). Resuming: the table's rows must be this plan's (row n is grid
//! current n / T, temperature n % T of the plan's T temperatures; its temperature within
//! the tolerance plus `max_temperature_change_c` of the step's, and a series' first row at
//! E_T = 0 within the search window of its grid current); they are kept and the capture
//! goes on from the next sample, the series' reference and last current taken from its
//! rows ([`Series::resume`]).
//!
//! Frames of 16 bits are scaled to 8 (v / 257, the image crate's conversion) for the
//! sharpness: a 10- or 12-bit sensor's samples then use a fraction of the 8-bit range;
//! set the camera to Mono8 for this procedure.

use std::cell::RefCell;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use etl_calib::thermal_calibration::{fit_samples, refocus_step, ProcedureOptions, Series};
use etl_core::lens::Lens;
use etl_core::progress::Progress;
use etl_formats::plan::{Plan, ThermalPlan, THERMAL_COARSE_POINTS};
use etl_formats::thermal::{read_thermal_table, write_thermal_table, ThermalFile, ThermalSample};
use image::GrayImage;

use super::{settle, CaptureOptions};
use crate::camera::{Camera, Pixels};
use crate::error::{Error, ErrorKind, Result};
use crate::lens::RigLens;
use crate::rig::Rig;

/// The table of samples in the output folder (CSV `temperature_c,e_in_ma,e_t_ma`).
pub const THERMAL_TABLE_FILE: &str = "thermal.csv";
/// The fitted surface in the output folder (`etlcal.thermal/1`).
pub const THERMAL_FILE: &str = "thermal.json";
/// How often a real lens's temperature is read while waiting for a step's, s.
pub const TEMPERATURE_POLL_S: f64 = 0.5;

/// What a temperature capture did.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ThermalReport {
    /// Samples kept from an earlier run.
    pub samples_kept: usize,
    /// Samples taken now.
    pub samples_taken: usize,
    /// Sharpness evaluations of the refocus searches now (each on one frame, grabbed once
    /// the sharpness settled: two or more frames each).
    pub evaluations: usize,
    /// Whether `stop` ended the capture before the grid was done.
    pub stopped: bool,
    /// The fit's RMS residual, mA, once the grid is done (then `thermal.json` is written).
    pub rms_ma: Option<f64>,
}

/// The lens for the procedure: every current approached from below; the first failure
/// kept (the procedure only sees it as text).
struct StepLens<'a> {
    lens: &'a mut RigLens,
    failure: &'a RefCell<Option<Error>>,
}

/// `result`, its error also kept in `failure` (the first one only).
fn keep<T>(failure: &RefCell<Option<Error>>, result: Result<T>) -> Result<T> {
    result.map_err(|e| {
        let copy = Error::device(e.device_name().unwrap_or("rig"), e.kind(), strip_device(&e));
        failure.borrow_mut().get_or_insert(e);
        copy
    })
}

/// A device error's message without its device.
fn strip_device(e: &Error) -> String {
    match e {
        Error::Device { message, .. } => message.clone(),
        other => other.to_string(),
    }
}

impl Lens for StepLens<'_> {
    type Error = Error;
    fn set_current_ma(&mut self, e_in_ma: f64) -> Result<f64> {
        keep(self.failure, self.lens.approach_ma(e_in_ma))
    }
    fn current_ma(&mut self) -> Result<f64> {
        keep(self.failure, self.lens.current_ma())
    }
    fn temperature_c(&mut self) -> Result<f64> {
        keep(self.failure, self.lens.temperature_c())
    }
}

/// The camera for the procedure: a frame once the sharpness has settled; the board is
/// already where the stage put it.
struct StepCamera<'a> {
    camera: &'a mut dyn Camera,
    options: &'a CaptureOptions,
    lens_name: String,
    failure: &'a RefCell<Option<Error>>,
}

impl etl_calib::thermal_calibration::Camera for StepCamera<'_> {
    fn capture(&mut self) -> etl_formats::Result<GrayImage> {
        let frame = settle::settle_on_sharpness(self.camera, self.options, &self.lens_name);
        let (frame, _) = keep(self.failure, frame).map_err(etl_formats::Error::from)?;
        Ok(match frame.pixels {
            Pixels::Mono8(g) => g,
            Pixels::Mono16(g) => image::DynamicImage::ImageLuma16(g).to_luma8(),
        })
    }

    fn place_board_in_focus(&mut self) -> etl_formats::Result<()> {
        Ok(())
    }
}

/// The procedure's options of the plan's grid.
fn procedure_options(t: &ThermalPlan, currents_ma: &[f64]) -> ProcedureOptions {
    ProcedureOptions {
        e_in_grid_ma: currents_ma.to_vec(),
        temperatures_c: t.temperatures_c.clone(),
        search_half_width_ma: t.search_half_width_ma(),
        coarse_points: THERMAL_COARSE_POINTS,
        max_frames: t.refocus_frames(),
        ..ProcedureOptions::default()
    }
}

/// Captures the plan's temperature grid into `out_dir` (module docs), resuming what an
/// earlier run left there; `stop` is polled between samples.
///
/// Errors: a bad plan or options (nothing written); a device's failure or a refused step
/// (one line naming it; the table keeps the samples before it); the fit's.
pub fn capture_thermal(
    plan: &Plan,
    rig: &mut Rig,
    out_dir: &Path,
    options: &CaptureOptions,
    progress: &dyn Progress,
    stop: &AtomicBool,
) -> Result<ThermalReport> {
    plan.validate()?;
    options.validate(plan)?;
    let (tp, currents) = plan.thermal_grid()?;
    let limits = rig.stage.limits_mm()?;
    plan.check_stage_limits(limits, rig.stage.name().trim_start_matches("stage "))?;
    rig.show_boards(plan.board, plan.offstate_board());
    rig.lens.set_shaper(options.shaper);
    let procedure = procedure_options(tp, currents);
    let table = out_dir.join(THERMAL_TABLE_FILE);
    let mut samples = resumed_samples(&table, tp, currents, options)?;
    let n_t = tp.temperatures_c.len();
    let total = currents.len() * n_t;
    let mut report = ThermalReport { samples_kept: samples.len(), ..ThermalReport::default() };
    progress.start(total - samples.len(), "thermal");
    for n in samples.len()..total {
        if stop.load(Ordering::SeqCst) {
            report.stopped = true;
            break;
        }
        let (k, j) = (n / n_t, n % n_t);
        let (sample, frames) = thermal_step(plan, rig, &procedure, options, [k, j], &samples[k * n_t..])?;
        samples.push(sample);
        std::fs::create_dir_all(out_dir)
            .map_err(|source| etl_formats::Error::Io { path: out_dir.to_owned(), source })?;
        write_thermal_table(&table, &samples)?;
        report.samples_taken += 1;
        report.evaluations += frames;
        progress.advance(1);
    }
    progress.finish();
    if samples.len() == total {
        let (calibration, rms_ma) = fit_samples(&samples)?;
        ThermalFile::new(&calibration, rms_ma).save(&out_dir.join(THERMAL_FILE))?;
        report.rms_ma = Some(rms_ma);
    }
    Ok(report)
}

/// Step `[k, j]`: grid current k at temperature j (module docs, 1 to 4); `series` are the
/// samples its series has so far.
fn thermal_step(
    plan: &Plan,
    rig: &mut Rig,
    procedure: &ProcedureOptions,
    options: &CaptureOptions,
    [k, j]: [usize; 2],
    series: &[ThermalSample],
) -> Result<(ThermalSample, usize)> {
    let t_c = procedure.temperatures_c[j];
    let key = format!("thermal step currents_ma[{k}] at temperatures_c[{j}] ({t_c} degC)");
    rig.stage.move_mm(plan.stage_mm[k])?;
    let tp = plan.thermal.as_ref().ok_or_else(|| Error::view(&key, "the plan has no thermal keys"))?;
    reach_temperature(&mut rig.lens, t_c, tp)?;
    let t0 = rig.lens.temperature_c()?;
    let mut state = Series::resume(procedure.e_in_grid_ma[k], series);
    let failure = RefCell::new(None);
    let lens_name = rig.lens.name().to_owned();
    let result = {
        let mut lens = StepLens { lens: &mut rig.lens, failure: &failure };
        let mut camera = StepCamera { camera: rig.camera.as_mut(), options, lens_name, failure: &failure };
        refocus_step(&mut lens, &mut camera, &mut state, t_c, procedure)
    };
    if let Some(e) = failure.take() {
        return Err(e);
    }
    let (sample, frames) =
        result.map_err(|e| Error::Formats(e.rename_input("search_half_width_ma", "thermal.search_half_width_ma")))?;
    let t1 = rig.lens.temperature_c()?;
    options.check_temperature_drift(t0, t1, &key, "the refocus")?;
    Ok((sample, frames))
}

/// Brings the lens to `t_c` (module docs, 2): the virtual lens's mount is set; any lens is
/// then read until it is within the plan's tolerance, for at most its time-out.
fn reach_temperature(lens: &mut RigLens, t_c: f64, tp: &ThermalPlan) -> Result<()> {
    if let Some(v) = lens.virtual_lens() {
        v.device().set_target_temperature_c(t_c);
        v.device().settle();
    }
    let start = Instant::now();
    loop {
        let now_c = lens.temperature_c()?;
        if (now_c - t_c).abs() <= tp.temperature_tolerance_c {
            return Ok(());
        }
        if start.elapsed().as_secs_f64() > tp.temperature_timeout_s {
            let message = format!(
                "did not reach {t_c} degC within {} s (it reads {now_c:.2} degC, tolerance {} degC): \
                 the capture waits for the lens's mount to bring it there",
                tp.temperature_timeout_s, tp.temperature_tolerance_c
            );
            return Err(Error::device(lens.name(), ErrorKind::Timeout, message));
        }
        std::thread::sleep(Duration::from_secs_f64(TEMPERATURE_POLL_S));
    }
}

/// The samples an earlier run left in `table`, checked against the plan (module docs);
/// none when there is no table.
fn resumed_samples(
    table: &Path,
    tp: &ThermalPlan,
    currents: &[f64],
    options: &CaptureOptions,
) -> Result<Vec<ThermalSample>> {
    if let Some(dir) = table.parent().filter(|d| d.is_dir()) {
        etl_formats::output::remove_stale_temps(dir, std::ffi::OsStr::new(THERMAL_TABLE_FILE));
        etl_formats::output::remove_stale_temps(dir, std::ffi::OsStr::new(THERMAL_FILE));
    }
    if !table.exists() {
        return Ok(vec![]);
    }
    let rows = read_thermal_table(table)?;
    let n_t = tp.temperatures_c.len();
    let other = |what: String| {
        Error::Formats(etl_formats::Error::invalid(
            "--out",
            format!("{}: {what}: it is another capture's; choose another --out", table.display()),
        ))
    };
    if rows.len() > currents.len() * n_t {
        return Err(other(format!("{} rows, more than the plan's grid of {}", rows.len(), currents.len() * n_t)));
    }
    let slack_c = tp.temperature_tolerance_c + options.max_temperature_change_c;
    for (n, r) in rows.iter().enumerate() {
        let (k, j) = (n / n_t, n % n_t);
        let t = tp.temperatures_c[j];
        if (r.temperature_c - t).abs() > slack_c {
            return Err(other(format!(
                "row {} is at {} degC, the plan's temperatures_c[{j}] {t} degC",
                n + 1,
                r.temperature_c
            )));
        }
        if j == 0 && (r.e_t_ma != 0.0 || (r.e_in_ma - currents[k]).abs() > tp.search_half_width_ma()) {
            return Err(other(format!(
                "row {} (E_in {} mA, E_T {} mA) does not begin the series of the plan's currents_ma[{k}] {} mA",
                n + 1,
                r.e_in_ma,
                r.e_t_ma,
                currents[k]
            )));
        }
    }
    Ok(rows)
}
