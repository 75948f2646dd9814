//! `autofocus(...)`: the lens current of best focus, with the sharpness measured by a
//! Python callable (set the lens, grab a frame, measure).

use etl_core::focus::{autofocus as search, AutofocusOptions};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::CoreResultExt;

/// Finds the lens current of best focus with few evaluations: a coarse scan of the range,
/// then Brent's parabolic/golden-section refinement (etl-core's `focus::autofocus`).
///
/// Args:
///     sharpness_at: a callable current_ma -> sharpness (float, larger is sharper), e.g.
///         set the lens, grab a frame, return `etlcal.sharpness(frame, "tenengrad")`.
///     range_ma: (lo, hi) searched, mA.
///     coarse_points: points of the coarse scan (>= 3; spaced finer than the peak's width).
///     max_evaluations: total calls allowed (>= coarse_points).
///     tolerance_ma: stop when the bracket is narrower than twice this, mA.
///
/// Returns: an AutofocusResult (attributes, also dict keys): "best_ma", "best_sharpness", "evaluations", "bracket_ma",
/// "converged".
///
/// Raises: InputError for bad options or a non-finite sharpness; TypeError when the
/// callable returns something that is not a number; the callable's own exception as it is.
#[pyfunction]
#[pyo3(signature = (sharpness_at, range_ma=(75.0, 240.0), coarse_points=7, max_evaluations=15, tolerance_ma=0.1),
    text_signature = "(sharpness_at, range_ma=(75.0, 240.0), coarse_points=7, max_evaluations=15, tolerance_ma=0.1)")]
pub fn autofocus<'py>(
    py: Python<'py>,
    sharpness_at: &Bound<'py, PyAny>,
    range_ma: (f64, f64),
    coarse_points: usize,
    max_evaluations: usize,
    tolerance_ma: f64,
) -> PyResult<Bound<'py, PyAny>> {
    let options = AutofocusOptions { range_ma: [range_ma.0, range_ma.1], coarse_points, max_evaluations, tolerance_ma };
    let mut raised: Option<PyErr> = None;
    let r = search(
        |e| match sharpness_at.call1((e,)).and_then(|v| v.extract::<f64>()) {
            Ok(v) => Ok(v),
            Err(err) => {
                raised = Some(err);
                Err(etl_core::Error::InvalidArgument { what: "sharpness_at raised" })
            }
        },
        &options,
    );
    if let Some(err) = raised {
        return Err(err);
    }
    let r = r.py()?;
    let d = PyDict::new(py);
    d.set_item("best_ma", r.best_ma)?;
    d.set_item("best_sharpness", r.best_sharpness)?;
    d.set_item("evaluations", r.evaluations)?;
    d.set_item("bracket_ma", (r.bracket_ma[0], r.bracket_ma[1]))?;
    d.set_item("converged", r.converged)?;
    crate::results::make(py, "AutofocusResult", &d)
}
