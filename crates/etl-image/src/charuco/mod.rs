//! ChArUco detection: the markers of a [`CharucoBoard`] found and identified in a grey
//! image, and every board corner next to a marker located and refined to a few hundredths of
//! a pixel, with its id. A board seen in part (overflowing the frame, partly hidden) gives
//! the corners that are seen, each with its id: no hint about which part is visible.
//!
//! The steps, one file each:
//! 1. `threshold`: at a detection level (the image box-downsampled 2x from 1280 x 800, as
//!    the checkerboard detector's), dark pixels by an adaptive mean threshold (7 grey levels
//!    below the mean of a 15 x 15 neighbourhood, OpenCV's offset; at full resolution also
//!    5 x 5 and 3 x 3, which separate small markers from the black squares).
//! 2. `contours`: 8-connected dark regions, the outer boundary of each traced.
//! 3. `quad`: boundaries that a convex quadrilateral approximates (Douglas-Peucker, 3 % of
//!    the perimeter), not touching the frame; their sides are then located at full
//!    resolution (half-way crossing next to the steepest rise across each side, a line
//!    through the points).
//! 4. `decode`: the cells sampled through the quad's homography, split into black and white
//!    (Otsu over the cells), the border checked, the data identified with the dictionary's
//!    error correction (OpenCV's defaults), ties refused. A quad whose sides could not be
//!    located, or that does not decode with them, is read from its outline's corners.
//! 5. `layout`: ids on the board, each once, each confirmed by a neighbouring marker (one's
//!    homography puts the other where it was found: a misread id cannot be confirmed).
//! 6. `corners`: each inner corner of a confirmed marker's square predicted by the
//!    marker's homography and refined by the checkerboard detector's point-symmetry
//!    refinement over the part of the neighbourhood that is point-symmetric on a ChArUco
//!    board (the black squares and the white margins, the markers masked); kept when its
//!    window fits in the frame and the refined point is a saddle of the board's colours.
//!
//! If no marker is found at the detection level, the image is searched again at full
//! resolution (small markers). Where the image allows a level twice as coarse (at least
//! 320 x 200 px) that level is searched first, and its markers kept when the smallest is at
//! least twice the smallest it can see (a 640 x 480 view: 4.4 ms against 8.9 ms, all 88
//! corners of benches/detect_sizes.py's renders); a board whose markers differ more than
//! twofold in size could lose its smallest there, so the usual level searches again when
//! the smallest found is below that.
//!
//! Accuracy (1936 x 1458 renders, squares of 150-200 px, noise 2 grey levels): RMS
//! 0.007-0.011 px at blur sigma 0.5 to 3 px, 96 % of the corners in the frame; OpenCV 5's
//! `CharucoDetector` on the same images 0.026-0.052 px and 76 %, and slower
//! (docs/PERFORMANCE-HISTORY.md, tests/charuco.rs; current figures: docs/BENCHMARKS.md).
//!
//! Pixel (0, 0) is the centre of the top-left pixel. Ids, board layout and marker corner
//! order are OpenCV's (see [`etl_core::board`]; OpenCV's legacy layout of boards with an even
//! number of rows, before 4.6, is not read: its markers would not confirm each other).

mod contours;
mod corners;
mod decode;
mod homography;
mod layout;
mod quad;
mod threshold;

use std::path::{Path, PathBuf};

use etl_core::board::{CharucoBoard, Dictionary};
use image::{DynamicImage, GrayImage, ImageBuffer, Luma};
use rayon::prelude::*;

use crate::grey::{self, GrayView, Sample};
use crate::grey::{view_of, with_grey_view};
use etl_formats::{Error, Result};

/// A marker found in the image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectedMarker {
    /// Its id in the board's dictionary.
    pub id: u32,
    /// Its corners as printed: top left, top right, bottom right, bottom left (OpenCV's
    /// order), px.
    pub corners_px: [[f64; 2]; 4],
}

/// A ChArUco board found in an image.
#[derive(Debug, Clone, PartialEq)]
pub struct CharucoDetection {
    /// Image width and height, px.
    pub image_size: [u32; 2],
    /// The ids of the corners found (`row * (cols - 1) + col`), increasing, each once.
    pub ids: Vec<u32>,
    /// `corners_px[k]` is corner `ids[k]`, px ((0, 0) the centre of the top-left pixel).
    pub corners_px: Vec<[f64; 2]>,
    /// The markers the corners were located from, in increasing id order.
    pub markers: Vec<DetectedMarker>,
}

