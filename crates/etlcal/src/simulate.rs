//! `etlcal simulate --out DIR [--observations-only] [--config sim.json] [--seed N]
//! [--stage-noise-um X] [--setting-views] [--json]`: the paper rig's synthetic data without
//! calibrating: without `--observations-only`, every view rendered by the synthetic camera
//! (`views/`, `offstate/`: ChArUco boards, partial at the near views, no per-view hints)
//! with `dataset.json` recording them (`simulate::images`); always observations.json (with
//! the paper's noise model, lens-off views included, and with `--setting-views` the
//! per-setting baseline's views), a0.json (the A0 a lens-off calibration would give) and
//! truth.json (the true model and per-view errors; with images also `"dataset_model"`,
//! the true model in dataset.json's world frame, the ChArUco board's).
//! `--config` (`etlcal.simconfig/1`) sets seed, rig (`"paper"`, or `"strong"`: the
//! strong-distortion rig, corners only), noise and setting rig in one file; flags given on
//! the command line override it.
//!
//! `--optics FILE` (`etlcal.optics/1`) traces the paper's procedure through a physical rig
//! instead (`etl_sim::optics`: an ETL in front of a published prime lens, real refraction,
//! each corner the centroid of its traced spot, the file's pixel noise or
//! `--pixel-noise-px`, seeded by `--seed`): observations.json (the ETL views with their
//! E_com, the lens-off views, the file's tilted views per current as setting views) and
//! truth.json (`etlcal.optics-truth/1`: per current the paraxial focal length, the
//! entrance pupil, the distance in focus). It writes corners only: images of traced rigs
//! are not rendered, and the flags of the model's simulation (`--config`, the stage and
//! current noises, `--setting-views`) are refused beside it.
//!
//! `--focal-power` runs the paper rig in the lens driver's focal-power mode
//! (`etl_sim::simulate::focal_power`): its views record `focal_power_dpt` at 25, 30 and
//! 35 degC instead of a current, the driver's firmware compensating the temperature with
//! the virtual lens's 4 % residual; truth.json's `de_ma` are then each view's true
//! focal-power error, dpt. Corners only (`--observations-only`), with the paper rig.
//!
//! `--rig N` simulates a rig of N cameras around one stage instead
//! (`etl_sim::multi_camera`, with `--baseline-mm`, `--views`, `--moving-centre` and the
//! noise flags): `rig_dataset.json` (`etlcal.rig-dataset/1`, lens-off views included) and
//! `truth_rig.json` (`etlcal.rig/1`, the true calibrations and extrinsics), for `etlcal
//! calibrate-rig`. Without `--observations-only` every camera's views are rendered
//! (`images/camK/`, `etl_sim::multi_camera::images`: the rig's ChArUco board, each
//! camera's truth, pose and focus) and the dataset gives images, its world frame (and
//! truth_rig.json's) the ChArUco board's; with it, points per camera and view. `--views`
//! sets how many stage positions (and so images) there are.
//!
//! `--rig N --optics FILE [--optics FILE ...]` traces a rig of N physical cameras on one
//! stage instead (`etl_sim::optics::multi_camera`: one optics file for every camera, or
//! one each, camera 0 first; camera 0 where its file puts it, the others `--baseline-mm`
//! away (5..150, default 30) verging on the board, each refocused per view; `--views`
//! stage positions over the travel every camera can focus): `rig_dataset.json` (points,
//! camera 0's file's pixel noise or `--pixel-noise-px`, seeded) and truth.json
//! (`etlcal.optics-rig-truth/1`: each camera's pose and its optics' truth per current).
//! Points only; `--moving-centre` and the stage and current noises are refused.
//!
//! DIR is created if missing (with its missing parents) and replaced as one set: a kill
//! or an error leaves the earlier set whole (docs/RELIABILITY.md).

use std::path::PathBuf;

use serde_json::json;

use super::print_json;
use crate::output::write_dir_set;
use etl_formats::output::Output;
use etl_formats::{Error, Result};

