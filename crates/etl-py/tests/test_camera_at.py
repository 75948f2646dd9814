"""CameraAt: the camera at one setting, `Calibration.at(e_in_ma, temperature_c)` or
`Calibration.at_e_com(e_com_ma)`, holds the run-time operations; Calibration's methods
taking `e_com_ma` are that camera's, to the bit. `distortion()` is named for its family
(checked against the numbers of the file), and a calibration made from views with E_com
and no thermal calibration is usable at a known E_com (issue 26)."""
import json
import math
import os
import pathlib
import pickle
import subprocess
import warnings
from typing import Callable, List, Tuple

import numpy as np
import numpy.typing as npt
import pytest

import etlcal

_F64 = npt.NDArray[np.float64]


@pytest.fixture(scope="module")
def uncompensated() -> etlcal.Calibration:
    """The simulated paper rig calibrated from its views' recorded E_com, no thermal=."""
    sim = etlcal.simulate.paper_rig(seed=1)
    with pytest.warns(UserWarning, match="no temperature compensation") as said:
        cal = etlcal.calibrate(sim.observations, sim.a0)
    mine = [w for w in said if "temperature compensation" in str(w.message)]
    assert len(mine) == 1, "said once"
    assert mine[0].filename == __file__, "at the caller's line, not inside etlcal"
    assert str(mine[0].message).endswith("use it with at_e_com(e_com_ma)")
    return cal


def board_view(cal: etlcal.Calibration, e_com_ma: float) -> Tuple[_F64, _F64, _F64]:
    """A 14 x 12 board at 60 mm, its world points, board points and pixels."""
    board = np.array([[1.5 * i, 1.5 * j, 0.0] for j in range(12) for i in range(14)])
    world = board + [0.0, 0.0, 60.0]
    return world, board, cal.project(world, e_com_ma)


