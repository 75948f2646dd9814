//! `etlcal simulate --out DIR --observations-only [--seed N] [--stage-noise-um X] [--json]`:
//! the paper rig's synthetic data without calibrating: observations.json (with the
//! paper's noise model), a0.json (the A0 a lens-off calibration would give) and
//! truth.json (the true model and per-view errors).
//!
//! Rendering images (without `--observations-only`) needs the synthetic camera, which is
//! not implemented yet; asking for it is an error that says so.

use std::path::PathBuf;

use serde_json::json;

use super::print_json;
use crate::error::{Error, Result};
use crate::formats::a0::A0File;
use crate::formats::write_json;
use crate::simulate::{paper_rig, NoiseModel, Simulation};

/// Arguments of `etlcal simulate`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Output directory (must exist).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Write corner observations only (no images).
    #[arg(long)]
    pub observations_only: bool,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Stage-position noise per view, um (paper: 10).
    #[arg(long, default_value_t = 10.0)]
    pub stage_noise_um: f64,
    /// Current noise per view, mA (paper: 0.4).
    #[arg(long, default_value_t = 0.4)]
    pub current_noise_ma: f64,
    /// Pixel noise, px (paper: 0.2).
    #[arg(long, default_value_t = 0.2)]
    pub pixel_noise_px: f64,
    /// Print a JSON summary.
    #[arg(long)]
    pub json: bool,
}

/// The noise model of the simulation flags.
pub fn noise_from(stage_um: f64, current_ma: f64, pixel_px: f64) -> Result<NoiseModel> {
    if ![stage_um, current_ma, pixel_px].iter().all(|x| x.is_finite() && *x >= 0.0) {
        return Err(Error::InvalidInput("noise levels must be finite and not negative".into()));
    }
    Ok(NoiseModel { z_mm: stage_um / 1000.0, e_ma: current_ma, px: pixel_px, ..NoiseModel::PAPER })
}

/// Writes a simulation's files into `dir`.
pub fn write_simulation(sim: &Simulation, dir: &std::path::Path) -> Result<()> {
    sim.observations.save(&dir.join("observations.json"))?;
    A0File::new(&sim.a0).save(&dir.join("a0.json"))?;
    write_json(
        &dir.join("truth.json"),
        &json!({"format": "etlcal.truth/1", "model": sim.truth, "dz_mm": sim.true_dz_mm, "de_ma": sim.true_de_ma}),
    )
}

/// Runs `etlcal simulate`.
pub fn run(args: Args) -> Result<()> {
    if !args.observations_only {
        return Err(Error::InvalidInput("rendering images is not implemented yet: pass --observations-only".into()));
    }
    if !args.out.is_dir() {
        return Err(Error::InvalidInput(format!("{}: output directory does not exist", args.out.display())));
    }
    let noise = noise_from(args.stage_noise_um, args.current_noise_ma, args.pixel_noise_px)?;
    let sim = paper_rig(&noise, args.seed);
    write_simulation(&sim, &args.out)?;
    let points: usize = sim.observations.views.iter().map(|v| v.points.len()).sum();
    if args.json {
        print_json(&json!({"views": sim.observations.views.len(), "points": points, "out": args.out}));
    } else {
        println!(
            "wrote observations.json, a0.json, truth.json ({} views, {points} points) to {}",
            sim.observations.views.len(),
            args.out.display()
        );
    }
    Ok(())
}
