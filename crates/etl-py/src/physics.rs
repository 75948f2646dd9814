//! `LensPhysics`: the physical model of the ETL group (paper section 2, Eq. 1-10).
//!
//! The functions of the `etlcal.physics` submodule are thin Python wrappers over the
//! methods of this class (with the paper's lens as default).

use etl_core::physics::LensPhysics as CoreLens;
use etl_formats::compact;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::arrays::map1;
use crate::errors::{invalid_value, CoreResultExt};

/// Parameters of the physical lens model (Eq. 1-10). Every argument defaults to the
/// paper's section 5.1.1 value, so `LensPhysics()` is the paper's lens.
///
/// Args:
///     young_modulus_pa: Young's modulus E of the membrane, Pa (3e6).
///     membrane_radius_mm: radius a of the membrane, mm (5).
///     membrane_thickness_mm: thickness h of the membrane, mm (0.1).
///     poisson_ratio: Poisson's ratio of the membrane, < 1 (0.48).
///     prestrain: pre-strain eps_0 of the membrane, a fraction > 0 (0.05).
///     n_liq: refractive index of the liquid, > n_0 (1.4).
///     n_0: refractive index of the surroundings (1.0).
///     p0_pa: initial pressure in the lens, Pa (1200).
///     k_e0_pa: k_E0 of Eq. 1, Pa (2.061e-13).
///     k_e1_pa_per_ma: k_E1 of Eq. 1, Pa/mA (7.8).
///     k_e2_pa_per_ma2: k_E2 of Eq. 1, Pa/mA^2 (-0.004).
///     f_pri_mm: focal length of the prime lens, mm (30).
///     d_lens_mm: distance between the prime lens and the ETL, mm (3).
///
/// Raises: InputError when the parameters break the model's preconditions.
#[pyclass(module = "etlcal", frozen, eq, from_py_object)]
#[derive(Clone, PartialEq)]
pub struct LensPhysics {
    pub(crate) inner: CoreLens,
}

const FIELDS: [&str; 13] = [
    "young_modulus_pa",
    "membrane_radius_mm",
    "membrane_thickness_mm",
    "poisson_ratio",
    "prestrain",
    "n_liq",
    "n_0",
    "p0_pa",
    "k_e0_pa",
    "k_e1_pa_per_ma",
    "k_e2_pa_per_ma2",
    "f_pri_mm",
    "d_lens_mm",
];

impl LensPhysics {
    fn values(&self) -> [f64; 13] {
        let l = &self.inner;
        [
            l.young_modulus_pa,
            l.membrane_radius_mm,
            l.membrane_thickness_mm,
            l.poisson_ratio,
            l.prestrain,
            l.n_liq,
            l.n_0,
            l.p0_pa,
            l.k_e0_pa,
            l.k_e1_pa_per_ma,
            l.k_e2_pa_per_ma2,
            l.f_pri_mm,
            l.d_lens_mm,
        ]
    }
}

