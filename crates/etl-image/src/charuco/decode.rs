//! Step 4: reading a quadrilateral's bits and identifying the marker.
//!
//! The quad is divided into `(n + 2)^2` cells through the homography of its corners (a
//! marker is a one-cell black border around `n x n` data cells); each cell's grey level is
//! the mean of `SAMPLES^2` bilinear samples over its middle (away from the blurred cell
//! edges). The cells split into black and white at the threshold that best separates their
//! levels (Otsu's, over the cells); too little contrast between the two classes, or too many
//! white border cells (OpenCV's limit: 35 %), and the quad is no marker. The data bits are
//! then identified with the dictionary's error correction (OpenCV's default: 60 % of the
//! dictionary's correctable bits), ties refused.

use etl_core::board::Dictionary;

use super::homography::Homography;
use crate::grey::{GrayView, Sample};

/// Samples per cell and direction.
const SAMPLES: usize = 3;
/// Span of the samples across a cell, as a fraction of the cell (the middle half).
const SPAN: f64 = 0.5;
/// Fewest grey levels between the black and the white cells.
const MIN_CONTRAST: f64 = 10.0;
/// Largest fraction of white border cells (OpenCV's `maxErroneousBitsInBorderRate`).
const BORDER_ERROR_RATE: f64 = 0.35;
/// Fraction of the dictionary's correctable bits corrected (OpenCV's `errorCorrectionRate`).
const CORRECTION_RATE: f64 = 0.6;

/// A decoded marker.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Decoded {
    pub id: u32,
    /// Printed top-left, top-right, bottom-right, bottom-left, px.
    pub corners_px: [[f64; 2]; 4],
    /// Mean grey level of the black and of the white cells.
    pub black: f64,
    pub white: f64,
}

/// Reads the marker in `quad` (corners clockwise in the image); `None` when it is no marker
/// of `dict`.
pub(crate) fn decode<T: Sample>(img: &GrayView<'_, T>, quad: &[[f64; 2]; 4], dict: &Dictionary) -> Option<Decoded> {
    let n = dict.marker_bits();
    let cells = n + 2;
    let side = cells as f64;
    let h = Homography::fit(&[[0.0, 0.0], [side, 0.0], [side, side], [0.0, side]], quad)?;
    let mut level = [0.0f64; 81];
    for r in 0..cells {
        for c in 0..cells {
            let mut sum = 0.0;
            for sy in 0..SAMPLES {
                for sx in 0..SAMPLES {
                    let f = |s: usize| 0.5 + SPAN * ((s as f64 + 0.5) / SAMPLES as f64 - 0.5);
                    let [u, v] = h.map([c as f64 + f(sx), r as f64 + f(sy)]);
                    sum += f64::from(img.bilinear(u, v)?);
                }
            }
            level[r * cells + c] = sum / (SAMPLES * SAMPLES) as f64;
        }
    }
    let levels = &level[..cells * cells];
    let (threshold, black, white) = otsu(levels)?;
    if white - black < MIN_CONTRAST {
        return None;
    }
    let is_border = |r: usize, c: usize| r == 0 || c == 0 || r == cells - 1 || c == cells - 1;
    let white_border = (0..cells * cells).filter(|&i| is_border(i / cells, i % cells) && levels[i] > threshold).count();
    if white_border as f64 > BORDER_ERROR_RATE * (4 * (cells - 1)) as f64 {
        return None;
    }
    let mut bits = 0u64;
    for r in 0..n {
        for c in 0..n {
            if levels[(r + 1) * cells + c + 1] > threshold {
                bits |= 1 << (r * n + c);
            }
        }
    }
    let max_errors = (CORRECTION_RATE * dict.max_correction_bits() as f64) as usize;
    let found = dict.identify(bits, max_errors)?;
    // The printed marker appears turned `rotation` quarter turns clockwise: its corner k
    // (top-left first, clockwise) is the quad's corner k + rotation.
    let r = found.rotation as usize;
    let corners_px = core::array::from_fn(|k| quad[(k + r) % 4]);
    Some(Decoded { id: found.id, corners_px, black, white })
}

/// Otsu's threshold over a few values: (threshold, mean below, mean above); `None` when all
/// are equal.
fn otsu(values: &[f64]) -> Option<(f64, f64, f64)> {
    let mut v: Vec<f64> = values.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let total: f64 = v.iter().sum();
    let (mut best, mut low_sum) = (None, 0.0);
    let mut best_score = 0.0;
    for k in 1..n {
        low_sum += v[k - 1];
        if v[k] == v[k - 1] {
            continue;
        }
        let (m0, m1) = (low_sum / k as f64, (total - low_sum) / (n - k) as f64);
        let score = (k * (n - k)) as f64 * (m1 - m0) * (m1 - m0);
        if score > best_score {
            best_score = score;
            best = Some((0.5 * (v[k - 1] + v[k]), m0, m1));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use etl_core::board::dictionary::rotate_cw;

    /// Marker `id` drawn sharp, `cell` px per cell, turned `turns` quarter turns clockwise,
    /// on a white surround of one cell; returns the image and the quad's corners clockwise
    /// from the image's top left.
    fn drawn(dict: &Dictionary, id: u32, turns: u8, cell: usize) -> (Vec<u8>, usize, [[f64; 2]; 4]) {
        let n = dict.marker_bits();
        let bits = rotate_cw(dict.code(id).unwrap(), n, turns);
        let size = (n + 4) * cell;
        let img = (0..size * size)
            .map(|i| {
                let (c, r) = ((i % size) / cell, (i / size) / cell);
                let inside = (1..=n + 2).contains(&c) && (1..=n + 2).contains(&r);
                let data = (2..=n + 1).contains(&c) && (2..=n + 1).contains(&r);
                let white = !inside || (data && (bits >> ((r - 2) * n + (c - 2))) & 1 == 1);
                if white {
                    210
                } else {
                    40
                }
            })
            .collect();
        let (a, b) = (cell as f64 - 0.5, ((n + 3) * cell) as f64 - 0.5);
        (img, size, [[a, a], [b, a], [b, b], [a, b]])
    }

    #[test]
    fn every_rotation_decodes_to_the_id_with_the_printed_corner_order() {
        let dict = Dictionary::by_name("DICT_5X5_100").unwrap();
        for turns in 0..4u8 {
            let (img, size, quad) = drawn(dict, 17, turns, 6);
            let view = GrayView::new(size, size, &img[..]).unwrap();
            let d = decode(&view, &quad, dict).expect("decoded");
            assert_eq!(d.id, 17);
            // The printed top-left corner turns with the marker.
            assert_eq!(d.corners_px[0], quad[turns as usize % 4], "turns {turns}");
            assert!(d.white - d.black > 150.0);
        }
    }

    #[test]
    fn a_black_square_and_a_marker_of_another_dictionary_are_no_marker() {
        let dict = Dictionary::by_name("DICT_5X5_100").unwrap();
        let size = 60;
        let img: Vec<u8> = (0..size * size)
            .map(|i| if (10..50).contains(&(i % size)) && (10..50).contains(&(i / size)) { 40 } else { 210 })
            .collect();
        let view = GrayView::new(size, size, &img[..]).unwrap();
        assert!(decode(&view, &[[9.5, 9.5], [49.5, 9.5], [49.5, 49.5], [9.5, 49.5]], dict).is_none());
        let other = Dictionary::by_name("DICT_APRILTAG_36h11").unwrap();
        let (img, size, quad) = drawn(other, 3, 0, 6);
        let view = GrayView::new(size, size, &img[..]).unwrap();
        assert!(decode(&view, &quad, dict).is_none());
    }
}