impl CharucoDetection {
    /// (id, board position in mm, pixel) for each corner found.
    pub fn board_points<'a>(&'a self, board: &'a CharucoBoard) -> impl Iterator<Item = (u32, [f64; 2], [f64; 2])> + 'a {
        self.ids.iter().zip(&self.corners_px).filter_map(|(&id, &p)| Some((id, board.corner_mm(id)?, p)))
    }
}

/// Adaptive threshold: neighbourhood radii at the detection level, px (the second at full
/// resolution only).
const THRESHOLD_RADII: [usize; 3] = [7, 2, 1];
/// Adaptive threshold: grey levels below the neighbourhood mean (OpenCV's 7).
const THRESHOLD_OFFSET: f32 = 7.0;
/// Smallest marker cell that can be read, full-resolution px.
const MIN_CELL_PX: f64 = 1.5;

/// Finds the ChArUco board in an 8-bit image.
///
/// ```
/// use etl_core::board::{CharucoBoard, Dictionary};
/// use etl_image::charuco::detect_charuco;
/// let board = CharucoBoard::new([5, 4], 7.0, 5.0, Dictionary::by_name("DICT_4X4_50").unwrap()).unwrap();
/// // The board drawn sharp at 10 px per mm, 20 px of white around it.
/// let img = image::GrayImage::from_fn(390, 320, |x, y| {
///     let (bx, by) = ((x as f64 + 0.5 - 20.0) / 10.0, (y as f64 + 0.5 - 20.0) / 10.0);
///     let dark = bx >= 0.0 && by >= 0.0 && bx < 35.0 && by < 28.0 && {
///         let (c, r) = ((bx / 7.0) as u32, (by / 7.0) as u32);
///         match board.marker_at(c, r) {
///             None => true,
///             Some(id) => {
///                 // Cell (i, j) of the marker's 6 x 6 cells, 1 mm inside its square.
///                 let (mx, my) = (bx - c as f64 * 7.0 - 1.0, by - r as f64 * 7.0 - 1.0);
///                 let (i, j) = ((mx / (5.0 / 6.0)).floor() as i32, (my / (5.0 / 6.0)).floor() as i32);
///                 let inside = (0..6).contains(&i) && (0..6).contains(&j);
///                 let data = (1..5).contains(&i) && (1..5).contains(&j);
///                 inside && !(data && board.dictionary().is_white(id, (j - 1) as usize, (i - 1) as usize).unwrap())
///             }
///         }
///     };
///     image::Luma([if dark { 40 } else { 210 }])
/// });
/// let det = detect_charuco(&img, &board)?;
/// assert_eq!(det.ids, (0..12).collect::<Vec<u32>>());
/// // Corner 0 is at (7, 7) mm on the board: 20 + 70 px, on a pixel boundary.
/// let c = det.corners_px[0];
/// assert!((c[0] - 89.5).abs() < 0.05 && (c[1] - 89.5).abs() < 0.05);
/// # Ok::<(), etl_formats::Error>(())
/// ```
pub fn detect_charuco(image: &GrayImage, board: &CharucoBoard) -> Result<CharucoDetection> {
    detect_charuco_view(view_of(image)?, board)
}

/// Finds the board in a 16-bit image (same as [`detect_charuco`]).
pub fn detect_charuco_u16(image: &ImageBuffer<Luma<u16>, Vec<u16>>, board: &CharucoBoard) -> Result<CharucoDetection> {
    detect_charuco_view(view_of(image)?, board)
}

/// Finds the board in a decoded image of any type: 16-bit images are read at 16 bits,
/// everything else as 8-bit grey.
pub fn detect_charuco_dynamic(image: &DynamicImage, board: &CharucoBoard) -> Result<CharucoDetection> {
    with_grey_view(image, |v| detect_charuco_view(v, board), |v| detect_charuco_view(v, board))
}

