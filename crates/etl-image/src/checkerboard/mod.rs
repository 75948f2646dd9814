//! Checkerboard detection with sub-pixel refinement.
//!
//! Named `checkerboard` for the board it finds (ChArUco boards are [`crate::charuco`]'s);
//! the primitives both detectors share are modules of their own, as OpenCV shares
//! `cornerSubPix`: grey images ([`crate::grey`]) and sub-pixel refinement
//! (`crate::subpixel`).
//!
//! [`detect_corners`] finds a board of `cols` x `rows` inner corners ([`Pattern`]) in a grey
//! image (8- or 16-bit) and returns every corner in a stable order (see below), refined to
//! a few hundredths of a pixel. A board that is not found, or found only in part, or of
//! another size, is an [`Error::BoardNotFound`] with the reason, never a wrong grid.
//!
//! The steps, one file each:
//! 1. `response`: the image is box-downsampled (2x from 1280 x 800, 4x from 2560 x 1600)
//!    and smoothed (Gaussian, sigma 1.5 px at that level); local maxima of the saddle
//!    response `I_xy^2 - I_xx I_yy` are the candidates. Where the image allows a level twice
//!    as coarse (at least 320 x 200 px) steps 1-4 run there first, at a quarter of the cost,
//!    and at the usual level only if the board is not found there (squares too small): a
//!    640 x 480 photograph is searched at 320 x 240 (1.0 ms against 4.8 ms). The refinement
//!    (step 5) is at full resolution either way; the coarser start moves the refined corners
//!    by 0.0005 px on average (at most 0.014 px, where a corner's window radius, 0.4 of the
//!    local square size from the coarse grid, rounds to the next pixel).
//! 2. `candidates`: a ring test keeps the candidates around which the image is light, dark,
//!    light, dark with the four transitions in two nearly opposite pairs, and gives the
//!    directions of the two edges through each.
//! 3. `grid`: from the strongest candidates as seeds, a grid grows by neighbour topology
//!    (next corner predicted by extrapolation and parallelograms, accepted within 0.3 of the
//!    local spacing when its edges agree with its neighbours'); it is trimmed to a complete
//!    rectangle and kept only if all its squares alternate in colour, including the outer
//!    ring of squares that a printed board has beyond its outermost inner corners. Border
//!    lines whose outer squares do not alternate are dropped (they are not the board's).
//! 4. `order`: the grid must then be exactly `cols` x `rows` (or `rows` x `cols`), and is
//!    put in the documented order.
//! 5. `refine`: every corner is refined at full resolution by point symmetry
//!    (`I(c + d) = I(c - d)` over a disc of radius 0.4 of the local square size, at most
//!    24 px, on the neighbourhood smoothed by a [1 2 1] binomial), unbiased under blur and
//!    perspective: RMS 0.009 / 0.008 / 0.010 px on rendered 1936 x 1458 boards at blur
//!    sigma 0.5 / 1.5 / 3 px with noise 2 grey levels (tests/detect.rs).
//!
//! # Order
//! Index `j * cols + i` is corner (i, j); the board square between corners (0,0), (1,0),
//! (0,1) and (1,1) is dark; (i, j) is right-handed in the image (the board seen from its
//! printed side: `(p(1,0) - p(0,0)) x (p(0,1) - p(0,0)) > 0` with u right, v down). This fixes
//! the order for boards whose colouring is not symmetric under a half turn (`cols + rows`
//! odd, e.g. 9x6 or 14x11) at any rotation. For symmetric boards (e.g. 14x12) corner 0 is the
//! candidate nearest the image's top-left pixel (0, 0): stable under small rotations. Pixel
//! (0, 0) is the centre of the top-left pixel.

mod candidates;
mod grid;
mod order;
mod response;

use std::collections::HashMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use image::{DynamicImage, GrayImage, ImageBuffer, Luma};
use rayon::prelude::*;

use crate::grey::{self, view_of, with_grey_view};
pub use crate::grey::{GrayView, Sample};
use crate::subpixel;

use etl_formats::{Error, Result};

/// A board's size in inner corners: `cols` along the board's x axis (corner index i),
/// `rows` along y (index j). Parses from `"CxR"`, e.g. `"14x12"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Pattern {
    /// Inner corners along x (at least 3).
    pub cols: usize,
    /// Inner corners along y (at least 3).
    pub rows: usize,
}

