//! `etlcal detect IMAGE... (--board FILE | --pattern CxR) [--json]`: finds the board in
//! every image (in parallel) and prints its corners with their ids (see
//! [`etl_image::board`]). `--board` reads an `etlcal.board/1` file: a ChArUco board (the
//! corners seen, partial views welcome, OpenCV's ids) or a checkerboard (the whole board);
//! `--pattern CxR` is the shorthand for a whole checkerboard of C x R inner corners.
//!
//! With `--json`: `{"images": [{"path", "found": bool, "error"?, "corners_px": [[u, v],
//! ...], "ids": [...]}]}` (`corners_px` and `ids` empty when not found; a checkerboard's ids
//! are the row-major corner index `row * cols + col`). Without: one line per image, then one
//! line per corner: `i j u v` for a checkerboard, `id u v` for a ChArUco board.
//!
//! Exit status: 0 when the board was found in every image; 1 when any image failed (file
//! missing, unreadable or not a decodable image, or board not found): the output still lists
//! every image, the failed ones with their error, and stderr has one line per failed image.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use serde_json::json;

use super::print_json;
use etl_formats::board::Board;
use etl_formats::{Error, Result};
use etl_image::board::detect_board_many;
use etl_image::checkerboard::Pattern;

/// Arguments of `etlcal detect`.
#[derive(clap::Args, Debug)]
#[command(group = clap::ArgGroup::new("target").required(true).args(["board", "pattern"]))]
pub struct Args {
    /// Images (PNG, JPEG, TIFF; 8- or 16-bit; colour is converted to grey).
    #[arg(required = true, value_name = "IMAGE")]
    pub images: Vec<PathBuf>,
    /// The board: an etlcal.board/1 file (ChArUco or checkerboard).
    #[arg(long, value_name = "FILE")]
    pub board: Option<PathBuf>,
    /// A whole checkerboard of inner corners, columns x rows (e.g. 14x12).
    #[arg(long, value_parser = parse_pattern)]
    pub pattern: Option<Pattern>,
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
    let board = match (&args.board, args.pattern) {
        (Some(path), _) => Board::load(path)?,
        // The square size plays no part in detection.
        (None, Some(p)) => Board::checkerboard([p.cols, p.rows], 1.0)?,
        (None, None) => return Err(Error::invalid("board", "give the board: --board FILE or --pattern CxR")),
    };
    let results = detect_board_many(&args.images, &board);
    let mut failures = Vec::new();
    let mut entries = Vec::with_capacity(results.len());
    for (path, r) in args.images.iter().zip(results) {
        match r {
            Ok(d) => {
                if args.json {
                    entries.push(json!({"path": path, "found": true, "corners_px": d.corners_px, "ids": d.ids}));
                } else {
                    outln!("{}: found {} corners", path.display(), d.corners_px.len());
                    for (&id, [u, v]) in d.ids.iter().zip(&d.corners_px) {
                        match &board {
                            Board::Checkerboard(c) => {
                                let cols = c.inner_corners[0] as u32;
                                outln!("{} {} {u:.4} {v:.4}", id % cols, id / cols)
                            }
                            Board::Charuco(_) => outln!("{id} {u:.4} {v:.4}"),
                        }
                    }
                }
            }
            Err(e) => {
                if args.json {
                    entries.push(
                        json!({"path": path, "found": false, "error": e.to_string(), "corners_px": [], "ids": []}),
                    );
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
