"""`etlcal.Rig` and `etlcal.stereo` against OpenCV on the synthetic two-camera rig of
fixtures/rig (opencv family, moving centres; `etl_sim::stereo_rig`): cv2.projectPoints
through each camera at its setting gives the pixels of a point, which `triangulate`
turns back into it; the rectification is cv2.stereoRectify's on the cameras' numbers at
the settings, its maps cv2.initUndistortRectifyMap's; the exports are read by
cv2.FileStorage, a YAML parser and mrcal; bad inputs raise InputError in one line and
write nothing. `etlcal.stereo` recovers a synthetic pair's R, T from noise-free views."""
import json
import os
import pathlib
import subprocess
from typing import Any, Callable, List, Optional, Tuple

import numpy as np
import numpy.typing as npt
import pytest

import etlcal

cv2: Any = pytest.importorskip("cv2")
yaml: Any = pytest.importorskip("yaml")

RIG = pathlib.Path(__file__).resolve().parents[3] / "fixtures" / "rig" / "rig.json"
SETTINGS = [150.0, 160.0]  # E_in, mA
TEMPERATURES_C = [30.0, 31.0]
Array = npt.NDArray[np.float64]


@pytest.fixture(scope="module")
def at() -> etlcal.RigAt:
    return etlcal.Rig.load(RIG).at(SETTINGS, TEMPERATURES_C)


def opencv(cam: etlcal.CameraAt) -> Tuple[Array, Array]:
    k, d = cam.to_opencv()
    return np.asarray(k), np.asarray(d)


def pixels_of(at: etlcal.RigAt, x0: Array) -> List[Array]:
    """Each camera's pixel of `x0` (camera 0's frame at its setting), by cv2.projectPoints."""
    out = []
    for cam, (r, t) in zip(at.cameras, at.poses):
        k, d = opencv(cam)
        rvec, _ = cv2.Rodrigues(r)
        px, _ = cv2.projectPoints(x0.reshape(1, 3), rvec, t, k, d)
        out.append(px.reshape(2))
    return out


def test_triangulate_gives_cv2s_point_back_with_its_covariance(at: etlcal.RigAt) -> None:
    for x0 in [np.array([25.0, -12.0, 820.0]), np.array([-40.0, 30.0, 450.0])]:
        p = pixels_of(at, x0)
        t = at.triangulate([(float(p[0][0]), float(p[0][1])), (float(p[1][0]), float(p[1][1]))], sigma_px=0.2)
        assert np.abs(t.point_mm - x0).max() < 1e-6, (t.point_mm, x0)
        assert t.from_calibration_mm2 is not None
        # The fixture's rig has no joint covariance: independent groups, said so.
        assert t.calibration_covariance == "independent"
        assert np.allclose(t.covariance_mm2, t.from_pixels_mm2 + t.from_calibration_mm2, rtol=1e-12, atol=0)
        assert np.allclose(t.std_mm, np.sqrt(np.diag(t.covariance_mm2)))
        # The pixels' part scales with sigma^2.
        half = at.triangulate([tuple(p[0]), tuple(p[1])], sigma_px=0.1, pixel_only=True)
        assert half.from_calibration_mm2 is None and half.calibration_covariance is None
        assert np.allclose(4.0 * half.covariance_mm2, t.from_pixels_mm2, rtol=1e-9)


def test_the_pose_follows_the_settings() -> None:
    """T_k(E_0, E_k) = T_k + s_0 R_k e_z - s_k e_z, s_c = dz_c(E_c) - dz_c(E_c,ref), from
    the files' own numbers."""
    rig = etlcal.Rig.load(RIG)
    file = json.loads(RIG.read_text())["extrinsics"][0]
    dz = [json.loads((RIG.parent / n).read_text())["centre"]["dz_mm"] for n in ["left.json", "right.json"]]
    r_file = cv2.Rodrigues(np.array(file["rotation_rodrigues"]))[0]
    for settings in [[120.0, 190.0], [190.0, 120.0], [150.0, 150.0]]:
        a = rig.at(settings, TEMPERATURES_C)
        s = [np.polyval(dz[c][::-1], a.cameras[c].e_com_ma) - np.polyval(dz[c][::-1], file["reference_setting"][c]) for c in range(2)]
        want = np.array(file["translation_mm"]) + s[0] * r_file[:, 2] - s[1] * np.array([0.0, 0.0, 1.0])
        assert np.abs(a.poses[1][1] - want).max() < 1e-9 and np.allclose(a.poses[1][0], r_file, atol=1e-15)
        assert abs(s[0]) + abs(s[1]) > 0.0 or settings == [150.0, 150.0]


