//! `etlcal.board/1`: the calibration target, a ChArUco board or a plain checkerboard.
//!
//! ```json
//! {"format": "etlcal.board/1", "type": "charuco", "squares": [12, 9], "square_mm": 1.5,
//!  "marker_mm": 1.1, "dictionary": "DICT_5X5_100"}
//! {"format": "etlcal.board/1", "type": "checkerboard", "inner_corners": [14, 12], "square_mm": 1.5}
//! ```
//!
//! A ChArUco board is laid out exactly as OpenCV (4.6 and later, non-legacy) lays it out
//! ([`etl_core::board::CharucoBoard`]): `squares` = [cols, rows] squares, the top-left one
//! black, the markers of `dictionary` (one of OpenCV's predefined ones) in the white
//! squares, row by row; board frame origin at the top-left outer corner, x right, y down;
//! corner id `row * (cols - 1) + col` at ((col + 1) square_mm, (row + 1) square_mm). So a
//! board printed by OpenCV's `generateImage`, or bought for OpenCV, is read with OpenCV's
//! ids and coordinates. Its corners are known by their ids wherever they are seen: a view
//! that sees part of it needs no hint.
//!
//! A checkerboard's inner corner (col, row) sits at (col square_mm, row square_mm): the
//! board frame's origin is its first inner corner; its id (`etlcal detect --json`) is
//! `row * cols + col`. A checkerboard seen in part cannot be indexed: the detector needs
//! it whole (or a per-view sub-board hint in a dataset, see [`crate::dataset`]).
//!
//! The same object stands inline wherever a dataset names a board (`board`,
//! `offstate_board`, a view's `board`); there `"format"` may be left out, and the board
//! object of the datasets written before this format, `{"inner_corners", "square_mm"}`
//! (no `"type"`), is read as a checkerboard.
//!
//! ```
//! use etl_formats::board::Board;
//! let b = Board::charuco([12, 9], 1.5, 1.1, "DICT_5X5_100").unwrap();
//! assert_eq!(b.corner_count(), 88);
//! assert_eq!(b.corner_mm(12), Some([3.0, 3.0])); // row 1, column 1
//! let text = serde_json::to_string(&b).unwrap();
//! assert_eq!(serde_json::from_str::<Board>(&text).unwrap(), b);
//! let e = Board::charuco([12, 9], 1.5, 1.5, "DICT_5X5_100").unwrap_err().to_string();
//! assert!(e.contains("marker_mm must be smaller than square_mm (square_mm 1.5, marker_mm 1.5)"), "{e}");
//! ```

use std::path::Path;

use etl_core::board::{CharucoBoard, Dictionary};
use serde::{Deserialize, Serialize};
use serde_json::Number;

use super::{compact, read_json, write_json};
use crate::{Error, InputValue, Result};

/// The format tag.
pub const FORMAT: &str = "etlcal.board/1";

/// Most inner corners of a checkerboard along a side (a ChArUco board has at most
/// [`etl_core::board::charuco::MAX_SQUARES`] squares): far beyond any printable board, so
/// that everything sized by a board stays bounded.
pub const MAX_INNER_CORNERS: usize = etl_core::board::charuco::MAX_SQUARES as usize - 1;

/// A plain checkerboard: inner corners [cols, rows] and square size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Checkerboard {
    /// Inner corners along the columns and rows, `[cols, rows]`.
    pub inner_corners: [usize; 2],
    /// Side of a square, mm.
    pub square_mm: f64,
}

/// The smallest square a board may have: 1 um. Below it no camera resolves the board, and
/// squares of 1e-300 mm made every later number denormal or zero.
pub const MIN_SQUARE_MM: f64 = 1e-3;

