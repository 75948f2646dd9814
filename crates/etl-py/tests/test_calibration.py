"""Calibration: the camera model at run time, against the Rust results (to 1e-12), files,
pickling, and every bad input surfacing as the right exception with the Rust message."""
import json
import math
import pathlib
import pickle
from typing import Any, Callable, Dict, List, Optional, Tuple, Type

import numpy as np
import pytest

import etlcal

PAPER_A = [-0.067, -5.19e-5, 1.09e-8, -0.0077, 0.103, -1.93e-5, 0.11, -0.0257, 5.6e-6]


@pytest.fixture
def cal() -> etlcal.Calibration:
    return etlcal.Calibration.paper_rig()


def test_paper_rig_numbers(cal: etlcal.Calibration) -> None:
    assert cal.kf_x.tolist() == [5380.0, -7.0, 0.02, -3e-5]
    assert cal.kf_y.tolist() == [5430.0, -7.0, 0.02, -3e-5]
    assert cal.principal_point.tolist() == [900.0, 550.0]
    assert cal.distortion_a.tolist() == PAPER_A
    assert cal.rotation_rodrigues.tolist() == [0.2, 0.2, 0.2]
    assert cal.translation_mm.tolist() == [-11.0, -4.0, 48.0]
    assert cal.image_size == (1936, 1458)
    assert cal.e_com_range_ma == (80.0, 225.0)
    assert cal.thermal == etlcal.ThermalSurface.paper()
    # A model given, not estimated: zero RMS and standard deviations, no estimator.
    assert cal.rms_px == 0.0 and cal.estimator is None and cal.iterations == 0
    assert cal.std["kf_x"].tolist() == [0.0] * 4 and cal.views == [] and cal.initial_rms_px == 0.0
    r = cal.rotation_matrix
    assert r.shape == (3, 3) and np.allclose(r @ r.T, np.eye(3), atol=1e-15)


def test_intrinsics_and_distortion_by_hand(cal: etlcal.Calibration) -> None:
    # fx(100) = 5380 - 700 + 200 - 30 = 4850, fy = 4900 (Eq. 16).
    k = cal.intrinsics(100.0)
    assert k.shape == (3, 3) and k.dtype == np.float64
    assert k.tolist() == [[4850.0, 0.0, 900.0], [0.0, 4900.0, 550.0], [0.0, 0.0, 1.0]]
    assert cal.focal_lengths(100.0) == (4850.0, 4900.0)
    w = 1 / 4875.0  # 1 / f_mean (Eq. 18)
    a = PAPER_A
    k1, p1, p2 = cal.distortion(100.0)
    assert k1 == pytest.approx(a[0] * w * w + a[1] * w + a[2], rel=1e-14)
    assert p1 == pytest.approx(a[3] * w * w + a[4] * w + a[5], rel=1e-14)
    assert p2 == pytest.approx(a[6] * w * w + a[7] * w + a[8], rel=1e-14)


def test_project_and_undistort_agree_with_rust(cal: etlcal.Calibration, rust_reference: Dict[str, Any]) -> None:
    world = np.array(rust_reference["world_mm"])
    assert world.shape == (504, 3)
    for ref in rust_reference["project"]:
        px = cal.project(world, ref["e_com_ma"])
        assert px.shape == (504, 2) and px.dtype == np.float64
        assert np.max(np.abs(px - np.array(ref["pixels"]))) <= 1e-12
    for ref in rust_reference["undistort"]:
        und = cal.undistort(np.array(ref["pixels"]), ref["e_com_ma"])
        assert np.max(np.abs(und - np.array(ref["undistorted"]))) <= 1e-12


def test_project_accepts_lists_single_points_and_any_layout(cal: etlcal.Calibration) -> None:
    world = np.array([[6.0, 9.0, 48.0], [0.0, 0.0, 48.0], [3.0, 1.5, 22.0]])
    ref = cal.project(world, 120.0)
    assert np.array_equal(cal.project(world.tolist(), 120.0), ref)
    assert np.array_equal(cal.project(np.asfortranarray(world), 120.0), ref)
    assert np.array_equal(cal.project(world.astype(np.float32).astype(np.float64), 120.0), ref)
    strided = np.zeros((3, 6))
    strided[:, ::2] = world
    assert np.array_equal(cal.project(strided[:, ::2], 120.0), ref)
    one = cal.project(world[0], 120.0)
    assert one.shape == (2,) and np.array_equal(one, ref[0])
    assert cal.project(np.zeros((0, 3)), 120.0).shape == (0, 2)
    assert np.array_equal(cal.undistort(ref[1], 120.0), cal.undistort(ref, 120.0)[1])