def file_coefficients(cal: etlcal.Calibration, e_com_ma: float) -> List[float]:
    """Eq. 18 from the file's own numbers: c_i = a_(3i) w^2 + a_(3i+1) w + a_(3i+2), w =
    1 / f_mean, f_mean the mean of fx, fy (the kf polynomials at E_com)."""
    f = json.loads(cal.to_json())
    fx = sum(k * e_com_ma**i for i, k in enumerate(f["kf_x"]))
    fy = sum(k * e_com_ma**i for i, k in enumerate(f["kf_y"]))
    w = 2.0 / (fx + fy)
    a = f["distortion_a"]
    return [a[3 * i] * w * w + a[3 * i + 1] * w + a[3 * i + 2] for i in range(len(a) // 3)]


def test_paper_family_distortion_is_named_k1_p1_p2() -> None:
    cal = etlcal.Calibration.paper_rig()
    d = cal.distortion(100.0)
    assert isinstance(d, etlcal.PaperDistortion) and isinstance(d, etlcal.Distortion)
    assert d.model == "paper" == cal.distortion_model and d.names == ("k1", "p1", "p2")
    want = file_coefficients(cal, 100.0)
    assert len(want) == 3
    for got, w in zip((d.k1, d.p1, d.p2), want):
        assert got == pytest.approx(w, rel=1e-13)
    # Still the tuple it was, and a dict on request.
    k1, p1, p2 = d
    assert (k1, p1, p2) == (d.k1, d.p1, d.p2) == tuple(d)
    assert d.to_dict() == {"k1": d.k1, "p1": d.p1, "p2": d.p2}
    assert repr(d).startswith("PaperDistortion(k1=")
    assert pickle.loads(pickle.dumps(d)) == d
    with pytest.raises(AttributeError):
        d.k1 = 0.0  # type: ignore[misc]  # frozen: the run-time check under test
    # The camera at the setting says the same.
    at = cal.at(150.0, 30.0)
    assert at.distortion == cal.distortion(at.e_com_ma)
    # Over an array of currents: each coefficient an array of its shape.
    arr = cal.distortion(np.array([[90.0, 100.0]]))
    assert isinstance(arr, etlcal.PaperDistortion)
    assert arr.k1.shape == (1, 2)
    assert float(arr.p2[0, 1]) == d.p2


def test_opencv_family_distortion_is_k1_k2_p1_p2_k3_of_the_file() -> None:
    cal = etlcal.simulate.strong_rig(3).truth
    assert cal.distortion_model == "opencv"
    for e in (80.0, 150.0, 225.0):
        d = cal.distortion(e)
        assert isinstance(d, etlcal.OpenCvDistortion) and d.model == "opencv"
        assert d.names == ("k1", "k2", "p1", "p2", "k3") and len(d) == 5
        want = file_coefficients(cal, e)
        assert len(want) == 5
        got = [d.k1, d.k2, d.p1, d.p2, d.k3]
        for g, w in zip(got, want):
            assert g == pytest.approx(w, rel=1e-13, abs=1e-300)
        # OpenCV's own coefficients, exactly: the dist_coeffs of the exact export.
        assert got == cal.to_opencv(e).dist_coeffs.tolist()
        assert cal.at_e_com(e).distortion == d
    # The strong rig's k2 is large (about 0.15), p1 small: no longer taken for each other.
    d = cal.distortion(150.0)
    assert isinstance(d, etlcal.OpenCvDistortion)
    assert abs(d.k2) > 0.05 and abs(d.p1) < 0.01 and d[1] == d.k2 and d[2] == d.p1
    with pytest.raises(ValueError):
        k1, p1, p2 = d  # five coefficients, not three


def test_distortion_result_refuses_a_wrong_count_and_an_unknown_family() -> None:
    with pytest.raises(TypeError, match=r"PaperDistortion takes 3 coefficients \(k1, p1, p2\), got 5"):
        etlcal.PaperDistortion(1.0, 2.0, 3.0, 4.0, 5.0)
    with pytest.raises(ValueError, match="no distortion family 'brown'"):
        etlcal.Distortion.of("brown", 1.0)


def test_at_e_com_is_the_camera_at_a_known_e_com() -> None:
    cal = etlcal.Calibration.paper_rig()
    at = cal.at_e_com(100.0)
    assert at.e_com_ma == 100.0 and at.e_in_ma is None and at.temperature_c is None
    assert not at.extrapolated and at.extrapolated_quantities == []
    assert at.camera_matrix.tolist() == [[4850.0, 0.0, 900.0], [0.0, 4900.0, 550.0], [0.0, 0.0, 1.0]]
    assert at.focal_lengths == (4850.0, 4900.0) == cal.focal_lengths(100.0)
    assert at.calibration == cal
    assert repr(at).startswith("CameraAt(e_com_ma=100.0, fx=4850.0")
    # The calibrated range 80..225 mA, margin 5: refused outside it unless asked for.
    with pytest.raises(etlcal.InputError, match=r"e_com_ma = 300 is outside \[75, 230\]") as e:
        cal.at_e_com(300.0)
    assert e.value.what == "e_com_ma" and e.value.value == "300"
    far = cal.at_e_com(300.0, allow_extrapolation=True)
    assert far.extrapolated and far.extrapolated_quantities == ["e_com_ma"]
    assert cal.at_e_com(229.0).extrapolated is False
    with pytest.raises(etlcal.InputError, match="e_com_ma is NaN"):
        cal.at_e_com(math.nan)


def test_calibration_methods_are_the_camera_at_e_com_to_the_bit(uncompensated: etlcal.Calibration,
                                                                tmp_path: pathlib.Path) -> None:
    cal, e = uncompensated, 150.0
    at = cal.at_e_com(e)
    world, board, pixels = board_view(cal, e)
    assert np.array_equal(cal.project(world, e), at.project(world))
    assert np.array_equal(cal.project(world[0], e), at.project(world[0]))
    assert np.array_equal(cal.undistort(pixels, e), at.undistort(pixels))
    for a, b in zip(cal.ray((600.0, 400.0), e), at.ray((600.0, 400.0))):
        assert np.array_equal(a, b)
    noisy = pixels + np.random.default_rng(0).normal(0.0, 0.1, pixels.shape)
    p, q = cal.solve_pnp(board, noisy, e), at.solve_pnp(board, noisy)
    assert p.covariance is not None and q.covariance is not None
    assert p == q and np.array_equal(p.covariance, q.covariance)
    assert np.array_equal(cal.projection_std(world, e), at.projection_std(world))
    assert np.array_equal(cal.intrinsics(e), at.camera_matrix) and cal.focal_lengths(e) == at.focal_lengths
    assert cal.distortion(e) == at.distortion
    k, dist = cal.to_opencv(e)
    kk, dd = at.to_opencv()
    assert np.array_equal(k, kk) and np.array_equal(dist, dd) and at.to_opencv().exact is False
    assert cal.to_opencv(e).fit_rms_px == at.to_opencv().fit_rms_px
    for m, n in zip(cal.undistort_maps(e, size=(64, 48)), at.undistort_maps(size=(64, 48))):
        assert np.array_equal(m, n)
    image = (np.arange(1936 * 1458, dtype=np.uint32) % 251).astype(np.uint8).reshape(1458, 1936)
    assert np.array_equal(cal.undistort_image(image, e), at.undistort_image(image))
    # A thermal calibration: export at (E_in, T) is at(E_in, T).export, the same file.
    paper = etlcal.Calibration.paper_rig()
    r1 = paper.export(tmp_path / "a.yaml", 150.0, 30.0, "ros")
    r2 = paper.at(150.0, 30.0).export(tmp_path / "b.yaml", "ros")
    assert r1 == r2 and (tmp_path / "a.yaml").read_bytes() == (tmp_path / "b.yaml").read_bytes()
    # Every refusal is the same: the current first, then the array.
    refused: List[Callable[[], object]] = [lambda: cal.project(world, 400.0),
                                            lambda: cal.undistort(np.zeros((2, 5)), 400.0)]
    for call in refused:
        with pytest.raises(etlcal.InputError, match="e_com_ma = 400 is outside"):
            call()


def test_the_camera_at_a_setting_projects_as_the_calibration_at_its_e_com() -> None:
    cal = etlcal.Calibration.paper_rig()
    at = cal.at(150.0, 31.0)
    world, _, _ = board_view(cal, at.e_com_ma)
    assert np.array_equal(at.project(world), cal.project(world, at.e_com_ma))
    assert np.array_equal(at.project(world), cal.at_e_com(at.e_com_ma).project(world))
    assert at.e_in_ma == 150.0 and at.temperature_c == 31.0


def test_a_calibration_without_temperature_compensation_end_to_end(uncompensated: etlcal.Calibration,
                                                                  tmp_path: pathlib.Path) -> None:
    cal = uncompensated
    assert cal.thermal is None and cal.temperature_compensation == "none"
    assert json.loads(cal.to_json())["temperature_compensation"] == "none"
    again = etlcal.Calibration.from_json(cal.to_json())
    assert again == cal and again.temperature_compensation == "none"
    assert etlcal.Calibration.paper_rig().temperature_compensation is None
    # at(E_in, T) cannot be had: the error names the Python way, not a CLI flag.
    no_thermal: List[Callable[[], object]] = [lambda: cal.at(150.0, 30.0),
                                               lambda: cal.export(tmp_path / "x.yaml", 150.0, 30.0, "opencv")]
    for call in no_thermal:
        with pytest.raises(etlcal.InputError, match=r"no temperature compensation \(thermal\): use "
                                                    r"at_e_com\(e_com_ma\) with a known E_com") as e:
            call()
        assert e.value.what == "thermal" and "--" not in str(e.value)
    assert not (tmp_path / "x.yaml").exists()
    # At a known E_com: the model's pixels of the simulated rig within a pixel, an export.
    sim = etlcal.simulate.paper_rig(seed=1)
    at = cal.at_e_com(150.0)
    world, _, _ = board_view(cal, 150.0)
    assert np.max(np.abs(at.project(world) - sim.truth.project(world, 150.0))) < 1.0
    r = at.export(tmp_path / "cam.yaml", "opencv")
    assert r.e_com_ma == 150.0 and r.extrapolated is False
    text = (tmp_path / "cam.yaml").read_text()
    assert "E_com 150.0 mA" in text and "E_in" not in text
    # Outside the calibrated E_com range: refused, or marked as extrapolated.
    lo, hi = cal.e_com_range_ma
    with pytest.raises(etlcal.InputError, match="e_com_ma = 240 is outside"):
        cal.at_e_com(240.0)
    assert cal.at_e_com(240.0, allow_extrapolation=True).export(tmp_path / "far.yaml", "ros").extrapolated
    assert "EXTRAPOLATED" in (tmp_path / "far.yaml").read_text()
    # A file saying "none" beside a thermal part is refused.
    d = json.loads(etlcal.Calibration.paper_rig().to_json())
    d["temperature_compensation"] = "none"
    with pytest.raises(etlcal.InputError, match="temperature_compensation"):
        etlcal.Calibration.from_json(json.dumps(d))


def test_a_calibration_with_thermal_says_nothing_about_compensation() -> None:
    sim = etlcal.simulate.paper_rig(seed=1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cal = etlcal.calibrate(sim.observations, sim.a0, thermal="paper")
    assert cal.temperature_compensation is None and "temperature_compensation" not in cal.to_json()


def test_diff_of_two_cameras_is_the_clis(tmp_path: pathlib.Path) -> None:
    root = pathlib.Path(__file__).resolve().parents[3]
    path = root / "fixtures" / "service" / "calibration.json"
    cal = etlcal.Calibration.load(path)
    same = etlcal.diff(cal.at_e_com(150.0), cal.at_e_com(150.0))
    assert isinstance(same, etlcal.ProjectionDiff) and same.max_px < 1e-9 and same.unmapped == 0
    assert same.diff_px.shape == (48, 64) and same.grid == (64, 48)
    d = json.loads(path.read_text())
    d["principal_point"][0] += 2.0
    moved = etlcal.Calibration.from_json(json.dumps(d))
    r = etlcal.diff(cal.at_e_com(150.0), moved.at_e_com(150.0), grid=(32, 24))
    assert abs(r.rms_px - 2.0) < 1e-6 and r.rotated_rms_px < 0.2 and r.rotated_diff_px.shape == (24, 32)
    b = tmp_path / "b.json"
    moved.save(b)
    out = subprocess.run(
        [os.environ["ETLCAL_TEST_BINARY"], "diff", str(path), str(b), "--e-com", "150", "--grid", "32x24", "--json"],
        check=True, capture_output=True, text=True,
    ).stdout
    cli = json.loads(out)
    assert cli["rms_px"] == r.rms_px and cli["rotated_max_px"] == r.rotated_max_px
    with pytest.raises(etlcal.InputError, match="grid"):
        etlcal.diff(cal.at_e_com(150.0), cal.at_e_com(150.0), grid=(0, 10))
