//! Step 5: the decoded markers checked against the board's layout.
//!
//! Kept: markers whose id is on the board, once (an id decoded at two places is ambiguous
//! and both are dropped; the same marker found twice is kept once), and confirmed by their
//! neighbours. Two decoded markers within two squares of each other on the board agree when
//! one's homography (board mm to image, from its four corners) puts the other's centre where
//! it was found, within 30 % of a square and 1.5 px per square of distance. A misread id
//! places its homography at least one square off, so a marker is kept when some neighbours
//! agree with it and those outnumber three times the nearest ones (diagonal) that disagree.
//! A lone marker, unconfirmed, gives no corner. On a board laid out otherwise than the board
//! asked for (another number of columns; OpenCV's legacy layout of boards with an even number
//! of rows: rows of one parity shifted against the others) most markers are contradicted by a
//! diagonal neighbour, and the detector refuses the image rather than give the few that
//! happen to agree.

use std::collections::HashMap;

use etl_core::board::CharucoBoard;

use super::decode::Decoded;
use super::homography::Homography;

/// A marker placed on the board.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Placed {
    pub id: u32,
    /// Printed top-left, top-right, bottom-right, bottom-left, px.
    pub corners_px: [[f64; 2]; 4],
    /// Board mm to image px, from the four corners.
    pub h: Homography,
    /// Its square [col, row].
    pub square: [u32; 2],
}

/// A marker is kept when its agreeing neighbours outnumber its disagreeing diagonal ones this
/// many times over.
const DISAGREEMENT: usize = 3;
/// The markers checked against the board.
pub(crate) struct Layout {
    /// The confirmed markers, in increasing id order.
    pub kept: Vec<Placed>,
    /// Markers decoded with an id on the board (each once).
    pub on_board: usize,
    /// Of those, how many a diagonal neighbour contradicts. On the board asked for, next to
    /// none; on a board of another size or layout, most (ids fall in other squares).
    pub contradicted: usize,
}

/// Farthest neighbour checked, squares along either axis.
const REACH: i64 = 2;
/// Agreement needed between a predicted and an observed marker centre, squares, plus
/// [`EXTRAPOLATION_PX`] per square of distance (a small marker's corners, a fraction of a
/// pixel off, tilt its homography noticeably a few squares away).
const TOLERANCE: f64 = 0.3;
const EXTRAPOLATION_PX: f64 = 1.5;

/// The markers of `decoded` that are on `board`, unique and confirmed by their neighbours.
pub(crate) fn confirmed(board: &CharucoBoard, decoded: &[Decoded]) -> Layout {
    let mut by_id: HashMap<u32, Vec<&Decoded>> = HashMap::new();
    for d in decoded {
        by_id.entry(d.id).or_default().push(d);
    }
    let mut placed: Vec<Placed> = Vec::new();
    for (id, found) in by_id {
        let Some(square) = board.marker_square(id) else { continue };
        let Some(board_mm) = board.marker_corners_mm(id) else { continue };
        let first = found[0];
        let size = side_px(&first.corners_px);
        if found.iter().any(|d| dist(centre(&d.corners_px), centre(&first.corners_px)) > 0.25 * size) {
            continue;
        }
        if let Some(h) = Homography::fit(&board_mm, &first.corners_px) {
            placed.push(Placed { id, corners_px: first.corners_px, h, square });
        }
    }
    placed.sort_by_key(|p| p.id);
    let at: HashMap<[u32; 2], usize> = placed.iter().enumerate().map(|(k, p)| (p.square, k)).collect();
    // (agreeing neighbours, disagreeing diagonal ones) of each marker.
    let votes: Vec<(usize, usize)> = placed
        .iter()
        .map(|p| {
            let (mut agree, mut disagree) = (0, 0);
            for dr in -REACH..=REACH {
                for dc in -REACH..=REACH {
                    let (c, r) = (p.square[0] as i64 + dc, p.square[1] as i64 + dr);
                    if (dc, dr) == (0, 0) || c < 0 || r < 0 {
                        continue;
                    }
                    let Some(&k) = at.get(&[c as u32, r as u32]) else { continue };
                    let q = &placed[k];
                    // Either marker's homography may place the other: a misread id puts
                    // both predictions a square or more off, while one marker seen small or
                    // obliquely may extrapolate poorly.
                    if predicts(board, p, q) || predicts(board, q, p) {
                        agree += 1;
                    } else if dc.abs() <= 1 && dr.abs() <= 1 {
                        // Only the nearest neighbours (diagonal, a square and a half apart)
                        // may veto: two squares away a small marker's homography can be
                        // off by more than the tolerance.
                        disagree += 1;
                    }
                }
            }
            (agree, disagree)
        })
        .collect();
    let contradicted = votes.iter().filter(|v| v.1 > 0).count();
    let on_board = placed.len();
    let kept = placed
        .into_iter()
        .zip(votes)
        .filter_map(|(p, (agree, disagree))| (agree > 0 && DISAGREEMENT * disagree < agree).then_some(p))
        .collect();
    Layout { kept, on_board, contradicted }
}

