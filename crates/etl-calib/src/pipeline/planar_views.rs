//! Zhang's input from board images: the detected corners of every image as planar views.

use std::path::PathBuf;

use etl_core::progress::Progress;
use etl_formats::dataset::Board;
use etl_formats::{Error, Result};
use rayon::prelude::*;

use super::dataset::{default_detector, CornerDetector};
use crate::zhang::PlanarView;

/// The board's views found in a set of images.
#[derive(Debug, Clone)]
pub struct PlanarViews {
    /// One view per image where the board was found, in the images' order.
    pub views: Vec<PlanarView>,
    /// The image of each view (same order as `views`).
    pub images: Vec<PathBuf>,
    /// The images' size, px (all alike).
    pub image_size: [u32; 2],
    /// Why each image without a view was skipped (the board not found), in order.
    pub skipped: Vec<String>,
}

/// Detects the board in every image (in parallel); images where it is not found are
/// skipped and named in [`PlanarViews::skipped`] for the caller to show.
///
/// Errors: a missing or unreadable image, images of different sizes, or the board found
/// in none.
pub fn detect_views(images: &[PathBuf], board: &Board, progress: &dyn Progress) -> Result<PlanarViews> {
    board.validate()?;
    for p in images {
        std::fs::metadata(p).map_err(|source| Error::Io { path: p.clone(), source })?;
    }
    let det = default_detector();
    progress.start(images.len(), "detecting");
    let results: Vec<_> = images
        .par_iter()
        .map(|p| {
            let r = det.detect(p, board.inner_corners);
            progress.advance(1);
            r
        })
        .collect();
    progress.finish();
    let (mut views, mut used, mut size, mut skipped) = (vec![], vec![], None::<[u32; 2]>, vec![]);
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
                used.push(p.clone());
            }
            Err(Error::BoardNotFound(m)) => skipped.push(m),
            Err(e) => return Err(e),
        }
    }
    let image_size = size.ok_or_else(|| Error::BoardNotFound(format!("in none of the {} images", images.len())))?;
    Ok(PlanarViews { views, images: used, image_size, skipped })
}
