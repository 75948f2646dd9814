//! `Dataset`: an `etlcal.dataset/1` file (images with what was recorded with each) and its
//! detection into `Observations`.

use std::path::{Path, PathBuf};

use etl_calib::pipeline::dataset::{default_detector, observations_from_dataset};
use etl_formats::dataset::{Board, Dataset as DatasetFile, DatasetView, OffstateImage, SettingImage, FORMAT};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple, PyType};

use crate::errors::{input_error, invalid, invalid_value, CoreResultExt};
use crate::observations::Observations;

/// The images of a calibration and what was recorded with each (the README's "File formats":
/// `etlcal.dataset/1`): the board, per view the image path (relative to the file), E_in,
/// the lens temperature and the stage position, and optionally lens-off and per-setting
/// views. `etlcal.simulate`-style rigs write one with `etlcal simulate --out DIR`.
#[pyclass(module = "etlcal")]
#[derive(Clone)]
pub struct Dataset {
    file: DatasetFile,
    /// Where it was read from (image paths resolve against it).
    path: Option<PathBuf>,
}

/// A finite number or an InputError naming it.
fn finite(v: f64, what: &str) -> PyResult<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(invalid_value(what, v, format!("{what} must be finite, got {v}")))
    }
}

/// A board argument: an `etlcal.Board` or the dict form of `Dataset.board`
/// ({"inner_corners": (cols, rows), "square_mm": mm} for a checkerboard, the fields of the
/// `etlcal.board/1` object otherwise).
fn board_of(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Board> {
    crate::board::board_arg(obj, what)
}

/// A view's lens setting (E_in, T and the optional E_com), each checked finite.
fn setting(e_in_ma: f64, temperature_c: f64, e_com_ma: Option<f64>) -> PyResult<(f64, f64, Option<f64>)> {
    let (e_in_ma, temperature_c) = (finite(e_in_ma, "e_in_ma")?, finite(temperature_c, "temperature_c")?);
    Ok((e_in_ma, temperature_c, e_com_ma.map(|e| finite(e, "e_com_ma")).transpose()?))
}

/// An image's own board (when it differs from the dataset's) and its first corner on the
/// physical board, as the file holds them.
fn own_board(
    board: Option<Bound<'_, PyAny>>,
    first_corner: Option<(usize, usize)>,
) -> PyResult<(Option<Board>, Option<[usize; 2]>)> {
    Ok((board.map(|b| board_of(&b, "board")).transpose()?, first_corner.map(|(i, j)| [i, j])))
}

#[pymethods]
impl Dataset {
    /// An empty dataset to fill with `add_view` (and `add_offstate_view`,
    /// `add_setting_view`) while capturing, then `save`.
    ///
    /// Args:
    ///     image_size: (width, height) of every image, px.
    ///     inner_corners: a checkerboard's inner corners (cols, rows), at least 3 x 3, with
    ///         square_mm (or give `board`).
    ///     square_mm: the checkerboard's square size, mm.
    ///     base_dir: where relative image paths resolve until the dataset is saved or
    ///         loaded (default: the working directory).
    ///     offstate_board: the lens-off views' board when it differs: an etlcal.Board, or a
    ///         dict {"inner_corners": (cols, rows), "square_mm": mm}.
    ///     board: the board, an etlcal.Board (e.g. `Board.charuco(...)`: its views need
    ///         no hints), instead of inner_corners and square_mm.
    ///
    /// Raises: InputError for a zero image size, a bad board, or both or neither of
    /// `board` and `inner_corners` with `square_mm`.
    #[new]
    #[pyo3(signature = (image_size, inner_corners=None, square_mm=None, base_dir=None, offstate_board=None, board=None))]
    fn new(
        image_size: (u32, u32),
        inner_corners: Option<(usize, usize)>,
        square_mm: Option<f64>,
        base_dir: Option<PathBuf>,
        offstate_board: Option<Bound<'_, PyAny>>,
        board: Option<Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        crate::errors::guarded("Dataset.__new__", || {
            if image_size.0 == 0 || image_size.1 == 0 {
                return Err(invalid_value("image_size", [image_size.0, image_size.1], "image_size must be positive"));
            }
            let board = match (board, inner_corners, square_mm) {
                (Some(b), None, None) => board_of(&b, "board")?,
                (None, Some((c, r)), Some(s)) => Board::checkerboard([c, r], s).py()?,
                _ => return Err(invalid("board", "give board=etlcal.Board(...), or inner_corners with square_mm")),
            };
            let mut file = DatasetFile::new([image_size.0, image_size.1], board);
            file.offstate_board = offstate_board.map(|b| board_of(&b, "offstate_board")).transpose()?;
            Ok(Dataset { file, path: base_dir.map(|d| d.join("dataset.json")) })
        })
    }

    /// Adds an ETL view: the image of the board on the stage and what was recorded with it.
    ///
    /// Args:
    ///     image: the image file, relative to the dataset file (or absolute).
    ///     e_in_ma: the commanded lens current, mA.
    ///     temperature_c: the lens temperature, degC.
    ///     z_w_mm: the stage position Z_W, mm.
    ///     e_com_ma: the compensated current, mA (None: computed from the thermal
    ///         calibration when the observations are made).
    ///     board: this image's board when it differs: an etlcal.Board, or for a part of a
    ///         physical checkerboard (e.g. when the rest is out of view) a dict
    ///         {"inner_corners": (cols, rows), "square_mm": mm}; a ChArUco board needs no part.
    ///     first_corner: (i, j), the index on the physical checkerboard of this image's
    ///         corner (0, 0) (default (0, 0)); refused with a ChArUco board when saved or
    ///         detected.
    ///
    /// Raises: InputError for a non-finite number or a bad board.
    #[pyo3(signature = (image, e_in_ma, temperature_c, z_w_mm, e_com_ma=None, board=None, first_corner=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_view(
        &mut self,
        image: PathBuf,
        e_in_ma: f64,
        temperature_c: f64,
        z_w_mm: f64,
        e_com_ma: Option<f64>,
        board: Option<Bound<'_, PyAny>>,
        first_corner: Option<(usize, usize)>,
    ) -> PyResult<()> {
        let (e_in_ma, temperature_c, e_com_ma) = setting(e_in_ma, temperature_c, e_com_ma)?;
        let z_w_mm = finite(z_w_mm, "z_w_mm")?;
        let (board, first_corner) = own_board(board, first_corner)?;
        let view =
            DatasetView { image, e_in_ma, focal_power_dpt: None, temperature_c, e_com_ma, z_w_mm, board, first_corner };
        self.file.views.push(view);
        Ok(())
    }

    /// Adds a lens-off view (E = 0; the views that give A0 by Zhang's method).
    ///
    /// Args:
    ///     image: the image file, relative to the dataset file (or absolute).
    ///     board: this image's board when it differs: an etlcal.Board, or for a part of a
    ///         physical checkerboard (e.g. when the rest is out of view) a dict
    ///         {"inner_corners": (cols, rows), "square_mm": mm}; a ChArUco board needs no part.
    ///     first_corner: (i, j), the index on the physical checkerboard of this image's
    ///         corner (0, 0) (default (0, 0)); refused with a ChArUco board when saved or
    ///         detected.
    ///
    /// Raises: InputError for a bad board.
    #[pyo3(signature = (image, board=None, first_corner=None))]
    fn add_offstate_view(
        &mut self,
        image: PathBuf,
        board: Option<Bound<'_, PyAny>>,
        first_corner: Option<(usize, usize)>,
    ) -> PyResult<()> {
        let (board, first_corner) = own_board(board, first_corner)?;
        self.file.offstate_views.push(OffstateImage { image, board, first_corner });
        Ok(())
    }

    /// Adds a view for the per-setting baseline (the board in a free pose at a current).
    ///
    /// Args:
    ///     image: the image file, relative to the dataset file (or absolute).
    ///     e_in_ma: the commanded lens current, mA.
    ///     temperature_c: the lens temperature, degC.
    ///     e_com_ma: the compensated current, mA (optional).
    ///     board: this image's board when it differs: an etlcal.Board, or for a part of a
    ///         physical checkerboard (e.g. when the rest is out of view) a dict
    ///         {"inner_corners": (cols, rows), "square_mm": mm}; a ChArUco board needs no part.
    ///     first_corner: (i, j), the index on the physical checkerboard of this image's
    ///         corner (0, 0) (default (0, 0)); refused with a ChArUco board when saved or
    ///         detected.
    ///
    /// Raises: InputError for a non-finite number or a bad board.
    #[pyo3(signature = (image, e_in_ma, temperature_c, e_com_ma=None, board=None, first_corner=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_setting_view(
        &mut self,
        image: PathBuf,
        e_in_ma: f64,
        temperature_c: f64,
        e_com_ma: Option<f64>,
        board: Option<Bound<'_, PyAny>>,
        first_corner: Option<(usize, usize)>,
    ) -> PyResult<()> {
        let (e_in_ma, temperature_c, e_com_ma) = setting(e_in_ma, temperature_c, e_com_ma)?;
        let (board, first_corner) = own_board(board, first_corner)?;
        self.file.setting_views.push(SettingImage {
            image,
            e_in_ma,
            focal_power_dpt: None,
            temperature_c,
            e_com_ma,
            board,
            first_corner,
        });
        Ok(())
    }

    /// Number of lens-off views.
    #[getter]
    fn offstate_count(&self) -> usize {
        self.file.offstate_views.len()
    }

    /// Number of per-setting baseline views.
    #[getter]
    fn setting_count(&self) -> usize {
        self.file.setting_views.len()
    }

    /// Reads an `etlcal.dataset/1` file.
    ///
    /// Args:
    ///     path: the file (str or os.PathLike).
    #[classmethod]
    fn load(_cls: &Bound<'_, PyType>, path: PathBuf) -> PyResult<Self> {
        Ok(Dataset { file: DatasetFile::load(&path).py()?, path: Some(path) })
    }

    /// Writes the file (atomically); image paths stay as they are (relative to the file).
    ///
    /// Raises: InputError for a dataset that would not load (no views); FileError.
    fn save(&mut self, path: PathBuf) -> PyResult<()> {
        self.file.validate().py()?;
        self.file.save(&path).py()?;
        self.path = Some(path);
        Ok(())
    }

    /// The `etlcal.dataset/1` JSON text.
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.file).map_err(|e| input_error(e.to_string()))
    }

    /// Parses `etlcal.dataset/1` JSON text; image paths then resolve against `base_dir`
    /// (default: the working directory).
    #[staticmethod]
    #[pyo3(signature = (text, base_dir=None))]
    fn from_json(text: &str, base_dir: Option<PathBuf>) -> PyResult<Self> {
        let p = Path::new("<json>");
        let f: DatasetFile = etl_formats::parse_json(text, p, FORMAT).py()?;
        f.validate().py()?;
        Ok(Dataset { file: f, path: base_dir.map(|d| d.join("dataset.json")) })
    }

    /// Number of ETL views.
    fn __len__(&self) -> PyResult<usize> {
        crate::errors::guarded_value("Dataset.__len__", || self.file.views.len())
    }

    /// (width, height), px.
    #[getter]
    fn image_size(&self) -> (u32, u32) {
        (self.file.image_size[0], self.file.image_size[1])
    }

    /// The board as a dict: {"inner_corners": (cols, rows), "square_mm"} for a
    /// checkerboard; {"type": "charuco", "squares": (cols, rows), "marker_mm",
    /// "dictionary", "square_mm"} for a ChArUco board (`etlcal.Board.from_dict` makes it
    /// a Board).
    #[getter]
    fn board<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        match &self.file.board {
            Board::Checkerboard(c) => {
                d.set_item("inner_corners", (c.inner_corners[0], c.inner_corners[1]))?;
            }
            Board::Charuco(b) => {
                d.set_item("type", "charuco")?;
                d.set_item("squares", (b.squares()[0], b.squares()[1]))?;
                d.set_item("marker_mm", b.marker_mm())?;
                d.set_item("dictionary", b.dictionary().name())?;
            }
        }
        d.set_item("square_mm", self.file.board.square_mm())?;
        Ok(d)
    }

    /// The image paths of the ETL views, resolved against the file's directory.
    fn images(&self) -> Vec<PathBuf> {
        let base = self.path.clone().unwrap_or_else(|| PathBuf::from("dataset.json"));
        self.file.views.iter().map(|v| DatasetFile::resolve(&base, &v.image)).collect()
    }

    /// Detects the board in every image (in parallel, without the GIL) and returns the
    /// observations and a DetectionSummary (attributes, also dict keys: "images", "detected", "views_detected", "skipped":
    /// list of (image, kind, reason)). Views whose board is not found are skipped.
    ///
    /// Raises: FileError for a missing or unreadable image (before any detection);
    /// BoardNotFoundError when the views left span fewer than 3 currents.
    fn detect<'py>(&self, py: Python<'py>) -> PyResult<(Observations, Bound<'py, PyAny>)> {
        let base = self.path.clone().unwrap_or_else(|| PathBuf::from("dataset.json"));
        let file = self.file.clone();
        let (obs, summary) = crate::pool::detach(py, || {
            observations_from_dataset(&file, &base, &default_detector(), &etl_core::progress::NoProgress)
        })
        .py()?;
        let d = PyDict::new(py);
        d.set_item("images", summary.images)?;
        d.set_item("detected", summary.detected)?;
        d.set_item("views_detected", summary.views_detected)?;
        let skipped: Vec<(String, &str, String)> =
            summary.skipped.iter().map(|s| (s.image.display().to_string(), s.kind, s.reason.clone())).collect();
        d.set_item("skipped", skipped)?;
        Ok((Observations { file: obs }, crate::results::make(py, "DetectionSummary", &d)?))
    }

    fn __repr__(&self) -> PyResult<String> {
        crate::errors::guarded_value("Dataset.__repr__", || {
            format!(
                "Dataset(image_size={:?}, views={}, offstate_views={}, board={})",
                self.file.image_size,
                self.file.views.len(),
                self.file.offstate_views.len(),
                self.file.board.describe()
            )
        })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        crate::errors::guarded("Dataset.__reduce__", || {
            let py = slf.py();
            let me = slf.borrow();
            let text = me.to_json()?;
            let base = me.path.as_ref().and_then(|p| p.parent()).map(|d| d.display().to_string());
            let ctor = py.get_type::<Dataset>().getattr("from_json")?;
            Ok((ctor, PyTuple::new(py, [text.into_pyobject(py)?.into_any(), base.into_pyobject(py)?.into_any()])?))
        })
    }
}
