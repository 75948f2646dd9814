//! `etlcal calibrate (--dataset FILE | --observations FILE) --out calibration.json
//! [--method proposed|per-setting] [--a0 A0.json] [--estimator paper|eiv]
//! [--sigma-z-um UM | --sigma-z-mm MM] [--sigma-e-ma MA] [--sigma-px PX] [--hold-a0]
//! [--robust huber|cauchy [--robust-k-px PX] | --huber-px PX]
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
//! `--json` prints the object written.
//!
//! The flags only parse into an [`etl_calib::request::CalibrationRequest`], which holds
//! every option's default, its refusals and the run; Python's `etlcal.calibrate(...)`
//! parses its keywords into the same request (the same names: `--hold-a0` is `hold_a0`),
//! so the two give the same file. Without `--a0`, A0 comes from the lens-off views by
//! Zhang's method with the calibration's distortion family. The model is the paper's (its
//! distortion, cubic fx(E), fy(E)) unless `--distortion` / `--focal-degree` say otherwise;
//! `auto` chooses among the families (and degrees 1..5) by the error with which each
//! predicts every view held out (`etl_calib::pipeline::select`), and writes the comparison
//! into the file's `"model_selection"`. The bundle adjustment is errors-in-variables
//! unless `--estimator paper` asks for the paper's Eq. 24. `--method per-setting` is the
//! paper's baseline (Zhang at each current, a cubic through fx(E), fy(E); needs
//! `setting_views`); it refuses the flags of the bundle adjustment (`--a0`, `--estimator`,
//! `--hold-a0`, `--robust` / `--huber-px`) and of the model.

use std::path::{Path, PathBuf};

use etl_core::calib::RobustLoss;
use etl_core::model::DistortionModel;

use super::print_json;
use etl_calib::pipeline::dataset::{default_detector, observations_from_dataset};
use etl_calib::pipeline::SettingViews;
use etl_calib::request::{
    CalibrationRequest, CentreChoice, DistortionChoice, EivPriors, EstimatorChoice, FocalDegreeChoice, Method,
    RequestOption, Spelling, StageSigma, DEFAULT_ROBUST_K_PX,
};
use etl_formats::a0::A0File;
use etl_formats::calibration::ThermalRef;
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

/// The projection centre of `--centre`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum CentreArg {
    /// The paper's: one centre and principal point for every current.
    Fixed,
    /// The centre moves along the axis by dz(E) and the principal point with E (the
    /// entrance pupil behind an ETL moves with its power).
    Moving,
    /// Chosen by the prediction error of held-out views.
    Auto,
}

/// What `--setting-views` does with the observations' setting views.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum SettingViewsArg {
    /// Not used (the paper's method; only `--method per-setting` reads them).
    Ignored,
    /// Solved together with the stage views, each board in a pose of its own.
    Joint,
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

/// The robust loss of `--robust`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum RobustArg {
    /// Huber: quadratic up to k px, linear beyond.
    Huber,
    /// Cauchy: k^2 ln(1 + s / k^2), s the squared error: bounded influence.
    Cauchy,
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
    /// Also write the observations detected in a dataset's images here (its directory is
    /// created if missing).
    #[arg(long, value_name = "FILE", requires = "dataset")]
    pub observations_out: Option<PathBuf>,
    /// Where to write etlcal.calibration/1 (its directory is created if missing).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// The calibration's options (the model, the estimator, A0).
    #[command(flatten)]
    pub request: RequestFlags,
    /// Thermal calibration for views without e_com_ma: an etlcal.thermal/1 file, or
    /// `paper` for the paper's surface. Required when a view has no e_com_ma (none is
    /// assumed); kept whole in the calibration, which uses it at run time.
    // Not one of the RequestFlags: calibrate-rig takes it per camera (`--thermal CAM=FILE`).
    #[arg(long, value_name = "FILE|paper")]
    pub thermal: Option<PathBuf>,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// The options of a calibration request but its temperature surface, shared by
