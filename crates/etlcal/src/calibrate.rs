//! `etlcal calibrate (--dataset FILE | --observations FILE) --out calibration.json
//! [--method proposed|per-setting] [--a0 A0.json] [--estimator paper|eiv] [--hold-a0]
//! [--distortion paper|opencv|auto] [--focal-degree 1..5|auto] [--fix-k3] [--zero-tangent]
//! [--thermal FILE] [--observations-out FILE] [--json]`.
//!
//! A dataset (`etlcal.dataset/1`, images) or observations (`etlcal.observations/1`,
//! corners) in, `etlcal.calibration/1` out (written atomically; nothing is written on
//! failure). From a dataset, boards are detected in every image (in parallel, with a
//! progress bar on a terminal); views whose board is not found are named on stderr and
//! skipped, and the run fails only if what remains breaks a precondition.
//! The calibration holds the focus law (the distance in focus against E_com, fitted to the
//! views; `etlcal focus` uses it) when the views allow one (>= 4 distinct currents);
//! otherwise a warning on stderr says why it is left out.
//! `--json` prints the object written. Without `--a0`, A0 comes from the lens-off views
//! by Zhang's method with the calibration's distortion family. The model is the paper's
//! (its distortion, cubic fx(E), fy(E)) unless `--distortion` / `--focal-degree` say
//! otherwise; `auto` chooses among the families (and degrees 1..5) by the error with
//! which each predicts every view held out (`etl_calib::pipeline::select`), and writes
//! the comparison into the file's `"model_selection"`. The bundle adjustment is errors-in-variables unless `--estimator
//! paper` asks for the paper's Eq. 24. `--method per-setting` is the paper's baseline (Zhang
//! at each current, a cubic through fx(E), fy(E); needs `setting_views`); it refuses the
//! flags of the bundle adjustment (`--a0`, `--estimator`, `--hold-a0`, `--huber-px`).

use std::path::{Path, PathBuf};

use etl_core::calib::{Estimator, Layout, RobustLoss};
use etl_core::model::{DistortionModel, OpenCvFlags};

use super::print_json;
use etl_calib::baseline::refuse_bundle_adjust_options;
use etl_calib::pipeline::dataset::{default_detector, observations_from_dataset};
use etl_calib::pipeline::select::{refuse_opencv_flags, select, A0Source, Candidates};
use etl_calib::pipeline::{a0_from_offstate_with, calibrate, CalibrateOptions};
use etl_calib::zhang::ZhangOptions;
use etl_formats::a0::A0File;
use etl_formats::calibration::{Calibration, ThermalRef};
use etl_formats::dataset::Dataset;
use etl_formats::observations::Observations;
use etl_formats::output::{write_file_set, Output};
use etl_formats::{Error, Result};

/// The bundle adjustment's estimator.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum EstimatorArg {
    /// The paper's Eq. 24: recorded stage positions and currents are exact.
    Paper,
    /// Errors-in-variables (the default): per-view stage/current corrections with
    /// Gaussian priors.
    Eiv,
}

/// The calibration method.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum MethodArg {
    /// The paper's method: RAC, focal polynomial, distortion, bundle adjustment.
    Proposed,
    /// The baseline of section 5.2.3: Zhang at each current, then a cubic.
    PerSetting,
}

/// The distortion family of `--distortion`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum DistortionArg {
    /// The paper's (Eq. 17: k1, p1, p2 in centred pixels, each quadratic in 1/f).
    Paper,
    /// OpenCV's (k1, k2, p1, p2, k3 in normalised coordinates, each quadratic in 1/f).
    Opencv,
    /// Chosen by the prediction error of held-out views (leave one view out).
    Auto,
}

/// `--focal-degree 1..5|auto`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FocalDegreeArg {
    /// This degree.
    Degree(usize),
    /// Chosen by the prediction error of held-out views.
    Auto,
}

