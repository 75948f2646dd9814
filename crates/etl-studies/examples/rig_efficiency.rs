//! The statistical efficiency of the joint rig calibration (docs/RESULTS.md):
//! `cargo run --release -p etl-studies --example rig_efficiency -- [TRIALS] [SEED]`
//! (default 300 trials from seed 1), a markdown table on stdout.

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let trials: usize = args.next().map_or(Ok(300), |a| a.parse())?;
    let seed: u64 = args.next().map_or(Ok(1), |a| a.parse())?;
    let r = etl_studies::rig_efficiency::rig_efficiency(trials, seed)?;
    print!("{}", r.markdown());
    Ok(())
}