/// Reads an image file (PNG, JPEG, TIFF) and finds the board. An unreadable file is
/// [`Error::Image`]; a board not found is [`Error::BoardNotFound`].
pub fn detect_charuco_file(path: &Path, board: &CharucoBoard) -> Result<CharucoDetection> {
    detect_charuco_dynamic(&crate::read_image(path)?, board)
}

/// [`detect_charuco_file`] on many images in parallel (rayon); one result per path, in order.
pub fn detect_charuco_many(paths: &[PathBuf], board: &CharucoBoard) -> Vec<Result<CharucoDetection>> {
    paths.par_iter().map(|p| detect_charuco_file(p, board)).collect()
}

/// Finds the board in a borrowed grey view (8- or 16-bit samples).
///
/// Errors: [`Error::BoardNotFound`] with the reason when no marker of the board's
/// dictionary is found, when the markers found cannot be confirmed by a neighbour (a lone
/// marker, or ids inconsistent with the board), or when no corner next to them could be
/// refined.
pub fn detect_charuco_view<T: Sample>(img: GrayView<'_, T>, board: &CharucoBoard) -> Result<CharucoDetection> {
    let (w, h) = (img.width, img.height);
    let image_size = [w as u32, h as u32];
    let dict = board.dictionary();
    if w < 16 || h < 16 {
        return Err(Error::BoardNotFound(format!("the image is {w}x{h} px, too small to hold a marker")));
    }
    let mut factor = 1;
    while w / (2 * factor) >= 640 && h / (2 * factor) >= 400 {
        factor *= 2;
    }
    // One level coarser first where the image allows it (at least 320 x 200 there): a 640 x
    // 480 view of large markers is searched at a quarter of the cost. Its markers are kept
    // only if the smallest is at least twice the smallest that level can see; otherwise a
    // smaller one may have been missed, and the usual level searches again.
    let extra = w / (2 * factor) >= COARSE_MIN[0] && h / (2 * factor) >= COARSE_MIN[1];
    if extra {
        factor *= 2;
    }
    let usual = if extra { factor / 2 } else { factor };
    let mut quads = 0;
    let found = loop {
        let (found, looked_at) = markers_at_level(&img, factor, dict);
        quads += looked_at;
        let trusted = factor <= usual || smallest_side_px(&found) >= 2.0 * level_min_side_px(factor, dict);
        if (!found.is_empty() && trusted) || factor == 1 {
            break found;
        }
        factor /= 2;
    };
    if found.is_empty() {
        return Err(Error::BoardNotFound(format!(
            "no marker of {} in the image ({quads} dark quadrilaterals looked at)",
            dict.name()
        )));
    }
    let decoded: Vec<decode::Decoded> = found.iter().map(|m| m.decoded).collect();
    let layout = layout::confirmed(board, &decoded);
    let [cols, rows] = board.squares();
    if layout.contradicted > layout.kept.len() {
        return Err(Error::BoardNotFound(format!(
            "the markers do not fit the {cols}x{rows} board's layout: {} of the {} decoded are contradicted by a \
             neighbour (a board of another size, or OpenCV's legacy layout?)",
            layout.contradicted, layout.on_board
        )));
    }
    let placed = layout.kept;
    if placed.is_empty() {
        return Err(Error::BoardNotFound(format!(
            "{} marker(s) of {} decoded, none confirmed by a neighbour where the {cols}x{rows} board puts it",
            decoded.len(),
            dict.name(),
        )));
    }
    let (blur_px, contrast) = blur_and_contrast(&found);
    let corners = corners::locate(&img, board, &placed, blur_px, contrast);
    if corners.is_empty() {
        return Err(Error::BoardNotFound(format!(
            "{} marker(s) confirmed, but no board corner next to them could be refined inside the image",
            placed.len()
        )));
    }
    let markers = placed.iter().map(|p| DetectedMarker { id: p.id, corners_px: p.corners_px }).collect();
    let (ids, corners_px) = corners.into_iter().unzip();
    Ok(CharucoDetection { image_size, ids, corners_px, markers })
}

/// A marker read in the image.
struct Found {
    decoded: decode::Decoded,
    /// The steepest rise across its sides, grey levels per px (`None` when its sides could
    /// not be located at full resolution and it was read from its outline).
    edge_slope: Option<f64>,
}

