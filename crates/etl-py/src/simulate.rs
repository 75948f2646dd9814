//! `simulate_paper_rig`: the paper rig (section 5.1.2) as synthetic observations with the
//! paper's noise model (Python: `etlcal.simulate.paper_rig`); `simulate_strong_rig`: the
//! strong-distortion rig (`etlcal.simulate.strong_rig`).

use etl_sim::simulate::{
    add_setting_views, paper_rig, strong_rig, NoiseModel, SettingRig, Simulation as CoreSimulation,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::calibration::Calibration;
use crate::errors::{invalid, invalid_value, CoreResultExt};
use crate::observations::{Observations, A0};
use crate::results::fields_dict;

/// A simulated data set and the truth behind it.
#[pyclass(module = "etlcal", frozen)]
pub struct Simulation {
    inner: CoreSimulation,
    seed: u64,
    noise: NoiseModel,
    setting_views: bool,
    /// The strong-distortion rig rather than the paper's.
    strong: bool,
}

#[pymethods]
impl Simulation {
    /// The observations as a user would record them (an `Observations`).
    #[getter]
    fn observations(&self) -> Observations {
        Observations { file: self.inner.observations.clone() }
    }

    /// The A0 a lens-off calibration would give, with its error (an `A0`).
    #[getter]
    fn a0(&self) -> A0 {
        A0 { inner: self.inner.a0 }
    }

    /// The true camera (a `Calibration` of the rig with the paper's thermal surface).
    #[getter]
    fn truth(&self) -> Calibration {
        let [w, h] = self.inner.observations.image_size;
        let mut c = Calibration::from_model(self.inner.truth, [w, h], [80.0, 225.0]);
        c.file_mut().thermal = Some(etl_formats::calibration::ThermalRef::paper());
        c
    }

    /// The true stage error of each view, mm.
    #[getter]
    fn true_dz_mm(&self) -> Vec<f64> {
        self.inner.true_dz_mm.clone()
    }

    /// The true current error of each view, mA.
    #[getter]
    fn true_de_ma(&self) -> Vec<f64> {
        self.inner.true_de_ma.clone()
    }

    /// The seed it was made with.
    #[getter]
    fn seed(&self) -> u64 {
        self.seed
    }

    /// The noise model it was made with: a dict of standard deviations (see
    /// `simulate.paper_rig`).
    #[getter]
    fn noise<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        noise_dict(py, &self.noise)
    }

    /// Pickles as the call that makes it (the simulation is deterministic).
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Reduced<'py>> {
        crate::errors::guarded("Simulation.__reduce__", || {
            let m = py.import("etlcal._etlcal")?;
            if self.strong {
                return Ok((
                    m.getattr("simulate_strong_rig")?,
                    (self.seed, noise_dict(py, &self.noise)?).into_pyobject(py)?.into_any(),
                ));
            }
            let args = (self.seed, noise_dict(py, &self.noise)?, self.setting_views);
            Ok((m.getattr("simulate_paper_rig")?, args.into_pyobject(py)?.into_any()))
        })
    }

    fn __repr__(&self) -> PyResult<String> {
        crate::errors::guarded_value("Simulation.__repr__", || {
            let o = &self.inner.observations;
            format!(
                "Simulation(views={}, points={})",
                o.views.len(),
                o.views.iter().map(|v| v.points.len()).sum::<usize>()
            )
        })
    }
}

/// What `__reduce__` returns: the callable and its arguments ((seed, noise,
/// setting_views) for the paper rig, (seed, noise) for the strong one).
type Reduced<'py> = (Bound<'py, PyAny>, Bound<'py, PyAny>);

fn noise_dict<'py>(py: Python<'py>, m: &NoiseModel) -> PyResult<Bound<'py, PyDict>> {
    fields_dict!(py, m, [xy_mm, z_mm, e_ma, px, kf0_rel, pp_px])
}

