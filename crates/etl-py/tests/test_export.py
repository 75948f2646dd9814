"""Exports of the camera at a setting, read back by each tool's own reader:
cv2.FileStorage (OpenCV), a YAML parser with ROS camera_info's keys, and mrcal itself
(Debian's python3-mrcal, for /usr/bin/python3: mrcal's PyPI release does not install
here; .ci/run installs it with apt-get)."""
import json
import os
import pathlib
import shutil
import subprocess

import numpy as np
import numpy.typing as npt
import pytest

import etlcal

cv2 = pytest.importorskip("cv2")
yaml = pytest.importorskip("yaml")

SETTING = (150.0, 30.0)  # E_in mA, degC: inside the paper's 40..240 mA, 27..37 degC


@pytest.fixture(scope="module")
def cal() -> etlcal.Calibration:
    return etlcal.Calibration.paper_rig()


def image_points(cal: etlcal.Calibration, e_com_ma: float) -> npt.NDArray[np.float64]:
    """World points whose pixels cover the image (off the fit's grid)."""
    w, h = cal.image_size
    px = np.array([[u, v] for u in np.linspace(17, w - 23, 9) for v in np.linspace(13, h - 29, 7)])
    pts = []
    for p in px:
        origin, direction = cal.ray((float(p[0]), float(p[1])), e_com_ma)
        pts.append(origin + 40.0 * direction)
    return np.array(pts)


def test_opencv_filestorage_reads_the_export(cal: etlcal.Calibration, tmp_path: pathlib.Path) -> None:
    out = tmp_path / "cam.yaml"
    r = cal.export(out, *SETTING, "opencv")
    fs = cv2.FileStorage(str(out), cv2.FILE_STORAGE_READ)
    k = fs.getNode("camera_matrix").mat()
    dist = fs.getNode("distortion_coefficients").mat().ravel()
    assert (int(fs.getNode("image_width").real()), int(fs.getNode("image_height").real())) == cal.image_size
    fs.release()
    assert np.array_equal(k, r["camera_matrix"]) and np.array_equal(dist, r["dist_coeffs"])
    e = r["e_com_ma"]
    assert e == cal.e_com(*SETTING)
    world = image_points(cal, e)
    theirs, _ = cv2.projectPoints(world, cal.rotation_rodrigues, cal.translation_mm, k, dist)
    err = np.abs(theirs.reshape(-1, 2) - cal.project(world, e)).max()
    # The stated fit error is the error users get (off the fit's grid too).
    assert err <= 1.5 * r["fit_max_px"] and r["fit_max_px"] < 0.1, (err, r)
    assert "rms" in out.read_text().splitlines()[3]


def test_ros_camera_info_yaml(cal: etlcal.Calibration, tmp_path: pathlib.Path) -> None:
    out = tmp_path / "camera_info.yaml"
    r = cal.export(out, *SETTING, "ros")
    d = yaml.safe_load(out.read_text())
    assert d["image_width"] == cal.image_size[0] and d["image_height"] == cal.image_size[1]
    assert d["distortion_model"] == "plumb_bob"
    for key, shape in [("camera_matrix", (3, 3)), ("distortion_coefficients", (1, 5)),
                       ("rectification_matrix", (3, 3)), ("projection_matrix", (3, 4))]:
        m = d[key]
        assert (m["rows"], m["cols"]) == shape
        assert all(isinstance(x, float) for x in m["data"]), key  # YAML 1.1 floats, not strings
    k = np.array(d["camera_matrix"]["data"]).reshape(3, 3)
    assert np.array_equal(k, r["camera_matrix"])
    assert np.array_equal(np.array(d["distortion_coefficients"]["data"]), r["dist_coeffs"])
    p = np.array(d["projection_matrix"]["data"]).reshape(3, 4)
    assert np.array_equal(p[:, :3], k) and np.all(p[:, 3] == 0)


def debian_python_with_mrcal() -> str:
    py = "/usr/bin/python3"
    if os.path.exists(py) and subprocess.run([py, "-c", "import mrcal"], capture_output=True).returncode == 0:
        return py
    if os.environ.get("CI"):
        pytest.fail("CI must install python3-mrcal (.ci/run does, with apt-get)")
    pytest.skip("python3-mrcal is not installed for /usr/bin/python3")


MRCAL_READ = """
import json, sys
import mrcal, numpy as np
m = mrcal.cameramodel(sys.argv[1])
lensmodel, intrinsics = m.intrinsics()
pts = np.array(json.loads(sys.argv[2]))
rt = m.extrinsics_rt_fromref()
pc = mrcal.transform_point_rt(rt, pts)
print(json.dumps({"lensmodel": lensmodel, "imagersize": m.imagersize().tolist(),
                  "pixels": mrcal.project(pc, lensmodel, intrinsics).tolist()}))
"""


def test_mrcal_reads_the_cameramodel_and_projects_as_etlcal(cal: etlcal.Calibration, tmp_path: pathlib.Path) -> None:
    py = debian_python_with_mrcal()
    out = tmp_path / "cam.cameramodel"
    r = cal.export(out, *SETTING, "mrcal")
    world = image_points(cal, r["e_com_ma"])
    got = subprocess.run([py, "-c", MRCAL_READ, str(out), json.dumps(world.tolist())],
                         capture_output=True, text=True, check=True)
    m = json.loads(got.stdout)
    assert m["lensmodel"] == "LENSMODEL_OPENCV5" and tuple(m["imagersize"]) == cal.image_size
    err = np.abs(np.array(m["pixels"]) - cal.project(world, r["e_com_ma"])).max()
    assert err <= 1.5 * r["fit_max_px"], (err, r)


def test_bad_exports_are_refused_and_write_nothing(cal: etlcal.Calibration, tmp_path: pathlib.Path) -> None:
    out = tmp_path / "x.yaml"
    with pytest.raises(etlcal.InputError, match="opencv, ros, mrcal"):
        cal.export(out, *SETTING, "json")  # type: ignore[arg-type]
    with pytest.raises(etlcal.InputError, match="temperature_c"):
        cal.export(out, 150.0, 80.0, "opencv")
    with pytest.raises(etlcal.InputError, match="e_in_ma"):
        cal.export(out, 260.0, 30.0, "opencv")
    assert not out.exists()
    r = cal.export(out, 150.0, 80.0, "opencv", allow_extrapolation=True)
    assert r["extrapolated"] and "EXTRAPOLATED" in out.read_text()