/// Parses `--focal-degree`: 1..5 or `auto`.
fn parse_focal_degree(s: &str) -> std::result::Result<FocalDegreeArg, String> {
    match s {
        "auto" => Ok(FocalDegreeArg::Auto),
        _ => match s.parse::<usize>() {
            Ok(d) if (1..=etl_core::model::MAX_FOCAL_DEGREE).contains(&d) => Ok(FocalDegreeArg::Degree(d)),
            _ => Err(format!("\"{s}\" is not a degree 1..5 or auto")),
        },
    }
}

/// Arguments of `etlcal calibrate`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Corner observations (etlcal.observations/1).
    #[arg(long, value_name = "FILE")]
    pub observations: Option<PathBuf>,
    /// A dataset of images (etlcal.dataset/1).
    #[arg(long, value_name = "FILE", conflicts_with = "observations")]
    pub dataset: Option<PathBuf>,
    /// The method: the paper's (one calibration over all currents) or the per-setting
    /// baseline.
    #[arg(long, value_enum, default_value = "proposed")]
    pub method: MethodArg,
    /// Also write the observations detected in a dataset's images here (its directory is
    /// created if missing).
    #[arg(long, value_name = "FILE", requires = "dataset")]
    pub observations_out: Option<PathBuf>,
    /// Lens-off intrinsics (etlcal.a0/1); default: Zhang's method on the lens-off views.
    #[arg(long, value_name = "FILE")]
    pub a0: Option<PathBuf>,
    /// Where to write etlcal.calibration/1 (its directory is created if missing).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Bundle-adjustment estimator [default: eiv]: under the paper's noise model it reaches
    /// the Cramer-Rao bound and beats the paper's Eq. 24 (docs/RESULTS.md).
    // An Option, not a clap default, so that `--method per-setting` can refuse an
    // estimator the user gave (the baseline has no bundle adjustment), as Python does.
    #[arg(long, value_enum)]
    pub estimator: Option<EstimatorArg>,
    /// Prior standard deviation of the stage position for --estimator eiv, um.
    #[arg(long, default_value_t = 10.0)]
    pub sigma_z_um: f64,
    /// Prior standard deviation of the current for --estimator eiv, mA.
    #[arg(long, default_value_t = 0.4)]
    pub sigma_e_ma: f64,
    /// Hold A0 (kf0x, kf0y, u0, v0) fixed in the bundle adjustment.
    #[arg(long)]
    pub hold_a0: bool,
    /// Huber loss with this threshold (px) for bad corners.
    #[arg(long, value_name = "PX")]
    pub huber_px: Option<f64>,
    /// Distortion family [default: paper]; `auto` chooses by held-out views and records
    /// the comparison in the file's "model_selection".
    #[arg(long, value_enum)]
    pub distortion: Option<DistortionArg>,
    /// Degree of fx(E), fy(E): 1..5 or auto [default: 3, the paper's cubic].
    #[arg(long, value_name = "1..5|auto", value_parser = parse_focal_degree)]
    pub focal_degree: Option<FocalDegreeArg>,
    /// Hold k3 at 0 (OpenCV's CALIB_FIX_K3; --distortion opencv or auto).
    #[arg(long)]
    pub fix_k3: bool,
    /// Hold p1 = p2 = 0 (OpenCV's CALIB_ZERO_TANGENT_DIST; --distortion opencv or auto).
    #[arg(long)]
    pub zero_tangent: bool,
    /// Thermal calibration for views without e_com_ma: an etlcal.thermal/1 file, or
    /// `paper` for the paper's surface. Required when a view has no e_com_ma (none is
    /// assumed); kept whole in the calibration, which uses it at run time.
    #[arg(long, value_name = "FILE|paper")]
    pub thermal: Option<PathBuf>,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// The observations of `--observations`, or detected in the images of `--dataset`.