/// The smallest detection level (width, height, px) of the coarse first search of
/// [`detect_charuco_view`].
const COARSE_MIN: [usize; 2] = [320, 200];

/// The side of the smallest marker a detection level `factor` finds, full-resolution px.
fn level_min_side_px(factor: usize, dict: &Dictionary) -> f64 {
    let min_side_px = MIN_CELL_PX * (dict.marker_bits() + 2) as f64;
    ((min_side_px / factor as f64).floor().max(4.0)) * factor as f64
}

/// The side of the smallest marker in `found`, px (infinite for none).
fn smallest_side_px(found: &[Found]) -> f64 {
    found.iter().map(|m| layout::side_px(&m.decoded.corners_px)).fold(f64::INFINITY, f64::min)
}

/// The markers of `dict` found at detection level `factor`, and how many quadrilaterals
/// were looked at. A quad is read with its sides located at full resolution, or failing
/// that, with its outline's corners (a marker of a few pixels per cell, whose sides are too
/// short to locate).
///
/// At full resolution (small images, small markers) the threshold runs at two
/// neighbourhood sizes, as OpenCV's runs at several: the large one keeps a big marker's
/// border dark across its width, the small one separates a small marker from the black
/// squares when the white margin between them is a pixel or two.
fn markers_at_level<T: Sample>(img: &GrayView<'_, T>, factor: usize, dict: &Dictionary) -> (Vec<Found>, usize) {
    let level = grey::downsample(*img, factor);
    let f = factor as f64;
    let min_side = (level_min_side_px(factor, dict) / f) as usize;
    let max_side = level.width.max(level.height);
    let radii: &[usize] = if factor == 1 { &THRESHOLD_RADII } else { &THRESHOLD_RADII[..1] };
    let mut coarse: Vec<[[f64; 2]; 4]> = Vec::new();
    for &radius in radii {
        let mask = threshold::dark_mask(&level, radius, THRESHOLD_OFFSET);
        let contours = contours::outer_contours(&mask, min_side, max_side, min_side);
        let quads = contours.iter().filter(|c| !c.touches_border);
        for q in quads.filter_map(|c| quad::approximate(&c.points, 0.5 * min_side as f64)) {
            // The same marker outlined at another neighbourhood size.
            let (c, side) = (layout::centre(&q), layout::side_px(&q));
            if !coarse.iter().any(|o| layout::dist(layout::centre(o), c) < 0.25 * side) {
                coarse.push(q);
            }
        }
    }
    let looked_at = coarse.len();
    // Detection-level pixel x is centred on full-resolution f x + (f - 1) / 2; the outline
    // runs through the region's outer pixels, half a pixel inside the edge.
    let o = 0.5 * (f - 1.0);
    let reach = 1.5 * f + 1.0;
    let found = coarse
        .par_iter()
        .filter_map(|q| {
            let outline = q.map(|p| [p[0] * f + o, p[1] * f + o]);
            let sides = quad::refine(img, outline, reach);
            if let Some(d) = sides.and_then(|s| decode::decode(img, &s.corners, dict)) {
                return Some(Found { decoded: d, edge_slope: sides.map(|s| s.edge_slope) });
            }
            decode::decode(img, &outline, dict).map(|d| Found { decoded: d, edge_slope: None })
        })
        .collect();
    (found, looked_at)
}

/// The image's blur sigma (px) and the markers' contrast (grey levels), medians over the
/// markers: a blurred step of contrast C rises at most C / (sigma sqrt(2 pi)) per px. With
/// no marker's sides located, the blur is taken as one pixel.
fn blur_and_contrast(found: &[Found]) -> (f64, f64) {
    let mut sigma: Vec<f64> = found
        .iter()
        .filter_map(|m| {
            let d = &m.decoded;
            Some((d.white - d.black) / (m.edge_slope? * (2.0 * std::f64::consts::PI).sqrt()))
        })
        .collect();
    let mut contrast: Vec<f64> = found.iter().map(|m| m.decoded.white - m.decoded.black).collect();
    sigma.sort_by(f64::total_cmp);
    contrast.sort_by(f64::total_cmp);
    (sigma.get(sigma.len() / 2).copied().unwrap_or(1.0), contrast[contrast.len() / 2])
}
