//! What any per-current central model can reach on the ray-traced rigs of fixtures/optics,
//! noise-free ([`etl_studies::optics::floor`]); prints one Markdown table per rig
//! (docs/RESULTS.md). Run:
//! `cargo run --release -p etl-studies --example optics_floor -- [--stop-scale S] [OPTICS_FILE...]`
//! (default: the fixtures' rigs; `--stop-scale S` scales the aperture stop's
//! semi-diameter by S, 0 < S <= 1: the same rig stopped down).

use std::path::Path;

use etl_formats::optics::OpticsFile;
use etl_formats::{Error, Result};
use etl_sim::optics::OpticalRig;
use etl_studies::optics::floor::central_floor;
use etl_studies::optics::stopped_down;

/// The rigs run when no file is given.
const FIXTURES: [&str; 2] = ["cooke-16mm-centred.json", "double-gauss-25mm-toleranced.json"];

fn main() -> Result<()> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/optics");
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut scale = 1.0;
    if args.first().map(String::as_str) == Some("--stop-scale") {
        let value = args.get(1).and_then(|s| s.parse::<f64>().ok());
        scale = value.ok_or_else(|| Error::invalid("--stop-scale", "--stop-scale takes a number in (0, 1]"))?;
        args.drain(..2);
    }
    let files: Vec<std::path::PathBuf> = if args.is_empty() {
        FIXTURES.iter().map(|n| dir.join(n)).collect()
    } else {
        args.iter().map(Into::into).collect()
    };
    for path in files {
        let rig = OpticalRig::new(stopped_down(OpticsFile::load(&path)?, scale)?)?;
        println!("{}", central_floor(&rig, &[80.0, 150.0, 225.0])?.markdown());
    }
    Ok(())
}
