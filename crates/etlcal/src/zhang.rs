//! `etlcal zhang IMAGE... (--pattern CxR --square MM | --board FILE) [--json]`: monofocal
//! calibration of one fixed-focus camera (Zhang 2000, with the paper's distortion k1, p1,
//! p2 in centred pixels) from a whole checkerboard or a ChArUco board (each view the
//! corners it shows, no hints), printing `{"fx", "fy", "u0", "v0", "k1", "p1", "p2", "rms_px", "views_used"}`
//! with `--json`. Images whose board is not found are named on stderr and skipped; at
//! least 3 views must remain.

use std::path::PathBuf;

use serde_json::json;

use super::print_json;
use crate::board::BoardArgs;
use etl_calib::pipeline::detect_views;
use etl_calib::zhang::zhang;
use etl_formats::{Error, Result};

/// Arguments of `etlcal zhang`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Images of the board (at least 3 in distinct orientations).
    #[arg(required = true, value_name = "IMAGE")]
    pub images: Vec<PathBuf>,
    /// The board.
    #[command(flatten)]
    pub board: BoardArgs,
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

/// Runs `etlcal zhang`.
pub fn run(args: Args) -> Result<()> {
    let board = args.board.board()?;
    let found = detect_views(&args.images, &board, &crate::progress::Bar::new(!args.json))?;
    for m in &found.skipped {
        eprintln!("etlcal: warning: skipped: {m}");
    }
    let (views, size) = (found.views, found.image_size);
    if views.len() < 3 {
        return Err(Error::BoardNotFound(format!(
            "the board was found in {} of {} images; Zhang's method needs at least 3",
            views.len(),
            args.images.len()
        )));
    }
    let z = zhang(&views, size)?;
    let j = json!({"fx": z.fx, "fy": z.fy, "u0": z.u0, "v0": z.v0, "k1": z.k1, "p1": z.p1, "p2": z.p2,
        "rms_px": z.rms_px, "views_used": z.views_used});
    if args.json {
        print_json(&j);
    } else {
        outln!(
            "fx {:.3} +- {:.3}, fy {:.3} +- {:.3}, u0 {:.3} +- {:.3}, v0 {:.3} +- {:.3} px",
            z.fx,
            z.std[0],
            z.fy,
            z.std[1],
            z.u0,
            z.std[2],
            z.v0,
            z.std[3]
        );
        outln!("k1 {:.4e}, p1 {:.4e}, p2 {:.4e}; rms {:.4} px over {} views", z.k1, z.p1, z.p2, z.rms_px, z.views_used);
    }
    Ok(())
}
