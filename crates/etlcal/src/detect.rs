//! `etlcal detect IMAGE... --pattern CxR [--json]`: finds the checkerboard in every image
//! (in parallel) and prints its corners in the documented order (see [`crate::detect`]).
//!
//! With `--json`: `{"images": [{"path", "found": bool, "error"?, "corners_px": [[u, v],
//! ...]}]}` (`corners_px` empty when not found). Without: one line per image, then one line
//! `i j u v` per corner.
//!
//! Exit status: 0 when the board was found in every image; 1 when any image failed (file
//! missing, unreadable or not a decodable image, or board not found): the output still lists
//! every image, the failed ones with their error, and stderr has one line per failed image.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

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
    /// Set from the global `--json` (one JSON object on stdout).
    #[arg(skip)]
    pub json: bool,
}

fn parse_pattern(s: &str) -> std::result::Result<Pattern, String> {
    s.parse::<Pattern>().map_err(|e| e.to_string())
}

/// Runs `etlcal detect`: `FAILURE` when any image failed (after listing every image and
/// one stderr line per failed one), `SUCCESS` otherwise.
pub fn run(args: Args) -> Result<ExitCode> {
    let results = detect_many(&args.images, args.pattern);
    let mut failures = Vec::new();
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
                failures.push(failure_line(path, &e));
            }
        }
    }
    if args.json {
        print_json(&json!({"images": entries}));
    }
    for line in &failures {
        eprintln!("{line}");
    }
    Ok(if failures.is_empty() { ExitCode::SUCCESS } else { ExitCode::FAILURE })
}

/// The stderr line of a failed image, naming it once (file errors already carry the path).
fn failure_line(path: &Path, e: &Error) -> String {
    match e {
        Error::Io { .. } | Error::Image { .. } => format!("etlcal: error: {e}"),
        _ => format!("etlcal: error: {}: {e}", path.display()),
    }
}
