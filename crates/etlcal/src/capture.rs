//! `etlcal capture views|offstate|thermal --plan F --camera SPEC --lens SPEC --stage SPEC
//! --out DIR`: runs a capture plan (`etlcal.plan/1`) on a rig and writes `DIR/dataset.json`
//! with its images (etl-rig's `capture_views` / `capture_offstate`), or for `thermal` the
//! temperature procedure's `DIR/thermal.csv` and `DIR/thermal.json` (etl-rig's
//! `capture_thermal`; docs/RIG.md, "Capture").
//!
//! The same command resumes a capture a kill or a failure ended: what is on disk is
//! verified and kept. Ctrl-C ends the capture after the current view (a second Ctrl-C,
//! SIGTERM or SIGHUP end it at once; the dataset stays whole either way).
//!
//! With `--json`: `{"dataset", "offstate_kept", "offstate_taken", "views_kept",
//! "views_taken", "stopped"}`; for `thermal` `{"table", "thermal", "samples_kept",
//! "samples_taken", "evaluations", "rms_ma", "stopped"}` (`thermal` and `rms_ma` null until the
//! grid is done).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use etl_formats::plan::Plan;
use etl_formats::{Error, Result};
use etl_hw::virtual_lens::VirtualLensConfig;
use etl_rig::capture::{
    capture_offstate, capture_thermal, capture_views, CaptureOptions, CaptureReport, ThermalReport,
};
use etl_rig::rig::{paper_virtual_lens, Rig, RigSpec};
use etl_rig::spec::{CameraSpec, LensSpec, StageSpec};
use nix::sys::signal::{pthread_sigmask, raise, signal, SigHandler, SigSet, SigmaskHow, Signal};
use serde_json::json;

use super::print_json;

/// Arguments of `etlcal capture`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Which capture.
    #[command(subcommand)]
    pub command: CaptureCommand,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// The captures.
#[derive(clap::Subcommand, Debug)]
pub enum CaptureCommand {
    /// The plan's lens-off views (if it asks for them), then its ETL views.
    Views(CaptureArgs),
    /// The plan's lens-off views only (its offstate_views).
    Offstate(CaptureArgs),
    /// The temperature procedure over the plan's thermal grid: thermal.csv, then thermal.json.
    Thermal(CaptureArgs),
}

/// The rig, the plan and where to write.
#[derive(clap::Args, Debug)]
pub struct CaptureArgs {
    /// The capture plan (etlcal.plan/1).
    #[arg(long, value_name = "FILE")]
    pub plan: PathBuf,
    /// The camera: sim, files:DIR, aravis:NAME, v4l2:/dev/videoN.
    #[arg(long, value_name = "SPEC")]
    pub camera: String,
    /// The lens: virtual (the paper rig's lens at 27 degC ambient), ld4:PORT (or a port path),
    /// `genicam:NAME[,feature=F][,unit=dpt|ma][,temperature=F]` (feature aravis).
    #[arg(long, value_name = "SPEC")]
    pub lens: String,
    /// The stage: sim, manual, `zaber:PORT,microstep_um=UM[,device=N][,axis=N]`.
    #[arg(long, value_name = "SPEC")]
    pub stage: String,
    /// The output folder (dataset.json, views/, offstate/); created if missing.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// The lens has settled when the board's corners move at most this between frames (RMS, px).
    #[arg(long, default_value_t = CaptureOptions::default().settle_tolerance_px, value_name = "PX")]
    pub settle_tolerance_px: f64,
    /// The longest wait for the lens to settle, s.
    #[arg(long, default_value_t = CaptureOptions::default().settle_timeout_s, value_name = "S")]
    pub settle_timeout_s: f64,
    /// Refuse a view whose lens temperature moved more than this during it, degC.
    #[arg(long, default_value_t = CaptureOptions::default().max_temperature_change_c, value_name = "C")]
    pub max_temperature_change_c: f64,
    /// The autofocus search range, mA (plans with "focus": "autofocus").
    #[arg(long, num_args = 2, value_names = ["LO_MA", "HI_MA"])]
    pub autofocus_range_ma: Option<Vec<f64>>,
    /// Split each approach's last step by the zero-vibration shaper of these dynamics
    /// (etlcal.lens-dynamics/1, e.g. measured by `etlcal lens characterise --out`): the
    /// lens settles sooner; the frames still judge when it has.
    #[arg(long, value_name = "FILE")]
    pub shaped: Option<PathBuf>,
    /// With --lens virtual: the lens's dynamics (etlcal.lens-dynamics/1: step response,
    /// creep, hysteresis), which the settling from frames then waits out.
    #[arg(long, value_name = "FILE")]
    pub dynamics: Option<PathBuf>,
    /// Seed of the sim camera's noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// With --camera sim: render only this window of the sensor, px (a temperature capture
    /// needs sharpness, not the whole board, and runs many times faster on a small window).
    #[arg(long, num_args = 4, value_names = ["X", "Y", "W", "H"])]
    pub sim_roi: Option<Vec<u32>>,
}