#[pymethods]
impl LensPhysics {
    #[new]
    #[pyo3(signature = (
        young_modulus_pa=3.0e6, membrane_radius_mm=5.0, membrane_thickness_mm=0.1,
        poisson_ratio=0.48, prestrain=0.05, n_liq=1.4, n_0=1.0, p0_pa=1200.0,
        k_e0_pa=2.061e-13, k_e1_pa_per_ma=7.8, k_e2_pa_per_ma2=-0.004, f_pri_mm=30.0,
        d_lens_mm=3.0),
        text_signature = "(young_modulus_pa=3000000.0, membrane_radius_mm=5.0, membrane_thickness_mm=0.1, \
            poisson_ratio=0.48, prestrain=0.05, n_liq=1.4, n_0=1.0, p0_pa=1200.0, k_e0_pa=2.061e-13, \
            k_e1_pa_per_ma=7.8, k_e2_pa_per_ma2=-0.004, f_pri_mm=30.0, d_lens_mm=3.0)")]
    #[allow(clippy::too_many_arguments)]
    fn new(
        young_modulus_pa: f64,
        membrane_radius_mm: f64,
        membrane_thickness_mm: f64,
        poisson_ratio: f64,
        prestrain: f64,
        n_liq: f64,
        n_0: f64,
        p0_pa: f64,
        k_e0_pa: f64,
        k_e1_pa_per_ma: f64,
        k_e2_pa_per_ma2: f64,
        f_pri_mm: f64,
        d_lens_mm: f64,
    ) -> PyResult<Self> {
        crate::errors::guarded("LensPhysics.__new__", || {
            let inner = CoreLens {
                young_modulus_pa,
                membrane_radius_mm,
                membrane_thickness_mm,
                poisson_ratio,
                prestrain,
                n_liq,
                n_0,
                p0_pa,
                k_e0_pa,
                k_e1_pa_per_ma,
                k_e2_pa_per_ma2,
                f_pri_mm,
                d_lens_mm,
            };
            inner.validate().py()?;
            Ok(LensPhysics { inner })
        })
    }

    /// The lens of the paper's section 5.1.1 (f_liq 120.5 mm at 0 mA to 50.5 mm at 250 mA).
    #[staticmethod]
    fn paper() -> Self {
        LensPhysics { inner: CoreLens::paper() }
    }

    /// The parameters as a dict (the constructor's keyword arguments).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (k, v) in FIELDS.iter().zip(self.values()) {
            d.set_item(*k, v)?;
        }
        Ok(d)
    }

    /// Applied pressure p_a = k_E2 E^2 + k_E1 E + k_E0 (Eq. 1), Pa.
    ///
    /// Args:
    ///     e_ma: (compensated) lens current, mA (a float or an array).
    fn applied_pressure_pa<'py>(&self, e_ma: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let l = self.inner;
        map1(e_ma, "e_ma", |e| l.applied_pressure_pa(e).py())
    }

    /// Total pressure on the membrane p_0 + p_a, Pa.
    ///
    /// Args:
    ///     e_ma: (compensated) lens current, mA (a float or an array).
    fn membrane_pressure_pa<'py>(&self, e_ma: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let l = self.inner;
        map1(e_ma, "e_ma", |e| l.membrane_pressure_pa(e).py())
    }

    /// Total pressure at which the membrane becomes a hemisphere, Pa (the model holds for
    /// total pressures in (0, this]).
    fn hemisphere_pressure_pa(&self) -> PyResult<f64> {
        self.inner.hemisphere_pressure_pa().py()
    }

    /// Peak deflection of the membrane (Eq. 2), mm.
    ///
    /// Args:
    ///     e_ma: (compensated) lens current, mA (a float or an array).
    fn peak_deflection_mm<'py>(&self, e_ma: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let l = self.inner;
        map1(e_ma, "e_ma", |e| l.peak_deflection_mm(e).py())
    }

    /// Radius of curvature of the membrane (Eq. 3), mm.
    ///
    /// Args:
    ///     e_ma: (compensated) lens current, mA (a float or an array).
    fn radius_of_curvature_mm<'py>(&self, e_ma: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let l = self.inner;
        map1(e_ma, "e_ma", |e| l.radius_of_curvature_mm(e).py())
    }

    /// Focal length of the liquid lens f_liq (Eq. 5), mm.
    ///
    /// Args:
    ///     e_ma: (compensated) lens current, mA (a float or an array).
    fn f_liq_mm<'py>(&self, e_ma: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let l = self.inner;
        map1(e_ma, "e_ma", |e| l.f_liq_mm(e).py())
    }

    /// Compound focal length of the ETL behind the prime lens f_com (Eq. 10), mm.
    ///
    /// Args:
    ///     e_ma: (compensated) lens current, mA (a float or an array).
    fn f_com_mm<'py>(&self, e_ma: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let l = self.inner;
        map1(e_ma, "e_ma", |e| l.f_com_mm(e).py())
    }

    /// f_com for a given liquid-lens focal length (Eq. 10), mm.
    ///
    /// Args:
    ///     f_liq_mm: focal length of the liquid lens, mm (a float or an array).
    fn f_com_for_f_liq_mm<'py>(&self, f_liq_mm: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let l = self.inner;
        map1(f_liq_mm, "f_liq_mm", |f| l.f_com_for_f_liq_mm(f).py())
    }

    /// Focal-length error of a vertical lens from the liquid's weight (Eq. 6), mm.
    ///
    /// Args:
    ///     e_ma: (compensated) lens current, mA (a float or an array).
    ///     dp_gravity_pa: pressure change the liquid's weight adds, Pa.
    fn gravity_error_mm<'py>(&self, e_ma: &Bound<'py, PyAny>, dp_gravity_pa: f64) -> PyResult<Bound<'py, PyAny>> {
        let l = self.inner;
        map1(e_ma, "e_ma", |e| l.gravity_error_mm(e, dp_gravity_pa).py())
    }

    /// Gravity coefficient k_gravity of a horizontal lens (Eq. 9), dimensionless.
    ///
    /// Args:
    ///     e_ma: (compensated) lens current, mA (a float or an array).
    ///     rho_liq_kg_m3: density of the liquid, kg/m^3.
    ///     rho_sur_kg_m3: density of the surroundings, kg/m^3.
    fn gravity_coefficient<'py>(
        &self,
        e_ma: &Bound<'py, PyAny>,
        rho_liq_kg_m3: f64,
        rho_sur_kg_m3: f64,
    ) -> PyResult<Bound<'py, PyAny>> {
        let l = self.inner;
        map1(e_ma, "e_ma", |e| l.gravity_coefficient(e, rho_liq_kg_m3, rho_sur_kg_m3).py())
    }

    /// Fits polynomials of degree 1..6 to f_com(E) over a current range (paper Fig. 5).
    ///
    /// Args:
    ///     e_from_ma: first current, mA (0).
    ///     e_to_ma: last current, mA (260).
    ///     step_ma: sampling step, mA (0.1).
    ///
    /// Returns: the RMS error of each degree's fit, mm (a list of 6 floats; the cubic's is
    /// about 1.1e-3 mm for the paper's lens).
    #[pyo3(signature = (e_from_ma=0.0, e_to_ma=260.0, step_ma=0.1))]
    fn polynomial_fit_rmse_mm(&self, py: Python<'_>, e_from_ma: f64, e_to_ma: f64, step_ma: f64) -> PyResult<Vec<f64>> {
        if !(step_ma > 0.0
            && e_to_ma > e_from_ma
            && step_ma.is_finite()
            && e_from_ma.is_finite()
            && e_to_ma.is_finite())
        {
            let message = format!(
                "need finite e_from_ma < e_to_ma and step_ma > 0, got {}, {}, {}",
                compact(e_from_ma),
                compact(e_to_ma),
                compact(step_ma)
            );
            let (what, value) = if !e_from_ma.is_finite() {
                ("e_from_ma", e_from_ma)
            } else if !(e_to_ma.is_finite() && e_to_ma > e_from_ma) {
                ("e_to_ma", e_to_ma)
            } else {
                ("step_ma", step_ma)
            };
            return Err(invalid_value(what, value, message));
        }
        // Counted in f64 first: a range of 1e308 mA would saturate the usize.
        let intervals = ((e_to_ma - e_from_ma) / step_ma + 1e-9).floor();
        if intervals >= 10_000_000.0 {
            let samples = intervals + 1.0;
            return Err(invalid_value(
                "step_ma",
                step_ma,
                format!("{samples:.3e} samples are too many: raise step_ma"),
            ));
        }
        let n = intervals as usize;
        let l = self.inner;
        crate::pool::detach(py, || {
            let mut out = Vec::with_capacity(6);
            for degree in 1..=6 {
                let mut fit = etl_core::fit::PolyFit::new(degree, [e_from_ma, e_to_ma])?;
                for i in 0..=n {
                    let e = e_from_ma + step_ma * i as f64;
                    fit.add(e, l.f_com_mm(e)?)?;
                }
                out.push(fit.solve()?.1);
            }
            Ok::<_, etl_core::Error>(out)
        })
        .py()
    }

    fn __repr__(&self) -> PyResult<String> {
        crate::errors::guarded_value("LensPhysics.__repr__", || {
            let parts: Vec<String> = FIELDS.iter().zip(self.values()).map(|(k, v)| format!("{k}={v:?}")).collect();
            format!("LensPhysics({})", parts.join(", "))
        })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        crate::errors::guarded("LensPhysics.__reduce__", || {
            let py = slf.py();
            Ok((py.get_type::<LensPhysics>().into_any(), PyTuple::new(py, slf.get().values())?))
        })
    }
}