pub fn load_input(
    observations: Option<&std::path::Path>,
    dataset: Option<&std::path::Path>,
    progress: bool,
) -> Result<Observations> {
    match (observations, dataset) {
        (Some(p), None) => Observations::load(p),
        (None, Some(p)) => {
            let ds = Dataset::load(p)?;
            let (obs, summary) =
                observations_from_dataset(&ds, p, &default_detector(), &crate::progress::Bar::new(progress))?;
            for s in &summary.skipped {
                eprintln!("etlcal: warning: {} ({} image) skipped: {}", s.image.display(), s.kind, s.reason);
            }
            Ok(obs)
        }
        _ => Err(Error::invalid(
            "--observations",
            "pass --observations FILE (etlcal.observations/1) or --dataset FILE (etlcal.dataset/1)",
        )),
    }
}

/// Runs `etlcal calibrate`.
pub fn run(args: Args) -> Result<()> {
    // Cheap checks first: a bad flag or output path must not cost a detection run, and an
    // output that is an input must be refused before the input is read.
    let mut outputs = vec![Output::File(&args.out)];
    outputs.extend(args.observations_out.as_deref().map(Output::File));
    let thermal_file = crate::output::thermal_file(args.thermal.as_deref());
    crate::output::check(
        [args.observations.as_deref(), args.dataset.as_deref(), args.a0.as_deref(), thermal_file],
        &outputs,
    )?;
    let sigmas = [("--sigma-z-um", args.sigma_z_um), ("--sigma-e-ma", args.sigma_e_ma)];
    if let Some((flag, x)) = sigmas.into_iter().find(|(_, x)| !(*x > 0.0)) {
        return Err(Error::invalid_value(flag, x, "--sigma-z-um and --sigma-e-ma must be positive"));
    }
    if args.method == MethodArg::PerSetting {
        refuse_bundle_adjust_options(
            "--method per-setting",
            [
                ("--a0", args.a0.is_some()),
                ("--estimator", args.estimator.is_some()),
                ("--hold-a0", args.hold_a0),
                ("--huber-px", args.huber_px.is_some()),
            ],
        )?;
        let model = [
            ("--distortion", args.distortion.is_some()),
            ("--focal-degree", args.focal_degree.is_some()),
            ("--fix-k3", args.fix_k3),
            ("--zero-tangent", args.zero_tangent),
        ];
        if let Some((flag, _)) = model.iter().find(|(_, given)| *given) {
            return Err(Error::invalid(
                *flag,
                format!("--method per-setting takes no {flag}: the baseline fits the paper's model (cubic, paper distortion)"),
            ));
        }
    }
    model_choice(&args)?;
    let thermal = args.thermal.as_deref().map(ThermalRef::choose).transpose()?;
    let obs = load_input(args.observations.as_deref(), args.dataset.as_deref(), !args.json)?;
    let calibration = match args.method {
        MethodArg::PerSetting => etl_calib::baseline::per_setting(&obs, thermal.as_ref())?.calibration,
        MethodArg::Proposed => calibrate_proposed(&args, &obs, thermal.as_ref())?,
    };
    let files: Vec<&Path> = std::iter::once(&args.out).chain(&args.observations_out).map(PathBuf::as_path).collect();
    for out in &files {
        crate::output::create_parent(out)?;
    }
    // Both files or neither: a calibration beside observations of another run is wrong.
    write_file_set(&files, |tmp| {
        calibration.save(&tmp[0])?;
        tmp.get(1).map_or(Ok(()), |p| obs.save(p))
    })?;
    if args.json {
        print_json(&serde_json::to_value(&calibration).map_err(|e| Error::invalid("--json", e.to_string()))?);
    } else {
        let c = &calibration;
        outln!(
            "calibrated {} views: rms {:.4} px (before BA {:.4} px), {} iterations, estimator {}",
            c.views.len(),
            c.rms_reprojection_px,
            c.initial_rms_px,
            c.iterations,
            c.estimator
        );
        if !c.outliers.is_empty() {
            outln!("left out {} outlier corners (listed in the file's \"outliers\")", c.outliers.len());
        }
        if !c.setting_outliers.is_empty() {
            let n = c.setting_outliers.len();
            outln!("left out {n} outlier corners of setting views (listed in the file's \"setting_outliers\")");
        }
        if let Some(chosen) = c.model_selection.as_ref().and_then(|s| s.chosen()) {
            outln!(
                "model: {} distortion, focal degree {} (predicts held-out views to {:.4} px; {} candidates in the file's \"model_selection\")",
                chosen.distortion_model,
                chosen.focal_degree,
                chosen.prediction_rms_px.unwrap_or(f64::NAN),
                c.model_selection.as_ref().map_or(0, |s| s.candidates.len())
            );
        }
        outln!("wrote {}", args.out.display());
    }
    Ok(())
}