/// Runs `etlcal capture`.
pub fn run(args: Args) -> Result<()> {
    let (a, kind) = match args.command {
        CaptureCommand::Views(a) => (a, Kind::Views),
        CaptureCommand::Offstate(a) => (a, Kind::Offstate),
        CaptureCommand::Thermal(a) => (a, Kind::Thermal),
    };
    let plan = Plan::load(&a.plan)?;
    if kind == Kind::Thermal {
        plan.thermal_grid().map_err(|e| e.within(a.plan.display(), None))?;
        refuse_view_flags(&a)?;
    }
    let lens = a.lens.parse::<LensSpec>()?;
    if a.dynamics.is_some() && lens != LensSpec::Virtual {
        return Err(Error::invalid(
            "--dynamics",
            "--dynamics FILE describes the virtual lens: pass it with --lens virtual",
        ));
    }
    let virtual_lens =
        VirtualLensConfig { dynamics: crate::lens_sim::dynamics(a.dynamics.as_deref())?, ..paper_virtual_lens() };
    let spec = RigSpec {
        camera: a.camera.parse::<CameraSpec>()?,
        lens,
        stage: a.stage.parse::<StageSpec>()?,
        sim_seed: a.seed,
        sim_roi: a.sim_roi.as_deref().map(|r| [r[0], r[1], r[2], r[3]]),
        virtual_lens,
    };
    let options = CaptureOptions {
        settle_tolerance_px: a.settle_tolerance_px,
        settle_timeout_s: a.settle_timeout_s,
        max_temperature_change_c: a.max_temperature_change_c,
        autofocus_range_ma: a.autofocus_range_ma.as_deref().map(|r| [r[0], r[1]]),
        shaper: a.shaped.as_deref().map(shaper_of).transpose()?,
    };
    options.validate(&plan)?;
    let stop = stop_after_view_on_interrupt()?;
    let mut rig = Rig::open(&spec)?;
    let bar = crate::progress::Bar::new(!args.json);
    let report = match kind {
        Kind::Offstate => capture_offstate(&plan, &mut rig, &a.out, &options, &bar, &stop)?,
        Kind::Views => capture_views(&plan, &mut rig, &a.out, &options, &bar, &stop)?,
        Kind::Thermal => {
            let report = capture_thermal(&plan, &mut rig, &a.out, &options, &bar, &stop)?;
            print_thermal_report(&report, &a.out, args.json);
            return Ok(());
        }
    };
    print_report(&report, &a.out.join(etl_rig::capture::store::DATASET_FILE), args.json);
    Ok(())
}

/// The flags of the views' capture that the temperature capture has no use for: refused,
/// not ignored (it refocuses by its own search and settles on sharpness, not corners).
fn refuse_view_flags(a: &CaptureArgs) -> Result<()> {
    if a.autofocus_range_ma.is_some() {
        let message =
            "--autofocus-range-ma: capture thermal searches thermal.search_half_width_ma around each step's current";
        return Err(Error::invalid("--autofocus-range-ma", message));
    }
    if a.settle_tolerance_px != CaptureOptions::default().settle_tolerance_px {
        let message =
            "--settle-tolerance-px: capture thermal settles each frame on its sharpness, not on the board's corners";
        return Err(Error::invalid("--settle-tolerance-px", message));
    }
    Ok(())
}