/// The names `simulate` writes into its directory.
const SIMULATION_FILES: &[&str] = &["observations.json", "a0.json", "truth.json", "dataset.json", "views", "offstate"];
use etl_sim::multi_camera::images::{dataset_truths, render_multi_camera};
use etl_sim::multi_camera::{simulate_multi_camera, truth_rig, MultiCameraDesign, MultiCameraSimulation};
use etl_sim::optics::multi_camera::{trace_multi_camera, TracedRigDesign, RIG_TRUTH_FORMAT};
use etl_sim::optics::truth::{setting_truths, TRUTH_FORMAT};
use etl_sim::optics::{procedure, OpticalRig};
use etl_sim::simulate::focal_power::{focal_power_rig, FOCAL_POWER_TEMPERATURES_C};
use etl_sim::simulate::images::{dataset_truth, render_rig, ImageOptions};
use etl_sim::simulate::{simulate, write_simulation, write_truth, SettingRig, SimConfig, SimRig};

/// Arguments of `etlcal simulate`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Output directory (created with its missing parents).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Write corner observations only (no images).
    #[arg(long)]
    pub observations_only: bool,
    /// Simulation configuration (etlcal.simconfig/1).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Trace the procedure through a physical rig (etlcal.optics/1) instead of the camera
    /// model: corners only, with the file's pixel noise unless --pixel-noise-px. With
    /// --rig N: the cameras' optics (one file for every camera, or N files, camera 0
    /// first; repeat the flag).
    #[arg(long, value_name = "FILE",
        conflicts_with_all = ["config", "stage_noise_um", "current_noise_ma", "setting_views"])]
    pub optics: Vec<PathBuf>,
    /// Random seed [default: 1].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Stage-position noise per view, um [default: 10, the paper's].
    #[arg(long)]
    pub stage_noise_um: Option<f64>,
    /// Current noise per view, mA [default: 0.4].
    #[arg(long)]
    pub current_noise_ma: Option<f64>,
    /// Pixel noise, px [default: 0.2].
    #[arg(long)]
    pub pixel_noise_px: Option<f64>,
    /// Add the per-setting baseline's views (the default setting rig) unless the config
    /// has one.
    #[arg(long)]
    pub setting_views: bool,
    /// Run the paper rig in the lens driver's focal-power mode: views at focal powers
    /// (dpt) at 25, 30 and 35 degC, the firmware compensating the temperature with a 4 %
    /// residual (corners only: with --observations-only).
    #[arg(long, requires = "observations_only", conflicts_with_all = ["optics", "setting_views"])]
    pub focal_power: bool,
    /// Simulate a rig of N cameras around one stage instead (2..64; etl_sim::multi_camera):
    /// rig_dataset.json (etlcal.rig-dataset/1: rendered images under images/, or points
    /// with --observations-only) and truth_rig.json (etlcal.rig/1).
    #[arg(long, value_name = "N",
        conflicts_with_all = ["config", "setting_views", "focal_power"])]
    pub rig: Option<usize>,
    /// With --rig: the distance of cameras 1.. from camera 0, mm (60..150) [default: 60;
    /// with --optics 5..150, default 30].
    #[arg(long, value_name = "MM", requires = "rig")]
    pub baseline_mm: Option<f64>,
    /// With --rig: the number of stage positions (3..10000) [default: 15].
    #[arg(long, value_name = "N", requires = "rig")]
    pub views: Option<usize>,
    /// With --rig: every camera's centre moves with its lens setting (dz(E), u0(E), v0(E)).
    #[arg(long, requires = "rig")]
    pub moving_centre: bool,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// The names `simulate --rig` writes into its directory.
const RIG_FILES: &[&str] = &["rig_dataset.json", "truth_rig.json", "images"];