def test_undistort_inverts_project_without_distortion(cal: etlcal.Calibration) -> None:
    # The undistorted pixel is the pinhole projection (Eq. 15) in the same image frame.
    world = np.array([[i * 1.5, j * 1.5, 31.0] for i in range(14) for j in range(12)])
    e = 130.0
    fx, fy = cal.focal_lengths(e)
    r, t = cal.rotation_matrix, cal.translation_mm
    pc = world @ r.T + t
    ideal = np.stack([fx * pc[:, 0] / pc[:, 2] + 900.0, fy * pc[:, 1] / pc[:, 2] + 550.0], axis=1)
    und = cal.undistort(cal.project(world, e), e)
    assert np.max(np.abs(und - ideal)) < 1e-8


def test_ray_goes_through_the_point(cal: etlcal.Calibration) -> None:
    p = np.array([4.5, 7.5, 31.0])
    px = cal.project(p, 150.0)
    origin, direction = cal.ray(tuple(px), 150.0)
    assert direction.shape == (3,) and math.isclose(np.linalg.norm(direction), 1.0, rel_tol=1e-14)
    v = p - origin
    s = v @ direction
    assert np.linalg.norm(v - s * direction) < 1e-9 and s > 0


def test_e_com_uses_the_thermal_surface(cal: etlcal.Calibration, rust_reference: Dict[str, Any]) -> None:
    th = cal.thermal_calibration
    assert th is not None
    (t0, t1), (e0, e1) = th.t_range_c, th.e_in_range_ma
    for ref in rust_reference["thermal"]:
        t, e_in = ref["temperature_c"], ref["e_in_ma"]
        inside = t0 - 1.0 <= t <= t1 + 1.0 and e0 - 5.0 <= e_in <= e1 + 5.0
        if not inside:
            # Outside the calibrated 27..37 degC x 40..240 mA (margins 1 degC, 5 mA):
            # refused, naming the quantity.
            with pytest.raises(etlcal.InputError, match="temperature_c|e_in_ma"):
                cal.e_com(e_in, t)
        e = cal.e_com(ref["e_in_ma"], ref["temperature_c"], allow_extrapolation=not inside)
        assert isinstance(e, float) and abs(e - ref["e_com_ma"]) <= 1e-12
    grid = cal.e_com(np.array([40.0, 120.0, 200.0]), 33.0)
    assert grid.shape == (3,)
    back = cal.e_in_for_e_com(grid, 33.0)
    assert np.max(np.abs(back - [40.0, 120.0, 200.0])) < 1e-8


def test_constructor_round_trips_and_validates() -> None:
    c = etlcal.Calibration(
        [0.1, -0.2, 0.05], [1, 2, 100], [5000, -5, 0.01, 0], [5000, -5, 0.01, 0], (960, 540), [0] * 9,
        image_size=(1920, 1080), e_com_range_ma=(50, 200), rms_px=0.25,
    )
    assert c.image_size == (1920, 1080) and c.rms_px == 0.25 and c.thermal is None
    assert c.distortion(100.0) == (0.0, 0.0, 0.0)
    with pytest.raises(etlcal.InputError) as info:
        etlcal.Calibration([math.nan, 0, 0], [0, 0, 1], [1, 0, 0, 0], [1, 0, 0, 0], (0, 0), [0] * 9)
    assert str(info.value) == "rotation_rodrigues is NaN or infinite; pass finite numbers"
    with pytest.raises(etlcal.InputError, match="kf_x must be 4 numbers"):
        etlcal.Calibration([0, 0, 0], [0, 0, 1], [1, 0, 0], [1, 0, 0, 0], (0, 0), [0] * 9)
    with pytest.raises(etlcal.InputError) as info:
        etlcal.Calibration([0, 0, 0], [0, 0, 1], [1, 0, 0, 0], [1, 0, 0, 0], (0, 0), [0] * 9, rms_px=math.inf)
    assert str(info.value) == "rms_px is NaN or infinite; pass finite numbers"
    with pytest.raises(etlcal.InputError, match="e_com_range_ma"):
        etlcal.Calibration([0, 0, 0], [0, 0, 1], [1, 0, 0, 0], [1, 0, 0, 0], (0, 0), [0] * 9, e_com_range_ma=(5, 1))
    with pytest.raises(etlcal.InputError, match="image_size"):
        etlcal.Calibration([0, 0, 0], [0, 0, 1], [1, 0, 0, 0], [1, 0, 0, 0], (0, 0), [0] * 9, image_size=(0, 10))