/// The model the flags ask for: the family and the degree (None: chosen by the data) and
/// OpenCV's flags, refused with the paper's family (naming the flag).
fn model_choice(args: &Args) -> Result<(Option<DistortionModel>, Option<usize>, OpenCvFlags)> {
    let family = match args.distortion.unwrap_or(DistortionArg::Paper) {
        DistortionArg::Paper => Some(DistortionModel::Paper),
        DistortionArg::Opencv => Some(DistortionModel::OpenCv),
        DistortionArg::Auto => None,
    };
    let degree = match args.focal_degree.unwrap_or(FocalDegreeArg::Degree(etl_core::model::PAPER_FOCAL_DEGREE)) {
        FocalDegreeArg::Degree(d) => Some(d),
        FocalDegreeArg::Auto => None,
    };
    let flags = OpenCvFlags { fix_k3: args.fix_k3, zero_tangent: args.zero_tangent };
    refuse_opencv_flags(family, flags, ["--fix-k3", "--zero-tangent"], "--distortion opencv or auto")?;
    Ok((family, degree, flags))
}

fn calibrate_proposed(args: &Args, obs: &Observations, thermal: Option<&ThermalRef>) -> Result<Calibration> {
    let (family, degree, flags) = model_choice(args)?;
    let given_a0 = args.a0.as_deref().map(|p| A0File::load(p).map(|f| f.a0())).transpose()?;
    let robust = match args.huber_px {
        Some(k) if k > 0.0 => Some(RobustLoss::Huber { k_px: k }),
        Some(k) => return Err(Error::invalid_value("--huber-px", k, "--huber-px must be positive")),
        None => None,
    };
    let estimator = match args.estimator.unwrap_or(EstimatorArg::Eiv) {
        EstimatorArg::Paper => Estimator::Paper,
        EstimatorArg::Eiv => {
            Estimator::Eiv { sigma_z_mm: args.sigma_z_um / 1000.0, sigma_e_ma: args.sigma_e_ma, sigma_px: None }
        }
    };
    let opts = CalibrateOptions { estimator, hold_a0: args.hold_a0, robust, layout: Layout::PAPER, flags };
    let result = match (family, degree) {
        (Some(family), Some(degree)) => {
            let layout = Layout::new(family, degree).map_err(Error::Core)?;
            let a0 = match given_a0 {
                Some(a0) => a0,
                None => a0_from_offstate_with(obs, &ZhangOptions { model: family, flags })?.a0(),
            };
            calibrate(obs, &a0, thermal, &CalibrateOptions { layout, ..opts })?
        }
        _ => {
            let candidates = Candidates {
                families: family.map_or(DistortionModel::ALL.to_vec(), |f| vec![f]),
                focal_degrees: degree.map_or((1..=etl_core::model::MAX_FOCAL_DEGREE).collect(), |d| vec![d]),
            };
            let source = given_a0.map_or(A0Source::Offstate, A0Source::Given);
            select(obs, &source, thermal, &opts, &candidates)?
        }
    };
    if let Some(why) = &result.focus_law_warning {
        eprintln!("etlcal: warning: {why}");
    }
    // Implausible data (outliers left out, an RMS far above the noise, corrections far
    // beyond their priors) are said on stderr as well as kept in the file's "warnings".
    for why in &result.calibration.warnings {
        eprintln!("etlcal: warning: {why}");
    }
    Ok(result.calibration)
}