/// `etlcal simulate --rig N`: the N-camera rig's points and truth.
fn run_rig(args: &Args, cameras: usize) -> Result<()> {
    crate::output::check([None], &[Output::Dir(&args.out)])?;
    for (flag, value, hi, unit) in [
        ("--stage-noise-um", args.stage_noise_um, 10_000.0, "um"),
        ("--current-noise-ma", args.current_noise_ma, 50.0, "mA"),
        ("--pixel-noise-px", args.pixel_noise_px, 100.0, "px"),
    ] {
        if let Some(v) = value {
            etl_formats::check_range(flag, v, [0.0, hi], unit)?;
        }
    }
    let paper = etl_sim::simulate::NoiseModel::PAPER;
    let noise = etl_sim::simulate::NoiseModel {
        z_mm: args.stage_noise_um.map_or(paper.z_mm, |um| um / 1000.0),
        e_ma: args.current_noise_ma.unwrap_or(paper.e_ma),
        px: args.pixel_noise_px.unwrap_or(paper.px),
        ..paper
    };
    let base = MultiCameraDesign::new(cameras);
    let design = MultiCameraDesign {
        baseline_mm: args.baseline_mm.unwrap_or(base.baseline_mm),
        views: args.views.unwrap_or(base.views),
        moving_centre: args.moving_centre,
        ..base
    };
    let sim = simulate_multi_camera(&design, &noise, args.seed.unwrap_or(1)).map_err(rig_flag_names)?;
    let images = write_dir_set(&args.out, RIG_FILES, |staging| {
        if args.observations_only {
            sim.dataset.save(&staging.join("rig_dataset.json"))?;
            truth_rig(&sim).save(&staging.join("truth_rig.json"))?;
            return Ok(0);
        }
        let bar = crate::progress::Bar::new(!args.json);
        let seed = args.seed.unwrap_or(1);
        let dataset = render_multi_camera(&sim, staging, &ImageOptions::default(), seed, &bar)?;
        dataset.save(&staging.join("rig_dataset.json"))?;
        let in_frame = MultiCameraSimulation { truths: dataset_truths(&sim), ..sim.clone() };
        truth_rig(&in_frame).save(&staging.join("truth_rig.json"))?;
        Ok(dataset.images().count())
    })?;
    let points: usize =
        sim.dataset.views.iter().flat_map(|v| &v.cameras).map(|s| s.points.as_ref().map_or(0, Vec::len)).sum();
    if args.json {
        print_json(&json!({"cameras": cameras, "views": sim.dataset.views.len(), "points": points,
            "images": images, "out": args.out}));
    } else {
        let what = if images > 0 { format!("{images} images") } else { format!("{points} points") };
        outln!(
            "wrote rig_dataset.json, truth_rig.json ({cameras} cameras, {} views, {what}) to {}",
            sim.dataset.views.len(),
            args.out.display()
        );
    }
    Ok(())
}

/// The configuration of the flags: `--config` (or the defaults), overridden by flags.
pub fn config_from(args: &Args) -> Result<SimConfig> {
    let mut c = match &args.config {
        Some(p) => SimConfig::load(p)?,
        None => SimConfig::default(),
    };
    if let Some(s) = args.seed {
        c.seed = s;
    }
    // The flags by their names first; the configuration's own keys in `validate`.
    for (flag, value, hi, unit) in [
        ("--stage-noise-um", args.stage_noise_um, 10_000.0, "um"),
        ("--current-noise-ma", args.current_noise_ma, 50.0, "mA"),
        ("--pixel-noise-px", args.pixel_noise_px, 100.0, "px"),
    ] {
        if let Some(v) = value {
            etl_formats::check_range(flag, v, [0.0, hi], unit)?;
        }
    }
    let n = &mut c.noise;
    let flags = [args.stage_noise_um.map(|v| v / 1000.0), args.current_noise_ma, args.pixel_noise_px];
    for (slot, v) in [&mut n.z_mm, &mut n.e_ma, &mut n.px].into_iter().zip(flags) {
        if let Some(v) = v {
            *slot = v;
        }
    }
    if args.setting_views && c.setting_rig.is_none() {
        c.setting_rig = Some(SettingRig::default());
    }
    c.validate()?;
    Ok(c)
}

