//! `etlcal.dataset/1`: the images of a calibration and what was recorded with each
//! (docs/FORMATS.md): the observations' shape with an image per view instead of points.
//!
//! ```json
//! {"format": "etlcal.dataset/1", "image_size": [1936, 1458],
//!  "board": {"inner_corners": [14, 12], "square_mm": 1.5},
//!  "views": [{"image": "views/view00.png", "e_in_ma": 80.0, "temperature_c": 27.0,
//!             "z_w_mm": 75.0}],
//!  "offstate_board": {"inner_corners": [11, 8], "square_mm": 4.0},
//!  "offstate_views": [{"image": "offstate/off00.png"}],
//!  "setting_views": [{"image": "settings/s150_00.png", "e_in_ma": 150.0, "temperature_c": 27.0}]}
//! ```
//!
//! Image paths are relative to the dataset file (absolute paths are taken as they are).
//! Corner (X, Y) of the board frame is at world (X, Y, z_w_mm) in an ETL view (the stage
//! moves the board along Z_W); a checkerboard's inner corner (i, j), i along the `cols`
//! direction, is at (i * square_mm, j * square_mm).
//! `e_com_ma` is optional as in the observations. `offstate_board` defaults to `board`.
//! A view taken in the lens driver's focal-power mode gives `"focal_power_dpt"` instead of
//! `e_in_ma`, as in the observations ([`crate::lens_setting`]).
//! `setting_views` are the per-setting baseline's views (several per current, board in a
//! free pose each).
//!
//! A board is an `etlcal.board/1` object inline ([`crate::board`]; `"format"` may be left
//! out there): a ChArUco board, whose corners are known by their ids wherever they are
//! seen, or a checkerboard (`{"inner_corners", "square_mm"}` without `"type"`, as written
//! before the board format, still reads as one). A view's world points are its detected
//! corners' board coordinates ([`Board::corner_mm`]) at Z = `z_w_mm`.
//!
//! Extension (optional, per view of any kind): `"board"` overrides the dataset's board for
//! that image. For a checkerboard, `"first_corner": [i0, j0]` says which inner corner of
//! the physical board the image's corner (0, 0) is; corner (i, j) of the image then sits at
//! ((i0 + i) square_mm, (j0 + j) square_mm). This is how views that see only part of a
//! large checkerboard are recorded: the detector is asked for the part that is fully
//! visible (a checkerboard found only in part is otherwise an error). A ChArUco view needs
//! neither: the detector reads which corners it sees from the markers (`first_corner` is
//! refused with a ChArUco board).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{read_json, write_json};
pub use crate::board::{Board, Checkerboard};
use crate::lens_setting::{self, SettingKind};
use crate::{Error, Result};

/// The format tag.
pub const FORMAT: &str = "etlcal.dataset/1";

/// An image of a dataset with the board it shows ([`Dataset::images_with_boards`]).
struct ImageBoard<'a> {
    kind: &'static str,
    key: String,
    image: &'a Path,
    board: Board,
    /// Where the board is given: `"views[3].board"`, `"board"`, `"offstate_board"`.
    from: String,
    first_corner: Option<[usize; 2]>,
}

