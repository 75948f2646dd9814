//! The `etlcal` command line. Each verb lives in its own file with an `Args` struct (clap)
//! and a `run(args) -> Result<()>`; `main` dispatches and prints a failure as one line on
//! stderr. `--json` (before or after the verb) makes the output one JSON object on stdout.
//!
//! Exit status: 0 on success (`--help` and `--version` included, printed on stdout); 1 when
//! the verb failed (bad input value, unreadable file, device error, ...; `detect` also when
//! any image failed); 2 when the command line does not parse (clap's usage errors, as clap
//! and the BSD `EX_USAGE` convention have it), rendered as one line
//! `etlcal: error: <what>; see etlcal VERB --help` instead of clap's usage block.
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use etl_formats::Result;

mod output;
mod progress;
mod rig_setting;
mod setting;
mod signals;

/// `println!` for everything the verbs print on stdout (human-readable lines and
/// [`print_json`]), ignoring a closed stdout (`etlcal ... | head`): `println!` panics there.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout().lock(), $($arg)*);
    }};
}

pub mod board;
pub mod calibrate;
pub mod calibrate_rig;
pub mod camera;
pub mod capture;
pub mod demo;
pub mod detect;
pub mod diff;
pub mod export;
pub mod focus;
pub mod lens;
pub mod lens_characterise;
pub mod lens_focal;
pub mod lens_sim;
pub mod measure;
pub mod model;
pub mod rectify;
pub mod render;
pub mod report;
pub mod sharpness;
pub mod simulate;
pub mod stage;
pub mod stereo;
pub mod study;
pub mod thermal;
pub mod triangulate;
pub mod undistort;
pub mod zhang;

/// Calibrate a camera focused by an electrically tunable lens, then use it at any lens
/// current and temperature.
#[derive(Parser)]
#[command(
    name = "etlcal",
    version,
    propagate_version = true,
    about = "Calibrate a camera focused by an electrically tunable lens (ETL), then use it at any lens current and temperature.",
    long_about = "Calibrate a camera focused by an electrically tunable lens (ETL), then use it at any lens current and \
temperature: the method of \"Calibration method for the electrically tunable lens based on shape-changing polymer\" \
(Optics Express 2020), with an errors-in-variables bundle adjustment by default.\n\n\
New here? etlcal demo runs everything on a simulated rig and writes etlcal-demo/ (open \
etlcal-demo/index.html). A real rig: etlcal board, then etlcal calibrate --dataset, then \
export, measure, undistort or focus at the lens's setting (docs/RIG.md, docs/CLI.md)."
)]
pub struct Cli {
    /// Print one JSON object on stdout (accepted before or after the verb).
    #[arg(long, global = true)]
    json: bool,
    /// No progress on stderr: neither the terminal's bar nor, without a terminal, the log
    /// line written every few seconds of long work (accepted before or after the verb).
    #[arg(long, global = true)]
    quiet: bool,
    #[command(subcommand)]
    command: Command,
}

