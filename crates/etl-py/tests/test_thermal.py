"""ThermalSurface and ThermalCalibration: evaluation against Rust, the fit, files, and
bad inputs."""
import math
import pathlib
import pickle
from typing import Any, Dict, Tuple

import numpy as np
import numpy.typing as npt
import pytest

import etlcal

PAPER = [-348.1, 36.03, -0.414, -1.266, 0.02957, 1.176e-4, 0.01514, -5.276e-4, -4.632e-6, 2.761e-8]


def paper_grid() -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    t, e = np.meshgrid(np.arange(27.0, 38.0), np.arange(40.0, 241.0, 20.0))
    return e.ravel(), t.ravel()


def test_eval_agrees_with_rust(rust_reference: Dict[str, Any]) -> None:
    s = etlcal.ThermalSurface.paper()
    assert s.coefficients.tolist() == PAPER
    for ref in rust_reference["thermal"]:
        assert abs(s.e_t(ref["e_in_ma"], ref["temperature_c"]) - ref["e_t_ma"]) <= 1e-12
        assert abs(s.e_com(ref["e_in_ma"], ref["temperature_c"]) - ref["e_com_ma"]) <= 1e-12


def test_eval_by_hand_and_broadcast() -> None:
    s = etlcal.ThermalSurface(PAPER)
    t, e = 31.5, 187.0
    c = PAPER
    expect = (c[0] + c[1] * t + c[2] * e + c[3] * t * t + c[4] * t * e + c[5] * e * e + c[6] * t ** 3
              + c[7] * t * t * e + c[8] * t * e * e + c[9] * e ** 3)
    assert s.e_t(e, t) == pytest.approx(expect, abs=1e-11)
    grid = s.e_t(np.array([[40.0], [120.0]]), np.array([27.0, 30.0, 37.0]))
    assert grid.shape == (2, 3)
    assert grid[1, 2] == s.e_t(120.0, 37.0)
    assert s.e_com(np.float64(120.0), 33) == pytest.approx(120.0 - s.e_t(120.0, 33.0), abs=1e-12)
    e_com = s.e_com(120.0, 33.0)
    assert abs(s.e_in_for_e_com(e_com, 33.0) - 120.0) < 1e-9
    assert s.e_in_for_e_com([e_com, e_com], 33.0).shape == (2,)


def test_fit_recovers_the_paper_surface() -> None:
    s = etlcal.ThermalSurface.paper()
    e, t = paper_grid()
    y = s.e_t(e, t)
    cal = etlcal.ThermalSurface.fit(e, t, y)
    assert isinstance(cal, etlcal.ThermalCalibration)
    assert np.allclose(cal.surface.coefficients, PAPER, rtol=1e-8, atol=0)
    assert cal.rms_ma < 1e-9
    assert cal.t_range_c == (27.0, 37.0) and cal.e_in_range_ma == (40.0, 240.0)
    weighted = etlcal.ThermalSurface.fit(e, t, y, weights=np.full(e.shape, 4.0))
    assert np.allclose(weighted.surface.coefficients, PAPER, rtol=1e-8, atol=0)


def test_fit_with_noise_reports_the_noise() -> None:
    rng = np.random.default_rng(3)
    s = etlcal.ThermalSurface.paper()
    e, t = paper_grid()
    cal = etlcal.ThermalSurface.fit(e, t, s.e_t(e, t) + rng.normal(0, 0.2, e.shape))
    assert 0.15 < cal.rms_ma < 0.25


def test_fit_bad_inputs() -> None:
    e, t = paper_grid()
    y = np.zeros_like(e)
    with pytest.raises(etlcal.InputError) as info:
        etlcal.ThermalSurface.fit(e[:5], t[:5], y[:5])
    assert str(info.value) == "too few thermal samples: the method needs at least 10, got 5"
    with pytest.raises(etlcal.InputError) as info:
        etlcal.ThermalSurface.fit(e, np.full(e.shape, 30.0), y)
    assert str(info.value) == "degenerate input: all samples at one temperature"
    with pytest.raises(etlcal.InputError) as info:
        etlcal.ThermalSurface.fit(e, t + 300.0, y)
    assert str(info.value) == "t_c = 327 is outside [-40, 125]"
    y_nan = y.copy()
    y_nan[3] = math.nan
    with pytest.raises(etlcal.InputError) as info:
        etlcal.ThermalSurface.fit(e, t, y_nan)
    assert str(info.value) == "e_t_ma is NaN or infinite; pass finite numbers"
    with pytest.raises(etlcal.InputError, match="same length"):
        etlcal.ThermalSurface.fit(e, t[:-1], y)
    with pytest.raises(etlcal.InputError, match="1-D"):
        etlcal.ThermalSurface.fit(e.reshape(11, 11), t.reshape(11, 11), y.reshape(11, 11))
    with pytest.raises(etlcal.InputError) as info:
        etlcal.ThermalSurface.fit(e, t, y, weights=-np.ones(e.shape))
    assert "weight" in str(info.value)