impl Pattern {
    /// A pattern; `InvalidInput` unless both counts are in 3..=1000.
    pub fn new(cols: usize, rows: usize) -> Result<Self> {
        if !(3..=1000).contains(&cols) || !(3..=1000).contains(&rows) {
            return Err(Error::invalid_value(
                "pattern",
                format!("{cols}x{rows}"),
                format!("pattern {cols}x{rows}: a board needs 3 to 1000 inner corners each way"),
            ));
        }
        Ok(Self { cols, rows })
    }

    /// Number of corners.
    pub fn len(&self) -> usize {
        self.cols * self.rows
    }

    /// Never true for a valid pattern.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl FromStr for Pattern {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        let bad =
            || Error::invalid_value("pattern", s, format!("pattern \"{s}\" is not CxR inner corners (e.g. 14x12)"));
        let (c, r) = s.trim().split_once(['x', 'X']).ok_or_else(bad)?;
        let c = c.trim().parse::<usize>().map_err(|_| bad())?;
        let r = r.trim().parse::<usize>().map_err(|_| bad())?;
        Self::new(c, r)
    }
}

impl fmt::Display for Pattern {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}x{}", self.cols, self.rows)
    }
}

/// A board found in an image.
#[derive(Debug, Clone, PartialEq)]
pub struct Detection {
    /// The pattern asked for.
    pub pattern: Pattern,
    /// Image width and height, px.
    pub image_size: [u32; 2],
    /// `cols * rows` corners, row by row (i fastest): `corners_px[j * cols + i]` is corner
    /// (i, j), in px with (0, 0) the centre of the top-left pixel.
    pub corners_px: Vec<[f64; 2]>,
}

impl Detection {
    /// (grid index [i, j], pixel) pairs, row by row.
    pub fn indexed(&self) -> impl Iterator<Item = ([usize; 2], [f64; 2])> + '_ {
        let cols = self.pattern.cols;
        self.corners_px.iter().enumerate().map(move |(k, &p)| ([k % cols, k / cols], p))
    }
}

/// Smoothing at the detection level, px.
const SMOOTH_SIGMA: f32 = 1.5;
/// Ring radii of the corner test at the detection level, px.
const RING_RADII: [f32; 3] = [3.5, 5.5, 8.0];
/// Seeds tried before giving up.
const MAX_SEEDS: usize = 60;
/// Refinement window: fraction of the local square size (perpendicular spacing of the edges).
const WINDOW_FRACTION: f64 = 0.4;
/// Largest refinement window radius, px (more costs time and gains little).
const MAX_WINDOW: usize = 24;
/// Smallest, px.
const MIN_WINDOW: usize = 2;

/// Finds the board in an 8-bit image.
///
/// ```
/// use etl_image::checkerboard::{detect_corners, Pattern};
/// // A sharp 5 x 4 board (inner corners) of 20 px squares, dark square at the first corner.
/// let img = image::GrayImage::from_fn(160, 140, |x, y| {
///     let (i, j) = ((x as i32 - 20) / 20, (y as i32 - 20) / 20);
///     let inside = x >= 20 && y >= 20 && x < 140 && y < 120;
///     image::Luma([if inside && (i + j) % 2 == 0 { 40 } else { 210 }])
/// });
/// let det = detect_corners(&img, "5x4".parse()?)?;
/// assert_eq!(det.corners_px.len(), 20);
/// // Corner (i, j) lies between pixels: at 39.5 + 20 i, 39.5 + 20 j.
/// let c = det.corners_px[1 * 5 + 2];
/// assert!((c[0] - 79.5).abs() < 0.02 && (c[1] - 59.5).abs() < 0.02);
/// # Ok::<(), etl_formats::Error>(())
/// ```
pub fn detect_corners(image: &GrayImage, pattern: Pattern) -> Result<Detection> {
    detect_view(view_of(image)?, pattern)
}

/// Finds the board in a 16-bit image (same as [`detect_corners`]).
pub fn detect_corners_u16(image: &ImageBuffer<Luma<u16>, Vec<u16>>, pattern: Pattern) -> Result<Detection> {
    detect_view(view_of(image)?, pattern)
}