/// Refuses a square below [`MIN_SQUARE_MM`] (NaN and the non-positive are refused before).
fn check_square_mm(square_mm: f64) -> Result<()> {
    if square_mm < MIN_SQUARE_MM {
        // The minimum as written in MIN_SQUARE_MM's doc (compact would print 0.001).
        let message = format!("square_mm {} mm is below the smallest board square, 1e-3 mm", compact(square_mm));
        return Err(Error::invalid_value("square_mm", square_mm, message));
    }
    Ok(())
}

impl Checkerboard {
    /// Checks the board: 3 to [`MAX_INNER_CORNERS`] inner corners each way and a positive,
    /// finite square, small enough that the whole pattern's size is finite too.
    pub fn validate(&self) -> Result<()> {
        // The messages of the checkerboards of before the board format, which users match
        // on; `what` names the key.
        if !(self.square_mm.is_finite() && self.square_mm > 0.0) {
            let message = format!("square_mm must be a positive square size, got {} mm", compact(self.square_mm));
            return Err(Error::invalid_value("square_mm", self.square_mm, message));
        }
        check_square_mm(self.square_mm)?;
        let [c, r] = self.inner_corners;
        if c < 3 || r < 3 {
            let message = format!("inner_corners: a board needs at least 3 x 3 inner corners, got {c} x {r}");
            return Err(Error::invalid_value("inner_corners", self.inner_corners, message));
        }
        if c > MAX_INNER_CORNERS || r > MAX_INNER_CORNERS {
            let message =
                format!("a board has at most {MAX_INNER_CORNERS} x {MAX_INNER_CORNERS} inner corners, got {c} x {r}");
            return Err(Error::invalid_value("inner_corners", self.inner_corners, message));
        }
        // The pattern spans (corners + 1) squares: when that overflows, the far corners
        // would be infinite (fuzz target `board_parser`).
        if !((c.max(r) + 1) as f64 * self.square_mm).is_finite() {
            let message = format!(
                "square_mm: a board of {c} x {r} inner corners of {} mm does not fit in a number",
                compact(self.square_mm)
            );
            return Err(Error::invalid_value("square_mm", self.square_mm, message));
        }
        Ok(())
    }

    /// Board-frame (X, Y) of every inner corner, row by row (col fastest), mm.
    pub fn corners_mm(&self) -> Vec<[f64; 2]> {
        let [cols, rows] = self.inner_corners;
        (0..rows).flat_map(|j| (0..cols).map(move |i| [i as f64 * self.square_mm, j as f64 * self.square_mm])).collect()
    }
}

/// The calibration target of a view: a ChArUco board (markers make every corner known by
/// its id, so partial views need no hint) or a plain checkerboard.
///
/// A `Board` is valid once made by [`Board::charuco`], [`Board::checkerboard`] or a reader;
/// [`Board::validate`] checks one built from its variants by hand (a [`Checkerboard`]'s
/// fields are public; a [`CharucoBoard`] is checked by its constructor).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "BoardObject", into = "BoardObject")]
pub enum Board {
    /// A ChArUco board in OpenCV's layout.
    Charuco(CharucoBoard),
    /// A plain checkerboard.
    Checkerboard(Checkerboard),
}

