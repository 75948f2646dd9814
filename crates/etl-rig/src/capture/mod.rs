//! The capture procedures: the ETL views of a plan ([`capture_views`], lens-off views
//! first when the plan asks for them) and the lens-off views alone ([`capture_offstate`]),
//! each writing `DIR/dataset.json` and its images resumably ([`store`]); the temperature
//! procedure ([`capture_thermal`], its own module [`thermal`]), writing the table and the
//! fitted surface.
//!
//! One ETL view, in order:
//! 1. the stage moves to the plan's position (the position read back is recorded);
//! 2. the lens goes to the view's current, always approached from below
//!    ([`crate::lens::RigLens::approach_ma`]: from [`crate::lens::APPROACH_MA`] under it):
//!    the plan's current, or with `"autofocus"` the sharpest current of a search over
//!    [`CaptureOptions::autofocus_range_ma`] (etl-core's autofocus; each evaluation
//!    approached from below and settled on the sharpness, [`settle`]);
//! 3. the lens settles, judged from the frames: the board's corners stop moving
//!    ([`settle::settle_on_corners`], with a time-out);
//! 4. the lens temperature is read, `frames` frames are grabbed and averaged, the
//!    temperature is read again: a view whose temperature moved more than
//!    [`CaptureOptions::max_temperature_change_c`] is refused; the view records the mean;
//! 5. the board is detected in the averaged image: a view without it is refused;
//! 6. the image is written, then the dataset.
//!
//! A lens-off view: the lens at 0 mA, the stage asked for the next tilted pose
//! ([`crate::stage::Stage::present_offstate_pose`]), then 3 to 6 with the lens-off board.
//!
//! A refused view or a device failure ends the capture with one line naming the view or
//! the device; what was taken before stays whole on disk, and the same call resumes.
//! `stop` is polled between views: when set, the capture ends after the current view.

pub mod settle;
pub mod store;
pub mod thermal;

pub use thermal::{capture_thermal, ThermalReport};

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

use etl_core::focus::{autofocus, AutofocusOptions};
use etl_core::progress::Progress;
use etl_formats::board::Board;
use etl_formats::plan::{Focus, Plan};

use crate::camera::{average, Pixels};
use crate::error::{Error, ErrorKind, Result};
use crate::rig::Rig;
use store::{offstate_image, view_image, Store};

/// How the procedures judge a view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CaptureOptions {
    /// The lens has settled when the RMS motion of the board's corners between two
    /// consecutive frames is at most this, px.
    pub settle_tolerance_px: f64,
    /// The longest wait for the lens to settle, s (wall time).
    pub settle_timeout_s: f64,
    /// A view is refused when the lens temperature moved more than this during it, degC.
    pub max_temperature_change_c: f64,
    /// The autofocus search range, mA (needed by plans with `"focus": "autofocus"`).
    pub autofocus_range_ma: Option<[f64; 2]>,
    /// Split each approach's last step by this zero-vibration shaper (the lens's measured
    /// dynamics, `etlcal lens characterise --out`); None: plain steps.
    pub shaper: Option<etl_core::physics::shaping::ZvShaper>,
}

impl Default for CaptureOptions {
    /// 0.05 px, 10 s, 0.5 degC, no autofocus range.
    fn default() -> Self {
        CaptureOptions {
            settle_tolerance_px: 0.05,
            settle_timeout_s: 10.0,
            max_temperature_change_c: 0.5,
            autofocus_range_ma: None,
            shaper: None,
        }
    }
}

impl CaptureOptions {
    /// Checks every option, naming it.
    pub fn validate(&self, plan: &Plan) -> Result<()> {
        let bad = |what: &str, message: String| Error::Formats(etl_formats::Error::invalid(what, message));
        if !(self.settle_tolerance_px.is_finite() && self.settle_tolerance_px > 0.0) {
            return Err(bad(
                "settle_tolerance_px",
                format!("settle_tolerance_px {} must be > 0 px", self.settle_tolerance_px),
            ));
        }
        if !(self.settle_timeout_s.is_finite() && (0.0..=3600.0).contains(&self.settle_timeout_s)) {
            return Err(bad(
                "settle_timeout_s",
                format!("settle_timeout_s {} must lie in 0..=3600 s", self.settle_timeout_s),
            ));
        }
        if !(self.max_temperature_change_c.is_finite() && self.max_temperature_change_c > 0.0) {
            let message = format!("max_temperature_change_c {} must be > 0 degC", self.max_temperature_change_c);
            return Err(bad("max_temperature_change_c", message));
        }
        if plan.focus == Focus::Autofocus && self.autofocus_range_ma.is_none() {
            let message = "the plan's focus is \"autofocus\": give the search range, autofocus_range_ma [lo, hi] mA";
            return Err(bad("autofocus_range_ma", message.into()));
        }
        Ok(())
    }