/// `calibrate` and `calibrate-rig` (each camera of a rig is calibrated with them, and
/// `--camera-flags` gives them per camera): with the surface (each verb's `--thermal`)
/// they parse into an [`etl_calib::request::CalibrationRequest`].
#[derive(clap::Args, Debug)]
pub struct RequestFlags {
    /// The method: the paper's (one calibration over all currents) or the per-setting
    /// baseline.
    #[arg(long, value_enum, default_value = "proposed")]
    pub method: MethodArg,
    /// Lens-off intrinsics (etlcal.a0/1); default: Zhang's method on the lens-off views.
    #[arg(long, value_name = "FILE")]
    pub a0: Option<PathBuf>,
    /// Bundle-adjustment estimator [default: eiv]: under the paper's noise model it reaches
    /// the Cramer-Rao bound and beats the paper's Eq. 24 (docs/RESULTS.md).
    // An Option, not a clap default, so that `--method per-setting` can refuse an
    // estimator the user gave (the baseline has no bundle adjustment), as Python does.
    #[arg(long, value_enum)]
    pub estimator: Option<EstimatorArg>,
    /// Standard deviation of a view's recorded stage position, um [default: 10, the
    /// paper's]: the prior of --estimator eiv, and the error --estimator paper's
    /// covariance accounts for.
    // The sigmas are Options: their defaults are the request's (defined once, in etl-calib).
    #[arg(long, value_name = "UM")]
    pub sigma_z_um: Option<f64>,
    /// The same prior in mm [default: 0.010] (Python's `sigma_z_mm`); not with --sigma-z-um.
    #[arg(long, value_name = "MM", conflicts_with = "sigma_z_um")]
    pub sigma_z_mm: Option<f64>,
    /// Standard deviation of a view's recorded current, mA [default: 0.4, the paper's]:
    /// the prior of --estimator eiv, and the error --estimator paper's covariance accounts
    /// for.
    #[arg(long, value_name = "MA")]
    pub sigma_e_ma: Option<f64>,
    /// Standard deviation of a focal-power view's setting, dpt [default: 0.05, half the
    /// driver's stated 0.1 dpt reproducibility]: as --sigma-e-ma, for views at focal
    /// powers (refused with views at currents).
    #[arg(long, value_name = "DPT")]
    pub sigma_p_dpt: Option<f64>,
    /// Pixel noise standard deviation, px [default: estimated: --estimator eiv from a plain
    /// solution, --estimator paper from its residuals with the input errors' share out].
    #[arg(long, value_name = "PX")]
    pub sigma_px: Option<f64>,
    /// Hold A0 (kf0x, kf0y, u0, v0) fixed in the bundle adjustment.
    #[arg(long)]
    pub hold_a0: bool,
    /// A robust loss on each corner's error, against bad corners (threshold / scale
    /// --robust-k-px).
    #[arg(long, value_enum)]
    pub robust: Option<RobustArg>,
    /// Threshold (huber) or scale (cauchy) of --robust, px [default: 1].
    #[arg(long, value_name = "PX", requires = "robust")]
    pub robust_k_px: Option<f64>,
    /// Huber loss with this threshold, px: an alias of `--robust huber --robust-k-px PX`,
    /// kept for existing scripts; not with --robust or --robust-k-px.
    #[arg(long, value_name = "PX", conflicts_with_all = ["robust", "robust_k_px"])]
    pub huber_px: Option<f64>,
    /// Distortion family [default: paper]; `auto` chooses by held-out views and records
    /// the comparison in the file's "model_selection".
    #[arg(long, value_enum)]
    pub distortion: Option<DistortionArg>,
    /// Degree of fx(E), fy(E): 1..5 or auto [default: 3, the paper's cubic].
    #[arg(long, value_name = "1..5|auto", value_parser = parse_focal_degree)]
    pub focal_degree: Option<FocalDegreeArg>,
    /// Projection centre [default: fixed, the paper's]: `moving` fits dz(E) = dz1 E + dz2
    /// E^2 along the axis and u0(E), v0(E) linear in E (the file's "centre"); `auto`
    /// chooses by held-out views.
    #[arg(long, value_enum)]
    pub centre: Option<CentreArg>,
    /// The observations' setting views in the bundle adjustment [default: ignored, the
    /// paper's method]: `joint` solves them with the stage views, each board in a free
    /// pose (started by PnP), so that tilted views tell fx(E) from a moving centre's
    /// dz(E); not with --method per-setting, --robust or an `auto` model choice.
    #[arg(long, value_enum)]
    pub setting_views: Option<SettingViewsArg>,
    /// `auto`: choose the distortion family, the focal degree and the centre together by
    /// the error of held-out views (all 20 candidates, in the file's "model_selection");
    /// not with --distortion, --focal-degree or --centre.
    #[arg(long, value_name = "auto", value_parser = ["auto"])]
    pub model: Option<String>,
    /// Hold k3 at 0 (OpenCV's CALIB_FIX_K3; --distortion opencv or auto).
    #[arg(long)]
    pub fix_k3: bool,
    /// Hold p1 = p2 = 0 (OpenCV's CALIB_ZERO_TANGENT_DIST; --distortion opencv or auto).
    #[arg(long)]
    pub zero_tangent: bool,
    /// Keep a calibration the data do not determine (a focal length not positive over the
    /// range, a principal point std above 5 % of the image), marked in its warnings;
    /// refused otherwise, naming the cause.
    #[arg(long)]
    pub accept_ill_conditioned: bool,
}

/// The CLI's words for the options of a request ([`Spelling`]): `--hold-a0`,
/// `--distortion opencv`. `huber_alias`: the robust loss was given as `--huber-px`, which
/// its refusals then name.
#[derive(Debug, Clone, Copy, Default)]
pub struct FlagSpelling {
    /// `--huber-px` was given (for `--robust huber --robust-k-px`).
    pub huber_alias: bool,
}

