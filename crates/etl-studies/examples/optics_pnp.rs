//! The 2 mm move by PnP on the ray-traced rigs of fixtures/optics, the fixed-centre model
//! against a per-current OpenCV calibration ([`etl_studies::optics`]); prints one Markdown
//! table per rig (docs/RESULTS.md). Run:
//! `cargo run --release -p etl-studies --example optics_pnp -- [SEEDS]` (default 20).

use std::path::Path;

use etl_formats::optics::OpticsFile;
use etl_sim::optics::OpticalRig;
use etl_studies::optics::optics_pnp;

fn main() -> etl_formats::Result<()> {
    let seeds: u64 = std::env::args().nth(1).map_or(Ok(20), |s| s.parse()).expect("SEEDS: a whole number");
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/optics");
    for name in ["cooke-16mm-centred.json", "double-gauss-25mm-toleranced.json"] {
        let rig = OpticalRig::new(OpticsFile::load(&dir.join(name))?)?;
        println!("{}", optics_pnp(&rig, seeds, &[80.0, 150.0, 225.0])?.markdown());
    }
    Ok(())
}