    /// Refuses a step (`during`: "the view", "the refocus") of view `key` whose lens
    /// temperature moved from `t0_c` to `t1_c` by more than
    /// [`CaptureOptions::max_temperature_change_c`]: the temperature compensation takes one
    /// temperature per step.
    pub fn check_temperature_drift(&self, t0_c: f64, t1_c: f64, key: &str, during: &str) -> Result<()> {
        if (t1_c - t0_c).abs() > self.max_temperature_change_c {
            let message = format!(
                "the lens temperature moved from {t0_c:.2} to {t1_c:.2} degC during {during}, more than {} degC",
                self.max_temperature_change_c
            );
            return Err(Error::view(key, message));
        }
        Ok(())
    }
}

/// What a capture did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CaptureReport {
    /// Lens-off views kept from an earlier run (verified).
    pub offstate_kept: usize,
    /// Lens-off views taken now.
    pub offstate_taken: usize,
    /// ETL views kept from an earlier run (verified).
    pub views_kept: usize,
    /// ETL views taken now.
    pub views_taken: usize,
    /// Whether `stop` ended the capture before the plan was done.
    pub stopped: bool,
}

/// Takes the plan's lens-off views (if any) and then its ETL views into `out_dir`
/// (module docs), resuming what an earlier run left there.
pub fn capture_views(
    plan: &Plan,
    rig: &mut Rig,
    out_dir: &Path,
    options: &CaptureOptions,
    progress: &dyn Progress,
    stop: &AtomicBool,
) -> Result<CaptureReport> {
    run(plan, rig, out_dir, options, progress, stop, true)
}

/// Takes the plan's lens-off views only (`offstate_views`, which the plan must give).
pub fn capture_offstate(
    plan: &Plan,
    rig: &mut Rig,
    out_dir: &Path,
    options: &CaptureOptions,
    progress: &dyn Progress,
    stop: &AtomicBool,
) -> Result<CaptureReport> {
    if plan.offstate_count() == 0 {
        let message = "offstate_views: the plan asks for no lens-off views (give offstate_views: N)";
        return Err(Error::Formats(etl_formats::Error::invalid("offstate_views", message)));
    }
    run(plan, rig, out_dir, options, progress, stop, false)
}

/// Checks the plan against the rig before anything is written: the plan, the options,
/// the stage's limits. Returns the camera's image size.
fn preflight(plan: &Plan, rig: &mut Rig, options: &CaptureOptions, views: bool) -> Result<[u32; 2]> {
    plan.validate()?;
    options.validate(plan)?;
    if views {
        let limits = rig.stage.limits_mm()?;
        let name = rig.stage.name();
        plan.check_stage_limits(limits, name.trim_start_matches("stage "))?;
    }
    rig.show_boards(plan.board, plan.offstate_board());
    Ok(rig.camera.info()?.image_size)
}

