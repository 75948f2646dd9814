"""The physical model of the ETL group (paper section 2, Eq. 1-10) as functions.

Each function takes the (compensated) lens current `e_ma` in mA, as a float or an array,
and an optional `lens` (a `LensPhysics`; the paper's section 5.1.1 lens by default).
"""
from typing import Any, List, Optional, Sequence, Union, overload

import numpy as np
import numpy.typing as npt

from ._etlcal import LensPhysics

__all__ = [
    "LensPhysics",
    "paper_lens",
    "applied_pressure_pa",
    "membrane_pressure_pa",
    "peak_deflection_mm",
    "radius_of_curvature_mm",
    "f_liq_mm",
    "f_com_mm",
    "gravity_error_mm",
    "gravity_coefficient",
    "polynomial_fit_rmse_mm",
]


_F64 = npt.NDArray[np.float64]
# Currents as an array or a list: the functions return an array for them (a number for a
# number).
_Numbers = Union[npt.NDArray[Any], Sequence[float]]


def paper_lens() -> LensPhysics:
    """The lens of the paper's section 5.1.1."""
    return LensPhysics.paper()


def _lens(lens: Optional[LensPhysics]) -> LensPhysics:
    return LensPhysics.paper() if lens is None else lens


@overload
def applied_pressure_pa(e_ma: float, lens: Optional[LensPhysics] = None) -> float: ...
@overload
def applied_pressure_pa(e_ma: _Numbers, lens: Optional[LensPhysics] = None) -> _F64: ...
@overload
def applied_pressure_pa(e_ma: npt.ArrayLike, lens: Optional[LensPhysics] = None) -> Union[float, _F64]: ...
def applied_pressure_pa(e_ma: npt.ArrayLike, lens: Optional[LensPhysics] = None) -> Union[float, _F64]:
    """Applied pressure p_a(E) (Eq. 1), Pa.

    Args:
        e_ma: lens current, mA (a float or an array).
        lens: the lens (default: the paper's).
    """
    return _lens(lens).applied_pressure_pa(e_ma)


@overload
def membrane_pressure_pa(e_ma: float, lens: Optional[LensPhysics] = None) -> float: ...
@overload
def membrane_pressure_pa(e_ma: _Numbers, lens: Optional[LensPhysics] = None) -> _F64: ...
@overload
def membrane_pressure_pa(e_ma: npt.ArrayLike, lens: Optional[LensPhysics] = None) -> Union[float, _F64]: ...
def membrane_pressure_pa(e_ma: npt.ArrayLike, lens: Optional[LensPhysics] = None) -> Union[float, _F64]:
    """Total pressure on the membrane p_0 + p_a(E), Pa.

    Args:
        e_ma: lens current, mA (a float or an array).
        lens: the lens (default: the paper's).
    """
    return _lens(lens).membrane_pressure_pa(e_ma)


@overload
def peak_deflection_mm(e_ma: float, lens: Optional[LensPhysics] = None) -> float: ...
@overload
def peak_deflection_mm(e_ma: _Numbers, lens: Optional[LensPhysics] = None) -> _F64: ...
@overload
def peak_deflection_mm(e_ma: npt.ArrayLike, lens: Optional[LensPhysics] = None) -> Union[float, _F64]: ...
def peak_deflection_mm(e_ma: npt.ArrayLike, lens: Optional[LensPhysics] = None) -> Union[float, _F64]:
    """Peak deflection of the membrane (Eq. 2), mm.

    Args:
        e_ma: lens current, mA (a float or an array).
        lens: the lens (default: the paper's).
    """
    return _lens(lens).peak_deflection_mm(e_ma)


@overload
def radius_of_curvature_mm(e_ma: float, lens: Optional[LensPhysics] = None) -> float: ...
@overload
def radius_of_curvature_mm(e_ma: _Numbers, lens: Optional[LensPhysics] = None) -> _F64: ...
@overload
def radius_of_curvature_mm(e_ma: npt.ArrayLike, lens: Optional[LensPhysics] = None) -> Union[float, _F64]: ...
def radius_of_curvature_mm(e_ma: npt.ArrayLike, lens: Optional[LensPhysics] = None) -> Union[float, _F64]:
    """Radius of curvature of the membrane (Eq. 3), mm.

    Args:
        e_ma: lens current, mA (a float or an array).
        lens: the lens (default: the paper's).
    """
    return _lens(lens).radius_of_curvature_mm(e_ma)


