//! Step 6: the ChArUco corners, located from the confirmed markers and refined.
//!
//! Each corner of a confirmed marker's square that is an inner corner of the board is
//! predicted by that marker's homography (board mm to image); a corner seen by both its
//! markers takes the mean of the two predictions, which must agree within 25 % of a square
//! and 2 px.
//!
//! The prediction is refined by the checkerboard detector's point-symmetry refinement
//! (`crate::subpixel`: `I(c + d) = I(c - d)`, unbiased under blur and perspective for two
//! straight edges crossing at `c`) over a window masked to where a ChArUco board really is
//! point-symmetric about its corner: the two black squares, and in the two white squares
//! only the white margin between the corner's edges and the markers (within `margin - delta`
//! of an edge, on the board, `margin = (square - marker) / 2`). The markers are left out
//! entirely: their data differ between the two squares, and their borders are edges that do
//! not pass through the corner (under perspective, their point reflections do not line up).
//! `delta` keeps the blurred marker edge out: 2.5 sigma of the image's blur (estimated from
//! the markers' edges) plus the prediction's uncertainty. When the margin is too thin for
//! that, the markers' black borders are let in too (they are the same in both squares; only
//! the data cells are masked).
//!
//! A corner is kept when its window, shrunk to fit in the image, still has a radius of at
//! least [`MIN_RADIUS`] px (the saddle's four squares are in the image), the refinement
//! converges near the prediction, and the refined point is a saddle of the board's colours
//! (its black quadrants darker than its white margins).

use std::collections::BTreeMap;

use etl_core::board::CharucoBoard;
use rayon::prelude::*;

use super::homography::inverse2;
use super::layout::Placed;
use crate::grey::{GrayView, Sample};
use crate::subpixel::{self, Window};

/// Refinement window radius: fraction of the local square size (as the checkerboard's).
const WINDOW_FRACTION: f64 = 0.4;
/// Largest window radius, px (more costs time and gains little).
const MAX_RADIUS: f64 = 24.0;
/// Smallest window radius that refines reliably, px; a corner nearer the frame is dropped.
pub(crate) const MIN_RADIUS: f64 = 4.0;
/// Margins of blur kept out of the window: this many sigma of the blur.
const BLUR_SIGMAS: f64 = 2.5;
/// The binomial smoothing of the refinement, as a Gaussian variance (px^2).
const SMOOTHING_VAR: f64 = 0.5;
/// Uncertainty of the prediction (and the walk of the refinement over a few pixel cells), px,
/// at most this fraction of the square.
const PREDICTION_PX: f64 = 1.5;
const PREDICTION_FRACTION: f64 = 0.05;
/// Smallest unmasked window of a board too small for the mask, px.
const MIN_SMALL_RADIUS: f64 = 2.0;
/// Narrowest margin strip worth refining on, px.
const MIN_STRIP_PX: f64 = 1.5;
/// Two predictions of one corner must agree within this fraction of a square, plus a few
/// px (markers of a few pixels per cell are read from their outlines, a pixel or two off).
const AGREEMENT: f64 = 0.25;
const AGREEMENT_PX: f64 = 2.0;

/// Locates and refines every corner next to a confirmed marker: (id, px) in increasing id
/// order. `blur_px`: the image's blur sigma; `contrast`: the markers' white minus black.
pub(crate) fn locate<T: Sample>(
    img: &GrayView<'_, T>,
    board: &CharucoBoard,
    markers: &[Placed],
    blur_px: f64,
    contrast: f64,
) -> Vec<(u32, [f64; 2])> {
    let s = board.square_mm();
    let [cols, rows] = board.squares();
    // Corner id -> the markers that predict it.
    let mut predicted: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
    for (k, m) in markers.iter().enumerate() {
        for (dc, dr) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let (gc, gr) = (m.square[0] + dc, m.square[1] + dr);
            if gc == 0 || gr == 0 || gc >= cols || gr >= rows {
                continue;
            }
            if let Some(id) = board.corner_id(gc - 1, gr - 1) {
                predicted.entry(id).or_default().push(k);
            }
        }
    }
    let jobs: Vec<(u32, Vec<usize>)> = predicted.into_iter().collect();
    jobs.par_iter()
        .filter_map(|(id, from)| {
            let corner_mm = board.corner_mm(*id)?;
            let preds: Vec<[f64; 2]> = from.iter().map(|&k| markers[k].h.map(corner_mm)).collect();
            let jac = markers[from[0]].h.jacobian(corner_mm);
            let spacing = spacing_px(jac, s);
            if preds.len() == 2 && dist(preds[0], preds[1]) > AGREEMENT * spacing + AGREEMENT_PX {
                return None;
            }
            let n = preds.len() as f64;
            let p = [preds.iter().map(|q| q[0]).sum::<f64>() / n, preds.iter().map(|q| q[1]).sum::<f64>() / n];
            let corner = Corner { board, cell: board.corner_cell(*id)?, jac, spacing };
            corner.refine(img, p, blur_px, contrast).map(|c| (*id, c))
        })
        .collect()
}

/// One corner's geometry: its cell among the inner corners, the board's local derivative
/// (px per mm) and the perpendicular spacing of its edges (px per square).
struct Corner<'a> {
    board: &'a CharucoBoard,
    cell: [u32; 2],
    jac: [[f64; 2]; 2],
    spacing: f64,
}

