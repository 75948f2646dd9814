//! Typed results: Rust gathers the fields in a dict, `etlcal.results` (frozen Python
//! dataclasses that are also read-only mappings) gives them attributes and a repr.

use pyo3::prelude::*;
use pyo3::types::PyDict;

/// `etlcal.results.<class>(**fields)`: one result object (its fields are the dict's keys).
pub fn make<'py>(py: Python<'py>, class: &str, fields: &Bound<'py, PyDict>) -> PyResult<Bound<'py, PyAny>> {
    py.import("etlcal.results")?.getattr(class)?.call((), Some(fields))
}