// Verbs: one variant per verb, one file per verb (add yours here and in `run` below).
#[derive(Subcommand)]
enum Command {
    /// The paper rig's camera model and lens physics over a range of currents (Fig. 5 fits
    /// with --fit-degrees).
    Model(model::Args),
    /// Temperature compensation: evaluate or fit the E_T(T, E_in) surface.
    Thermal(thermal::Args),
    /// Simulate the paper rig, calibrate it (paper and errors-in-variables estimators) and
    /// validate against the truth: the main job on the built-in simulated rig.
    Demo(demo::Args),
    /// The paper rig's synthetic data without calibrating.
    Simulate(simulate::Args),
    /// Calibrate from corner observations: RAC, focal polynomial, distortion, bundle adjustment.
    Calibrate(calibrate::Args),
    /// Calibrate a multi-camera ETL rig jointly from a rig dataset: every camera's numbers
    /// and the extrinsics, with the shared stage corrections.
    CalibrateRig(calibrate_rig::Args),
    /// Plots of a calibration (focal lengths, distortion, residuals) and an index.html.
    Report(report::Args),
    /// Monofocal calibration of a fixed-focus camera from board images (Zhang).
    Zhang(zhang::Args),
    /// A fixed-focus camera pair from synchronised board images: each camera by Zhang, then R, T.
    Stereo(stereo::Args),
    /// The board's pose in two images at a lens current and the displacement between them.
    Measure(measure::Args),
    /// The camera at a lens current and temperature for OpenCV, ROS or mrcal.
    Export(export::Args),
    /// Points seen by two or more cameras of a rig at their settings, with their covariance.
    Triangulate(triangulate::Args),
    /// Bouguet's rectification of two cameras of a rig at their settings: stereo YAML, exports, maps.
    Rectify(rectify::Args),
    /// The lens current that focuses the calibrated camera at a distance (the focus law).
    Focus(focus::Args),
    /// Undistort images taken at a lens current and temperature (exact maps of the model).
    Undistort(undistort::Args),
    /// How far apart two calibrations project the same directions at one lens setting.
    Diff(diff::Args),
    /// The paper's simulations and comparisons (Fig. 5, Fig. 6, Tables 1-2, Fig. 12, CRLB).
    Study(study::Args),
    /// Sharpness of images: CPBD (as the reference package) or a gradient measure.
    Sharpness(sharpness::Args),
    /// Find a board's corners in images, sub-pixel: a ChArUco board's with their ids (partial views
    /// welcome) or a whole checkerboard's.
    Detect(detect::Args),
    /// A synthetic image of a board through the paper rig's camera, and its true corners.
    Render(render::Args),
    /// A print-ready board (SVG at true size in mm, or PNG at a dpi) from its etlcal.board/1 file.
    Board(board::Args),
    /// Drive an Optotune lens (Lens Driver 4) or the virtual lens: info, current, temperature, hold.
    Lens(lens::Args),
    /// Run a virtual lens on a pseudo-terminal and print its port path.
    LensSim(lens_sim::Args),
    /// Capture a dataset on a rig from a plan (camera, lens, stage), resumably.
    Capture(capture::Args),
    /// List cameras, or grab an image from one.
    Camera(camera::Args),
    /// Move a stage, read its position, home it.
    Stage(stage::Args),
}

/// Prints `value` as one JSON object on stdout.
///
/// A closed stdout (`etlcal ... --json | head`) is not an error worth a panic: the write
/// is dropped.
pub fn print_json(value: &serde_json::Value) {
    outln!("{value}");
}

/// The out-of-range policy of a verb's `--allow-extrapolation` flag (one policy for every
/// verb: refuse outside the calibrated ranges unless asked).
pub fn trust(allow_extrapolation: bool) -> etl_formats::Trust {
    if allow_extrapolation {
        etl_formats::Trust::Extrapolate
    } else {
        etl_formats::Trust::Refuse
    }
}

