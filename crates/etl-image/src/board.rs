//! Detection of any calibration target an `etlcal.board/1` file describes: a ChArUco board
//! ([`crate::charuco`]: the corners seen, each with its id, partial views welcome) or a
//! plain checkerboard ([`crate::checkerboard`]: the whole board, ids the row-major corner index
//! `row * cols + col`). One result type for both, so that `etlcal detect`, the calibration
//! pipeline and Python treat every board alike: corner `ids[k]` at `corners_px[k]`, its
//! board position from [`Board::corner_mm`].

use std::path::{Path, PathBuf};

use etl_formats::board::Board;
use etl_formats::Result;
use image::{DynamicImage, GrayImage};
use rayon::prelude::*;

use crate::charuco::{detect_charuco_view, DetectedMarker};
use crate::checkerboard::{detect_view, Pattern};
use crate::grey::{view_of, with_grey_view, GrayView, Sample};

/// A board found in an image.
#[derive(Debug, Clone, PartialEq)]
pub struct BoardDetection {
    /// Image width and height, px.
    pub image_size: [u32; 2],
    /// The ids of the corners found, increasing, each once (a checkerboard's: all of them,
    /// `row * cols + col`; a ChArUco board's: OpenCV's `row * (cols - 1) + col`).
    pub ids: Vec<u32>,
    /// `corners_px[k]` is corner `ids[k]`, px ((0, 0) the centre of the top-left pixel).
    pub corners_px: Vec<[f64; 2]>,
    /// The ChArUco markers the corners were located from (empty for a checkerboard).
    pub markers: Vec<DetectedMarker>,
}

impl BoardDetection {
    /// (id, board position in mm (z = 0), pixel) of every corner found.
    pub fn board_points<'a>(&'a self, board: &'a Board) -> impl Iterator<Item = (u32, [f64; 2], [f64; 2])> + 'a {
        self.ids.iter().zip(&self.corners_px).filter_map(|(&id, &p)| Some((id, board.corner_mm(id)?, p)))
    }
}

/// Finds `board` in an 8-bit image.
///
/// ```
/// use etl_formats::board::Board;
/// use etl_image::board::detect_board;
/// // A sharp 5 x 4 checkerboard (inner corners) of 20 px squares.
/// let img = image::GrayImage::from_fn(160, 140, |x, y| {
///     let (i, j) = ((x as i32 - 20) / 20, (y as i32 - 20) / 20);
///     let inside = x >= 20 && y >= 20 && x < 140 && y < 120;
///     image::Luma([if inside && (i + j) % 2 == 0 { 40 } else { 210 }])
/// });
/// let det = detect_board(&img, &Board::checkerboard([5, 4], 2.0)?)?;
/// assert_eq!(det.ids, (0..20).collect::<Vec<u32>>());
/// assert!((det.corners_px[7][0] - 79.5).abs() < 0.02); // corner (2, 1)
/// # Ok::<(), etl_formats::Error>(())
/// ```
pub fn detect_board(image: &GrayImage, board: &Board) -> Result<BoardDetection> {
    detect_board_view(view_of(image)?, board)
}

/// Finds `board` in a decoded image of any type: 16-bit images are read at 16 bits,
/// everything else as 8-bit grey.
pub fn detect_board_dynamic(image: &DynamicImage, board: &Board) -> Result<BoardDetection> {
    with_grey_view(image, |v| detect_board_view(v, board), |v| detect_board_view(v, board))
}

/// Reads an image file (PNG, JPEG, TIFF) and finds `board`. An unreadable file is
/// [`etl_formats::Error::Image`]; a board not found is
/// [`etl_formats::Error::BoardNotFound`] with the reason.
pub fn detect_board_file(path: &Path, board: &Board) -> Result<BoardDetection> {
    detect_board_dynamic(&crate::read_image(path)?, board)
}

/// [`detect_board_file`] on many images in parallel (rayon); one result per path, in order.
pub fn detect_board_many(paths: &[PathBuf], board: &Board) -> Vec<Result<BoardDetection>> {
    paths.par_iter().map(|p| detect_board_file(p, board)).collect()
}

/// Finds `board` in a borrowed grey view (8- or 16-bit samples).
pub fn detect_board_view<T: Sample>(img: GrayView<'_, T>, board: &Board) -> Result<BoardDetection> {
    match board {
        Board::Charuco(b) => {
            let d = detect_charuco_view(img, b)?;
            Ok(BoardDetection { image_size: d.image_size, ids: d.ids, corners_px: d.corners_px, markers: d.markers })
        }
        Board::Checkerboard(c) => {
            let d = detect_view(img, Pattern::new(c.inner_corners[0], c.inner_corners[1])?)?;
            let ids = (0..d.corners_px.len() as u32).collect();
            Ok(BoardDetection { image_size: d.image_size, ids, corners_px: d.corners_px, markers: Vec::new() })
        }
    }
}
