//! `Board`: a calibration target, an `etlcal.board/1` file (README, "File formats"): a
//! ChArUco board in OpenCV's layout and ids, or a checkerboard; its print-ready SVG and
//! raster ([`etl_sim::print`]).

use std::path::PathBuf;

use etl_formats::board::{Board as BoardFile, FORMAT};
use numpy::ndarray::Array2;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::errors::{input_error, CoreResultExt};

/// A calibration target: a ChArUco board (markers in the white squares tell every corner's
/// id, so views that see part of the board need no hint) or a plain checkerboard.
///
/// Make one with `Board.charuco(...)`, `Board.checkerboard(...)`, `Board.load(path)` or
/// `Board.from_dict(d)`. Corner ids run row by row over the corner grid (OpenCV's ChArUco
/// ids; a checkerboard's row-major index); `corners_mm` are their board coordinates (a
/// ChArUco board: OpenCV's frame, origin at the top-left outer corner; a checkerboard: its
/// first inner corner at the origin).
#[pyclass(module = "etlcal", frozen)]
#[derive(Clone)]
pub struct Board {
    /// The board.
    pub inner: BoardFile,
}

/// The board of a Python argument: an `etlcal.Board`, or a dict of the board's JSON object
/// (`{"type": "charuco", "squares": ..., ...}`, or `{"inner_corners": (cols, rows),
/// "square_mm": mm}` for a checkerboard). `what` names the argument in errors.
pub fn board_arg(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<BoardFile> {
    if let Ok(b) = obj.cast::<Board>() {
        return Ok(b.get().inner);
    }
    let Ok(d) = obj.cast::<PyDict>() else {
        return Err(input_error(format!("{what} must be an etlcal.Board or a dict of its fields")));
    };
    let text: String = obj.py().import("json")?.call_method1("dumps", (d,))?.extract()?;
    serde_json::from_str::<BoardFile>(&text).map_err(|e| {
        // serde's place in a one-line text of our making says nothing: the message alone.
        let message = e.to_string();
        let message = message.split(" at line ").next().unwrap_or(&message).to_owned();
        input_error(format!("{what}: {message}"))
    })
}

#[pymethods]
impl Board {
    /// A ChArUco board in OpenCV's layout (as `cv2.aruco.CharucoBoard(squares,
    /// square_mm, marker_mm, dictionary)`): the top-left square black, markers in the white
    /// squares row by row.
    ///
    /// Args:
    ///     squares: (cols, rows) squares.
    ///     square_mm: side of a square, mm.
    ///     marker_mm: side of a marker (its black border included), mm; smaller than
    ///         square_mm.
    ///     dictionary: one of OpenCV's predefined dictionaries by name, e.g. "DICT_5X5_100",
    ///         "DICT_APRILTAG_36h11".
    ///
    /// Raises: InputError naming the field (unknown dictionary, marker not smaller than the
    /// square, more white squares than the dictionary has markers, sizes not positive).
    #[staticmethod]
    fn charuco(squares: (u32, u32), square_mm: f64, marker_mm: f64, dictionary: &str) -> PyResult<Self> {
        Ok(Board { inner: BoardFile::charuco([squares.0, squares.1], square_mm, marker_mm, dictionary).py()? })
    }

    /// A plain checkerboard of (cols, rows) inner corners (at least 3 x 3) and `square_mm`.
    ///
    /// Raises: InputError naming the field.
    #[staticmethod]
    fn checkerboard(inner_corners: (usize, usize), square_mm: f64) -> PyResult<Self> {
        Ok(Board { inner: BoardFile::checkerboard([inner_corners.0, inner_corners.1], square_mm).py()? })
    }

    /// Reads an `etlcal.board/1` file.
    ///
    /// Raises: FileError; InputError for a malformed or invalid board (naming the field).
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Self> {
        Ok(Board { inner: BoardFile::load(&path).py()? })
    }

    /// Writes the `etlcal.board/1` file (atomically).
    fn save(&self, path: PathBuf) -> PyResult<()> {
        self.inner.save(&path).py()
    }

    /// The board from a dict of its JSON object (as `Dataset.board` gives it, or a parsed
    /// board file).
    #[staticmethod]
    fn from_dict(d: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(Board { inner: board_arg(d, "board")? })
    }

    /// The `etlcal.board/1` JSON text.
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.inner).map_err(|e| input_error(e.to_string()))
    }

    /// Parses `etlcal.board/1` JSON text.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        let b: BoardFile = etl_formats::parse_json(text, std::path::Path::new("<json>"), FORMAT).py()?;
        b.validate().py()?;
        Ok(Board { inner: b })
    }

    /// The print-ready SVG document: `width`/`height` in mm and a viewBox in mm (it prints
    /// at true size at 100 % scale), a white margin of `margin_mm` around the pattern
    /// (default: one square).
    #[pyo3(signature = (margin_mm=None))]
    fn to_svg(&self, margin_mm: Option<f64>) -> PyResult<String> {
        etl_sim::print::svg(&self.inner, margin_mm.unwrap_or(self.inner.square_mm())).py()
    }

    /// The board rasterised at `dpi` (uint8 (height, width), 0 black, 255 white, every
    /// pixel the exact area mean of the board over it), with a white margin of `margin_mm`
    /// (default: one square).
    #[pyo3(signature = (dpi, margin_mm=None))]
    fn to_image<'py>(&self, py: Python<'py>, dpi: f64, margin_mm: Option<f64>) -> PyResult<Bound<'py, PyAny>> {
        let margin = margin_mm.unwrap_or(self.inner.square_mm());
        let board = self.inner;
        let img = crate::pool::detach(py, || etl_sim::print::raster(&board, dpi, margin)).py()?;
        let bytes: Vec<u8> = img.data.iter().map(|&v| v.min(255) as u8).collect();
        let a = Array2::from_shape_vec((img.height as usize, img.width as usize), bytes)
            .map_err(|e| input_error(e.to_string()))?;
        Ok(a.into_pyarray(py).into_any())
    }

    /// "charuco" or "checkerboard".
    #[getter(r#type)]
    fn type_name(&self) -> &'static str {
        self.inner.type_name()
    }

    /// (cols, rows) squares of a ChArUco board; None for a checkerboard.
    #[getter]
    fn squares(&self) -> Option<(u32, u32)> {
        self.inner.as_charuco().map(|b| (b.squares()[0], b.squares()[1]))
    }

    /// Side of a square, mm.
    #[getter]
    fn square_mm(&self) -> f64 {
        self.inner.square_mm()
    }

    /// Side of a marker, mm (None for a checkerboard).
    #[getter]
    fn marker_mm(&self) -> Option<f64> {
        self.inner.as_charuco().map(|b| b.marker_mm())
    }

    /// The dictionary's name (None for a checkerboard).
    #[getter]
    fn dictionary(&self) -> Option<&'static str> {
        self.inner.as_charuco().map(|b| b.dictionary().name())
    }

    /// (cols, rows) of the corner grid: a checkerboard's inner corners, a ChArUco board's
    /// squares less one each way.
    #[getter]
    fn inner_corners(&self) -> (usize, usize) {
        let [c, r] = self.inner.corner_grid();
        (c, r)
    }

    /// Number of corners (ids 0 .. corner_count - 1).
    #[getter]
    fn corner_count(&self) -> usize {
        self.inner.corner_count()
    }

    /// (corner_count, 2) board coordinates of the corners in id order, mm.
    #[getter]
    fn corners_mm<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        crate::arrays::points_out(py, self.inner.corners_mm(), false)
    }

    /// The fields as the JSON object has them (a dict: "format", "type", then the board's
    /// own fields).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        py.import("json")?.call_method1("loads", (self.to_json()?,))
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> PyResult<bool> {
        crate::errors::guarded_value("Board.__eq__", || {
            other.cast::<Board>().is_ok_and(|o| o.get().inner == self.inner)
        })
    }

    fn __hash__(&self) -> PyResult<u64> {
        crate::errors::guarded("Board.__hash__", || {
            use std::hash::{Hash, Hasher};
            let mut h = std::collections::hash_map::DefaultHasher::new();
            self.to_json()?.hash(&mut h);
            Ok(h.finish())
        })
    }

    fn __repr__(&self) -> PyResult<String> {
        crate::errors::guarded_value("Board.__repr__", || format!("Board({})", self.inner.describe()))
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        crate::errors::guarded("Board.__reduce__", || {
            let py = slf.py();
            let ctor = py.get_type::<Board>().getattr("from_json")?;
            Ok((ctor, PyTuple::new(py, [slf.get().to_json()?])?))
        })
    }
}
