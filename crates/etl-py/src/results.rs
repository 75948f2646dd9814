//! Typed results: Rust gathers the fields in a dict, `etlcal.results` (frozen Python
//! dataclasses that are also read-only mappings) gives them attributes and a repr.

use pyo3::prelude::*;
use pyo3::types::PyDict;

/// `etlcal.results.<class>(**fields)`: one result object (its fields are the dict's keys).
pub fn make<'py>(py: Python<'py>, class: &str, fields: &Bound<'py, PyDict>) -> PyResult<Bound<'py, PyAny>> {
    py.import("etlcal.results")?.getattr(class)?.call((), Some(fields))
}

/// A dict of the fields `$field` of `$source` under their own names: what most result
/// objects are (a Rust struct's fields as they are), so that each states only its field
/// list.
macro_rules! fields_dict {
    ($py:expr, $source:expr, [$($field:ident),* $(,)?]) => {{
        let source = $source;
        let d = pyo3::types::PyDict::new($py);
        (|| -> pyo3::PyResult<_> {
            $(d.set_item(stringify!($field), source.$field)?;)*
            Ok(d)
        })()
    }};
}
pub(crate) use fields_dict;

/// `etlcal.results.<class>` of the fields `$field` of `$source` (see [`fields_dict`]).
macro_rules! fields_object {
    ($py:expr, $class:literal, $source:expr, [$($field:ident),* $(,)?]) => {
        crate::results::fields_dict!($py, $source, [$($field),*])
            .and_then(|d| crate::results::make($py, $class, &d))
    };
}
pub(crate) use fields_object;
