//! `etlcal.diff(a, b, grid=(64, 48))`: the projection difference of two cameras at one
//! setting (etl_calib::diff), as `etlcal diff` gives it.

use etl_calib::diff::projection_diff;
use numpy::ndarray::Array2;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::camera::CameraAt;
use crate::errors::{input_error, invalid_value, CoreResultExt};

/// How far apart two cameras at a setting project the same directions, over the image:
/// each pixel of a grid turned into its direction by `a` and projected by `b`, with the
/// intrinsics only and after the rotation that best aligns them (after mrcal's projection
/// diff; `etlcal diff`).
///
/// Args:
///     a: a `CameraAt` (e.g. `cal_a.at(150.0, 30.0)`): its pixels' directions.
///     b: a `CameraAt` of a calibration of the same image size: where it projects them.
///     grid: (columns, rows) of pixels compared, each 1..=1000.
///
/// Returns: a ProjectionDiff (attributes, also dict keys): `grid`, `rms_px`, `max_px`,
/// `rotated_rms_px`, `rotated_max_px`, `rotation_rodrigues` (a's frame to b's, rad),
/// `unmapped` (pixels that did not map through both), `diff_px` and `rotated_diff_px`
/// ((rows, columns) arrays, px; NaN where unmapped).
///
/// Raises: InputError for a grid out of range or different image sizes.
#[pyfunction]
#[pyo3(signature = (a, b, grid=(64, 48)), text_signature = "(a, b, grid=(64, 48))")]
pub fn diff<'py>(
    py: Python<'py>,
    a: PyRef<'py, CameraAt>,
    b: PyRef<'py, CameraAt>,
    grid: (usize, usize),
) -> PyResult<Bound<'py, PyAny>> {
    if a.image_size() != b.image_size() {
        let [w, h] = b.image_size();
        return Err(invalid_value(
            "b",
            [w, h],
            format!("b's calibration is for {w} x {h} px, a's for {:?} px", a.image_size()),
        ));
    }
    let (ca, cb, size) = (a.inner, b.inner, a.image_size());
    let d = crate::pool::detach(py, || projection_diff(&ca, &cb, size, [grid.0, grid.1])).py()?;
    let map = |v: Vec<f64>| Array2::from_shape_vec((d.grid[1], d.grid[0]), v).map_err(|e| input_error(e.to_string()));
    let out = PyDict::new(py);
    out.set_item("grid", (d.grid[0], d.grid[1]))?;
    out.set_item("rms_px", d.rms_px)?;
    out.set_item("max_px", d.max_px)?;
    out.set_item("rotated_rms_px", d.rotated_rms_px)?;
    out.set_item("rotated_max_px", d.rotated_max_px)?;
    out.set_item("rotation_rodrigues", d.rotation_rodrigues.to_vec())?;
    out.set_item("unmapped", d.unmapped)?;
    out.set_item("diff_px", map(d.diff_px.clone())?.into_pyarray(py))?;
    out.set_item("rotated_diff_px", map(d.rotated_diff_px.clone())?.into_pyarray(py))?;
    crate::results::make(py, "ProjectionDiff", &out)
}