fn run(
    plan: &Plan,
    rig: &mut Rig,
    out_dir: &Path,
    options: &CaptureOptions,
    progress: &dyn Progress,
    stop: &AtomicBool,
    views: bool,
) -> Result<CaptureReport> {
    let image_size = preflight(plan, rig, options, views)?;
    rig.lens.set_shaper(options.shaper);
    let mut store = Store::open(out_dir, plan, image_size)?;
    let (offstate_kept, views_kept) = store.resumed;
    let mut report = CaptureReport { offstate_kept, views_kept, ..CaptureReport::default() };
    let n_off = plan.offstate_count();
    let n_views = if views { plan.stage_mm.len() } else { 0 };
    let todo = (n_off - offstate_kept.min(n_off)) + (n_views - views_kept.min(n_views));
    progress.start(todo, "capturing");
    for k in offstate_kept..n_off {
        if stop.load(Ordering::SeqCst) {
            report.stopped = true;
            break;
        }
        offstate_view(plan, rig, &mut store, options, k)?;
        report.offstate_taken += 1;
        progress.advance(1);
    }
    for k in views_kept..n_views {
        if report.stopped || stop.load(Ordering::SeqCst) {
            report.stopped = true;
            break;
        }
        etl_view(plan, rig, &mut store, options, k)?;
        report.views_taken += 1;
        progress.advance(1);
    }
    progress.finish();
    Ok(report)
}

/// Lens-off view `k`.
fn offstate_view(plan: &Plan, rig: &mut Rig, store: &mut Store, options: &CaptureOptions, k: usize) -> Result<()> {
    rig.lens.set_current_ma(0.0)?;
    rig.stage.present_offstate_pose(k, plan.offstate_count())?;
    let key = format!("offstate_views[{k}]");
    let (pixels, _) = take(rig, &plan.offstate_board(), plan.frames, options, &key)?;
    let image = offstate_image(k);
    store.write_image(&image, &pixels)?;
    store.push_offstate(image)
}

/// ETL view `k`.
fn etl_view(plan: &Plan, rig: &mut Rig, store: &mut Store, options: &CaptureOptions, k: usize) -> Result<()> {
    let z_w_mm = rig.stage.move_mm(plan.stage_mm[k])?;
    let e_in_ma = match (plan.focus, &plan.currents_ma) {
        (Focus::Current, Some(c)) => rig.lens.approach_ma(c[k])?,
        _ => focus_search(rig, options)?,
    };
    let key = format!("views[{k}]");
    let (pixels, temperature_c) = take(rig, &plan.board, plan.frames, options, &key)?;
    let image = view_image(k);
    store.write_image(&image, &pixels)?;
    store.push_view(image, e_in_ma, temperature_c, z_w_mm)
}

/// The sharpest current at the present stage position, approached from below and
/// commanded; returns it, mA.
fn focus_search(rig: &mut Rig, options: &CaptureOptions) -> Result<f64> {
    let range_ma = options.autofocus_range_ma.unwrap_or([0.0, 0.0]);
    let search = AutofocusOptions { range_ma, ..AutofocusOptions::default() };
    let lens_name = rig.lens.name().to_owned();
    let mut failure: Option<Error> = None;
    let result = autofocus(
        |e| {
            let measured = rig
                .lens
                .approach_ma(e)
                .and_then(|_| settle::settle_on_sharpness(rig.camera.as_mut(), options, &lens_name))
                .map(|(_, s)| s);
            measured.map_err(|err| {
                failure = Some(err);
                etl_core::Error::InvalidArgument { what: "autofocus evaluation failed" }
            })
        },
        &search,
    );
    if let Some(e) = failure {
        return Err(e);
    }
    let found = result.map_err(|e| Error::device(&lens_name, ErrorKind::Other, format!("autofocus: {e}")))?;
    rig.lens.approach_ma(found.best_ma)
}

/// Settles, reads the temperature, grabs and averages `frames` frames, reads the
/// temperature again and detects `board`: the averaged image and the mean temperature.
fn take(rig: &mut Rig, board: &Board, frames: u32, options: &CaptureOptions, key: &str) -> Result<(Pixels, f64)> {
    let lens_name = rig.lens.name().to_owned();
    settle::settle_on_corners(rig.camera.as_mut(), board, options, &lens_name, key)?;
    let t0 = rig.lens.temperature_c()?;
    let grabbed = (0..frames).map(|_| rig.camera.grab()).collect::<Result<Vec<_>>>()?;
    let t1 = rig.lens.temperature_c()?;
    options.check_temperature_drift(t0, t1, key, "the view")?;
    let pixels = average(&grabbed, &rig.camera.name())?;
    if let Err(e) = settle::detect(&pixels, board) {
        return Err(Error::view(key, format!("no board in the averaged image ({e})")));
    }
    Ok((pixels, 0.5 * (t0 + t1)))
}