impl Corner<'_> {
    /// Whether the board square on the side of board offset `b` (mm) is black.
    fn black_at(&self, b: [f64; 2]) -> bool {
        let col = self.cell[0] + u32::from(b[0] > 0.0);
        let row = self.cell[1] + u32::from(b[1] > 0.0);
        self.board.is_black(col, row)
    }

    fn refine<T: Sample>(&self, img: &GrayView<'_, T>, p: [f64; 2], blur_px: f64, contrast: f64) -> Option<[f64; 2]> {
        let (w, h) = (img.width as f64, img.height as f64);
        let room = p[0].min(p[1]).min(w - 3.0 - p[0]).min(h - 3.0 - p[1]).floor();
        let radius = (WINDOW_FRACTION * self.spacing).min(MAX_RADIUS).min(room);
        let window = self.window(radius, blur_px)?;
        let refined = subpixel::refine_smoothed(img, &window, p, 0.1 * self.spacing + 2.0)?;
        let margin_mm = 0.5 * (self.board.square_mm() - self.board.marker_mm());
        self.is_saddle(img, refined, margin_mm.min(0.25 * self.board.square_mm()), contrast).then_some(refined)
    }

    /// The refinement window of radius `radius` px, masked to the board's point-symmetric
    /// part: the black squares and, in the white squares, the margin strips along the
    /// corner's edges (`margin - delta` wide), or when those are too thin, the margins and
    /// the markers' black borders. When even those are narrower than [`MIN_STRIP_PX`] (a
    /// board of a few pixels per cell) the window is the unmasked disc that reaches no
    /// farther than the markers' borders: biased by their blurred data, but the only part
    /// of the image that tells where the corner is. `None` when the radius is below
    /// [`MIN_RADIUS`] (the corner is too near the frame) or the board too small to refine.
    fn window(&self, radius: f64, blur_px: f64) -> Option<Window> {
        let inv = inverse2(self.jac)?;
        let b = self.board;
        // px of image across the board lines x = const and y = const, per mm.
        let det = (self.jac[0][0] * self.jac[1][1] - self.jac[0][1] * self.jac[1][0]).abs();
        let across = [det / self.jac[0][1].hypot(self.jac[1][1]), det / self.jac[0][0].hypot(self.jac[1][0])];
        let prediction_px = PREDICTION_PX.min(PREDICTION_FRACTION * self.spacing);
        let delta_px = BLUR_SIGMAS * (blur_px * blur_px + SMOOTHING_VAR).sqrt() + prediction_px;
        let margin_mm = 0.5 * (b.square_mm() - b.marker_mm());
        let cell_mm = b.marker_mm() / (b.dictionary().marker_bits() + 2) as f64;
        let narrow = across[0].min(across[1]);
        let limit_mm = [margin_mm, margin_mm + cell_mm].into_iter().find(|l| l * narrow - delta_px >= MIN_STRIP_PX);
        let Some(limit_mm) = limit_mm else {
            let small = ((margin_mm + cell_mm) * narrow).max(MIN_SMALL_RADIUS).min(radius).floor();
            return (small >= MIN_SMALL_RADIUS).then(|| Window::new(small as usize, 1));
        };
        if !(radius >= MIN_RADIUS) {
            return None;
        }
        let limit = [limit_mm - delta_px / across[0], limit_mm - delta_px / across[1]];
        let to_board = |dx: f64, dy: f64| [inv[0][0] * dx + inv[0][1] * dy, inv[1][0] * dx + inv[1][1] * dy];
        Some(Window::masked(radius as usize, |dx, dy| {
            let q = to_board(dx as f64, dy as f64);
            self.black_at(q) || q[0].abs() <= limit[0] || q[1].abs() <= limit[1]
        }))
    }

    /// Whether the black quadrants at `c` are darker than the white ones by a quarter of
    /// the markers' contrast, sampled at board offsets (+-q/2, +-q/2) mm.
    fn is_saddle<T: Sample>(&self, img: &GrayView<'_, T>, c: [f64; 2], q_mm: f64, contrast: f64) -> bool {
        let (mut black, mut white, mut nb, mut nw) = (0.0, 0.0, 0, 0);
        for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            let bq = [0.5 * q_mm * sx, 0.5 * q_mm * sy];
            let d = [self.jac[0][0] * bq[0] + self.jac[0][1] * bq[1], self.jac[1][0] * bq[0] + self.jac[1][1] * bq[1]];
            let Some(v) = img.bilinear(c[0] + d[0], c[1] + d[1]) else { return false };
            if self.black_at(bq) {
                (black, nb) = (black + f64::from(v), nb + 1);
            } else {
                (white, nw) = (white + f64::from(v), nw + 1);
            }
        }
        nb > 0 && nw > 0 && white / nw as f64 - black / nb as f64 >= 0.25 * contrast
    }
}

/// The perpendicular spacing of the board's lines at a point, px per square: the smaller of
/// the distances between neighbouring lines of either family.
fn spacing_px(jac: [[f64; 2]; 2], square_mm: f64) -> f64 {
    let det = (jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0]).abs();
    let longest = jac[0][0].hypot(jac[1][0]).max(jac[0][1].hypot(jac[1][1]));
    square_mm * det / longest.max(1e-12)
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}
