"""`etlcal.calibrate_rig` on the simulated 2-camera rig of `etlcal simulate --rig 2
--observations-only`: the same numbers as `etlcal calibrate-rig` (to 1e-12), the run-time
`Rig` it returns saved as the same `etlcal.rig/1`; bad input raises InputError / FileError
in one line naming it."""
import json
import pathlib
import subprocess
from typing import Any, Dict, List, Tuple

import pytest

import etlcal


def _numbers(value: Any) -> List[float]:
    """Every number of a JSON value, depth first."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return []
    if isinstance(value, (int, float)):
        return [float(value)]
    if isinstance(value, dict):
        return [x for k in sorted(value) for x in _numbers(value[k])]
    return [x for v in value for x in _numbers(v)]


def test_calibrate_rig_equals_the_cli(tmp_path: pathlib.Path, etlcal_binary: str) -> None:
    sim = tmp_path / "sim"
    subprocess.run([etlcal_binary, "simulate", "--rig", "2", "--observations-only", "--seed", "4", "--out",
                    str(sim)], check=True, capture_output=True)
    dataset = sim / "rig_dataset.json"
    cli = tmp_path / "cli.json"
    subprocess.run([etlcal_binary, "calibrate-rig", "--dataset", str(dataset), "--out", str(cli), "--solver",
                    "dense"], check=True, capture_output=True)
    rig = etlcal.calibrate_rig(dataset, solver="dense")
    assert isinstance(rig, etlcal.Rig) and len(rig) == 2
    py = tmp_path / "py.json"
    rig.save(py)
    a: Dict[str, Any] = json.loads(cli.read_text())
    b: Dict[str, Any] = json.loads(py.read_text())
    for key in ["extrinsics", "cameras"]:
        x, y = _numbers(a[key]), _numbers(b[key])
        assert len(x) == len(y) > 0
        worst = max(abs(p - q) / max(abs(p), 1.0) for p, q in zip(x, y))
        assert worst <= 1e-12, (key, worst)
    # Against the truth: camera 1's translation within 3 std.
    truth: Dict[str, Any] = json.loads((sim / "truth_rig.json").read_text())
    e, t = b["extrinsics"][0], truth["extrinsics"][0]
    for c in range(3):
        std = e["covariance"][3 + c][3 + c] ** 0.5
        assert abs(e["translation_mm"][c] - t["translation_mm"][c]) <= 3 * std


def test_calibrate_rig_refuses_bad_input(tmp_path: pathlib.Path, etlcal_binary: str) -> None:
    sim = tmp_path / "sim"
    subprocess.run([etlcal_binary, "simulate", "--rig", "2", "--observations-only", "--seed", "4", "--out",
                    str(sim)], check=True, capture_output=True)
    d: Dict[str, Any] = json.loads((sim / "rig_dataset.json").read_text())
    d["views"][0]["cameras"][0]["camera"] = 7
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(d))
    with pytest.raises(etlcal.InputError) as err:
        etlcal.calibrate_rig(bad)
    assert "views[0].cameras[0].camera: 7 is not a camera of the rig" in str(err.value)
    assert len(str(err.value).splitlines()) == 1
    with pytest.raises(etlcal.InputError) as err:
        etlcal.calibrate_rig(sim / "rig_dataset.json", solver="fastest")  # type: ignore[arg-type]
    assert 'solver must be "auto", "dense" or "sparse", got "fastest"' in str(err.value)
    with pytest.raises(etlcal.InputError) as err:
        etlcal.calibrate_rig(sim / "rig_dataset.json", method="per-setting")
    assert "a rig is calibrated by the proposed method only" in str(err.value)
    with pytest.raises(etlcal.FileError):
        etlcal.calibrate_rig(tmp_path / "nowhere.json")


def _e_in_only(tmp_path: pathlib.Path, etlcal_binary: str) -> pathlib.Path:
    """The simulated 2-camera rig's dataset with every view's e_com_ma removed (E_in only:
    each lens's temperature surface is needed)."""
    sim = tmp_path / "sim"
    subprocess.run([etlcal_binary, "simulate", "--rig", "2", "--observations-only", "--seed", "4", "--out",
                    str(sim)], check=True, capture_output=True)
    d: Dict[str, Any] = json.loads((sim / "rig_dataset.json").read_text())
    for v in d["views"]:
        for s in v["cameras"]:
            del s["e_com_ma"]
    path = tmp_path / "e_in_only.json"
    path.write_text(json.dumps(d))
    return path


def test_per_camera_keywords_equal_the_cli_per_camera_flags(tmp_path: pathlib.Path, etlcal_binary: str) -> None:
    """`per_camera` gives camera 1 its own surface and OpenCV's family: the same numbers as
    `--thermal cam1=FILE --camera-flags cam1="--distortion opencv"` (to 1e-12), each
    camera's family in its calibration."""
    dataset = _e_in_only(tmp_path, etlcal_binary)
    surface = tmp_path / "cam1-thermal.json"
    etlcal.ThermalCalibration.paper().save(surface)
    cli = tmp_path / "cli.json"
    subprocess.run([etlcal_binary, "calibrate-rig", "--dataset", str(dataset), "--out", str(cli), "--thermal",
                    "paper", "--thermal", f"cam1={surface}", "--camera-flags", "cam1=--distortion opencv"],
                   check=True, capture_output=True)
    own = {"cam1": {"distortion": "opencv", "thermal": etlcal.ThermalCalibration.load(surface)}}
    rig = etlcal.calibrate_rig(dataset, thermal="paper", per_camera=own)
    assert [c.distortion_model for c in rig.calibrations] == ["paper", "opencv"]
    py = tmp_path / "py.json"
    rig.save(py)
    a: Dict[str, Any] = json.loads(cli.read_text())
    b: Dict[str, Any] = json.loads(py.read_text())
    for key in ["extrinsics", "cameras"]:
        x, y = _numbers(a[key]), _numbers(b[key])
        assert len(x) == len(y) > 0
        worst = max(abs(p - q) / max(abs(p), 1.0) for p, q in zip(x, y))
        assert worst <= 1e-12, (key, worst)


def test_per_camera_refuses_unknown_cameras_and_keywords(tmp_path: pathlib.Path, etlcal_binary: str) -> None:
    dataset = _e_in_only(tmp_path, etlcal_binary)
    cases: List[Tuple[Dict[str, Dict[str, Any]], str]] = [
        ({"cam1": {"distortions": "opencv"}}, 'per_camera["cam1"]: "distortions" is not a keyword of calibrate'),
        ({"cam9": {"distortion": "opencv"}}, 'the rig has no camera "cam9" (its cameras: cam0, cam1)'),
        ({"cam1": {"distortion": "fisheye"}}, 'per_camera["cam1"]: '),
        ({"cam1": {"estimator": "paper"}}, "camera 1 (cam1): invalid input: estimator: one estimator serves every"),
    ]
    for per_camera, expected in cases:
        with pytest.raises(ValueError) as err:
            etlcal.calibrate_rig(dataset, thermal="paper", per_camera=per_camera)
        assert expected in str(err.value) and len(str(err.value).splitlines()) == 1, str(err.value)
    # No silent default: camera 1's lens has no surface, shared or its own.
    with pytest.raises(etlcal.InputError) as err:
        etlcal.calibrate_rig(dataset, per_camera={"cam0": {"thermal": "paper"}})
    assert "camera 1 (cam1): views[0].cameras[1] records e_in_ma without e_com_ma" in str(err.value)


def test_per_camera_setting_views_is_honoured(tmp_path: pathlib.Path, etlcal_binary: str) -> None:
    """A camera's `setting_views="joint"` reaches its calibration: the simulated rig has no
    free views, so that camera's own calibration refuses it, named."""
    sim = tmp_path / "sim"
    subprocess.run([etlcal_binary, "simulate", "--rig", "2", "--observations-only", "--seed", "4", "--out",
                    str(sim)], check=True, capture_output=True)
    with pytest.raises(etlcal.InputError) as e:
        etlcal.calibrate_rig(sim / "rig_dataset.json", per_camera={"cam1": {"setting_views": "joint"}})
    assert "camera 1" in str(e.value) and "setting_views" in str(e.value), str(e.value)
    assert len(str(e.value).splitlines()) == 1


def test_shared_setting_views_reaches_every_camera(tmp_path: pathlib.Path, etlcal_binary: str) -> None:
    """The shared `setting_views=` is `calibrate-rig --setting-views`: "ignored" gives the
    default's numbers exactly; "joint" reaches each camera's own calibration, which refuses
    it, named, on a rig without free views (camera 0 is the first to be calibrated)."""
    sim = tmp_path / "sim"
    subprocess.run([etlcal_binary, "simulate", "--rig", "2", "--observations-only", "--seed", "4", "--out",
                    str(sim)], check=True, capture_output=True)
    dataset = sim / "rig_dataset.json"
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    etlcal.calibrate_rig(dataset, solver="dense").save(a)
    etlcal.calibrate_rig(dataset, solver="dense", setting_views="ignored").save(b)
    assert _numbers(json.loads(a.read_text())) == _numbers(json.loads(b.read_text()))
    with pytest.raises(etlcal.InputError) as e:
        etlcal.calibrate_rig(dataset, setting_views="joint")
    assert "camera 0" in str(e.value) and "setting_views" in str(e.value), str(e.value)
    assert len(str(e.value).splitlines()) == 1
    with pytest.raises(etlcal.InputError, match="setting_views must be"):
        etlcal.calibrate_rig(dataset, setting_views="both")  # type: ignore[arg-type]  # the run-time check under test