/// Finds the board in a decoded image of any type: 16-bit images are read at 16 bits,
/// everything else as 8-bit grey.
pub fn detect_dynamic(image: &DynamicImage, pattern: Pattern) -> Result<Detection> {
    with_grey_view(image, |v| detect_view(v, pattern), |v| detect_view(v, pattern))
}

/// Reads an image file (PNG, JPEG, TIFF) and finds the board. An unreadable file is
/// [`Error::Image`]; a board not found is [`Error::BoardNotFound`].
pub fn detect_file(path: &Path, pattern: Pattern) -> Result<Detection> {
    detect_dynamic(&crate::read_image(path)?, pattern)
}

/// [`detect_file`] on many images in parallel (rayon); one result per path, in order.
pub fn detect_many(paths: &[PathBuf], pattern: Pattern) -> Vec<Result<Detection>> {
    paths.par_iter().map(|p| detect_file(p, pattern)).collect()
}

/// Finds the board in a borrowed grey view (8- or 16-bit samples).
pub fn detect_view<T: Sample>(img: GrayView<'_, T>, pattern: Pattern) -> Result<Detection> {
    let pattern = Pattern::new(pattern.cols, pattern.rows)?;
    let (w, h) = (img.width, img.height);
    let min_side = 4 * (pattern.cols.min(pattern.rows) + 1);
    if w < 16 || h < 16 || w.max(h) < 4 * (pattern.cols.max(pattern.rows) + 1) || w.min(h) < min_side {
        return Err(Error::BoardNotFound(format!(
            "the image is {w}x{h} px, too small to hold a {pattern} board (squares of at least 4 px)"
        )));
    }
    let (factor, coarse) = levels(w, h);
    // A coarser level first where the image allows one: a board of large squares is found
    // there at a quarter of the cost; small squares fall back to the usual level.
    if coarse {
        if let Ok(d) = detect_at_level(&img, pattern, 2 * factor) {
            return Ok(d);
        }
    }
    detect_at_level(&img, pattern, factor)
}

/// The smallest detection level (width, height, px) the coarse first attempt of
/// [`detect_view`] works at.
const COARSE_MIN: [usize; 2] = [320, 200];

/// The usual detection level of a `w` x `h` image (its downsampling factor) and whether
/// [`detect_view`] tries the coarser level (twice the factor) first.
fn levels(w: usize, h: usize) -> (usize, bool) {
    let mut factor = 1;
    while w / (2 * factor) >= 640 && h / (2 * factor) >= 400 {
        factor *= 2;
    }
    (factor, w / (2 * factor) >= COARSE_MIN[0] && h / (2 * factor) >= COARSE_MIN[1])
}

/// Prepares the memory of a first detection in `width` x `height` images (at the level it
/// starts at): the two float planes it works on, allocated and their pages touched now.
/// For a program that cares about its first detection's latency, called once at start-up
/// (the Python module calls it at import for 640 x 480: 0.6 MB, ~0.15 ms); later
/// detections reuse their planes anyway. Detections of other sizes work as before: larger
/// ones allocate what does not fit.
pub fn prepare(width: usize, height: usize) {
    let (factor, coarse) = levels(width, height);
    let f = if coarse { 2 * factor } else { factor };
    grey::reserve((width / f) * (height / f), 2);
}

