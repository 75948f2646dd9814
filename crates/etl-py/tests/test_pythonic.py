"""The Pythonic surface: vectorised per-current functions against the scalar
ones, typed result objects (attributes and dict access), Observations as a sequence of
views, option checking, and the stubs under mypy --strict (the whole test suite, fully
typed, and the package's own sources)."""
from __future__ import annotations

import json
import pathlib
import subprocess
import sys
from typing import Any, List, get_args

import numpy as np
import numpy.typing as npt
import pytest

import etlcal
from etlcal.options import ExportFormat, NoisePreset, SharpnessMetric, StudyName
from etlcal.results import (
    AutofocusResult,
    Compensation,
    CompensationArray,
    ExportResult,
    ModelStd,
    OffstateView,
    StudyResult,
    View,
    ViewSummary,
    ZhangResult,
)

ROOT = pathlib.Path(__file__).resolve().parents[3]
# Currents of shape (2, 3) inside the paper rig's 80..225 mA.
E_MA: npt.NDArray[np.float64] = np.array([[90.0, 120.0, 150.0], [180.0, 200.0, 220.0]])
# The paper rig's fx(E), fy(E) (CameraModel::paper_rig), the ground truth.
KF_X = [5380.0, -7.0, 0.02, -3e-5]
KF_Y = [5430.0, -7.0, 0.02, -3e-5]


@pytest.fixture(scope="module")
def cal() -> etlcal.Calibration:
    return etlcal.Calibration.paper_rig()


@pytest.fixture(scope="module")
def sim() -> etlcal.Simulation:
    return etlcal.simulate.paper_rig(seed=1)