def test_save_load_json_and_pickle(cal: etlcal.Calibration, tmp_path: pathlib.Path) -> None:
    path = tmp_path / "calibration.json"
    cal.save(path)
    back = etlcal.Calibration.load(path)
    assert back == cal
    assert etlcal.Calibration.load(str(path)) == cal
    assert etlcal.Calibration.from_json(cal.to_json()) == cal
    assert pickle.loads(pickle.dumps(cal)) == cal
    assert '"format": "etlcal.calibration/1"' in cal.to_json()
    # A misspelt key is an error, not a silent default.
    text = cal.to_json().replace('"kf_x"', '"kfx"', 1)
    with pytest.raises(etlcal.InputError, match="unknown field `kfx`"):
        etlcal.Calibration.from_json(text)


def test_file_errors(tmp_path: pathlib.Path) -> None:
    missing = tmp_path / "nope.json"
    with pytest.raises(etlcal.FileError) as info:
        etlcal.Calibration.load(missing)
    assert str(info.value).startswith(str(missing) + ": ")
    assert isinstance(info.value, OSError)
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "etlcal.thermal/1"}')
    with pytest.raises(etlcal.InputError) as refused:
        etlcal.Calibration.load(bad)
    assert str(refused.value) == f'{bad}: format "etlcal.thermal/1" is not supported (expected "etlcal.calibration/1")'
    bad.write_text("{ not json")
    with pytest.raises(etlcal.InputError, match=r"key must be a string at line 1"):
        etlcal.Calibration.load(bad)
    with pytest.raises(etlcal.InputError, match="missing field"):
        etlcal.Calibration.from_json('{"format": "etlcal.calibration/1"}')
    with pytest.raises(etlcal.FileError):
        etlcal.Calibration.paper_rig().save(tmp_path / "no" / "such" / "dir.json")


def test_bad_inputs_raise_the_rust_message(cal: etlcal.Calibration) -> None:
    cases: List[Tuple[Callable[[], object], Type[etlcal.Error], Optional[str]]] = [
        (lambda: cal.project([[math.nan, 0, 48]], 100.0), etlcal.InputError,
         "world_mm is NaN or infinite; pass finite numbers"),
        (lambda: cal.project([[0, 0, -1000]], 100.0), etlcal.InputError,
         "point is at or behind the camera (Z_C <= 0); check the pose and units (mm)"),
        (lambda: cal.project([[0, 0, 48]], math.inf), etlcal.InputError,
         "e_com_ma is NaN or infinite; pass finite numbers"),
        # Outside the calibrated E_com range (80..225 mA, margin 5): refused by name...
        (lambda: cal.intrinsics(2000.0), etlcal.InputError, "e_com_ma = 2000 is outside [75, 230]"),
        # ...and where asked to extrapolate, the model's own limit still holds.
        (lambda: cal.intrinsics(2000.0, allow_extrapolation=True), etlcal.InputError,
         "degenerate input: focal length is not positive at this current"),
        (lambda: cal.distortion(math.nan), etlcal.InputError,
         "e_com_ma is NaN or infinite; pass finite numbers"),
        (lambda: cal.focal_lengths(400.0), etlcal.InputError, "e_com_ma = 400 is outside [75, 230]"),
        (lambda: cal.to_opencv(2000.0), etlcal.InputError, "e_com_ma = 2000 is outside [75, 230]"),
        (lambda: cal.undistort([[math.nan, 3.0]], 100.0), etlcal.InputError,
         "pixel is NaN or infinite; pass finite numbers"),
        (lambda: cal.ray((1e7, 1e7), 100.0), etlcal.InputError, None),
        # The thermal calibration's ranges (27..37 degC, 40..240 mA, margins 1 degC, 5 mA).
        (lambda: cal.e_com(150.0, 80.0), etlcal.InputError, "temperature_c = 80 is outside [26, 38]"),
        (lambda: cal.e_com(1e5, 30.0), etlcal.InputError, "e_in_ma = 1e5 is outside [35, 245]"),
        # Beyond the lens's operating domain even extrapolation is refused.
        (lambda: cal.e_com(100.0, 300.0, allow_extrapolation=True), etlcal.InputError,
         "t_c = 300 is outside [-40, 125]"),
        (lambda: cal.e_com(math.nan, 30.0), etlcal.InputError, "e_in_ma is NaN or infinite; pass finite numbers"),
        (lambda: cal.e_in_for_e_com(math.nan, 30.0), etlcal.InputError,
         "e_com_ma is NaN or infinite; pass finite numbers"),
    ]
    for call, cls, message in cases:
        with pytest.raises(cls) as info:
            call()
        if message is not None:
            assert str(info.value) == message


