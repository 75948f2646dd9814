//! The ChArUco board: a checkerboard whose white squares hold ArUco markers, laid out
//! exactly as OpenCV (4.6 and later, non-legacy `cv::aruco::CharucoBoard`) lays it out,
//! so that a board printed by OpenCV's `generateImage`, or bought for OpenCV, is read with
//! OpenCV's ids and coordinates.
//!
//! Board frame (mm, z = 0 on the printed surface): origin at the board's top-left outer
//! corner, x to the right along the `cols` squares, y down along the `rows` squares, as
//! printed. Square (c, r) spans [c s, (c + 1) s] x [r s, (r + 1) s]; it is black when
//! c + r is even (the top-left square is black), white otherwise. The white squares hold
//! the markers, in row-major order: marker id k sits in the k-th white square counted
//! row by row, centred, `marker_mm` wide, with its first corner at the top left and the
//! others clockwise (OpenCV's marker corner order). The ChArUco corners are the inner
//! corners of the checkerboard: corner (c, r), c in 0..cols-1 and r in 0..rows-1, lies at
//! ((c + 1) s, (r + 1) s) and has id `r * (cols - 1) + c`.

use super::dictionary::Dictionary;
use crate::error::{Error, Result};

/// Most squares along a side: boards far beyond any printable one are refused, so that
/// everything sized by a board stays bounded.
pub const MAX_SQUARES: u32 = 1000;

/// A ChArUco board: squares (columns, rows), square and marker sizes, dictionary.
///
/// Invariants (checked by [`CharucoBoard::new`], the only constructor): at least 2 x 2 and
/// at most [`MAX_SQUARES`] squares each way; `0 < marker_mm < square_mm`, both finite; the
/// dictionary holds at least as many markers as the board has white squares.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CharucoBoard {
    squares: [u32; 2],
    square_mm: f64,
    marker_mm: f64,
    dictionary: &'static Dictionary,
}

impl CharucoBoard {
    /// A board of `squares` = [cols, rows] squares of `square_mm` with markers of
    /// `marker_mm` from `dictionary`.
    ///
    /// Errors ([`Error::InvalidArgument`] naming the field): fewer than 2 or more than
    /// [`MAX_SQUARES`] squares on a side; a size not positive and finite, or squares so large
    /// that the board's side overflows; a marker not smaller than its square; a dictionary
    /// with fewer markers than the board's white squares.
    ///
    /// ```
    /// use etl_core::board::{CharucoBoard, Dictionary};
    /// let dict = Dictionary::by_name("DICT_5X5_100").unwrap();
    /// let b = CharucoBoard::new([12, 9], 1.5, 1.1, dict).unwrap();
    /// assert_eq!((b.markers(), b.corners()), (54, 88));
    /// assert_eq!(b.corner_mm(0), Some([1.5, 1.5]));
    /// // Marker 0 is in square (1, 0), the first white one.
    /// assert_eq!(b.marker_square(0), Some([1, 0]));
    /// ```
    pub fn new(squares: [u32; 2], square_mm: f64, marker_mm: f64, dictionary: &'static Dictionary) -> Result<Self> {
        if squares.iter().any(|&n| !(2..=MAX_SQUARES).contains(&n)) {
            return Err(Error::InvalidArgument { what: "squares: a ChArUco board has 2 to 1000 squares each way" });
        }
        if !(square_mm.is_finite() && square_mm > 0.0) {
            return Err(Error::InvalidArgument { what: "square_mm must be positive and finite" });
        }
        if !(marker_mm.is_finite() && marker_mm > 0.0) {
            return Err(Error::InvalidArgument { what: "marker_mm must be positive and finite" });
        }
        if !(marker_mm < square_mm) {
            return Err(Error::InvalidArgument { what: "marker_mm must be smaller than square_mm" });
        }
        // Every position on the board (corners, markers, the pattern's extent) is at most
        // the board's side: when that overflows, they would be infinite (fuzz target
        // `board_parser`).
        if !(f64::from(squares[0].max(squares[1])) * square_mm).is_finite() {
            return Err(Error::InvalidArgument { what: "square_mm: the board (squares x square_mm) must be finite" });
        }
        let board = CharucoBoard { squares, square_mm, marker_mm, dictionary };
        if board.markers() > dictionary.len() {
            return Err(Error::InvalidArgument {
                what: "dictionary: the board has more white squares than the dictionary has markers",
            });
        }
        Ok(board)
    }

    /// Squares [cols, rows].
    pub fn squares(&self) -> [u32; 2] {
        self.squares
    }

    /// Side of a square, mm.
    pub fn square_mm(&self) -> f64 {
        self.square_mm
    }

