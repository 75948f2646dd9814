//! `Dataset`: an `etlcal.dataset/1` file (images with what was recorded with each) and its
//! detection into `Observations`.

use std::path::{Path, PathBuf};

use etl_calib::formats::dataset::{Dataset as DatasetFile, FORMAT};
use etl_calib::pipeline::dataset::{default_detector, observations_from_dataset};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple, PyType};

use crate::errors::{input_error, CoreResultExt};
use crate::observations::Observations;

/// The images of a calibration and what was recorded with each (DESIGN.md's
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

#[pymethods]
impl Dataset {
    /// Reads an `etlcal.dataset/1` file.
    ///
    /// Args:
    ///     path: the file (str or os.PathLike).
    #[classmethod]
    fn load(_cls: &Bound<'_, PyType>, path: PathBuf) -> PyResult<Self> {
        Ok(Dataset { file: DatasetFile::load(&path).py()?, path: Some(path) })
    }

    /// Writes the file (atomically); image paths stay as they are (relative to the file).
    fn save(&mut self, path: PathBuf) -> PyResult<()> {
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
        let f: DatasetFile = etl_calib::formats::parse_json(text, p, FORMAT).py()?;
        f.validate().py()?;
        Ok(Dataset { file: f, path: base_dir.map(|d| d.join("dataset.json")) })
    }

    /// Number of ETL views.
    fn __len__(&self) -> usize {
        self.file.views.len()
    }

    /// (width, height), px.
    #[getter]
    fn image_size(&self) -> (u32, u32) {
        (self.file.image_size[0], self.file.image_size[1])
    }

    /// The board: dict with "inner_corners" (cols, rows) and "square_mm".
    #[getter]
    fn board<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("inner_corners", (self.file.board.inner_corners[0], self.file.board.inner_corners[1]))?;
        d.set_item("square_mm", self.file.board.square_mm)?;
        Ok(d)
    }

    /// The image paths of the ETL views, resolved against the file's directory.
    fn images(&self) -> Vec<PathBuf> {
        let base = self.path.clone().unwrap_or_else(|| PathBuf::from("dataset.json"));
        self.file.views.iter().map(|v| DatasetFile::resolve(&base, &v.image)).collect()
    }

    /// Detects the board in every image (in parallel, without the GIL) and returns the
    /// observations and a summary dict ("images", "detected", "views_detected", "skipped":
    /// list of (image, kind, reason)). Views whose board is not found are skipped.
    ///
    /// Raises: FileError for a missing or unreadable image (before any detection);
    /// BoardNotFoundError when the views left span fewer than 3 currents.
    fn detect<'py>(&self, py: Python<'py>) -> PyResult<(Observations, Bound<'py, PyDict>)> {
        let base = self.path.clone().unwrap_or_else(|| PathBuf::from("dataset.json"));
        let file = self.file.clone();
        let (obs, summary) = py.detach(|| observations_from_dataset(&file, &base, &default_detector(), false)).py()?;
        let d = PyDict::new(py);
        d.set_item("images", summary.images)?;
        d.set_item("detected", summary.detected)?;
        d.set_item("views_detected", summary.views_detected)?;
        let skipped: Vec<(String, &str, String)> =
            summary.skipped.iter().map(|s| (s.image.display().to_string(), s.kind, s.reason.clone())).collect();
        d.set_item("skipped", skipped)?;
        Ok((Observations { file: obs }, d))
    }

    fn __repr__(&self) -> String {
        format!(
            "Dataset(image_size={:?}, views={}, offstate_views={}, board={}x{} @ {} mm)",
            self.file.image_size,
            self.file.views.len(),
            self.file.offstate_views.len(),
            self.file.board.inner_corners[0],
            self.file.board.inner_corners[1],
            self.file.board.square_mm
        )
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let me = slf.borrow();
        let text = me.to_json()?;
        let base = me.path.as_ref().and_then(|p| p.parent()).map(|d| d.display().to_string());
        let ctor = py.get_type::<Dataset>().getattr("from_json")?;
        Ok((ctor, PyTuple::new(py, [text.into_pyobject(py)?.into_any(), base.into_pyobject(py)?.into_any()])?))
    }
}
