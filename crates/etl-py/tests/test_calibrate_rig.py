"""`etlcal.calibrate_rig` on the simulated 2-camera rig of `etlcal simulate --rig 2
--observations-only`: the same numbers as `etlcal calibrate-rig` (to 1e-12), the run-time
`Rig` it returns saved as the same `etlcal.rig/1`; bad input raises InputError / FileError
in one line naming it."""
import json
import pathlib
import subprocess
from typing import Any, Dict, List

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