    /// Side of a marker (its black border included), mm.
    pub fn marker_mm(&self) -> f64 {
        self.marker_mm
    }

    /// The dictionary the markers are taken from.
    pub fn dictionary(&self) -> &'static Dictionary {
        self.dictionary
    }

    /// Number of markers: the white squares, ids `0..markers()`.
    pub fn markers(&self) -> usize {
        let [c, r] = self.squares;
        (c as usize * r as usize) / 2
    }

    /// Number of ChArUco corners, `(cols - 1) * (rows - 1)`, ids `0..corners()`.
    pub fn corners(&self) -> usize {
        let [c, r] = self.squares;
        (c as usize - 1) * (r as usize - 1)
    }

    /// Whether square (col, row) is black (false outside the board).
    pub fn is_black(&self, col: u32, row: u32) -> bool {
        col < self.squares[0] && row < self.squares[1] && (col + row) % 2 == 0
    }

    /// The marker in square (col, row); `None` for a black square or outside the board.
    pub fn marker_at(&self, col: u32, row: u32) -> Option<u32> {
        let [cols, rows] = self.squares;
        if col >= cols || row >= rows || (col + row) % 2 == 0 {
            return None;
        }
        // Row r holds cols / 2 white squares, one more when cols is odd and r is odd
        // (its first square is white): (r * cols + c) / 2 counts the white squares before.
        Some((row * cols + col) / 2)
    }

    /// Square [col, row] of marker `id`; `None` beyond the board's markers.
    pub fn marker_square(&self, id: u32) -> Option<[u32; 2]> {
        if id as usize >= self.markers() {
            return None;
        }
        // Marker id k is in the white square of linear index k = r * cols + c with
        // (r * cols + c) / 2 = id, so k is 2 id or 2 id + 1, whichever is white.
        let cols = self.squares[0];
        [2 * id, 2 * id + 1].into_iter().find_map(|k| {
            let (c, r) = (k.checked_rem(cols)?, k.checked_div(cols)?);
            ((c + r) % 2 == 1).then_some([c, r])
        })
    }

    /// The four corners of marker `id` on the board, mm: top left, top right, bottom right,
    /// bottom left (OpenCV's order, clockwise as printed); `None` beyond the board.
    pub fn marker_corners_mm(&self, id: u32) -> Option<[[f64; 2]; 4]> {
        let [c, r] = self.marker_square(id)?;
        let inset = 0.5 * (self.square_mm - self.marker_mm);
        let x0 = c as f64 * self.square_mm + inset;
        let y0 = r as f64 * self.square_mm + inset;
        let m = self.marker_mm;
        Some([[x0, y0], [x0 + m, y0], [x0 + m, y0 + m], [x0, y0 + m]])
    }

    /// ChArUco corner `id` on the board, mm; `None` beyond the board's corners.
    pub fn corner_mm(&self, id: u32) -> Option<[f64; 2]> {
        let [c, r] = self.corner_cell(id)?;
        Some([(c + 1) as f64 * self.square_mm, (r + 1) as f64 * self.square_mm])
    }

    /// The (col, row) of corner `id` among the inner corners.
    pub fn corner_cell(&self, id: u32) -> Option<[u32; 2]> {
        if id as usize >= self.corners() {
            return None;
        }
        let per_row = self.squares[0].saturating_sub(1);
        Some([id.checked_rem(per_row)?, id.checked_div(per_row)?])
    }

    /// The id of the inner corner (col, row); `None` outside the inner corners.
    pub fn corner_id(&self, col: u32, row: u32) -> Option<u32> {
        let [cols, rows] = self.squares;
        (col + 1 < cols && row + 1 < rows).then_some(row * (cols - 1) + col)
    }

    /// The two markers that touch corner `id` (in the two white squares of its four), in
    /// increasing id order; `None` beyond the board.
    pub fn corner_markers(&self, id: u32) -> Option<[u32; 2]> {
        let [c, r] = self.corner_cell(id)?;
        // The squares around corner (c, r) are (c, r), (c + 1, r), (c, r + 1), (c + 1, r + 1);
        // the white ones are (c + 1, r) and (c, r + 1) when c + r is even, else the others.
        let (a, b) = if (c + r) % 2 == 0 {
            (self.marker_at(c + 1, r)?, self.marker_at(c, r + 1)?)
        } else {
            (self.marker_at(c, r)?, self.marker_at(c + 1, r + 1)?)
        };
        Some([a.min(b), a.max(b)])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn board(cols: u32, rows: u32) -> CharucoBoard {
        CharucoBoard::new([cols, rows], 10.0, 6.0, Dictionary::by_name("DICT_4X4_250").unwrap()).unwrap()
    }

    /// OpenCV 5.0's `CharucoBoard((5, 4), 10, 6, DICT_4X4_50)`: marker 0 at
    /// (12, 2)-(18, 8), marker 1 at x = 32; corners (10, 10), (20, 10), (30, 10), ...;
    /// square (0, 0) black.
    #[test]
    fn layout_is_opencvs() {
        let b = board(5, 4);
        assert_eq!(b.marker_corners_mm(0), Some([[12.0, 2.0], [18.0, 2.0], [18.0, 8.0], [12.0, 8.0]]));
        assert_eq!(b.marker_corners_mm(1).map(|m| m[0]), Some([32.0, 2.0]));
        assert_eq!(b.corner_mm(0), Some([10.0, 10.0]));
        assert_eq!(b.corner_mm(2), Some([30.0, 10.0]));
        assert_eq!(b.corner_mm(4), Some([10.0, 20.0]));
        assert_eq!((b.markers(), b.corners()), (10, 12));
        assert!(b.is_black(0, 0) && !b.is_black(1, 0) && !b.is_black(0, 1));
    }

    /// Marker ids run over the white squares row by row, for odd and even widths, and
    /// `marker_square` inverts `marker_at`.
    #[test]
    fn markers_are_numbered_row_by_row_over_the_white_squares() {
        for (cols, rows) in [(5, 4), (4, 5), (5, 5), (4, 4), (12, 9), (2, 2), (3, 7)] {
            let b = board(cols, rows);
            let mut next = 0;
            for r in 0..rows {
                for c in 0..cols {
                    match b.marker_at(c, r) {
                        Some(id) => {
                            assert_eq!(id, next, "{cols}x{rows} ({c}, {r})");
                            assert_eq!(b.marker_square(id), Some([c, r]));
                            next += 1;
                        }
                        None => assert!(b.is_black(c, r)),
                    }
                }
            }
            assert_eq!(next as usize, b.markers());
            assert_eq!(b.marker_square(next), None);
        }
    }

    #[test]
    fn each_corner_touches_two_markers_diagonally() {
        let b = board(6, 5);
        for id in 0..b.corners() as u32 {
            let [c, r] = b.corner_cell(id).unwrap();
            assert_eq!(b.corner_id(c, r), Some(id));
            let [m0, m1] = b.corner_markers(id).unwrap();
            let p = b.corner_mm(id).unwrap();
            for m in [m0, m1] {
                let sq = b.marker_square(m).unwrap();
                // The marker's square has the corner as one of its own corners.
                let (x0, y0) = (sq[0] as f64 * 10.0, sq[1] as f64 * 10.0);
                assert!((p[0] == x0 || p[0] == x0 + 10.0) && (p[1] == y0 || p[1] == y0 + 10.0));
            }
        }
        assert_eq!(b.corner_id(5, 0), None);
    }

    #[test]
    fn bad_boards_are_refused_naming_the_field() {
        let d = Dictionary::by_name("DICT_4X4_50").unwrap();
        let what = |r: Result<CharucoBoard>| match r {
            Err(Error::InvalidArgument { what }) => what,
            other => panic!("{other:?}"),
        };
        assert!(what(CharucoBoard::new([1, 5], 1.0, 0.5, d)).starts_with("squares"));
        assert!(what(CharucoBoard::new([5, 5], 0.0, 0.5, d)).starts_with("square_mm"));
        assert!(what(CharucoBoard::new([5, 5], -1.0, 0.5, d)).starts_with("square_mm"));
        assert!(what(CharucoBoard::new([5, 5], 1.0, f64::NAN, d)).starts_with("marker_mm"));
        assert!(what(CharucoBoard::new([5, 5], 1.0, 1.0, d)).starts_with("marker_mm must be smaller"));
        // 12 x 9 squares need 54 markers; DICT_4X4_50 has 50.
        assert!(what(CharucoBoard::new([12, 9], 1.5, 1.1, d)).starts_with("dictionary"));
        assert!(CharucoBoard::new([10, 10], 1.5, 1.1, d).is_ok());
        // 1000 squares of 1e306 mm: a board 1e309 mm wide, whose far corners are infinite.
        let d = Dictionary::by_name("DICT_7X7_1000").unwrap();
        assert!(what(CharucoBoard::new([1000, 2], 1e306, 1.0, d)).starts_with("square_mm: the board"));
        let b = CharucoBoard::new([1000, 2], 1e305, 1.0, d).unwrap();
        assert!(b.corner_mm(b.corners() as u32 - 1).unwrap().iter().all(|v| v.is_finite()));
    }
}