/// [`detect_view`] at one detection level: the image box-downsampled by `factor`.
fn detect_at_level<T: Sample>(img: &GrayView<'_, T>, pattern: Pattern, factor: usize) -> Result<Detection> {
    let (w, h) = (img.width, img.height);
    let image_size = [w as u32, h as u32];
    let smooth = grey::smoothed_level(*img, factor, SMOOTH_SIGMA);
    let saddles = response::saddles(&smooth);
    let corners = candidates::corners(&smooth, &saddles, &RING_RADII, 12 * pattern.len() + 1000);
    if corners.len() < pattern.len() {
        return Err(Error::BoardNotFound(format!(
            "{} corner-like points in the image, the {pattern} board has {}",
            corners.len(),
            pattern.len()
        )));
    }
    let max_extent = (pattern.cols.max(pattern.rows) + 3) as i32;
    let mut tried = vec![false; corners.len()];
    let mut reason = String::from("no grid of corners grows from the strongest corner-like points");
    let mut best_found = 0usize;
    let mut seeds = 0;
    for seed in 0..corners.len() {
        if seeds >= MAX_SEEDS {
            break;
        }
        if tried[seed] {
            continue;
        }
        seeds += 1;
        let (outcome, touched) = grid::grid_from_seed(&smooth, &corners, seed, max_extent);
        for k in touched {
            tried[k] = true;
        }
        match outcome {
            grid::Outcome::Grid(g) => {
                if let Some(pts) = order::order(&g, pattern.cols, pattern.rows) {
                    let full: Vec<[f64; 2]> = pts
                        .iter()
                        .map(|p| {
                            let o = (factor as f64 - 1.0) * 0.5;
                            [p[0] as f64 * factor as f64 + o, p[1] as f64 * factor as f64 + o]
                        })
                        .collect();
                    let corners_px = refine_all(img, &full, pattern)?;
                    return Ok(Detection { pattern, image_size, corners_px });
                }
                if g.nc * g.nr > best_found {
                    best_found = g.nc * g.nr;
                    reason = format!("found a {}x{} grid of corners, not {pattern}", g.nc, g.nr);
                }
            }
            grid::Outcome::Rejected(grid::Reject::AtBorder) if best_found == 0 => {
                reason =
                    "a grid of corners runs into the image border (the board's outer squares must be visible)".into();
            }
            grid::Outcome::Rejected(_) | grid::Outcome::TooSmall => {}
        }
    }
    Err(Error::BoardNotFound(reason))
}

/// Refines every corner at full resolution; the window of each is sized by its grid
/// neighbours.
fn refine_all<T: Sample>(img: &GrayView<'_, T>, coarse: &[[f64; 2]], pattern: Pattern) -> Result<Vec<[f64; 2]>> {
    let (cols, rows) = (pattern.cols, pattern.rows);
    let at = |i: usize, j: usize| coarse[j * cols + i];
    // Perpendicular spacing of the edges at each corner.
    let spacing: Vec<(f64, f64)> = (0..rows)
        .flat_map(|j| (0..cols).map(move |i| (i, j)))
        .map(|(i, j)| {
            let p = at(i, j);
            let a = if i + 1 < cols { sub(at(i + 1, j), p) } else { sub(p, at(i - 1, j)) };
            let b = if j + 1 < rows { sub(at(i, j + 1), p) } else { sub(p, at(i, j - 1)) };
            let cross = (a[0] * b[1] - a[1] * b[0]).abs();
            let (la, lb) = (a[0].hypot(a[1]), b[0].hypot(b[1]));
            let perp = (cross / la.max(1e-9)).min(cross / lb.max(1e-9));
            (perp, la.min(lb))
        })
        .collect();
    // The window stays inside the image (a corner near the border gets a smaller one).
    let (w, h) = (img.width as f64, img.height as f64);
    let radius = |perp: f64, p: [f64; 2]| {
        let room = p[0].min(p[1]).min(w - 3.0 - p[0]).min(h - 3.0 - p[1]).floor().max(0.0) as usize;
        ((WINDOW_FRACTION * perp).floor() as usize).clamp(MIN_WINDOW, MAX_WINDOW).min(room.max(MIN_WINDOW))
    };
    let mut windows: HashMap<usize, subpixel::Window> = HashMap::new();
    for (&(perp, _), &p) in spacing.iter().zip(coarse) {
        let r = radius(perp, p);
        windows.entry(r).or_insert_with(|| subpixel::Window::new(r, 1));
    }
    coarse
        .par_iter()
        .zip(&spacing)
        .enumerate()
        .map(|(k, (&p, &(perp, side)))| {
            let win = &windows[&radius(perp, p)];
            subpixel::refine_smoothed(img, win, p, 0.25 * side + 1.0).ok_or_else(|| {
                Error::BoardNotFound(format!(
                    "corner ({}, {}) near ({:.1}, {:.1}) px could not be refined (too close to the image border?)",
                    k % cols,
                    k / cols,
                    p[0],
                    p[1]
                ))
            })
        })
        .collect()
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}