def poly(k: List[float], e: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    return k[0] + k[1] * e + k[2] * e**2 + k[3] * e**3


def test_focal_lengths_over_an_array_are_the_scalar_ones_stacked(cal: etlcal.Calibration) -> None:
    fx, fy = cal.focal_lengths(E_MA)
    assert fx.shape == fy.shape == (2, 3)
    for i in np.ndindex(E_MA.shape):
        assert (float(fx[i]), float(fy[i])) == cal.focal_lengths(float(E_MA[i]))
    np.testing.assert_allclose(fx, poly(KF_X, E_MA), rtol=1e-13)
    np.testing.assert_allclose(fy, poly(KF_Y, E_MA), rtol=1e-13)
    # A scalar (or a 0-d array) gives today's tuple of floats; a list, arrays.
    sx, sy = cal.focal_lengths(np.float64(150.0))
    assert isinstance(sx, float) and isinstance(sy, float)
    assert isinstance(cal.focal_lengths(np.array(150.0))[0], float)
    lx, _ = cal.focal_lengths([100.0, 150.0])
    assert lx.shape == (2,) and lx[1] == sx


def test_intrinsics_over_an_array_are_the_scalar_ones_stacked(cal: etlcal.Calibration) -> None:
    k = cal.intrinsics(E_MA)
    assert k.shape == (2, 3, 3, 3)
    for i in np.ndindex(E_MA.shape):
        np.testing.assert_array_equal(k[i], cal.intrinsics(float(E_MA[i])))
    np.testing.assert_allclose(k[..., 0, 0], poly(KF_X, E_MA), rtol=1e-13)
    assert np.all(k[..., 0, 2] == 900.0) and np.all(k[..., 1, 2] == 550.0) and np.all(k[..., 2, 2] == 1.0)
    assert cal.intrinsics(150.0).shape == (3, 3)


def test_distortion_over_an_array_is_the_scalar_one_stacked(cal: etlcal.Calibration) -> None:
    k1, p1, p2 = cal.distortion(E_MA)
    assert k1.shape == p1.shape == p2.shape == (2, 3)
    for i in np.ndindex(E_MA.shape):
        assert (float(k1[i]), float(p1[i]), float(p2[i])) == cal.distortion(float(E_MA[i]))
    assert all(isinstance(x, float) for x in cal.distortion(150.0))


def test_to_opencv_over_an_array_is_the_scalar_one_stacked(cal: etlcal.Calibration) -> None:
    k, dist = cal.to_opencv(E_MA)
    assert k.shape == (2, 3, 3, 3) and dist.shape == (2, 3, 5)
    for i in np.ndindex(E_MA.shape):
        k_one, dist_one = cal.to_opencv(float(E_MA[i]))
        np.testing.assert_array_equal(k[i], k_one)
        np.testing.assert_array_equal(dist[i], dist_one)
    assert cal.to_opencv(150.0)[1].shape == (5,)


def test_an_array_with_one_current_out_of_range_is_refused(cal: etlcal.Calibration) -> None:
    with pytest.raises(etlcal.InputError, match=r"e_com_ma = 300 is outside \[75, 230\]"):
        cal.focal_lengths(np.array([150.0, 300.0]))
    fx, _ = cal.focal_lengths(np.array([150.0, 300.0]), allow_extrapolation=True)
    np.testing.assert_allclose(fx, poly(KF_X, np.array([150.0, 300.0])), rtol=1e-13)
    with pytest.raises(etlcal.InputError, match="e_com_ma"):
        cal.intrinsics(np.array(["a", "b"]))


def test_focus_functions_over_arrays_are_the_scalar_ones(cal: etlcal.Calibration) -> None:
    # The golden calibration's focus law with the paper's thermal part.
    doc = json.loads((ROOT / "fixtures" / "golden" / "calibrate-eiv.json").read_text())
    doc["thermal"] = json.loads(cal.to_json())["thermal"]
    del doc["temperature_compensation"]  # "none": the file was made without a thermal part
    focused = etlcal.Calibration.from_json(json.dumps(doc))
    distance_mm = np.array([60.0, 85.0, 115.0])
    temperature_c = np.array([27.0, 31.5, 36.0])
    e_in = focused.focus_e_in(distance_mm, temperature_c)
    assert isinstance(e_in, np.ndarray) and e_in.shape == (3,)
    for k in range(3):
        assert e_in[k] == focused.focus_e_in(float(distance_mm[k]), float(temperature_c[k]))
    np.testing.assert_allclose(focused.focus_distance_mm(e_in, temperature_c), distance_mm, atol=1e-8)
    # Broadcast: one temperature for every distance.
    np.testing.assert_array_equal(focused.focus_e_in(distance_mm, 30.0),
                                  [focused.focus_e_in(float(d), 30.0) for d in distance_mm])


def test_principal_point_is_an_array_and_fx_poly_is_a_polynomial(cal: etlcal.Calibration) -> None:
    assert isinstance(cal.principal_point, np.ndarray) and cal.principal_point.tolist() == [900.0, 550.0]
    assert isinstance(cal.fx_poly, np.polynomial.Polynomial)
    assert cal.fx_poly.coef.tolist() == KF_X and cal.fy_poly.coef.tolist() == KF_Y
    fx, fy = cal.focal_lengths(E_MA)
    np.testing.assert_allclose(cal.fx_poly(E_MA), fx, rtol=1e-13)
    np.testing.assert_allclose(cal.fy_poly(E_MA), fy, rtol=1e-13)


def test_observations_are_a_sequence_of_views(sim: etlcal.Simulation) -> None:
    obs = sim.observations
    views = list(obs)
    assert len(views) == len(obs) == 15
    assert all(isinstance(v, View) for v in views)
    for i, v in enumerate(obs):
        assert v == obs[i] == obs.view(i) == obs[i - len(obs)]
    last = obs[-1]
    assert last.world_mm.shape == (last.pixels.shape[0], 3) and last.pixels.shape[1] == 2
    assert last["e_in_ma"] == last.e_in_ma and "temperature_c" in last
    assert list(last.keys()) == ["world_mm", "pixels", "e_in_ma", "temperature_c", "e_com_ma", "focal_power_dpt"]
    assert "View(world_mm=<array (" in repr(last)
    with pytest.raises(IndexError, match="view index 15 out of range"):
        obs[15]
    with pytest.raises(IndexError, match="view index -16"):
        obs[-16]
    off = obs.offstate_view(0)
    assert isinstance(off, OffstateView) and set(off) == {"world_mm", "pixels"}


def test_zhang_returns_a_zhang_result(sim: etlcal.Simulation) -> None:
    obs = sim.observations
    views = [(obs.offstate_view(k).world_mm[:, :2], obs.offstate_view(k).pixels) for k in range(obs.offstate_count)]
    r = etlcal.zhang(views, (1936, 1458))
    assert isinstance(r, ZhangResult)
    truth = sim.truth.intrinsics(0.0, allow_extrapolation=True)
    assert abs(r.fx / truth[0, 0] - 1.0) < 2e-3 and abs(r.fy / truth[1, 1] - 1.0) < 2e-3
    assert r["fx"] == r.fx and r["u0"] == r.u0 and r["views_used"] == r.views_used == obs.offstate_count
    assert set(r.keys()) == {"fx", "fy", "u0", "v0", "k1", "p1", "p2", "std", "rms_px", "iterations",
                             "views_used", "poses"}
    assert len(r.std) == 7 and len(r.poses) == r.views_used and "rms_px" in r
    assert repr(r).startswith("ZhangResult(fx=")


def test_autofocus_returns_an_autofocus_result() -> None:
    r = etlcal.autofocus(lambda e: -((e - 150.0) ** 2))
    assert isinstance(r, AutofocusResult)
    assert abs(r.best_ma - 150.0) < 0.2 and r["best_ma"] == r.best_ma and r.converged is r["converged"]
    assert r.evaluations <= 15 and r.bracket_ma[0] <= r.best_ma <= r.bracket_ma[1]
    assert dict(r) == {k: getattr(r, k) for k in ("best_ma", "best_sharpness", "evaluations", "bracket_ma",
                                                   "converged")}


def test_compensation_results() -> None:
    tc = etlcal.ThermalCalibration.paper()
    c = tc.compensate(150.0, 30.0)
    assert isinstance(c, Compensation)
    e_t = tc.surface.e_t(150.0, 30.0)
    assert c.e_t_ma == c["e_t_ma"] == e_t and c.e_com_ma == pytest.approx(150.0 - e_t, abs=1e-12)
    back = tc.e_in_for_e_com(c.e_com_ma, 30.0)
    assert isinstance(back, Compensation) and back.e_in_ma == pytest.approx(150.0, abs=1e-9)
    assert c == {"e_in_ma": 150.0, "e_t_ma": e_t, "e_com_ma": c.e_com_ma, "extrapolated": False}


# The paper's surface E_T(T, E) (section 5.2.2) written out: the ground truth of E_T.
PAPER_E_T = [-348.1, 36.03, -0.414, -1.266, 0.02957, 1.176e-4, 0.01514, -5.276e-4, -4.632e-6, 2.761e-8]


def e_t_by_hand(e: npt.NDArray[np.float64], t: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    c = PAPER_E_T
    return (c[0] + c[1] * t + c[2] * e + c[3] * t * t + c[4] * t * e + c[5] * e * e + c[6] * t**3
            + c[7] * t * t * e + c[8] * t * e * e + c[9] * e**3)


def test_compensate_over_arrays_is_the_scalar_one_broadcast() -> None:
    tc = etlcal.ThermalCalibration.paper()  # calibrated over 40..240 mA, 27..37 degC
    # A column of currents against a row of temperatures: shape (4, 3); 20 mA and 40 degC
    # lie outside the calibrated ranges (inside the lens's domain): flagged, not refused.
    e_in = np.array([[20.0], [100.0], [150.0], [230.0]])
    t = np.array([27.5, 33.0, 40.0])
    c = tc.compensate(e_in, t)
    assert isinstance(c, CompensationArray)
    assert c.e_in_ma.shape == c.e_t_ma.shape == c.e_com_ma.shape == c.extrapolated.shape == (4, 3)
    assert c.e_t_ma.dtype == np.float64 and c.extrapolated.dtype == np.bool_
    e_b, t_b = np.broadcast_arrays(e_in, t)
    np.testing.assert_array_equal(c.e_in_ma, e_b)
    np.testing.assert_allclose(c.e_t_ma, e_t_by_hand(e_b, t_b), rtol=0, atol=1e-10)
    np.testing.assert_array_equal(c.e_com_ma, c.e_in_ma - c.e_t_ma)
    for i in np.ndindex(c.e_com_ma.shape):
        one = tc.compensate(float(e_b[i]), float(t_b[i]))
        assert (one.e_in_ma, one.e_t_ma, one.e_com_ma, one.extrapolated) == (
            float(c.e_in_ma[i]), float(c.e_t_ma[i]), float(c.e_com_ma[i]), bool(c.extrapolated[i]))
    assert c.extrapolated.tolist() == [[True, True, True], [False, False, True], [False, False, True],
                                       [False, False, True]]
    # Dict access and the repr, as the other results.
    assert c["e_com_ma"] is c.e_com_ma and set(c) == {"e_in_ma", "e_t_ma", "e_com_ma", "extrapolated"}
    assert repr(c).startswith("CompensationArray(e_in_ma=<array (4, 3)>")
    # A list is an array; two numbers (or 0-d arrays) give today's Compensation.
    assert isinstance(tc.compensate([100.0, 150.0], 30.0), CompensationArray)
    assert isinstance(tc.compensate(np.array(100.0), np.array(30.0)), Compensation)


def test_e_in_for_e_com_over_arrays_inverts_compensate() -> None:
    tc = etlcal.ThermalCalibration.paper()
    e_com = np.array([60.0, 120.0, 180.0])
    t = np.array([[28.0], [36.0]])
    back = tc.e_in_for_e_com(e_com, t)
    assert isinstance(back, CompensationArray) and back.e_in_ma.shape == (2, 3)
    np.testing.assert_array_equal(back.e_com_ma, np.broadcast_to(e_com, (2, 3)))
    # E_in - E_T(T, E_in) = E_com, with E_T written out (the inverse's tolerance 1e-9 mA).
    e_com_b, t_b = np.broadcast_arrays(e_com, t)
    np.testing.assert_allclose(back.e_in_ma - e_t_by_hand(back.e_in_ma, t_b), e_com_b, rtol=0, atol=1e-8)
    for i in np.ndindex(back.e_in_ma.shape):
        one = tc.e_in_for_e_com(float(e_com_b[i]), float(t_b[i]))
        assert (one.e_in_ma, one.e_t_ma, one.extrapolated) == (
            float(back.e_in_ma[i]), float(back.e_t_ma[i]), bool(back.extrapolated[i]))


def test_one_reading_outside_the_lens_domain_refuses_the_whole_array() -> None:
    tc = etlcal.ThermalCalibration.paper()
    with pytest.raises(etlcal.InputError) as scalar:
        tc.compensate(400.0, 30.0)
    with pytest.raises(etlcal.InputError) as vector:
        tc.compensate(np.array([100.0, 400.0]), 30.0)
    assert str(vector.value) == str(scalar.value) == "e_in_ma = 400 is outside [-292.84, 292.84]"
    with pytest.raises(etlcal.InputError, match=r"t_c = 200 is outside \[-40, 125\]"):
        tc.e_in_for_e_com([100.0, 120.0], np.array([30.0, 200.0]))
    with pytest.raises(etlcal.InputError, match="do not broadcast"):
        tc.compensate(np.zeros(3), np.zeros(4))


def test_calibration_results(sim: etlcal.Simulation, tmp_path: pathlib.Path) -> None:
    cal = etlcal.Calibration.load(ROOT / "fixtures" / "golden" / "calibrate-eiv.json")
    views = cal.views
    assert views and all(isinstance(v, ViewSummary) for v in views)
    v = views[0]
    assert v.points == v["points"] > 0 and v.rms_px == v["rms_px"] and {"fx_px", "fy_px"} <= set(v)
    std = cal.std
    assert isinstance(std, ModelStd) and std.kf_x.shape == (4,) and np.all(std.kf_x > 0)
    np.testing.assert_array_equal(std["principal_point"], std.principal_point)
    assert cal.covariance is not None
    np.testing.assert_allclose(std.kf_x ** 2, np.diag(cal.covariance)[6:10], rtol=1e-12)
    law = cal.focus_law
    if law is not None:
        assert law.views == law["views"] and len(law.coefficients_ma) == 3
    exported = etlcal.Calibration.paper_rig().export(tmp_path / "cam.yaml", 150.0, 30.0, "opencv")
    assert isinstance(exported, ExportResult) and exported.camera_matrix.shape == (3, 3)
    assert exported["fit_rms_px"] == exported.fit_rms_px < 0.1 and (tmp_path / "cam.yaml").exists()
    crlb = etlcal.cramer_rao_std(sim.observations, sim.truth, 0.1)
    assert isinstance(crlb, ModelStd) and crlb.distortion_a.shape == (9,) and "kf_y" in crlb


def test_study_returns_a_study_result() -> None:
    r = etlcal.study("fig5")
    assert isinstance(r, StudyResult) and r.name == "fig5"
    assert r["fit_rmse_mm"] == r.fit_rmse_mm == r.table["fit_rmse_mm"]
    assert "fit_rmse_mm" in r and dict(r) == r.table == r.to_dict()
    with pytest.raises(AttributeError, match="'fig5' study has no 'nope'"):
        r.nope


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda o: etlcal.calibrate(o, estimator="best"),  # type: ignore[arg-type]
         'estimator must be "paper" or "eiv", got "best"'),
        (lambda o: etlcal.calibrate(o, robust="l1"),  # type: ignore[arg-type]
         'robust must be None, "huber" or "cauchy", got "l1"'),
        (lambda o: etlcal.calibrate(o, method="zhang"),  # type: ignore[arg-type]
         'method must be "proposed" or "per-setting", got "zhang"'),
        (lambda o: etlcal.sharpness(np.zeros((8, 8), np.uint8), "sobel"),  # type: ignore[arg-type]
         'sharpness metric "sobel" .*cpbd'),
        (lambda o: etlcal.study("fig7"),  # type: ignore[arg-type]
         'no study named "fig7" .*fig5'),
        (lambda o: etlcal.simulate.paper_rig(noise="loud"),  # type: ignore[arg-type]
         'noise must be "paper", "none" or a dict'),
        (lambda o: etlcal.Calibration.paper_rig().export("x.yaml", 150.0, 30.0, "json"),  # type: ignore[arg-type]
         'format "json" is not one of opencv, ros, mrcal'),
    ],
)
def test_options_are_checked_with_a_one_line_error(sim: etlcal.Simulation, call: Any, message: str) -> None:
    with pytest.raises(etlcal.InputError, match=message) as e:
        call(sim.observations)
    assert "\n" not in str(e.value)


