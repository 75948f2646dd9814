"""LensPhysics and the etlcal.physics functions (paper section 2, 5.1.1)."""
import math
import pickle

import numpy as np
import pytest

import etlcal
from etlcal import physics


def test_paper_lens_focal_lengths() -> None:
    assert physics.f_liq_mm(0.0) == pytest.approx(120.5, abs=0.1)
    assert physics.f_liq_mm(250.0) == pytest.approx(50.5, abs=0.1)
    f = physics.f_liq_mm(np.array([0.0, 100.0, 250.0]))
    assert f.shape == (3,) and f[0] > f[1] > f[2]
    fl = physics.f_liq_mm(0.0)
    assert physics.f_com_mm(0.0) == pytest.approx(fl * 30.0 / (fl + 27.0), rel=1e-14)
    assert etlcal.LensPhysics().f_com_for_f_liq_mm(fl) == physics.f_com_mm(0.0)


def test_pressures_deflection_curvature_by_hand() -> None:
    lens = physics.paper_lens()
    e = 120.0
    pa = -0.004 * e * e + 7.8 * e + 2.061e-13
    assert physics.applied_pressure_pa(e) == pytest.approx(pa, rel=1e-14)
    p = 1200.0 + pa
    assert physics.membrane_pressure_pa(e, lens) == pytest.approx(p, rel=1e-14)
    delta = p / 3e6 * (1 - 0.48) * 25.0 / (4 * 0.05 * 0.1)  # Eq. 2, mm
    assert physics.peak_deflection_mm(e) == pytest.approx(delta, rel=1e-12)
    r = delta / 2 + 25.0 / (2 * delta)  # Eq. 3
    assert physics.radius_of_curvature_mm(e) == pytest.approx(r, rel=1e-12)
    assert physics.f_liq_mm(e) == pytest.approx(r * 1.0 / 0.4, rel=1e-12)  # Eq. 4
    assert lens.hemisphere_pressure_pa() == pytest.approx(4 * 3e6 * 0.05 * 0.1 / (0.52 * 5.0), rel=1e-12)


def test_gravity() -> None:
    dp = 900.0 * 9.80665 * 5e-3
    g0 = physics.gravity_error_mm(0.0, dp)
    diff = etlcal.LensPhysics(p0_pa=1200.0 + dp).f_liq_mm(0.0) - physics.f_liq_mm(0.0)
    assert g0 == pytest.approx(diff, rel=1e-9)
    assert abs(physics.gravity_error_mm(200.0, dp)) < abs(g0)
    k = physics.gravity_coefficient(0.0, 1000.0, 1.2)
    assert k == pytest.approx(1200.0 / (2 * (1000.0 - 1.2) * 9.80665 * 5e-3), rel=1e-12)
    with pytest.raises(etlcal.InputError) as info:
        physics.gravity_coefficient(0.0, 1000.0, 1000.0)
    assert str(info.value) == "degenerate input: liquid and surrounding densities are equal"


def test_fig5_cubic_rmse_matches_the_paper() -> None:
    rmse = physics.polynomial_fit_rmse_mm(0.0, 260.0, 0.1)
    assert len(rmse) == 6
    assert rmse[2] == pytest.approx(1.10e-3, rel=0.1)
    assert all(rmse[d] < 0.5 * rmse[d - 1] for d in range(1, 6))
    with pytest.raises(etlcal.InputError, match="step_ma > 0"):
        physics.polynomial_fit_rmse_mm(0.0, 260.0, 0.0)


def test_bad_inputs() -> None:
    with pytest.raises(etlcal.InputError) as info:
        physics.f_liq_mm(math.nan)
    assert str(info.value) == "e_ma is NaN or infinite; pass finite numbers"
    with pytest.raises(etlcal.InputError) as info:
        etlcal.LensPhysics(poisson_ratio=1.5)
    assert str(info.value) == "invalid argument: poisson_ratio must be below 1"
    with pytest.raises(etlcal.InputError) as info:
        etlcal.LensPhysics(n_liq=0.9)
    assert str(info.value) == "invalid argument: refractive indices must satisfy n_liq > n_0 > 0"
    with pytest.raises(etlcal.InputError) as info:
        etlcal.LensPhysics(young_modulus_pa=math.inf)
    assert str(info.value) == "lens physics parameters is NaN or infinite; pass finite numbers"
    with pytest.raises(etlcal.InputError) as info:
        physics.f_liq_mm(-1000.0)
    assert "is outside" in str(info.value)
    afocal = etlcal.LensPhysics(d_lens_mm=30.0 + physics.f_liq_mm(0.0))
    with pytest.raises(etlcal.InputError) as info:
        afocal.f_com_mm(0.0)
    assert str(info.value) == "degenerate input: f_liq + f_pri - d_lens = 0 (afocal lens group)"


def test_lens_object() -> None:
    lens = etlcal.LensPhysics(f_pri_mm=25.0)
    assert lens.to_dict()["f_pri_mm"] == 25.0
    assert etlcal.LensPhysics(**lens.to_dict()) == lens
    assert pickle.loads(pickle.dumps(lens)) == lens
    assert etlcal.LensPhysics() == etlcal.LensPhysics.paper()
    assert "f_pri_mm=25.0" in repr(lens)
