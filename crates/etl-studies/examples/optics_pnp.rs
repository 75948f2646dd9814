//! The 2 mm move by PnP on the ray-traced rigs of fixtures/optics, the fixed-centre model
//! against a per-current OpenCV calibration ([`etl_studies::optics`]); prints one Markdown
//! table per rig (docs/RESULTS.md). Run:
//! `cargo run --release -p etl-studies --example optics_pnp -- [SEEDS] [OPTICS_FILE...]`
//! (default 20 seeds, the fixtures' rigs).

use std::path::Path;

use etl_formats::optics::OpticsFile;
use etl_sim::optics::OpticalRig;
use etl_studies::optics::optics_pnp;

/// The rigs run when no file is given.
const FIXTURES: [&str; 2] = ["cooke-16mm-centred.json", "double-gauss-25mm-toleranced.json"];

fn main() -> etl_formats::Result<()> {
    let seeds: u64 = std::env::args().nth(1).map_or(Ok(20), |s| s.parse()).expect("SEEDS: a whole number");
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/optics");
    let given: Vec<std::path::PathBuf> = std::env::args().skip(2).map(Into::into).collect();
    let files = if given.is_empty() { FIXTURES.iter().map(|n| dir.join(n)).collect() } else { given };
    for path in files {
        let rig = OpticalRig::new(OpticsFile::load(&path)?)?;
        println!("{}", optics_pnp(&rig, seeds, &[80.0, 150.0, 225.0])?.markdown());
    }
    Ok(())
}