/// Which capture.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Views,
    Offstate,
    Thermal,
}

fn print_thermal_report(r: &ThermalReport, out: &std::path::Path, json_out: bool) {
    let table = out.join(etl_rig::capture::thermal::THERMAL_TABLE_FILE);
    let thermal = r.rms_ma.map(|_| out.join(etl_rig::capture::thermal::THERMAL_FILE));
    if json_out {
        print_json(&json!({
            "table": table, "thermal": thermal, "samples_kept": r.samples_kept, "samples_taken": r.samples_taken,
            "evaluations": r.evaluations, "rms_ma": r.rms_ma, "stopped": r.stopped,
        }));
        return;
    }
    let state = match (&thermal, r.rms_ma) {
        (Some(t), Some(rms)) => format!("fitted, RMS {rms:.3} mA: wrote {}", t.display()),
        _ if r.stopped => "stopped; run the same command to resume".to_owned(),
        _ => "not done".to_owned(),
    };
    outln!(
        "{}: {} samples taken ({} kept) from {} sharpness evaluations; {state}",
        table.display(),
        r.samples_taken,
        r.samples_kept,
        r.evaluations
    );
}

fn print_report(r: &CaptureReport, dataset: &std::path::Path, json_out: bool) {
    if json_out {
        print_json(&json!({
            "dataset": dataset, "offstate_kept": r.offstate_kept, "offstate_taken": r.offstate_taken,
            "views_kept": r.views_kept, "views_taken": r.views_taken, "stopped": r.stopped,
        }));
    } else {
        let state = if r.stopped { "stopped; run the same command to resume" } else { "done" };
        outln!(
            "{}: {} lens-off views taken ({} kept), {} views taken ({} kept): {state}",
            dataset.display(),
            r.offstate_taken,
            r.offstate_kept,
            r.views_taken,
            r.views_kept
        );
    }
}

/// Ctrl-C sets the returned flag (the capture stops after the current view); a second
/// Ctrl-C, SIGTERM or SIGHUP remove the virtual lens's folder and end the process by the
/// signal. No code runs in a signal handler: the signals are blocked here (call before
/// any thread starts, so that every thread inherits the mask) and one thread waits.
fn stop_after_view_on_interrupt() -> Result<Arc<AtomicBool>> {
    let stop = Arc::new(AtomicBool::new(false));
    let mut set = SigSet::empty();
    for s in [Signal::SIGINT, Signal::SIGTERM, Signal::SIGHUP] {
        set.add(s);
    }
    pthread_sigmask(SigmaskHow::SIG_BLOCK, Some(&set), None)
        .map_err(|e| Error::invalid("signals", format!("cannot block the stop signals: {e}")))?;
    let flag = Arc::clone(&stop);
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || loop {
            let Ok(sig) = set.wait() else { return };
            if sig == Signal::SIGINT && !flag.swap(true, Ordering::SeqCst) {
                eprintln!("etlcal: stopping after the current view (Ctrl-C again to stop now)");
                continue;
            }
            etl_hw::virtual_lens::folders::remove_live();
            // SAFETY: SIG_DFL installs no Rust code as a handler.
            let _ = unsafe { signal(sig, SigHandler::SigDfl) };
            let _ = pthread_sigmask(SigmaskHow::SIG_UNBLOCK, Some(&set), None);
            let _ = raise(sig);
            std::process::exit(128 + sig as i32);
        })
        .map_err(|e| Error::invalid("signals", format!("cannot start the signal thread: {e}")))?;
    Ok(stop)
}

/// The zero-vibration shaper of the dynamics in `f`; an overdamped membrane has none,
/// refused in one line.
fn shaper_of(f: &std::path::Path) -> Result<etl_core::physics::shaping::ZvShaper> {
    let d = etl_formats::LensDynamicsFile::load(f)?.dynamics();
    etl_core::physics::shaping::ZvShaper::of(&d).ok_or_else(|| {
        let why =
            format!("--shaped {}: damping {} is not below 1: a step does not ring, no shaper", f.display(), d.damping);
        etl_formats::Error::invalid("--shaped", why)
    })
}
