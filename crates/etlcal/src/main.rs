//! The `etlcal` command line. Each verb lives in its own file with an `Args` struct (clap)
//! and a `run(args) -> Result<()>`; `main` dispatches, prints a failure as one line on
//! stderr and exits with status 1. `--json` output is one JSON object on stdout.
use clap::{Parser, Subcommand};

use etl_formats::Result;

mod progress;

/// `println!` for everything the verbs print on stdout (human-readable lines and
/// [`print_json`]), ignoring a closed stdout (`etlcal ... | head`): `println!` panics there.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout().lock(), $($arg)*);
    }};
}

pub mod calibrate;
pub mod demo;
pub mod detect;
pub mod lens;
pub mod lens_sim;
pub mod measure;
pub mod model;
pub mod render;
pub mod report;
pub mod sharpness;
pub mod simulate;
pub mod study;
pub mod thermal;
pub mod zhang;

/// Calibrate and run cameras focused by an electrically tunable lens.
#[derive(Parser)]
#[command(name = "etlcal", version, about, propagate_version = true)]
pub struct Cli {
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
    /// Plots of a calibration (focal lengths, distortion, residuals) and an index.html.
    Report(report::Args),
    /// Monofocal calibration of a fixed-focus camera from board images (Zhang).
    Zhang(zhang::Args),
    /// The board's pose in two images at a lens current and the displacement between them.
    Measure(measure::Args),
    /// The paper's simulations and comparisons (Fig. 5, Fig. 6, Tables 1-2, Fig. 12, CRLB).
    Study(study::Args),
    /// Sharpness of images: CPBD (as the reference package) or a gradient measure.
    Sharpness(sharpness::Args),
    /// Find the checkerboard's corners in images (sub-pixel, stable order).
    Detect(detect::Args),
    /// A synthetic image of a board through the paper rig's camera, and its true corners.
    Render(render::Args),
    /// Drive an Optotune lens (Lens Driver 4) or the virtual lens: info, current, temperature, hold.
    Lens(lens::Args),
    /// Run a virtual lens on a pseudo-terminal and print its port path.
    LensSim(lens_sim::Args),
}

/// Prints `value` as one JSON object on stdout.
///
/// A closed stdout (`etlcal ... --json | head`) is not an error worth a panic: the write
/// is dropped.
pub fn print_json(value: &serde_json::Value) {
    outln!("{value}");
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Model(a) => model::run(a),
        Command::Thermal(a) => thermal::run(a),
        Command::Demo(a) => demo::run(a),
        Command::Simulate(a) => simulate::run(a),
        Command::Calibrate(a) => calibrate::run(a),
        Command::Report(a) => report::run(a),
        Command::Zhang(a) => zhang::run(a),
        Command::Measure(a) => measure::run(a),
        Command::Study(a) => study::run(a),
        Command::Sharpness(a) => sharpness::run(a),
        Command::Detect(a) => detect::run(a),
        Command::Render(a) => render::run(a),
        Command::Lens(a) => lens::run(a),
        Command::LensSim(a) => lens_sim::run(a),
    }
}

fn main() {
    let cli = Cli::parse();
    if let Err(e) = run(cli) {
        eprintln!("etlcal: error: {e}");
        std::process::exit(1);
    }
}