/// Whether `p`'s homography puts `q`'s centre where `q` was found.
fn predicts(board: &CharucoBoard, p: &Placed, q: &Placed) -> bool {
    let s = board.square_mm();
    let predicted = p.h.map([(q.square[0] as f64 + 0.5) * s, (q.square[1] as f64 + 0.5) * s]);
    let square_px = side_px(&q.corners_px) * s / board.marker_mm();
    let squares = (p.square[0] as f64 - q.square[0] as f64).abs().max((p.square[1] as f64 - q.square[1] as f64).abs());
    dist(predicted, centre(&q.corners_px)) <= TOLERANCE * square_px + EXTRAPOLATION_PX * squares
}

pub(crate) fn centre(q: &[[f64; 2]; 4]) -> [f64; 2] {
    [0.25 * (q[0][0] + q[1][0] + q[2][0] + q[3][0]), 0.25 * (q[0][1] + q[1][1] + q[2][1] + q[3][1])]
}

/// Mean side of a quadrilateral, px.
pub(crate) fn side_px(q: &[[f64; 2]; 4]) -> f64 {
    0.25 * (0..4).map(|k| dist(q[k], q[(k + 1) % 4])).sum::<f64>()
}

pub(crate) fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

#[cfg(test)]
mod tests {
    use super::*;
    use etl_core::board::Dictionary;

    /// Every marker of a 6 x 5 board seen face-on at 10 px per mm.
    fn markers(board: &CharucoBoard) -> Vec<Decoded> {
        (0..board.markers() as u32)
            .map(|id| {
                let c = board.marker_corners_mm(id).unwrap().map(|p| [10.0 * p[0] + 20.0, 10.0 * p[1] + 30.0]);
                Decoded { id, corners_px: c, black: 40.0, white: 210.0 }
            })
            .collect()
    }

    #[test]
    fn a_misread_id_is_dropped_and_its_neighbours_kept() {
        let board = CharucoBoard::new([6, 5], 10.0, 7.0, Dictionary::by_name("DICT_4X4_50").unwrap()).unwrap();
        let mut found = markers(&board);
        let all = confirmed(&board, &found);
        assert_eq!((all.kept.len(), all.on_board, all.contradicted), (15, 15, 0));
        // Marker 7 read as 9 (another square of the board), 12 read as 40 (not on it).
        found[7].id = 9;
        found[12].id = 40;
        let l = confirmed(&board, &found);
        let ids: Vec<u32> = l.kept.iter().map(|p| p.id).collect();
        // 9 is now at two places: both dropped; 12 and 40 are gone; the rest kept.
        let want: Vec<u32> = (0..15).filter(|i| ![7, 9, 12].contains(i)).collect();
        assert_eq!(ids, want);
        // A lone marker is not confirmed.
        assert!(confirmed(&board, &found[..1]).kept.is_empty());
    }

    #[test]
    fn a_board_of_another_width_is_contradicted() {
        let printed = CharucoBoard::new([6, 5], 10.0, 7.0, Dictionary::by_name("DICT_4X4_50").unwrap()).unwrap();
        let asked = CharucoBoard::new([7, 5], 10.0, 7.0, Dictionary::by_name("DICT_4X4_50").unwrap()).unwrap();
        let l = confirmed(&asked, &markers(&printed));
        assert!(l.contradicted > l.kept.len(), "{} contradicted, {} kept", l.contradicted, l.kept.len());
    }
}