def test_surface_bad_inputs() -> None:
    s = etlcal.ThermalSurface.paper()
    with pytest.raises(etlcal.InputError) as info:
        s.e_t(100.0, math.nan)
    assert str(info.value) == "t_c is NaN or infinite; pass finite numbers"
    with pytest.raises(etlcal.InputError) as info:
        s.e_com([100.0, 400.0], 30.0)
    assert str(info.value) == "e_in_ma = 400 is outside [-292.84, 292.84]"
    with pytest.raises(etlcal.InputError) as info:
        s.e_in_for_e_com(100.0, 200.0)
    assert str(info.value) == "t_c = 200 is outside [-40, 125]"
    with pytest.raises(etlcal.InputError) as info:
        s.e_in_for_e_com(5000.0, 30.0)
    assert str(info.value).startswith("e_com_ma (no driver current reaches it at this temperature) = 5000 is outside")
    with pytest.raises(etlcal.InputError) as info:
        etlcal.ThermalSurface([math.nan] * 10)
    assert str(info.value) == "thermal coefficients is NaN or infinite; pass finite numbers"
    with pytest.raises(etlcal.InputError, match="coefficients must be 10 numbers"):
        etlcal.ThermalSurface([1.0, 2.0])
    with pytest.raises(etlcal.InputError, match="do not broadcast"):
        s.e_t(np.zeros(3), np.zeros(4))


def test_thermal_calibration_compensate_and_files(tmp_path: pathlib.Path) -> None:
    cal = etlcal.ThermalCalibration.paper()
    assert cal.rms_ma == 0.2106 and cal.t_range_c == (27.0, 37.0)
    inside = cal.compensate(100.0, 30.0)
    assert inside["extrapolated"] is False
    assert inside["e_com_ma"] == etlcal.ThermalSurface.paper().e_com(100.0, 30.0)
    assert cal.compensate(100.0, 45.0)["extrapolated"] is True
    back = cal.e_in_for_e_com(inside["e_com_ma"], 30.0)
    assert abs(back["e_in_ma"] - 100.0) < 1e-9 and back["extrapolated"] is False
    assert cal.contains(100.0, 30.0) and not cal.contains(100.0, math.nan)
    with pytest.raises(etlcal.InputError) as info:
        cal.compensate(400.0, 30.0)
    assert str(info.value) == "e_in_ma = 400 is outside [-292.84, 292.84]"
    path = tmp_path / "thermal.json"
    cal.save(path)
    assert etlcal.ThermalCalibration.load(path) == cal
    assert etlcal.ThermalCalibration.from_json(cal.to_json()) == cal
    assert pickle.loads(pickle.dumps(cal)) == cal
    s = etlcal.ThermalSurface.paper()
    assert pickle.loads(pickle.dumps(s)) == s
    made = etlcal.ThermalCalibration(s, e_in_range_ma=(40, 240), t_range_c=(27, 37), rms_ma=0.2106)
    assert made == cal
    assert made.e_in_range_ma == (40.0, 240.0) and made.t_range_c == (27.0, 37.0)
    # The ranges are keyword-only: a call in the old positional order fails, never swaps.
    with pytest.raises(TypeError):
        etlcal.ThermalCalibration(s, (27, 37), (40, 240))  # type: ignore[call-arg]  # the refusal under test
    with pytest.raises(etlcal.InputError, match="min <= max"):
        etlcal.ThermalCalibration(s, e_in_range_ma=(40, 240), t_range_c=(37, 27))
    with pytest.raises(etlcal.InputError, match="rms_ma"):
        etlcal.ThermalCalibration(s, e_in_range_ma=(40, 240), t_range_c=(27, 37), rms_ma=-1.0)
    with pytest.raises(etlcal.FileError):
        etlcal.ThermalCalibration.load(tmp_path / "missing.json")
    (tmp_path / "c.json").write_text('{"format": "etlcal.calibration/1"}')
    with pytest.raises(etlcal.InputError, match="is not supported"):
        etlcal.ThermalCalibration.load(tmp_path / "c.json")
    assert repr(cal) == "ThermalCalibration(e_in_range_ma=[40.0, 240.0], t_range_c=[27.0, 37.0], rms_ma=0.2106)"
    assert "ThermalSurface(" in repr(s)
