"""zhang(model="opencv") against OpenCV's calibrateCamera on the two public wide-lens image
sets of fixtures/wide (sources in fixtures/wide/SOURCE.md; k1 < -0.25), live with cv2
(issue 16; benches/zhang_opencv.py --wide prints the same comparison):

* same corners: on etlcal's corners, etlcal reproduces cv2.calibrateCameraExtended: fx, fy,
  cx, cy, k1, k2, p1, p2, k3 each within 0.01 of OpenCV's standard deviation of it; the
  standard deviations and per-view RMS are OpenCV's too;
* end to end: etlcal (its corners, its solver) uses every view OpenCV uses (its corners:
  findChessboardCorners + cornerSubPix 11x11) and reaches at most OpenCV's RMS.
"""
import pathlib
from typing import Any, Dict, List, Tuple

import numpy as np
import numpy.typing as npt
import pytest

import etlcal

# cv2 as Any (through importorskip, as test_opencv.py): its stubs type calibrateCamera's
# optional outputs too narrowly for None.
cv2: Any = pytest.importorskip("cv2")

WIDE = pathlib.Path(__file__).resolve().parents[3] / "fixtures" / "wide"
SETS = [("opencv_left", (9, 6)), ("stereo752_left", (11, 8))]
CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 500, 1e-15)
FLAGS = [(False, False), (True, False), (True, True)]


def board(cols: int, rows: int) -> npt.NDArray[np.float32]:
    obj = np.zeros((rows * cols, 3), np.float32)
    obj[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2)
    return obj


def images(name: str) -> List[Tuple[pathlib.Path, npt.NDArray[np.uint8]]]:
    paths = sorted((WIDE / name).glob("*.jpg"))
    assert paths, f"fixtures/wide/{name} is empty"
    return [(p, cv2.imread(str(p), cv2.IMREAD_GRAYSCALE)) for p in paths]


def cv_flags(fix_k3: bool, zero_tangent: bool) -> int:
    return int((cv2.CALIB_FIX_K3 if fix_k3 else 0) | (cv2.CALIB_ZERO_TANGENT_DIST if zero_tangent else 0))


@pytest.mark.parametrize("name,pattern", SETS)
@pytest.mark.parametrize("fix_k3,zero_tangent", FLAGS)
def test_same_corners_reproduce_cv2_calibrate_camera(name: str, pattern: Tuple[int, int], fix_k3: bool,
                                                      zero_tangent: bool) -> None:
    imgs = images(name)
    size = (imgs[0][1].shape[1], imgs[0][1].shape[0])
    # etlcal's corners, rounded once to float32 (what cv2 takes) and given to both solvers.
    corners = [etlcal.detect_corners(g, pattern).astype(np.float32) for _, g in imgs]
    obj = board(*pattern)
    rms, k, dist, _, _, std, _, per_view = cv2.calibrateCameraExtended(
        [obj] * len(corners), [c.reshape(-1, 1, 2) for c in corners], size, None, None,
        flags=cv_flags(fix_k3, zero_tangent), criteria=CRITERIA)
    r = etlcal.zhang([(obj[:, :2], c.astype(np.float64)) for c in corners], size, model="opencv",
                     fix_k3=fix_k3, zero_tangent=zero_tangent)
    assert isinstance(r, etlcal.ZhangOpenCvResult) and isinstance(r, etlcal.ZhangResult)
    got = np.array([r.fx, r.fy, r.u0, r.v0, *r.dist_coeffs])
    want = np.array([k[0, 0], k[1, 1], k[0, 2], k[1, 2], *dist.ravel()[:5]])
    sd = std.ravel()[:9]
    free = sd > 0
    assert np.all(np.abs(got - want)[free] <= 0.01 * sd[free]), (got - want) / np.where(free, sd, 1.0)
    # A coefficient a flag holds is 0 on both sides, with no standard deviation.
    assert np.all(got[~free] == 0.0) and np.all(np.asarray(r.std)[~free] == 0.0)
    np.testing.assert_allclose(np.asarray(r.std)[free], sd[free], rtol=0.01)
    np.testing.assert_allclose(r.per_view_rms_px, per_view.ravel(), atol=1e-4)
    assert abs(r.rms_px - rms) < 1e-5
    np.testing.assert_array_equal(r.camera_matrix, [[r.fx, 0, r.u0], [0, r.fy, r.v0], [0, 0, 1]])
    assert (r.k1, r.k2, r.p1, r.p2, r.k3) == tuple(r.dist_coeffs) and r.model == "opencv"


@pytest.mark.parametrize("name,pattern", SETS)
def test_end_to_end_every_opencv_view_and_no_larger_rms(name: str, pattern: Tuple[int, int]) -> None:
    imgs = images(name)
    size = (imgs[0][1].shape[1], imgs[0][1].shape[0])
    cv_found: List[Any] = []
    views: List[Tuple[Any, Any]] = []
    for _, g in imgs:
        ok, c = cv2.findChessboardCorners(g, pattern)
        if ok:
            cv_found.append(cv2.cornerSubPix(g, c, (11, 11), (-1, -1),
                                             (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 100, 1e-4)))
        try:
            views.append((board(*pattern)[:, :2], etlcal.detect_corners(g, pattern)))
        except etlcal.BoardNotFoundError:
            assert not ok, "etlcal misses a board OpenCV finds"
    obj = board(*pattern)
    cv_rms = cv2.calibrateCamera([obj] * len(cv_found), cv_found, size, None, None, criteria=CRITERIA)[0]
    r = etlcal.zhang(views, size, model="opencv")
    # k1 < -0.25: wide lenses, as the sets were chosen.
    assert r.dist_coeffs[0] < -0.25
    assert r.views_used == len(views) >= len(cv_found) == len(imgs)
    assert r.rms_px <= cv_rms, (r.rms_px, cv_rms)


def test_bad_model_and_flags_are_one_line_errors() -> None:
    views = [(board(9, 6)[:, :2], etlcal.detect_corners(g, (9, 6))) for _, g in images("opencv_left")[:4]]
    cases: List[Tuple[Dict[str, Any], str]] = [
        ({"fix_k3": True}, "fix_k3=True is an OpenCV flag"),
        ({"zero_tangent": True}, "zero_tangent=True is an OpenCV flag"),
        ({"model": "brown"}, 'model must be "paper" or "opencv", got "brown"'),
    ]
    for kwargs, words in cases:
        with pytest.raises(etlcal.InputError, match=words) as e:
            etlcal.zhang(views, (640, 480), **kwargs)
        assert "\n" not in str(e.value)
    paper = etlcal.zhang(views, (640, 480))
    assert type(paper) is etlcal.ZhangResult and "dist_coeffs" not in paper