def test_rectification_and_maps_are_opencvs(at: etlcal.RigAt) -> None:
    m = at.stereo_rectify_maps(0, 1)
    (k1, d1), (k2, d2) = opencv(at.cameras[0]), opencv(at.cameras[1])
    size = m.image_size
    r1, r2, p1, p2, q, _, _ = cv2.stereoRectify(k1, d1, k2, d2, size, m.R, m.T.reshape(3, 1), flags=cv2.CALIB_ZERO_DISPARITY, alpha=-1)
    for ours, theirs in [(m.R1, r1), (m.R2, r2), (m.P1, p1), (m.P2, p2), (m.Q, q)]:
        assert np.allclose(ours, theirs, rtol=1e-9, atol=1e-9), (ours, theirs)
    for (mx, my), k, d, r, p in [(m.left_maps, k1, d1, r1, p1), (m.right_maps, k2, d2, r2, p2)]:
        assert mx.dtype == np.float32 and mx.shape == (size[1], size[0])
        cx, cy = cv2.initUndistortRectifyMap(k, d, r, p, size, cv2.CV_32FC1)
        inside = (cx > 0) & (cx < size[0] - 1) & (cy > 0) & (cy < size[1] - 1)
        assert inside.mean() > 0.5
        assert np.abs(mx - cx)[inside].max() < 2e-3 and np.abs(my - cy)[inside].max() < 2e-3
    # cv2.remap takes them: a point's rectified pixels lie on one row.
    x0 = np.array([20.0, -30.0, 650.0])
    rows = []
    for (r, t), rr, p in [(at.poses[0], m.R1, m.P1), (at.poses[1], m.R2, m.P2)]:
        q3 = rr @ (r @ x0 + t)
        rows.append(p[1, 1] * q3[1] / q3[2] + p[1, 2])
    assert abs(rows[0] - rows[1]) < 1e-6
    image = (np.arange(size[0] * size[1], dtype=np.uint32) % 251).astype(np.uint8).reshape(size[1], size[0])
    out = cv2.remap(image, m.left_maps[0], m.left_maps[1], cv2.INTER_LINEAR)
    assert out.shape == image.shape


def debian_python_with_mrcal() -> str:
    py = "/usr/bin/python3"
    if os.path.exists(py) and subprocess.run([py, "-c", "import mrcal"], capture_output=True).returncode == 0:
        return py
    if os.environ.get("CI"):
        pytest.fail("CI must install python3-mrcal (.ci/run does, with apt-get)")
    pytest.skip("python3-mrcal is not installed for /usr/bin/python3")


MRCAL_PROJECT = """
import json, sys
import mrcal, numpy as np
m = mrcal.cameramodel(sys.argv[1])
lensmodel, intrinsics = m.intrinsics()
pc = mrcal.transform_point_rt(m.extrinsics_rt_fromref(), np.array(json.loads(sys.argv[2])))
print(json.dumps(mrcal.project(pc, lensmodel, intrinsics).tolist()))
"""


def test_exports_are_read_by_each_tool(at: etlcal.RigAt, tmp_path: pathlib.Path) -> None:
    files = at.export_pair(tmp_path, formats=["ros", "mrcal"], maps=True)
    names = sorted(p.name for p in files)
    assert names == sorted(["stereo.yaml", "left.yaml", "right.yaml", "left.cameramodel", "right.cameramodel",
                            "left_map_x.npy", "left_map_y.npy", "right_map_x.npy", "right_map_y.npy"])
    m = at.stereo_rectify_maps(0, 1)
    fs = cv2.FileStorage(str(tmp_path / "stereo.yaml"), cv2.FILE_STORAGE_READ)
    for key in ["R1", "R2", "P1", "P2", "Q"]:
        assert np.array_equal(fs.getNode(key).mat(), getattr(m, key)), key
    assert np.array_equal(fs.getNode("T").mat().ravel(), m.T)
    fs.release()
    assert np.array_equal(np.load(tmp_path / "right_map_y.npy"), m.right_maps[1])
    right = yaml.safe_load((tmp_path / "right.yaml").read_text())
    p2 = np.array(right["projection_matrix"]["data"]).reshape(3, 4)
    assert np.array_equal(p2, m.P2) and np.array_equal(np.array(right["rectification_matrix"]["data"]).reshape(3, 3), m.R2)
    assert p2[0, 3] == pytest.approx(-p2[0, 0] * m.baseline_mm, rel=1e-3)  # stereo_image_proc's Tx = -fx' B
    py = debian_python_with_mrcal()
    x0 = np.array([[25.0, -12.0, 820.0], [-40.0, 30.0, 450.0]])
    for k, name in enumerate(["left", "right"]):
        got = subprocess.run([py, "-c", MRCAL_PROJECT, str(tmp_path / f"{name}.cameramodel"), json.dumps(x0.tolist())],
                             capture_output=True, text=True, check=True)
        theirs = np.array(json.loads(got.stdout))
        ours = np.array([pixels_of(at, x)[k] for x in x0])
        assert np.abs(theirs - ours).max() < 1e-6, (theirs, ours)