impl Board {
    /// A ChArUco board of `squares` = [cols, rows] squares of `square_mm`, markers of
    /// `marker_mm` from the predefined dictionary `dictionary` (OpenCV's name, e.g.
    /// `"DICT_5X5_100"`).
    ///
    /// Errors ([`Error::InvalidInput`], one line naming the field and the values): an
    /// unknown dictionary; fewer than 2 or more than 1000 squares on a side; a size not
    /// positive and finite, or squares so large that the board's side overflows; a marker
    /// not smaller than its square; more white squares than the dictionary has markers.
    pub fn charuco(squares: [u32; 2], square_mm: f64, marker_mm: f64, dictionary: &str) -> Result<Board> {
        let dict = Dictionary::by_name(dictionary).ok_or_else(|| {
            let name: String = dictionary.chars().take(40).collect();
            let message = format!(
                "dictionary \"{name}\" is not one of OpenCV's predefined dictionaries ({})",
                dictionary_names()
            );
            Error::invalid_value("dictionary", name, message)
        })?;
        let board = CharucoBoard::new(squares, square_mm, marker_mm, dict).map(Board::Charuco).map_err(|e| {
            // etl-core's message names the field; the values make it actionable.
            let what = match e {
                etl_core::Error::InvalidArgument { what } => what.to_string(),
                other => other.to_string(),
            };
            let field = what.split([' ', ':']).next().unwrap_or("board").to_owned();
            let (detail, value) = if field == "squares" {
                (format!("squares [{}, {}]", squares[0], squares[1]), squares.to_input_value())
            } else if field == "dictionary" {
                let white = (squares[0] as usize * squares[1] as usize) / 2;
                (format!("{} has {} markers, the board {white}", dict.name(), dict.len()), dict.name().into())
            } else {
                let value = if field == "square_mm" { square_mm } else { marker_mm };
                (format!("square_mm {}, marker_mm {}", compact(square_mm), compact(marker_mm)), compact(value))
            };
            Error::invalid_value(field, value, format!("{what} ({detail})"))
        })?;
        board.validate()?;
        Ok(board)
    }

    /// A checkerboard of `inner_corners` [cols, rows] and `square_mm`; errors as
    /// [`Checkerboard::validate`].
    pub fn checkerboard(inner_corners: [usize; 2], square_mm: f64) -> Result<Board> {
        let c = Checkerboard { inner_corners, square_mm };
        c.validate()?;
        Ok(Board::Checkerboard(c))
    }

    /// Reads and checks an `etlcal.board/1` file.
    pub fn load(path: &Path) -> Result<Board> {
        let b: Board = read_json(path, FORMAT)?;
        b.validate().map_err(|e| Error::Parse { path: path.to_owned(), message: e.to_string() })?;
        Ok(b)
    }

    /// Checks and writes the file atomically.
    pub fn save(&self, path: &Path) -> Result<()> {
        self.validate().map_err(|e| e.within(path.display(), None))?;
        write_json(path, self)
    }

    /// The one check of a board, made by every reader and writer: a checkerboard's
    /// [`Checkerboard::validate`]; a ChArUco board holds by construction, and its square
    /// is at least [`MIN_SQUARE_MM`].
    pub fn validate(&self) -> Result<()> {
        match self {
            Board::Charuco(b) => check_square_mm(b.square_mm()),
            Board::Checkerboard(c) => c.validate(),
        }
    }