/// Runs `etlcal simulate`.
pub fn run(args: Args) -> Result<()> {
    if let (Some(cameras), false) = (args.rig, args.optics.is_empty()) {
        return run_rig_optics(&args, cameras);
    }
    if let [optics] = args.optics.as_slice() {
        return run_optics(&args, optics);
    }
    if args.optics.len() > 1 {
        return Err(Error::invalid(
            "--optics",
            format!("--optics: {} files given; one traces one camera (several need --rig N)", args.optics.len()),
        ));
    }
    if let Some(cameras) = args.rig {
        return run_rig(&args, cameras);
    }
    crate::output::check([args.config.as_deref()], &[Output::Dir(&args.out)])?;
    let config = config_from(&args)?;
    if !args.observations_only && config.rig == SimRig::Strong {
        return Err(Error::invalid(
            "--observations-only",
            "the strong-distortion rig (\"rig\": \"strong\") is simulated as corners only: pass --observations-only",
        ));
    }
    if !args.observations_only && config.setting_rig.is_some() {
        return Err(Error::invalid(
            "--observations-only",
            "rendering the per-setting baseline's views is not supported: pass --observations-only with --setting-views",
        ));
    }
    let sim = if args.focal_power {
        if config.rig != SimRig::Paper {
            return Err(Error::invalid("--focal-power", "the focal-power mode is simulated on the paper rig only"));
        }
        let compensation = etl_hw::virtual_lens::FocalPowerCompensation::default();
        focal_power_rig(&config.noise, config.seed, &FOCAL_POWER_TEMPERATURES_C, &compensation)
    } else {
        simulate(&config)
    };
    // Images, dataset, observations and truth of one run, swapped in whole: a dataset
    // beside another seed's observations would calibrate to a wrong answer silently.
    let images = write_dir_set(&args.out, SIMULATION_FILES, |staging| {
        write_simulation(&sim, staging)?;
        if args.observations_only {
            return Ok(0);
        }
        let options = ImageOptions::default();
        let bar = crate::progress::Bar::new(!args.json);
        let dataset = render_rig(&sim, staging, &options, config.seed, &bar)?;
        dataset.save(&staging.join("dataset.json"))?;
        write_truth(&sim, Some(&dataset_truth(&sim.truth, &options)), staging)?;
        Ok(dataset.views.len() + dataset.offstate_views.len())
    })?;
    let points: usize = sim.observations.views.iter().map(|v| v.points.len()).sum();
    if args.json {
        print_json(&json!({"views": sim.observations.views.len(), "points": points,
            "setting_views": sim.observations.setting_views.len(), "images": images, "out": args.out}));
    } else {
        let rendered = if images > 0 { format!("{images} images, dataset.json, ") } else { String::new() };
        outln!(
            "wrote {rendered}observations.json, a0.json, truth.json ({} views, {points} points, {} setting views) to {}",
            sim.observations.views.len(),
            sim.observations.setting_views.len(),
            args.out.display()
        );
    }
    Ok(())
}

/// The names `simulate --rig N --optics FILE` writes into its directory.
const RIG_OPTICS_FILES: &[&str] = &["rig_dataset.json", "truth.json"];

/// The cameras' optics of `simulate --rig N --optics FILE...`: one file for every camera
/// or one per camera, each with `--pixel-noise-px` when given.
fn rig_optics(args: &Args, cameras: usize) -> Result<Vec<OpticalRig>> {
    if args.optics.len() != 1 && args.optics.len() != cameras {
        let message = format!(
            "--optics: {} files for {cameras} cameras (give one for every camera, or one each)",
            args.optics.len()
        );
        return Err(Error::invalid("--optics", message));
    }
    if args.moving_centre {
        return Err(Error::invalid("--moving-centre", "--moving-centre: a traced rig's centre is its optics'"));
    }
    let mut rigs = vec![];
    for k in 0..cameras {
        let mut file = etl_formats::optics::OpticsFile::load(&args.optics[k.min(args.optics.len() - 1)])?;
        if let Some(px) = args.pixel_noise_px {
            etl_formats::check_range("--pixel-noise-px", px, [0.0, 100.0], "px")?;
            file.procedure.pixel_noise_px = px;
        }
        rigs.push(OpticalRig::new(file)?);
    }
    Ok(rigs)
}

