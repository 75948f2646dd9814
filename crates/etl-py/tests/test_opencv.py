"""to_opencv: with fx = fy, cv2.projectPoints with the exported K and dist agrees with
etlcal's projection to 1e-3 px. Needs opencv-python-headless (scripts/test.sh installs
it into the test environment)."""
import numpy as np
import pytest

import etlcal

cv2 = pytest.importorskip("cv2")

A = [-0.067, -5.19e-5, 1.09e-8, -0.0077, 0.103, -1.93e-5, 0.11, -0.0257, 5.6e-6]


@pytest.mark.parametrize("e_com_ma", [80.0, 150.0, 225.0])
def test_cv2_project_points_agrees(e_com_ma: float) -> None:
    kf = [5380.0, -7.0, 0.02, -3e-5]
    cal = etlcal.Calibration([0.2, 0.2, 0.2], [-11.0, -4.0, 48.0], kf, kf, (900.0, 550.0), A)
    world = np.array([[1.5 * i, 1.5 * j, z] for z in (75.0, 31.0, 10.0) for j in range(12) for i in range(14)])
    ours = cal.project(world, e_com_ma)
    k, dist = cal.to_opencv(e_com_ma)
    theirs, _ = cv2.projectPoints(world, cal.rotation_rodrigues, cal.translation_mm, k, dist)
    err = np.max(np.abs(theirs.reshape(-1, 2) - ours))
    assert err < 1e-3, err
    # The distortion is not negligible there: without it the pixels differ by > 0.1 px.
    plain, _ = cv2.projectPoints(world, cal.rotation_rodrigues, cal.translation_mm, k, np.zeros(5))
    assert np.max(np.abs(plain.reshape(-1, 2) - ours)) > 0.1
