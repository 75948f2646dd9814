//! The acceptance of a calibrated 2-camera rig (docs/RESULTS.md):
//! `cargo run --release -p etl-studies --example rig_triangulation -- [TRIALS] [SEED] [fixed|moving]`
//! (default 200 trials from seed 1, fixed centres), a markdown summary on stdout.

use etl_studies::rig_triangulation::{rig_triangulation, RigTriangulationDesign, NOISE};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let trials: usize = args.next().map_or(Ok(200), |a| a.parse())?;
    let seed: u64 = args.next().map_or(Ok(1), |a| a.parse())?;
    let moving_centre = match args.next().as_deref() {
        None | Some("fixed") => false,
        Some("moving") => true,
        Some(other) => return Err(format!("centre: {other} is neither fixed nor moving").into()),
    };
    let r = rig_triangulation(&RigTriangulationDesign { moving_centre, noise: NOISE }, trials, seed);
    print!("{}", r.markdown());
    Ok(())
}