/// Declares an image entry of the dataset: the image first, then (with `setting`) the lens
/// setting it was taken at, then the entry's own fields, then the two every kind of image
/// may carry (`board`, `first_corner`; module docs). A macro rather than a flattened
/// common struct: serde cannot refuse unknown fields (`deny_unknown_fields`) through
/// `#[serde(flatten)]`.
macro_rules! image_entry {
    ($(#[$doc:meta])* $name:ident, setting, { $($own:tt)* }) => {
        image_entry! {
            $(#[$doc])*
            $name {
                /// Commanded lens current, mA (absent, NaN here, in a focal-power view).
                #[serde(default = "lens_setting::absent", skip_serializing_if = "lens_setting::is_absent")]
                e_in_ma: f64,
                /// Commanded focal power, dpt (a focal-power view, instead of `e_in_ma`;
                /// [`crate::lens_setting`]).
                #[serde(default, skip_serializing_if = "Option::is_none")]
                focal_power_dpt: Option<f64>,
                /// Lens temperature, degC.
                temperature_c: f64,
                /// Compensated current, mA (optional; used as is when present).
                #[serde(default, skip_serializing_if = "Option::is_none")]
                e_com_ma: Option<f64>,
                $($own)*
            }
        }
    };
    ($(#[$doc:meta])* $name:ident { $($(#[$field_attr:meta])* $field:ident: $ty:ty,)* }) => {
        $(#[$doc])*
        #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
        #[serde(deny_unknown_fields)]
        pub struct $name {
            /// The image, relative to the dataset file.
            pub image: PathBuf,
            $($(#[$field_attr])* pub $field: $ty,)*
            /// Board of this image when it differs from the dataset's (see the module docs).
            #[serde(default, skip_serializing_if = "Option::is_none")]
            pub board: Option<Board>,
            /// Index on the physical board of this image's corner (0, 0) (default [0, 0]).
            #[serde(default, skip_serializing_if = "Option::is_none")]
            pub first_corner: Option<[usize; 2]>,
        }
    };
}

image_entry! {
    /// One ETL view: an image of the board on the stage.
    DatasetView, setting, {
        /// The stage position, mm.
        z_w_mm: f64,
    }
}

image_entry! {
    /// A lens-off view (E = 0) of the lens-off board.
    OffstateImage {}
}

image_entry! {
    /// A view for the per-setting baseline: the board in a free pose at a current.
    SettingImage, setting, {}
}

/// The whole file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Dataset {
    /// `"etlcal.dataset/1"`.
    pub format: String,
    /// Image width and height, px (every image must have it).
    pub image_size: [u32; 2],
    /// The board of the ETL views (and of the setting views).
    pub board: Board,
    /// The ETL views.
    #[serde(default)]
    pub views: Vec<DatasetView>,
    /// The board of the lens-off views (default: `board`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub offstate_board: Option<Board>,
    /// Lens-off views (optional).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub offstate_views: Vec<OffstateImage>,
    /// Per-setting baseline views (optional).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub setting_views: Vec<SettingImage>,
}

impl Dataset {
    /// An empty dataset.
    pub fn new(image_size: [u32; 2], board: Board) -> Self {
        Dataset {
            format: FORMAT.into(),
            image_size,
            board,
            views: vec![],
            offstate_board: None,
            offstate_views: vec![],
            setting_views: vec![],
        }
    }

    /// Reads and checks a file (boards, finite numbers, at least one view).
    pub fn load(path: &Path) -> Result<Self> {
        let d: Dataset = read_json(path, FORMAT)?;
        d.validate().map_err(|e| Error::Parse { path: path.to_owned(), message: e.to_string() })?;
        Ok(d)
    }

    /// Checks and writes the file atomically.
    pub fn save(&self, path: &Path) -> Result<()> {
        self.validate().map_err(|e| e.within(path.display(), None))?;
        write_json(path, self)
    }

    /// The one kind of setting of the ETL and setting views, each view's setting checked
    /// ([`lens_setting::view_setting_kind`]); an error naming the first view that differs.
    pub fn setting_kind(&self) -> Result<SettingKind> {
        let views = self.views.iter().map(|v| (v.e_in_ma, v.focal_power_dpt, v.e_com_ma));
        let settings = self.setting_views.iter().map(|v| (v.e_in_ma, v.focal_power_dpt, v.e_com_ma));
        let all = (views.enumerate().map(|(i, s)| ("views", "view", i, s)))
            .chain(settings.enumerate().map(|(i, s)| ("setting_views", "setting view", i, s)));
        let mut kinds = vec![];
        for (key, name, i, (e_in, p, e_com)) in all {
            let kind =
                lens_setting::view_setting_kind(e_in, p, e_com, |f| format!("{key}[{i}].{f}"), &format!("{name} {i}"))?;
            kinds.push((kind, format!("{key}[{i}]")));
        }
        Ok(lens_setting::common_kind(kinds)?.unwrap_or_default())
    }

    /// The lens-off board.
    pub fn offstate_board(&self) -> Board {
        self.offstate_board.unwrap_or(self.board)
    }

    /// Every image with its kind (`"view"`, `"offstate view"`, `"setting view"`), its key
    /// path (`"views[3]"`), the board it shows, where that board is given (its own
    /// `board`, or the dataset's `board` or `offstate_board`) and its `first_corner`, in
    /// the file's order.
    fn images_with_boards(&self) -> impl Iterator<Item = ImageBoard<'_>> + '_ {
        let own_or = |own: Option<Board>, key: &str, default: Board, default_key: &'static str| match own {
            Some(b) => (b, format!("{key}.board")),
            None => (default, default_key.to_owned()),
        };
        let off_key = if self.offstate_board.is_some() { "offstate_board" } else { "board (no offstate_board)" };
        let views = self.views.iter().enumerate().map(move |(i, v)| {
            let key = format!("views[{i}]");
            let (board, from) = own_or(v.board, &key, self.board, "board");
            ImageBoard { kind: "view", key, image: &v.image, board, from, first_corner: v.first_corner }
        });
        let off = self.offstate_views.iter().enumerate().map(move |(i, v)| {
            let key = format!("offstate_views[{i}]");
            let (board, from) = own_or(v.board, &key, self.offstate_board(), off_key);
            ImageBoard { kind: "offstate view", key, image: &v.image, board, from, first_corner: v.first_corner }
        });
        let settings = self.setting_views.iter().enumerate().map(move |(i, v)| {
            let key = format!("setting_views[{i}]");
            let (board, from) = own_or(v.board, &key, self.board, "board");
            ImageBoard { kind: "setting view", key, image: &v.image, board, from, first_corner: v.first_corner }
        });
        views.chain(off).chain(settings)
    }

    /// Checks boards, numbers and that there is something to calibrate.
    pub fn validate(&self) -> Result<()> {
        self.board.validate().map_err(|e| e.under("board"))?;
        if let Some(b) = self.offstate_board {
            b.validate().map_err(|e| e.within("offstate_board", Some("offstate_board")))?;
        }
        if self.image_size[0] == 0 || self.image_size[1] == 0 {
            return Err(Error::invalid_value("image_size", self.image_size, "image_size must be positive"));
        }
        if self.views.is_empty() && self.setting_views.is_empty() {
            return Err(Error::invalid("views", "the dataset holds no views"));
        }
        self.setting_kind()?;
        for (i, v) in self.views.iter().enumerate() {
            let e_in = (v.focal_power_dpt.is_none()).then_some(v.e_in_ma);
            let numbers = [("e_in_ma", e_in), ("temperature_c", Some(v.temperature_c))]
                .into_iter()
                .chain([("z_w_mm", Some(v.z_w_mm)), ("e_com_ma", v.e_com_ma)]);
            if let Some((key, x)) = crate::first_not_finite(numbers) {
                let message = format!("view {i}: current, temperature or z_w_mm is not finite");
                return Err(Error::invalid_value(format!("views[{i}].{key}"), x, message));
            }
        }
        for (i, v) in self.setting_views.iter().enumerate() {
            let e_in = (v.focal_power_dpt.is_none()).then_some(v.e_in_ma);
            let numbers = [("e_in_ma", e_in), ("temperature_c", Some(v.temperature_c)), ("e_com_ma", v.e_com_ma)];
            if let Some((key, x)) = crate::first_not_finite(numbers) {
                let message = format!("setting view {i}: current or temperature is not finite");
                return Err(Error::invalid_value(format!("setting_views[{i}].{key}"), x, message));
            }
        }
        let views = self.views.iter().map(|v| (&v.image, v.board)).enumerate().map(|(i, v)| ("view", "views", i, v));
        let offstate = self.offstate_views.iter().map(|v| (&v.image, v.board)).enumerate();
        let setting = self.setting_views.iter().map(|v| (&v.image, v.board)).enumerate();
        let overrides = views
            .chain(offstate.map(|(i, v)| ("offstate view", "offstate_views", i, v)))
            .chain(setting.map(|(i, v)| ("setting view", "setting_views", i, v)));
        for (kind, key, i, (image, board)) in overrides {
            if let Some(b) = board {
                let context = format!("{kind} {}: board", image.display());
                b.validate().map_err(|e| e.within(context, Some(&format!("{key}[{i}].board"))))?;
            }
        }
        for v in self.images_with_boards() {
            if let (Board::Charuco(_), Some([i, j])) = (v.board, v.first_corner) {
                let message = format!(
                    "{} {}: first_corner [{i}, {j}] applies to checkerboards only, and its board ({}) is \
                     ChArUco (its corners are known by their ids)",
                    v.kind,
                    v.image.display(),
                    v.from
                );
                return Err(Error::invalid_value(format!("{}.first_corner", v.key), [i, j], message));
            }
        }
        Ok(())
    }

    /// The board and first corner of the ETL view `i` (its own, or the dataset's board and
    /// [0, 0]).
    pub fn view_board(&self, i: usize) -> Option<(Board, [usize; 2])> {
        let v = self.views.get(i)?;
        Some((v.board.unwrap_or(self.board), v.first_corner.unwrap_or([0, 0])))
    }

    /// `image` resolved against the directory of the dataset file `dataset_path`.
    pub fn resolve(dataset_path: &Path, image: &Path) -> PathBuf {
        if image.is_absolute() {
            return image.to_owned();
        }
        match dataset_path.parent() {
            Some(d) => d.join(image),
            None => image.to_owned(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corners_are_row_by_row() {
        let b = Checkerboard { inner_corners: [3, 4], square_mm: 2.0 };
        let c = b.corners_mm();
        assert_eq!(c.len(), 12);
        assert_eq!(c[1], [2.0, 0.0]);
        assert_eq!(c[3], [0.0, 2.0]);
        assert_eq!(c[11], [4.0, 6.0]);
    }

    fn dataset(text: &str) -> Result<Dataset> {
        let d: Dataset = crate::parse_json(text, Path::new("d.json"), FORMAT)?;
        d.validate()?;
        Ok(d)
    }

    const VIEW: &str = r#"{"image": "v.png", "e_in_ma": 100, "temperature_c": 30, "z_w_mm": 5"#;

    #[test]
    fn bad_boards_are_named() {
        let e = Board::Checkerboard(Checkerboard { inner_corners: [3, 4], square_mm: -1.5 });
        let e = e.validate().unwrap_err().to_string();
        assert!(e.contains("square_mm must be a positive square size, got -1.5 mm"), "{e}");
        let e = Board::Checkerboard(Checkerboard { inner_corners: [2, 4], square_mm: 1.5 });
        assert!(e.validate().unwrap_err().to_string().contains("3 x 3"));
        // Inline, a bad board of a dataset is named with the place in the file.
        let text = format!(
            r#"{{"format": "etlcal.dataset/1", "image_size": [10, 10], "board": {{"type": "charuco",
            "squares": [12, 9], "square_mm": 1.5, "marker_mm": 1.1, "dictionary": "DICT_9X9"}}, "views": [{VIEW}}}]}}"#
        );
        let e = dataset(&text).unwrap_err().to_string();
        assert!(e.contains("dictionary \"DICT_9X9\" is not") && e.contains("line 2"), "{e}");
    }

    /// Old datasets (checkerboard objects without a type, first_corner hints) read as
    /// before; a ChArUco board stands inline anywhere a board does; a hint with a ChArUco
    /// board is refused.
    #[test]
    fn boards_inline_old_and_new() {
        let old = format!(
            r#"{{"format": "etlcal.dataset/1", "image_size": [10, 10], "board": {{"inner_corners": [14, 12], "square_mm": 1.5}},
            "views": [{VIEW}, "board": {{"inner_corners": [4, 3], "square_mm": 1.5}}, "first_corner": [2, 3]}}],
            "offstate_board": {{"inner_corners": [11, 8], "square_mm": 4}}, "offstate_views": [{{"image": "o.png"}}]}}"#
        );
        let d = dataset(&old).unwrap();
        assert_eq!(d.board, Board::checkerboard([14, 12], 1.5).unwrap());
        assert_eq!(d.view_board(0), Some((Board::checkerboard([4, 3], 1.5).unwrap(), [2, 3])));
        assert_eq!(d.offstate_board(), Board::checkerboard([11, 8], 4.0).unwrap());
        let charuco = r#"{"format": "etlcal.board/1", "type": "charuco", "squares": [15, 13], "square_mm": 1.5, "marker_mm": 1.1, "dictionary": "DICT_5X5_100"}"#;
        let new = format!(
            r#"{{"format": "etlcal.dataset/1", "image_size": [10, 10], "board": {charuco},
            "views": [{VIEW}}}], "offstate_board": {charuco}, "offstate_views": [{{"image": "o.png", "board": {charuco}}}]}}"#
        );
        let d = dataset(&new).unwrap();
        assert_eq!(d.board.as_charuco().map(|b| b.squares()), Some([15, 13]));
        // Written and read back the same.
        let back = dataset(&serde_json::to_string(&d).unwrap()).unwrap();
        assert_eq!(back, d);
        let hinted = new.replace(r#""z_w_mm": 5}"#, r#""z_w_mm": 5, "first_corner": [1, 1]}"#);
        let e = dataset(&hinted).unwrap_err().to_string();
        assert!(
            e.contains("view v.png: first_corner [1, 1] applies to checkerboards only, and its board (board)"),
            "{e}"
        );
    }

    #[test]
    fn relative_images_resolve_against_the_file() {
        assert_eq!(Dataset::resolve(Path::new("/a/b/d.json"), Path::new("v/x.png")), PathBuf::from("/a/b/v/x.png"));
        assert_eq!(Dataset::resolve(Path::new("/a/b/d.json"), Path::new("/x.png")), PathBuf::from("/x.png"));
    }
}