def test_every_word_of_the_literal_options_is_accepted_at_run_time(tmp_path: pathlib.Path) -> None:
    image = (np.arange(64 * 64).reshape(64, 64) % 251).astype(np.uint8)
    for metric in get_args(SharpnessMetric):
        assert etlcal.sharpness(image, metric) >= 0.0
    for fmt in get_args(ExportFormat):
        etlcal.Calibration.paper_rig().export(tmp_path / f"cam.{fmt}", 150.0, 30.0, fmt)
    for noise in get_args(NoisePreset):
        assert len(etlcal.simulate.paper_rig(seed=1, noise=noise).observations) == 15
    with pytest.raises(etlcal.InputError) as e:
        etlcal.study("fig7")  # type: ignore[arg-type]
    assert f"one of {', '.join(get_args(StudyName))})" in str(e.value)


def test_nothing_private_is_exported() -> None:
    assert [n for n in etlcal.__all__ if n.startswith("_") and n != "__version__"] == []
    stub = pathlib.Path(etlcal.__file__).with_name("_etlcal.pyi").read_text()
    assert '"_raise_rust_error"' not in stub
    native_all: List[str] = getattr(etlcal._etlcal, "__all__", [])
    assert "_raise_rust_error" not in native_all


def test_the_stubs_type_check_the_test_suite_and_the_package_under_mypy_strict() -> None:
    """Every test file is typed and checked against the installed stubs, as a user's strict
    code would be; the installed package's own Python sources (results, options, physics,
    ...) and its stub are checked too."""
    pytest.importorskip("mypy")
    tests = pathlib.Path(__file__).resolve().parent
    # The package by its name (`-p`), as installed: mypy 2 refuses a directory inside
    # site-packages given as a path ("This file shadows library module ...").
    for target in ([str(tests)], ["-p", "etlcal"]):
        out = subprocess.run([sys.executable, "-m", "mypy", "--strict", "--no-error-summary", *target],
                             cwd=tests, capture_output=True, text=True, timeout=600)
        assert out.returncode == 0, out.stdout + out.stderr
