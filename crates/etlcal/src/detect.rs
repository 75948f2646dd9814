//! `etlcal detect IMAGE... --pattern CxR [--json]`: finds the checkerboard in every image
//! (in parallel) and prints its corners in the documented order (see [`crate::detect`]).
//!
//! With `--json`: `{"images": [{"path", "found": bool, "error"?, "corners_px": [[u, v],
//! ...]}]}` (`corners_px` empty when not found). Without: one line per image, then one line
//! `i j u v` per corner.
//!
//! Exit status: 0 when every image could be read, whether or not its board was found (a
//! board not found is a result, reported per image); 1 when any file is missing, unreadable
//! or not a decodable image (the output still lists every image, the failed ones with their
//! error, and stderr names the first failure).

use std::path::PathBuf;

use serde_json::json;

use super::print_json;
use etl_formats::{Error, Result};
use etl_image::detect::{detect_many, Pattern};

/// Arguments of `etlcal detect`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Images (PNG, JPEG, TIFF; 8- or 16-bit; colour is converted to grey).
    #[arg(required = true, value_name = "IMAGE")]
    pub images: Vec<PathBuf>,
    /// Inner corners, columns x rows (e.g. 14x12).
    #[arg(long, value_parser = parse_pattern)]
    pub pattern: Pattern,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

fn parse_pattern(s: &str) -> std::result::Result<Pattern, String> {
    s.parse::<Pattern>().map_err(|e| e.to_string())
}

/// Runs `etlcal detect`.
pub fn run(args: Args) -> Result<()> {
    let results = detect_many(&args.images, args.pattern);
    let mut first_unreadable: Option<Error> = None;
    let mut entries = Vec::with_capacity(results.len());
    for (path, r) in args.images.iter().zip(results) {
        match r {
            Ok(d) => {
                if args.json {
                    entries.push(json!({"path": path, "found": true, "corners_px": d.corners_px}));
                } else {
                    outln!("{}: found {} corners", path.display(), d.corners_px.len());
                    for ([i, j], [u, v]) in d.indexed() {
                        outln!("{i} {j} {u:.4} {v:.4}");
                    }
                }
            }
            Err(e) => {
                if args.json {
                    entries.push(json!({"path": path, "found": false, "error": e.to_string(), "corners_px": []}));
                } else {
                    outln!("{}: not found: {e}", path.display());
                }
                if matches!(e, Error::Io { .. } | Error::Image { .. }) && first_unreadable.is_none() {
                    first_unreadable = Some(e);
                }
            }
        }
    }
    if args.json {
        print_json(&json!({"images": entries}));
    }
    match first_unreadable {
        Some(e) => Err(e),
        None => Ok(()),
    }
}
