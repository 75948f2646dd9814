//! `etlcal zhang IMAGE... --pattern CxR --square MM [--json]`: monofocal calibration of one
//! fixed-focus camera (Zhang 2000, with the paper's distortion k1, p1, p2 in centred
//! pixels), printing `{"fx", "fy", "u0", "v0", "k1", "p1", "p2", "rms_px", "views_used"}`
//! with `--json`. Images whose board is not found are named on stderr and skipped; at
//! least 3 views must remain.

use std::path::PathBuf;

use rayon::prelude::*;
use serde_json::json;

use super::print_json;
use crate::error::{Error, Result};
use crate::formats::dataset::Board;
use crate::pipeline::dataset::{default_detector, CornerDetector};
use crate::zhang::{zhang, PlanarView};

/// Parses a pattern `CxR` (inner corners, columns x rows), e.g. `14x12`.
pub fn parse_pattern(s: &str) -> std::result::Result<[usize; 2], String> {
    let (c, r) = s.split_once(['x', 'X']).ok_or_else(|| format!("pattern \"{s}\" is not CxR (e.g. 14x12)"))?;
    let parse = |t: &str| t.trim().parse::<usize>().map_err(|_| format!("pattern \"{s}\" is not CxR (e.g. 14x12)"));
    Ok([parse(c)?, parse(r)?])
}

/// Arguments of `etlcal zhang`.
#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct Args {
    /// Images of the board (at least 3 in distinct orientations).
    #[arg(required = true, value_name = "IMAGE")]
    pub images: Vec<PathBuf>,
    /// Inner corners, columns x rows (e.g. 14x12).
    #[arg(long, value_parser = parse_pattern)]
    pub pattern: [usize; 2],
    /// Side of a square, mm.
    #[arg(long, value_name = "MM")]
    pub square: f64,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// Detects the board in every image (in parallel); images where it is not found are
/// named on stderr and skipped. Returns the views and the image size.
pub fn detect_views(images: &[PathBuf], board: &Board, progress: bool) -> Result<(Vec<PlanarView>, [u32; 2])> {
    board.validate()?;
    for p in images {
        std::fs::metadata(p).map_err(|source| Error::Io { path: p.clone(), source })?;
    }
    let det = default_detector();
    let bar =
        if progress { indicatif::ProgressBar::new(images.len() as u64) } else { indicatif::ProgressBar::hidden() };
    let results: Vec<_> = images
        .par_iter()
        .map(|p| {
            let r = det.detect(p, board.inner_corners);
            bar.inc(1);
            r
        })
        .collect();
    bar.finish_and_clear();
    let (mut views, mut size) = (vec![], None::<[u32; 2]>);
    for (p, r) in images.iter().zip(results) {
        match r {
            Ok(d) => {
                if let Some(s) = size.filter(|s| *s != d.image_size) {
                    return Err(Error::Image {
                        path: p.clone(),
                        message: format!(
                            "{} x {} px, the first image is {} x {}",
                            d.image_size[0], d.image_size[1], s[0], s[1]
                        ),
                    });
                }
                size = Some(d.image_size);
                let sq = board.square_mm;
                views.push(PlanarView {
                    board_mm: d.corners.iter().map(|(ij, _)| [ij[0] as f64 * sq, ij[1] as f64 * sq]).collect(),
                    pixels: d.corners.iter().map(|c| c.1).collect(),
                });
            }
            Err(Error::BoardNotFound(m)) => eprintln!("etlcal: warning: skipped: {m}"),
            Err(e) => return Err(e),
        }
    }
    let size = size.ok_or_else(|| Error::BoardNotFound(format!("in none of the {} images", images.len())))?;
    Ok((views, size))
}

/// Runs `etlcal zhang`.
pub fn run(args: Args) -> Result<()> {
    let board = Board { inner_corners: args.pattern, square_mm: args.square };
    let (views, size) = detect_views(&args.images, &board, !args.json)?;
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