def test_bad_inputs_raise_one_line_and_write_nothing(at: etlcal.RigAt, tmp_path: pathlib.Path) -> None:
    rig = etlcal.Rig.load(RIG)
    cases: List[Tuple[Callable[[], object], str]] = [
        (lambda: rig.at([150.0], TEMPERATURES_C), "settings: the rig has 2 cameras, got 1"),
        (lambda: rig.at(SETTINGS, [30.0]), "temperatures_c: the rig has 2 cameras, got 1"),
        (lambda: rig.at([150.0, "12dpt"], TEMPERATURES_C), "camera 1 (right): invalid input: a focal_power setting"),
        (lambda: at.stereo_rectify_maps(0, 2), "pair: camera 2 is not one of the rig's cameras 0..1"),
        (lambda: at.stereo_rectify_maps(0, 1, alpha=0.0), "only -1"),
        (lambda: at.triangulate([(1000.0, 700.0), None], 0.1), "too few cameras seeing the point"),
        (lambda: at.export_pair(tmp_path / "out", 0, 3), "camera 3 is not one of the rig's cameras"),
    ]
    for call, message in cases:
        with pytest.raises(etlcal.InputError) as e:
            call()
        assert message in str(e.value) and "\n" not in str(e.value), str(e.value)
    assert not (tmp_path / "out").exists()
    # A calibration without its covariance: refused unless pixel_only.
    for name in ["left.json", "right.json"]:
        cal = json.loads((RIG.parent / name).read_text())
        if name == "right.json":
            del cal["covariance"]
        (tmp_path / name).write_text(json.dumps(cal))
    (tmp_path / "rig.json").write_text(RIG.read_text())
    bare = etlcal.Rig.load(tmp_path / "rig.json").at(SETTINGS, TEMPERATURES_C)
    with pytest.raises(etlcal.InputError, match="camera 1 \\(right\\): pass pixel-only"):
        bare.triangulate([(1000.0, 700.0), (880.0, 705.0)], 0.1)
    assert bare.triangulate([(1000.0, 700.0), (880.0, 705.0)], 0.1, pixel_only=True).from_calibration_mm2 is None
    (tmp_path / "left.json").unlink()
    with pytest.raises(etlcal.InputError, match="cameras\\[0\\].calibration_path"):
        etlcal.Rig.load(tmp_path / "rig.json")


def test_stereo_recovers_a_synthetic_pairs_pose() -> None:
    k1 = np.array([[1010.0, 0, 645.0], [0, 1005.0, 478.0], [0, 0, 1]])
    k2 = np.array([[995.0, 0, 630.0], [0, 992.0, 486.0], [0, 0, 1]])
    d1, d2 = np.array([-0.21, 0.09, 4e-4, -3e-4, -0.01]), np.array([-0.18, 0.07, -2e-4, 5e-4, 0.0])
    om, t = np.array([0.01, -0.14, 0.005]), np.array([-120.0, 1.5, 4.0])
    board = np.array([[30.0 * i, 30.0 * j, 0.0] for j in range(6) for i in range(9)])
    rng = np.random.default_rng(3)
    pairs: List[Tuple[Optional[Tuple[Array, Array]], Optional[Tuple[Array, Array]]]] = []
    for _ in range(10):
        rvec = rng.normal(0.0, 0.25, 3)
        tvec = np.array([-120.0, -75.0, 600.0]) + rng.normal(0.0, [40.0, 30.0, 60.0])
        left, _ = cv2.projectPoints(board, rvec, tvec, k1, d1)
        rl = cv2.Rodrigues(rvec)[0]
        rr = cv2.Rodrigues(om)[0] @ rl
        right, _ = cv2.projectPoints(board, cv2.Rodrigues(rr)[0], cv2.Rodrigues(om)[0] @ tvec + t, k2, d2)
        pairs.append(((board[:, :2], left.reshape(-1, 2)), (board[:, :2], right.reshape(-1, 2))))
    pairs.append((None, pairs[0][1]))
    r = etlcal.stereo(pairs, (1280, 960), model="opencv")
    assert np.abs(r.rotation_rodrigues - om).max() < 1e-6 and np.abs(r.translation_mm - t).max() < 1e-4, r
    assert r.pairs_used == list(range(10)) and r.rms_px < 1e-6 and r.intrinsics == "fixed"
    assert abs(r.left.fx - k1[0, 0]) < 1e-4 and abs(r.right.v0 - k2[1, 2]) < 1e-4
    with pytest.raises(etlcal.InputError, match="intrinsics"):
        etlcal.stereo(pairs, (1280, 960), model="opencv", intrinsics="both")  # type: ignore[arg-type]