/// `etlcal simulate --rig N --optics FILE...`: the traced N-camera rig's points (camera
/// 0's pixel noise, seeded) and its truth (`etlcal.optics-rig-truth/1`).
fn run_rig_optics(args: &Args, cameras: usize) -> Result<()> {
    crate::output::check(args.optics.iter().map(|p| Some(p.as_path())), &[Output::Dir(&args.out)])?;
    let optics = rig_optics(args, cameras)?;
    let base = TracedRigDesign::new();
    let design = TracedRigDesign {
        baseline_mm: args.baseline_mm.unwrap_or(base.baseline_mm),
        views: args.views.unwrap_or(base.views),
        ..base
    };
    let rig = trace_multi_camera(&optics, &design).map_err(rig_flag_names)?;
    let (seed, sigma_px) = (args.seed.unwrap_or(1), optics[0].file.procedure.pixel_noise_px);
    let dataset = rig.with_pixel_noise(sigma_px, seed);
    let truths = rig.truths()?;
    let cams: Vec<serde_json::Value> = truths
        .iter()
        .zip(&rig.cameras)
        .enumerate()
        .map(|(k, (t, c))| {
            json!({"name": format!("cam{k}"), "optics": c.optics.file.name,
            "rotation_rodrigues": t.pose.0, "translation_mm": t.pose.1, "settings": t.settings})
        })
        .collect();
    let truth = json!({"format": RIG_TRUTH_FORMAT, "seed": seed, "pixel_noise_px": sigma_px,
        "baseline_mm": design.baseline_mm, "stage_travel_mm": rig.stage_travel_mm, "cameras": cams});
    write_dir_set(&args.out, RIG_OPTICS_FILES, |staging| {
        dataset.save(&staging.join("rig_dataset.json"))?;
        etl_formats::write_json(&staging.join("truth.json"), &truth)?;
        Ok(())
    })?;
    let points: usize =
        dataset.views.iter().flat_map(|v| &v.cameras).map(|s| s.points.as_ref().map_or(0, Vec::len)).sum();
    if args.json {
        print_json(&json!({"cameras": cameras, "views": dataset.views.len(), "points": points, "images": 0,
            "baseline_mm": design.baseline_mm, "stage_travel_mm": rig.stage_travel_mm, "pixel_noise_px": sigma_px,
            "out": args.out}));
    } else {
        outln!(
            "wrote rig_dataset.json, truth.json ({cameras} traced cameras {} mm apart, {} views over {:.2}..{:.2} mm, {points} points, {sigma_px} px of noise) to {}",
            design.baseline_mm,
            dataset.views.len(),
            rig.stage_travel_mm[0],
            rig.stage_travel_mm[1],
            args.out.display()
        );
    }
    Ok(())
}

/// The names `simulate --optics` writes into its directory.
const OPTICS_FILES: &[&str] = &["observations.json", "truth.json"];

/// `etlcal simulate --optics FILE`: the procedure traced through the rig of FILE.
fn run_optics(args: &Args, optics: &std::path::Path) -> Result<()> {
    crate::output::check([Some(optics)], &[Output::Dir(&args.out)])?;
    let mut file = etl_formats::optics::OpticsFile::load(optics)?;
    if let Some(px) = args.pixel_noise_px {
        etl_formats::check_range("--pixel-noise-px", px, [0.0, 100.0], "px")?;
        file.procedure.pixel_noise_px = px;
    }
    let rig = OpticalRig::new(file)?;
    let seed = args.seed.unwrap_or(1);
    let obs = procedure::observations(&rig, seed)?;
    let truth = json!({"format": TRUTH_FORMAT, "optics": rig.file.name, "seed": seed,
        "pixel_noise_px": rig.file.procedure.pixel_noise_px, "settings": setting_truths(&rig)?});
    write_dir_set(&args.out, OPTICS_FILES, |staging| {
        obs.save(&staging.join("observations.json"))?;
        etl_formats::write_json(&staging.join("truth.json"), &truth)?;
        Ok(())
    })?;
    let points: usize = obs.views.iter().map(|v| v.points.len()).sum();
    if args.json {
        print_json(&json!({"views": obs.views.len(), "points": points, "setting_views": obs.setting_views.len(),
            "offstate_views": obs.offstate_views.len(), "images": 0, "out": args.out}));
    } else {
        outln!(
            "wrote observations.json, truth.json of {} ({} views, {points} points, {} lens-off views, {} setting views) to {}",
            rig.file.name,
            obs.views.len(),
            obs.offstate_views.len(),
            obs.setting_views.len(),
            args.out.display()
        );
    }
    Ok(())
}

/// A rig design's refusal spelt with the flags that set its fields (`cameras` is `--rig`,
/// `views` `--views`, `baseline_mm` `--baseline-mm`).
fn rig_flag_names(e: etl_formats::Error) -> etl_formats::Error {
    let what = e.input_what().unwrap_or("").to_owned();
    match what.as_str() {
        "cameras" => e.rename_input("cameras", "--rig"),
        "views" => e.rename_input("views", "--views"),
        "baseline_mm" => e.rename_input("baseline_mm", "--baseline-mm"),
        _ => e,
    }
}