def test_undistort_beyond_the_fold_is_an_error_not_a_wrong_answer() -> None:
    # Strong barrel distortion (k1 = -1e-6 / px^2 at f = 1000) folds the image.
    a = [0, 0, -1e-6, 0, 0, 0, 0, 0, 0]
    c = etlcal.Calibration([0, 0, 0], [0, 0, 100], [1000, 0, 0, 0], [1000, 0, 0, 0], (0, 0), a)
    with pytest.raises(etlcal.Error) as info:
        c.undistort([[2000.0, 0.0]], 100.0)
    assert isinstance(info.value, (etlcal.InputError, etlcal.NotConvergedError))


def test_shape_errors_are_input_errors(cal: etlcal.Calibration) -> None:
    with pytest.raises(etlcal.InputError, match=r"world_mm must have shape \(N, 3\) or \(3,\), got \[4, 2\]"):
        cal.project(np.zeros((4, 2)), 100.0)
    with pytest.raises(etlcal.InputError, match=r"pixels must have shape \(N, 2\)"):
        cal.undistort(np.zeros((2, 2, 2)), 100.0)
    with pytest.raises(ValueError):
        cal.project("abc", 100.0)


def test_no_thermal_part(cal: etlcal.Calibration) -> None:
    d = json.loads(cal.to_json())
    del d["thermal"]
    c = etlcal.Calibration.from_json(json.dumps(d))
    assert c.thermal is None
    with pytest.raises(etlcal.InputError, match="no temperature compensation"):
        c.e_com(100.0, 30.0)


def test_to_opencv_conventions() -> None:
    # fx = fy: OpenCV's model holds etlcal's exactly (k1_cv = k1 f^2, p1_cv = p2 f,
    # p2_cv = p1 f, k2 = k3 = 0), and the fit finds those numbers.
    kf = [5380.0, -7.0, 0.02, -3e-5]
    a = [-0.067, -5.19e-5, 1.09e-8, -0.0077, 0.103, -1.93e-5, 0.11, -0.0257, 5.6e-6]
    c = etlcal.Calibration([0.2, 0.2, 0.2], [-11.0, -4.0, 48.0], kf, kf, (900.0, 550.0), a)
    k, dist = c.to_opencv(100.0)
    assert k.tolist() == c.intrinsics(100.0).tolist()
    k1, p1, p2 = c.distortion(100.0)
    f = 4850.0
    assert dist.shape == (5,)
    assert dist[0] == pytest.approx(k1 * f * f, rel=1e-9)
    assert abs(dist[1]) < 1e-9 and abs(dist[4]) < 1e-9
    assert dist[2] == pytest.approx(p2 * f, rel=1e-9)  # OpenCV's p1 is the paper's p2
    assert dist[3] == pytest.approx(p1 * f, rel=1e-9)


def test_repr(cal: etlcal.Calibration) -> None:
    assert repr(cal).startswith("Calibration(kf_x=[5380.0")
