"""The OpenCV export of an opencv-family calibration is exact (issue 16): with
`to_opencv(E)`, cv2.projectPoints reproduces `Calibration.project` to 1e-9 px at five
currents, and cv2.initUndistortRectifyMap reproduces etlcal's own undistortion maps (to
float32 rounding: both maps are float32, 6e-5 px apart near 1000 px; see the test). The calibration: the strong-distortion rig (k1 about -0.3, k2 about 0.15),
calibrated by etlcal from its simulated corners with distortion="opencv", and its truth.
The paper family's export says its fit error (`exact`, `fit_rms_px`)."""
from typing import Any, Tuple

import numpy as np
import numpy.typing as npt
import pytest

import etlcal

cv2: Any = pytest.importorskip("cv2")

CURRENTS = [80.0, 115.0, 150.0, 190.0, 225.0]


@pytest.fixture(scope="module")
def strong() -> Tuple[etlcal.simulate.Simulation, etlcal.Calibration]:
    sim = etlcal.simulate.strong_rig(3)
    cal = etlcal.calibrate(sim.observations, thermal="paper", distortion="opencv")
    return sim, cal


def world_points(sim: etlcal.simulate.Simulation) -> npt.NDArray[np.float64]:
    obs = sim.observations
    return np.concatenate([obs[k].world_mm for k in range(len(obs))])


@pytest.mark.parametrize("which", ["calibrated", "truth"])
def test_cv2_project_points_reproduces_project_to_1e_9_px(
        strong: Tuple[etlcal.simulate.Simulation, etlcal.Calibration], which: str) -> None:
    sim, cal = strong
    cal = cal if which == "calibrated" else sim.truth
    assert cal.distortion_model == "opencv" and cal.focal_degree == 3
    world = world_points(sim)
    for e in CURRENTS:
        ours = cal.project(world, e)
        k, dist = cal.to_opencv(e)
        exported = cal.to_opencv(e)
        assert exported.exact and exported.fit_rms_px == 0.0 and exported.fit_max_px == 0.0
        theirs, _ = cv2.projectPoints(world, cal.rotation_rodrigues, cal.translation_mm, k, dist)
        err = np.max(np.abs(theirs.reshape(-1, 2) - ours))
        assert err < 1e-9, (e, err)
        # A wide lens: without the distortion the pixels differ by tens of px.
        plain, _ = cv2.projectPoints(world, cal.rotation_rodrigues, cal.translation_mm, k, np.zeros(5))
        assert np.max(np.abs(plain.reshape(-1, 2) - ours)) > 20.0
        assert dist[0] < -0.25 and dist[1] > 0.1


def test_cv2_init_undistort_rectify_map_reproduces_undistort_maps(
        strong: Tuple[etlcal.simulate.Simulation, etlcal.Calibration]) -> None:
    """Both maps are float32 (cv2 has no float64 map): an entry near 1000 px is stored to
    6e-5 px. So: etlcal's map is OpenCV's map rounded once to float32 (checked against
    cv2.projectPoints of each output pixel's ray in float64, the definition of
    initUndistortRectifyMap, to half a float32 step + 1e-9 px), and the two float32 maps
    are within 1e-6 px entry for entry but where their float64 values straddle a rounding
    boundary (one float32 step, at most 1e-5 of the entries; measured: 1 of 5.6 million at
    one of ten settings). (cv2's own map is off its projectPoints by up to 3e-8 px near 0.)"""
    _, cal = strong
    w, h = cal.image_size
    differing = 0
    for e in CURRENTS:
        k, dist = cal.to_opencv(e)
        for new_k in (k, np.array([[0.7 * k[0, 0], 0, 900.0], [0, 0.7 * k[1, 1], 700.0], [0, 0, 1]])):
            ours = np.stack(cal.undistort_maps(e, new_camera_matrix=new_k), axis=-1)
            cv = np.stack(cv2.initUndistortRectifyMap(k, dist, None, new_k, (w, h), cv2.CV_32FC1), axis=-1)
            # 1e-6 px, or one float32 step where that is coarser (either side's step, where
            # they straddle a power of two).
            step = np.maximum(np.spacing(np.abs(cv)), np.spacing(np.abs(ours)))
            diff = np.abs(ours.astype(np.float64) - cv)
            assert np.all(diff <= np.maximum(1e-6, step)), (e, diff.max())
            differing += int(np.count_nonzero(diff > 1e-6))
            # The float64 map, every 9th row: each output pixel's ray through cv2.projectPoints.
            ys, xs = np.mgrid[0:h:9, 0:w].reshape(2, -1)
            rays = np.stack([(xs - new_k[0, 2]) / new_k[0, 0], (ys - new_k[1, 2]) / new_k[1, 1], np.ones(xs.size)], 1)
            exact, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), k, dist)
            ours_rows = ours[0:h:9].reshape(-1, 2).astype(np.float64)
            err = np.abs(ours_rows - exact.reshape(-1, 2)) - 0.5 * np.spacing(np.abs(exact.reshape(-1, 2)).astype(np.float32))
            assert err.max() <= 1e-9, (e, err.max())
    assert differing <= 1e-5 * 2 * w * h * 2 * len(CURRENTS), differing


def test_paper_family_export_says_its_fit_error() -> None:
    sim = etlcal.simulate.paper_rig(1, noise="none")
    cal = sim.truth
    assert cal.distortion_model == "paper"
    exported = cal.to_opencv(150.0)
    k, dist = exported  # unpacks as the (K, dist) tuple it always was
    assert isinstance(exported, tuple) and len(exported) == 2
    assert exported.camera_matrix is k and exported.dist_coeffs is dist
    assert not exported.exact
    # fx != fy on the paper rig: the fit is close, not exact (docs/METHOD.md).
    assert 0.0 < exported.fit_rms_px <= exported.fit_max_px < 0.1
    assert "least-squares fit" in repr(exported) and "exact" not in repr(exported)
    many = cal.to_opencv(np.array([100.0, 150.0, 200.0]))
    assert many[0].shape == (3, 3, 3) and many[1].shape == (3, 5) and many.fit_rms_px.shape == (3,)
    assert "exact" in repr(etlcal.simulate.strong_rig(1, noise="none").truth.to_opencv(150.0))