fn run(cli: Cli) -> Result<ExitCode> {
    let json = cli.json;
    progress::set_quiet(cli.quiet);
    let done = |r: Result<()>| r.map(|()| ExitCode::SUCCESS);
    match cli.command {
        Command::Model(a) => done(model::run(model::Args { json, ..a })),
        Command::Thermal(a) => done(thermal::run(a, json)),
        Command::Demo(a) => done(demo::run(demo::Args { json, ..a })),
        Command::Simulate(a) => done(simulate::run(simulate::Args { json, ..a })),
        Command::Calibrate(a) => done(calibrate::run(calibrate::Args { json, ..a })),
        Command::CalibrateRig(a) => done(calibrate_rig::run(calibrate_rig::Args { json, ..a })),
        Command::Report(a) => done(report::run(report::Args { json, ..a })),
        Command::Zhang(a) => done(zhang::run(zhang::Args { json, ..a })),
        Command::Stereo(a) => done(stereo::run(stereo::Args { json, ..a })),
        Command::Measure(a) => done(measure::run(measure::Args { json, ..a })),
        Command::Export(a) => done(export::run(export::Args { json, ..a })),
        Command::Triangulate(a) => done(triangulate::run(triangulate::Args { json, ..a })),
        Command::Rectify(a) => done(rectify::run(rectify::Args { json, ..a })),
        Command::Focus(a) => done(focus::run(focus::Args { json, ..a })),
        Command::Undistort(a) => done(undistort::run(undistort::Args { json, ..a })),
        Command::Diff(a) => done(diff::run(diff::Args { json, ..a })),
        Command::Study(a) => done(study::run(study::Args { json, ..a })),
        Command::Sharpness(a) => done(sharpness::run(sharpness::Args { json, ..a })),
        Command::Detect(a) => detect::run(detect::Args { json, ..a }),
        Command::Render(a) => done(render::run(render::Args { json, ..a })),
        Command::Board(a) => done(board::run(board::Args { json, ..a })),
        Command::Lens(a) => done(lens::run(lens::Args { json, ..a })),
        Command::LensSim(a) => done(lens_sim::run(lens_sim::Args { json, ..a })),
        Command::Capture(a) => done(capture::run(capture::Args { json, ..a })),
        Command::Camera(a) => done(camera::run(camera::Args { json, ..a })),
        Command::Stage(a) => done(stage::run(stage::Args { json, ..a })),
    }
}

/// Clap's error as one line: its first line (with the list that follows a trailing `:`,
/// e.g. the missing required arguments) and the `--help` of the verb it concerns.
fn one_line_usage_error(e: &clap::Error, argv: &[String]) -> String {
    let text = e.render().to_string();
    let mut lines = text.lines();
    let mut what = lines.next().unwrap_or("invalid command line").trim_start_matches("error: ").to_owned();
    if what.ends_with(':') {
        let items: Vec<&str> = lines.take_while(|l| l.starts_with(' ')).map(str::trim).collect();
        what = format!("{} {}", what, items.join(", "));
    }
    format!("etlcal: error: {what}; see {} --help", verb_of(argv))
}

/// The verb (and subcommand) named on the command line, e.g. `etlcal lens info`: the
/// words of `argv` that name a subcommand of the one before, in order.
fn verb_of(argv: &[String]) -> String {
    let mut command = <Cli as clap::CommandFactory>::command();
    let mut words = vec!["etlcal".to_owned()];
    for arg in argv.iter().skip(1) {
        let Some(sub) = command.find_subcommand(arg).cloned() else { continue };
        words.push(sub.get_name().to_owned());
        command = sub;
    }
    words.join(" ")
}

/// The command line parsed, with negative numbers taken as values by every verb and
/// subcommand (`render --e-com -292`, `thermal eval --t -10`): set here once rather than
/// on each `Args`, so that a new verb cannot forget it.
fn parse(argv: &[std::ffi::OsString]) -> std::result::Result<Cli, clap::Error> {
    fn negatives(c: clap::Command) -> clap::Command {
        c.allow_negative_numbers(true).mut_subcommands(negatives)
    }
    let matches = negatives(<Cli as clap::CommandFactory>::command()).try_get_matches_from(argv)?;
    <Cli as clap::FromArgMatches>::from_arg_matches(&matches)
}

fn main() -> ExitCode {
    // `args_os`: a path that is not UTF-8 is a legal path, and `args` would panic on it.
    let argv_os: Vec<std::ffi::OsString> = std::env::args_os().collect();
    let argv: Vec<String> = argv_os.iter().map(|a| a.to_string_lossy().into_owned()).collect();
    let cli = match parse(&argv_os) {
        Ok(cli) => cli,
        Err(e) if matches!(e.kind(), clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion) => {
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            eprintln!("{}", one_line_usage_error(&e, &argv));
            return ExitCode::from(2);
        }
    };
    match run(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("etlcal: error: {e}");
            ExitCode::FAILURE
        }
    }
}