    /// `"charuco"` or `"checkerboard"`, the file's `"type"`.
    pub fn type_name(&self) -> &'static str {
        match self {
            Board::Charuco(_) => "charuco",
            Board::Checkerboard(_) => "checkerboard",
        }
    }

    /// The ChArUco board's geometry; `None` for a checkerboard.
    pub fn as_charuco(&self) -> Option<&CharucoBoard> {
        match self {
            Board::Charuco(b) => Some(b),
            Board::Checkerboard(_) => None,
        }
    }

    /// The checkerboard; `None` for a ChArUco board.
    pub fn as_checkerboard(&self) -> Option<&Checkerboard> {
        match self {
            Board::Charuco(_) => None,
            Board::Checkerboard(c) => Some(c),
        }
    }

    /// Side of a square, mm.
    pub fn square_mm(&self) -> f64 {
        match self {
            Board::Charuco(b) => b.square_mm(),
            Board::Checkerboard(c) => c.square_mm,
        }
    }

    /// The grid of corners, [cols, rows]: a checkerboard's inner corners, a ChArUco board's
    /// squares less one each way. Corner ids run row by row over it.
    pub fn corner_grid(&self) -> [usize; 2] {
        match self {
            Board::Charuco(b) => b.squares().map(|n| n as usize - 1),
            Board::Checkerboard(c) => c.inner_corners,
        }
    }

    /// Number of corners (ids `0..corner_count()`).
    pub fn corner_count(&self) -> usize {
        let [c, r] = self.corner_grid();
        c * r
    }

    /// Board-frame (X, Y) of corner `id`, mm (see the module docs for each board's frame);
    /// `None` beyond the board.
    pub fn corner_mm(&self, id: u32) -> Option<[f64; 2]> {
        match self {
            Board::Charuco(b) => b.corner_mm(id),
            Board::Checkerboard(c) => {
                let [cols, rows] = c.inner_corners;
                let (i, j) = (id as usize % cols.max(1), id as usize / cols.max(1));
                (j < rows).then_some([i as f64 * c.square_mm, j as f64 * c.square_mm])
            }
        }
    }

    /// Board-frame (X, Y) of every corner in id order, mm.
    pub fn corners_mm(&self) -> Vec<[f64; 2]> {
        (0..self.corner_count() as u32).filter_map(|id| self.corner_mm(id)).collect()
    }

    /// The printed pattern's extent in the board frame, mm: `[x_min, y_min, x_max, y_max]`
    /// (the outer squares included; a checkerboard's start one square before its first
    /// inner corner).
    pub fn pattern_mm(&self) -> [f64; 4] {
        let s = self.square_mm();
        let [c, r] = self.corner_grid().map(|n| (n + 1) as f64 * s);
        match self {
            Board::Charuco(_) => [0.0, 0.0, c, r],
            Board::Checkerboard(_) => [-s, -s, c - s, r - s],
        }
    }

    /// One line for messages: `ChArUco 12 x 9 squares of 1.5 mm (markers 1.1 mm,
    /// DICT_5X5_100)` or `checkerboard 14 x 12 inner corners of 1.5 mm`.
    pub fn describe(&self) -> String {
        match self {
            Board::Charuco(b) => format!(
                "ChArUco {} x {} squares of {} mm (markers {} mm, {})",
                b.squares()[0],
                b.squares()[1],
                compact(b.square_mm()),
                compact(b.marker_mm()),
                b.dictionary().name()
            ),
            Board::Checkerboard(c) => format!(
                "checkerboard {} x {} inner corners of {} mm",
                c.inner_corners[0],
                c.inner_corners[1],
                compact(c.square_mm)
            ),
        }
    }
}

/// The names of the predefined dictionaries, for messages.
fn dictionary_names() -> String {
    Dictionary::all().iter().map(|d| d.name()).collect::<Vec<_>>().join(", ")
}