impl Spelling for FlagSpelling {
    fn name(&self, option: RequestOption) -> String {
        match option {
            RequestOption::Robust | RequestOption::RobustKPx if self.huber_alias => "--huber-px".to_owned(),
            _ => format!("--{}", option.key().replace('_', "-")),
        }
    }
    fn word(&self, word: &str) -> String {
        word.to_owned()
    }
    fn with_word(&self, option: RequestOption, word: &str) -> String {
        format!("{} {word}", self.name(option))
    }
    fn switched_on(&self, option: RequestOption) -> String {
        self.name(option)
    }
}

impl RequestFlags {
    /// The spelling of this command line's refusals.
    pub fn spelling(&self) -> FlagSpelling {
        FlagSpelling { huber_alias: self.huber_px.is_some() }
    }

    /// The request the flags ask for with the temperature surface `thermal` (an
    /// etlcal.thermal/1 file or `paper`), reading the `--a0` and thermal files, not the
    /// input.
    pub fn request(&self, thermal: Option<&Path>) -> Result<CalibrationRequest> {
        let robust = match (self.robust, self.huber_px) {
            (_, Some(k_px)) => Some(RobustLoss::Huber { k_px }),
            (Some(loss), None) => {
                let k_px = self.robust_k_px.unwrap_or(DEFAULT_ROBUST_K_PX);
                Some(match loss {
                    RobustArg::Huber => RobustLoss::Huber { k_px },
                    RobustArg::Cauchy => RobustLoss::Cauchy { k_px },
                })
            }
            (None, None) => None,
        };
        let sigma_z = self.sigma_z_mm.map(StageSigma::Mm).or(self.sigma_z_um.map(StageSigma::Um));
        Ok(CalibrationRequest {
            method: match self.method {
                MethodArg::Proposed => Method::Proposed,
                MethodArg::PerSetting => Method::PerSetting,
            },
            a0: self.a0.as_deref().map(|p| A0File::load(p).map(|f| f.a0())).transpose()?,
            thermal: thermal.map(ThermalRef::choose).transpose()?,
            estimator: self.estimator.map(|e| match e {
                EstimatorArg::Paper => EstimatorChoice::Paper,
                EstimatorArg::Eiv => EstimatorChoice::Eiv,
            }),
            priors: EivPriors {
                sigma_z,
                sigma_e_ma: self.sigma_e_ma,
                sigma_p_dpt: self.sigma_p_dpt,
                sigma_px: self.sigma_px,
            },
            hold_a0: self.hold_a0,
            robust,
            distortion: self.distortion.map(|d| match d {
                DistortionArg::Paper => DistortionChoice::Family(DistortionModel::Paper),
                DistortionArg::Opencv => DistortionChoice::Family(DistortionModel::OpenCv),
                DistortionArg::Auto => DistortionChoice::Auto,
            }),
            focal_degree: self.focal_degree.map(|d| match d {
                FocalDegreeArg::Degree(d) => FocalDegreeChoice::Degree(d),
                FocalDegreeArg::Auto => FocalDegreeChoice::Auto,
            }),
            fix_k3: self.fix_k3,
            zero_tangent: self.zero_tangent,
            accept_ill_conditioned: self.accept_ill_conditioned,
            centre: self.centre.map(|c| match c {
                CentreArg::Fixed => CentreChoice::Fixed,
                CentreArg::Moving => CentreChoice::Moving,
                CentreArg::Auto => CentreChoice::Auto,
            }),
            model_auto: self.model.is_some(),
            setting_views: self.setting_views.map(|s| match s {
                SettingViewsArg::Ignored => SettingViews::Ignored,
                SettingViewsArg::Joint => SettingViews::Joint,
            }),
        })
    }
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
    let flags = &args.request;
    let thermal_file = crate::output::thermal_file(args.thermal.as_deref());
    crate::output::check(
        [args.observations.as_deref(), args.dataset.as_deref(), flags.a0.as_deref(), thermal_file],
        &outputs,
    )?;
    let spelling = flags.spelling();
    let request = flags.request(args.thermal.as_deref())?;
    request.validate(&spelling)?;
    let obs = load_input(args.observations.as_deref(), args.dataset.as_deref(), !args.json)?;
    let calibrated = request.run(&obs, &spelling)?;
    // Said on stderr as well as kept in the file: no focus law, implausible data (outliers
    // left out, an RMS far above the noise, corrections far beyond their priors).
    for why in calibrated.warnings() {
        eprintln!("etlcal: warning: {why}");
    }
    let calibration = calibrated.into_calibration();
    if let Some(why) = calibration.temperature_compensation_warning() {
        eprintln!("etlcal: warning: {why}: use it with --e-com MA");
    }
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