@overload
def f_liq_mm(e_ma: float, lens: Optional[LensPhysics] = None) -> float: ...
@overload
def f_liq_mm(e_ma: _Numbers, lens: Optional[LensPhysics] = None) -> _F64: ...
@overload
def f_liq_mm(e_ma: npt.ArrayLike, lens: Optional[LensPhysics] = None) -> Union[float, _F64]: ...
def f_liq_mm(e_ma: npt.ArrayLike, lens: Optional[LensPhysics] = None) -> Union[float, _F64]:
    """Focal length of the liquid lens (Eq. 5), mm: 120.5 mm at 0 mA to 50.5 mm at 250 mA
    for the paper's lens.

    Args:
        e_ma: lens current, mA (a float or an array).
        lens: the lens (default: the paper's).
    """
    return _lens(lens).f_liq_mm(e_ma)


@overload
def f_com_mm(e_ma: float, lens: Optional[LensPhysics] = None) -> float: ...
@overload
def f_com_mm(e_ma: _Numbers, lens: Optional[LensPhysics] = None) -> _F64: ...
@overload
def f_com_mm(e_ma: npt.ArrayLike, lens: Optional[LensPhysics] = None) -> Union[float, _F64]: ...
def f_com_mm(e_ma: npt.ArrayLike, lens: Optional[LensPhysics] = None) -> Union[float, _F64]:
    """Compound focal length of the ETL behind the prime lens (Eq. 10), mm.

    Args:
        e_ma: lens current, mA (a float or an array).
        lens: the lens (default: the paper's).
    """
    return _lens(lens).f_com_mm(e_ma)


@overload
def gravity_error_mm(e_ma: float, dp_gravity_pa: float, lens: Optional[LensPhysics] = None) -> float: ...
@overload
def gravity_error_mm(e_ma: _Numbers, dp_gravity_pa: float, lens: Optional[LensPhysics] = None) -> _F64: ...
@overload
def gravity_error_mm(e_ma: npt.ArrayLike, dp_gravity_pa: float, lens: Optional[LensPhysics] = None) -> Union[float, _F64]: ...
def gravity_error_mm(e_ma: npt.ArrayLike, dp_gravity_pa: float, lens: Optional[LensPhysics] = None) -> Union[float, _F64]:
    """Focal-length error of a vertical lens from the liquid's weight (Eq. 6), mm.

    Args:
        e_ma: lens current, mA (a float or an array).
        dp_gravity_pa: pressure change the liquid's weight adds, Pa.
        lens: the lens (default: the paper's).
    """
    return _lens(lens).gravity_error_mm(e_ma, dp_gravity_pa)


@overload
def gravity_coefficient(e_ma: float, rho_liq_kg_m3: float, rho_sur_kg_m3: float, lens: Optional[LensPhysics] = None) -> float: ...
@overload
def gravity_coefficient(e_ma: _Numbers, rho_liq_kg_m3: float, rho_sur_kg_m3: float, lens: Optional[LensPhysics] = None) -> _F64: ...
@overload
def gravity_coefficient(e_ma: npt.ArrayLike, rho_liq_kg_m3: float, rho_sur_kg_m3: float, lens: Optional[LensPhysics] = None) -> Union[float, _F64]: ...
def gravity_coefficient(e_ma: npt.ArrayLike, rho_liq_kg_m3: float, rho_sur_kg_m3: float, lens: Optional[LensPhysics] = None) -> Union[float, _F64]:
    """Gravity coefficient of a horizontal lens (Eq. 9), dimensionless.

    Args:
        e_ma: lens current, mA (a float or an array).
        rho_liq_kg_m3: density of the liquid, kg/m^3.
        rho_sur_kg_m3: density of the surroundings, kg/m^3.
        lens: the lens (default: the paper's).
    """
    return _lens(lens).gravity_coefficient(e_ma, rho_liq_kg_m3, rho_sur_kg_m3)


def polynomial_fit_rmse_mm(
    e_from_ma: float = 0.0, e_to_ma: float = 260.0, step_ma: float = 0.1, lens: Optional[LensPhysics] = None
) -> List[float]:
    """RMS error (mm) of polynomials of degree 1..6 fitted to f_com(E) (paper Fig. 5).

    Args:
        e_from_ma: first current, mA.
        e_to_ma: last current, mA.
        step_ma: sampling step, mA.
        lens: the lens (default: the paper's).

    Returns: a list of 6 floats, mm (the cubic's about 1.1e-3 mm for the paper's lens).
    """
    return _lens(lens).polynomial_fit_rmse_mm(e_from_ma, e_to_ma, step_ma)