/// The board object as JSON has it: every field of either type optional, so that the
/// checks of [`TryFrom`] name what is wrong (serde alone would say "data did not match any
/// variant"). Counts are JSON numbers, so that a negative or fractional one is named too.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct BoardObject {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    format: Option<String>,
    #[serde(rename = "type", default, skip_serializing_if = "Option::is_none")]
    kind: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    inner_corners: Option<[Number; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    squares: Option<[Number; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    square_mm: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    marker_mm: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    dictionary: Option<String>,
}

/// A [`BoardObject`] field that must be there.
fn needed<T: Clone>(value: &Option<T>, field: &str, kind: &str) -> std::result::Result<T, String> {
    value.clone().ok_or_else(|| format!("a {kind} board needs \"{field}\""))
}

/// Whole counts from JSON numbers, or a message naming `field`.
fn counts(v: &[Number; 2], field: &str) -> std::result::Result<[u64; 2], String> {
    match (v[0].as_u64(), v[1].as_u64()) {
        (Some(a), Some(b)) => Ok([a, b]),
        _ => Err(format!("{field} [{}, {}] must be whole numbers, not negative", v[0], v[1])),
    }
}

impl TryFrom<BoardObject> for Board {
    type Error = String;

    fn try_from(o: BoardObject) -> std::result::Result<Board, String> {
        if let Some(f) = o.format.as_deref().filter(|f| *f != FORMAT) {
            return Err(format!(
                "format \"{}\" of a board is not \"{FORMAT}\"",
                f.chars().take(40).collect::<String>()
            ));
        }
        match o.kind.as_deref() {
            Some("charuco") => {
                if o.inner_corners.is_some() {
                    return Err("inner_corners is not a field of a ChArUco board (its size is \"squares\")".into());
                }
                let squares = counts(&needed(&o.squares, "squares", "charuco")?, "squares")?
                    .map(|n| u32::try_from(n).unwrap_or(u32::MAX));
                let square_mm = needed(&o.square_mm, "square_mm", "charuco")?;
                let marker_mm = needed(&o.marker_mm, "marker_mm", "charuco")?;
                let dictionary = needed(&o.dictionary, "dictionary", "charuco")?;
                Board::charuco(squares, square_mm, marker_mm, &dictionary).map_err(|e| without_prefix(&e))
            }
            Some("checkerboard") | None => {
                if o.squares.is_some() || o.marker_mm.is_some() || o.dictionary.is_some() {
                    return Err(
                        "squares, marker_mm and dictionary are fields of a ChArUco board (\"type\": \"charuco\")"
                            .into(),
                    );
                }
                let inner = counts(&needed(&o.inner_corners, "inner_corners", "checkerboard")?, "inner_corners")?
                    .map(|n| usize::try_from(n).unwrap_or(usize::MAX));
                let square_mm = needed(&o.square_mm, "square_mm", "checkerboard")?;
                Board::checkerboard(inner, square_mm).map_err(|e| without_prefix(&e))
            }
            Some(other) => Err(format!(
                "type \"{}\" is not \"charuco\" or \"checkerboard\"",
                other.chars().take(40).collect::<String>()
            )),
        }
    }
}

/// The message of an [`Error::InvalidInput`] without its "invalid input: " prefix (the
/// reader wraps it again).
fn without_prefix(e: &Error) -> String {
    match e {
        Error::InvalidInput { message, .. } => message.clone(),
        other => other.to_string(),
    }
}

impl From<Board> for BoardObject {
    fn from(b: Board) -> BoardObject {
        let pair = |a: u64, b: u64| [Number::from(a), Number::from(b)];
        match b {
            Board::Charuco(c) => BoardObject {
                format: Some(FORMAT.into()),
                kind: Some("charuco".into()),
                squares: Some(pair(c.squares()[0].into(), c.squares()[1].into())),
                square_mm: Some(c.square_mm()),
                marker_mm: Some(c.marker_mm()),
                dictionary: Some(c.dictionary().name().into()),
                ..BoardObject::default()
            },
            Board::Checkerboard(c) => BoardObject {
                format: Some(FORMAT.into()),
                kind: Some("checkerboard".into()),
                inner_corners: Some(pair(c.inner_corners[0] as u64, c.inner_corners[1] as u64)),
                square_mm: Some(c.square_mm),
                ..BoardObject::default()
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> std::result::Result<Board, String> {
        serde_json::from_str::<Board>(text).map_err(|e| e.to_string())
    }

    #[test]
    fn both_types_round_trip_and_the_old_object_reads_as_a_checkerboard() {
        let c = Board::charuco([12, 9], 1.5, 1.1, "DICT_5X5_100").unwrap();
        let k = Board::checkerboard([14, 12], 1.5).unwrap();
        for b in [c, k] {
            let text = serde_json::to_string(&b).unwrap();
            assert!(text.starts_with("{\"format\":\"etlcal.board/1\",\"type\":"), "{text}");
            assert_eq!(parse(&text).unwrap(), b);
        }
        assert_eq!(
            serde_json::to_string(&c).unwrap(),
            r#"{"format":"etlcal.board/1","type":"charuco","squares":[12,9],"square_mm":1.5,"marker_mm":1.1,"dictionary":"DICT_5X5_100"}"#
        );
        assert_eq!(parse(r#"{"inner_corners": [14, 12], "square_mm": 1.5}"#).unwrap(), k);
        // The AprilTag names are matched in either case, as OpenCV spells them both ways.
        let a = parse(r#"{"type": "charuco", "squares": [5, 5], "square_mm": 2, "marker_mm": 1.5, "dictionary": "DICT_APRILTAG_36H11"}"#).unwrap();
        assert_eq!(a.as_charuco().unwrap().dictionary().name(), "DICT_APRILTAG_36h11");
    }

    #[test]
    fn bad_boards_are_named_in_one_line() {
        let ch = |fields: &str| format!(r#"{{"format": "etlcal.board/1", "type": "charuco", {fields}}}"#);
        let cases = [
            (ch(r#""squares": [12, 9], "square_mm": 1.5, "marker_mm": 1.1, "dictionary": "DICT_5X5_99""#), "dictionary \"DICT_5X5_99\" is not one of OpenCV's"),
            (ch(r#""squares": [12, 9], "square_mm": 1.5, "marker_mm": 1.6, "dictionary": "DICT_5X5_100""#), "marker_mm must be smaller than square_mm (square_mm 1.5, marker_mm 1.6)"),
            (ch(r#""squares": [12, 9], "square_mm": 1.5, "marker_mm": 1.5, "dictionary": "DICT_5X5_100""#), "marker_mm must be smaller"),
            (ch(r#""squares": [12, 9], "square_mm": 1.5, "marker_mm": 1.1, "dictionary": "DICT_4X4_50""#), "dictionary: the board has more white squares than the dictionary has markers (DICT_4X4_50 has 50 markers, the board 54)"),
            (ch(r#""squares": [12, 9], "square_mm": 0, "marker_mm": 1.1, "dictionary": "DICT_5X5_100""#), "square_mm must be positive"),
            (ch(r#""squares": [12, 9], "square_mm": -1.5, "marker_mm": 1.1, "dictionary": "DICT_5X5_100""#), "square_mm must be positive and finite (square_mm -1.5"),
            (ch(r#""squares": [12, 9], "square_mm": 1.5, "marker_mm": -1, "dictionary": "DICT_5X5_100""#), "marker_mm must be positive"),
            (ch(r#""squares": [0, 9], "square_mm": 1.5, "marker_mm": 1.1, "dictionary": "DICT_5X5_100""#), "squares: a ChArUco board has 2 to 1000 squares each way (squares [0, 9])"),
            (ch(r#""squares": [-12, 9], "square_mm": 1.5, "marker_mm": 1.1, "dictionary": "DICT_5X5_100""#), "squares [-12, 9] must be whole numbers"),
            (ch(r#""squares": [12, 9], "square_mm": 1.5, "dictionary": "DICT_5X5_100""#), "a charuco board needs \"marker_mm\""),
            (ch(r#""inner_corners": [3, 3], "squares": [12, 9], "square_mm": 1.5, "marker_mm": 1, "dictionary": "DICT_5X5_100""#), "inner_corners is not a field of a ChArUco board"),
            (r#"{"type": "checkerboard", "inner_corners": [14, 0], "square_mm": 1.5}"#.into(), "a board needs at least 3 x 3 inner corners, got 14 x 0"),
            (r#"{"type": "checkerboard", "inner_corners": [14, 1000], "square_mm": 1.5}"#.into(), "at most 999 x 999 inner corners, got 14 x 1000"),
            (r#"{"type": "checkerboard", "inner_corners": [14, 12], "square_mm": -1}"#.into(), "square_mm must be a positive square size, got -1 mm"),
            (r#"{"type": "checkerboard", "inner_corners": [999, 3], "square_mm": 1e306}"#.into(), "square_mm: a board of 999 x 3 inner corners of 1e306 mm does not fit in a number"),
            (ch(r#""squares": [1000, 2], "square_mm": 1e306, "marker_mm": 1, "dictionary": "DICT_7X7_1000""#), "square_mm: the board (squares x square_mm) must be finite (square_mm 1e306, marker_mm 1)"),
            (r#"{"inner_corners": [14, 12], "square_mm": 1, "dictionary": "DICT_5X5_100"}"#.into(), "fields of a ChArUco board"),
            (r#"{"type": "circles", "inner_corners": [14, 12], "square_mm": 1}"#.into(), "type \"circles\" is not"),
            (r#"{"format": "etlcal.board/2", "type": "checkerboard", "inner_corners": [14, 12], "square_mm": 1}"#.into(), "format \"etlcal.board/2\""),
            (r#"{"type": "checkerboard", "inner_corners": [14, 12], "square_mm": 1, "colour": 1}"#.into(), "unknown field `colour`"),
        ];
        for (text, needle) in cases {
            let e = parse(&text).unwrap_err();
            assert!(e.contains(needle), "{text}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn corners_in_each_boards_frame() {
        let k = Board::checkerboard([3, 4], 2.0).unwrap();
        assert_eq!(k.corners_mm().len(), 12);
        assert_eq!(k.corner_mm(1), Some([2.0, 0.0]));
        assert_eq!(k.corner_mm(3), Some([0.0, 2.0]));
        assert_eq!(k.corner_mm(11), Some([4.0, 6.0]));
        assert_eq!(k.corner_mm(12), None);
        assert_eq!(k.pattern_mm(), [-2.0, -2.0, 6.0, 8.0]);
        // OpenCV's CharucoBoard((5, 4), 10, 6, DICT_4X4_50).getChessboardCorners():
        // (10, 10), (20, 10), (30, 10), (40, 10), (10, 20), ...
        let c = Board::charuco([5, 4], 10.0, 6.0, "DICT_4X4_50").unwrap();
        assert_eq!(c.corner_grid(), [4, 3]);
        assert_eq!(&c.corners_mm()[..5], &[[10.0, 10.0], [20.0, 10.0], [30.0, 10.0], [40.0, 10.0], [10.0, 20.0]]);
        assert_eq!(c.pattern_mm(), [0.0, 0.0, 50.0, 40.0]);
        assert_eq!(c.describe(), "ChArUco 5 x 4 squares of 10 mm (markers 6 mm, DICT_4X4_50)");
    }

    #[test]
    fn files_are_checked_both_ways_and_a_bad_board_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("board.json");
        let b = Board::charuco([12, 9], 1.5, 1.1, "DICT_5X5_100").unwrap();
        b.save(&p).unwrap();
        assert_eq!(Board::load(&p).unwrap(), b);
        let bad = Board::Checkerboard(Checkerboard { inner_corners: [2, 9], square_mm: 1.0 });
        let q = dir.path().join("bad.json");
        let e = bad.save(&q).unwrap_err();
        assert_eq!((e.input_what(), e.input_value().as_deref()), (Some("inner_corners"), Some("[2, 9]")));
        assert!(e.to_string().contains("a board needs at least 3 x 3 inner corners, got 2 x 9"), "{e}");
        assert!(!q.exists());
        std::fs::write(&q, r#"{"format": "etlcal.board/1", "type": "charuco", "squares": [12, 9], "square_mm": 1.5, "marker_mm": 2, "dictionary": "DICT_5X5_100"}"#).unwrap();
        let e = Board::load(&q).unwrap_err();
        assert_eq!(e.kind(), crate::ErrorKind::Parse);
        assert!(e.to_string().contains("marker_mm must be smaller than square_mm"), "{e}");
        // A standalone file needs its tag.
        std::fs::write(&q, r#"{"type": "checkerboard", "inner_corners": [3, 3], "square_mm": 1}"#).unwrap();
        assert_eq!(Board::load(&q).unwrap_err().kind(), crate::ErrorKind::Format);
    }
}
