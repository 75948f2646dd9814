//! `study(name, ...)`: the paper's simulations reproduced (`etlcal study`), from Python.

use std::path::PathBuf;

use etl_studies::{Study, StudyOptions, MAX_TRIALS};
use pyo3::prelude::*;

use crate::errors::{invalid_value, CoreResultExt};

/// Runs one of the paper's studies and returns its table as the command line's `--json`
/// object (a dict), optionally writing its JSON, markdown summary and plots into `out`.
///
/// Args:
///     name: "fig5" (polynomial degree vs the physics focal length), "fig6" (pixel noise,
///         current noise, number of images; plain and errors-in-variables BA), "subsets"
///         (6..9 of 9 views), "baseline" (per-setting Zhang vs the proposed method), or
///         "crlb" (Cramer-Rao bound vs Monte Carlo spread), or "crlb-strong" (the same on
///         the strong-distortion rig for OpenCV's family, with the paper family's bias).
///     trials: Monte Carlo trials per level, 0..=100000 (0: the study's default; fig6 100,
///         crlb 300; more is refused with InputError before anything runs).
///     seed: base random seed.
///     out: a directory for name.json, name.md and the SVG/PNG plots (None: not written).
///
/// Returns: a StudyResult: `name` and `table` (the --json object), whose keys are also the
/// result's keys and attributes, e.g. `r["fit_rmse_mm"]` or `r.fit_rmse_mm` for fig5, or
/// `r.parameters` ([{"name", "truth", "crlb_std", "mc_std", "efficiency"}, ...]) for crlb.
///
/// Runs without the GIL (the trials run in parallel).
#[pyfunction]
#[pyo3(signature = (name, trials=0, seed=1, out=None))]
pub fn study<'py>(
    py: Python<'py>,
    name: &str,
    trials: usize,
    seed: u64,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let which = Study::from_name(name).py()?;
    // The CLI's limit, checked before anything is allocated for the trials.
    if trials > MAX_TRIALS {
        return Err(invalid_value(
            "trials",
            trials,
            format!("trials {trials} must lie in 0..={MAX_TRIALS} (0: the study's default)"),
        ));
    }
    if let Some(dir) = &out {
        if !dir.is_dir() {
            return Err(invalid_value("out", dir, format!("{}: output directory does not exist", dir.display())));
        }
    }
    // As the CLI: with SOURCE_DATE_EPOCH set, the files carry no wall time.
    let wall_time = etl_formats::output::source_date_epoch().py()?.is_none();
    let opts = StudyOptions { trials, seed, wall_time, ..Default::default() };
    let result = crate::pool::detach(py, || which.run(&opts)).py()?;
    if let Some(dir) = &out {
        result.write(dir).py()?;
    }
    let text = result.json.to_string();
    let d = pyo3::types::PyDict::new(py);
    d.set_item("name", name)?;
    d.set_item("table", py.import("json")?.call_method1("loads", (text,))?)?;
    crate::results::make(py, "StudyResult", &d)
}