fn noise_model(noise: Option<&Bound<'_, PyAny>>) -> PyResult<NoiseModel> {
    let Some(n) = noise else { return Ok(NoiseModel::PAPER) };
    if let Ok(s) = n.extract::<String>() {
        return match s.as_str() {
            "paper" => Ok(NoiseModel::PAPER),
            "none" => Ok(NoiseModel::NONE),
            _ => Err(invalid_value("noise", &s, format!("noise must be \"paper\", \"none\" or a dict, got {s:?}"))),
        };
    }
    let d = n.cast::<PyDict>().map_err(|_| invalid("noise", "noise must be \"paper\", \"none\" or a dict"))?;
    let mut m = NoiseModel::PAPER;
    for (k, v) in d.iter() {
        let key: String = k.extract()?;
        let val: f64 = v.extract()?;
        match key.as_str() {
            "xy_mm" => m.xy_mm = val,
            "z_mm" => m.z_mm = val,
            "e_ma" => m.e_ma = val,
            "px" => m.px = val,
            "kf0_rel" => m.kf0_rel = val,
            "pp_px" => m.pp_px = val,
            _ => {
                return Err(invalid_value(
                    "noise",
                    &key,
                    format!("unknown noise key {key:?} (known: xy_mm, z_mm, e_ma, px, kf0_rel, pp_px)"),
                ))
            }
        }
    }
    m.validate(|key| format!("noise[{key:?}]")).py()?;
    Ok(m)
}

/// The paper rig's 15 views (section 5.1.2; 2311 corners) under the paper's noise model,
/// seeded (the same seed gives the same data as `etlcal simulate`).
///
/// Args:
///     seed: random seed (an int >= 0).
///     noise: "paper" (default), "none", or a dict overriding some standard deviations:
///         xy_mm (corner X, Y, mm), z_mm (stage, mm), e_ma (current, mA), px (pixels, px),
///         kf0_rel (relative, of A0's kf0), pp_px (A0's principal point, px).
///     setting_views: also simulate the per-setting baseline's views (section 5.2.3: 15
///         free views at each of 80, 100, ..., 225 mA, tilted as far as the depth of
///         field allows), for `calibrate(..., method="per-setting")`.
///
/// Returns: a `Simulation` (observations, a0, truth, true_dz_mm, true_de_ma).
#[pyfunction]
#[pyo3(signature = (seed=0, noise=None, setting_views=false))]
pub fn simulate_paper_rig(
    py: Python<'_>,
    seed: u64,
    noise: Option<&Bound<'_, PyAny>>,
    setting_views: bool,
) -> PyResult<Simulation> {
    let m = noise_model(noise)?;
    let inner = crate::pool::detach(py, || {
        let mut sim = paper_rig(&m, seed);
        if setting_views {
            add_setting_views(&mut sim.observations, &SettingRig::default(), &m, seed);
        }
        sim
    });
    Ok(Simulation { inner, seed, noise: m, setting_views, strong: false })
}

/// The strong-distortion rig (etl-sim's `strong_rig`: a short prime behind the ETL, k1
/// about -0.3 and k2 about 0.15 in OpenCV's normalised units, both varying with focus; the
/// paper's 15 currents; a 19 x 15 board of 16 mm squares), seeded.
///
/// Args:
///     seed: random seed (>= 0); the same data as `etlcal simulate --config` with
///         `"rig": "strong"` and that seed.
///     noise: as `simulate_paper_rig`'s.
///
/// Returns: a `Simulation` (its truth in the opencv distortion family).
#[pyfunction]
#[pyo3(signature = (seed=0, noise=None))]
pub fn simulate_strong_rig(py: Python<'_>, seed: u64, noise: Option<&Bound<'_, PyAny>>) -> PyResult<Simulation> {
    let m = noise_model(noise)?;
    let inner = crate::pool::detach(py, || strong_rig(&m, seed));
    Ok(Simulation { inner, seed, noise: m, setting_views: false, strong: true })
}
