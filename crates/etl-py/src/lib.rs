//! The Python module `etlcal` (built by maturin as `etlcal._etlcal`).
use pyo3::prelude::*;

#[pymodule]
fn _etlcal(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
