//! What any per-current central model can reach on the ray-traced rigs of fixtures/optics,
//! noise-free ([`etl_studies::optics::floor`]); prints one Markdown table per rig
//! (docs/RESULTS.md). Run:
//! `cargo run --release -p etl-studies --example optics_floor -- [OPTICS_FILE...]`
//! (default: the fixtures' rigs).

use std::path::Path;

use etl_formats::optics::OpticsFile;
use etl_sim::optics::OpticalRig;
use etl_studies::optics::floor::central_floor;

/// The rigs run when no file is given.
const FIXTURES: [&str; 2] = ["cooke-16mm-centred.json", "double-gauss-25mm-toleranced.json"];

fn main() -> etl_formats::Result<()> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/optics");
    let given: Vec<std::path::PathBuf> = std::env::args().skip(1).map(Into::into).collect();
    let files = if given.is_empty() { FIXTURES.iter().map(|n| dir.join(n)).collect() } else { given };
    for path in files {
        let rig = OpticalRig::new(OpticsFile::load(&path)?)?;
        println!("{}", central_floor(&rig, &[80.0, 150.0, 225.0])?.markdown());
    }
    Ok(())
}
