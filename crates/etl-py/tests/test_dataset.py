"""Dataset from Python: a rendered rig (written by `etlcal simulate`), detection into
Observations, calibration; bad files as the right exceptions; pickling."""
import pickle
import subprocess

import pytest

import etlcal



def test_dataset_detect_and_calibrate(tmp_path, etlcal_binary):
    subprocess.run([etlcal_binary, "simulate", "--out", str(tmp_path), "--seed", "4", "--json"], check=True,
                   capture_output=True)
    ds = etlcal.Dataset.load(tmp_path / "dataset.json")
    assert len(ds) == 15 and ds.image_size == (1936, 1458)
    assert ds.board["inner_corners"] == (14, 12)
    obs, summary = ds.detect()
    assert summary["views_detected"] == 15 and summary["skipped"] == []
    assert obs.offstate_count == 10
    cal = etlcal.calibrate(obs, etlcal.A0.load(tmp_path / "a0.json"), estimator="eiv")
    truth = etlcal.simulate.paper_rig(4).truth
    for e in [80.0, 150.0, 225.0]:
        assert abs(cal.intrinsics(e)[0, 0] / truth.intrinsics(e)[0, 0] - 1.0) < 0.01
    again = pickle.loads(pickle.dumps(ds))
    assert again.to_json() == ds.to_json() and again.images() == ds.images()
    # A missing image is a FileError before any work.
    (tmp_path / "views" / "view02.png").unlink()
    with pytest.raises(etlcal.FileError, match="view02.png"):
        ds.detect()


def test_bad_dataset_files(tmp_path):
    bad = tmp_path / "d.json"
    bad.write_text('{"format": "etlcal.dataset/2", "image_size": [10, 10], "board": {"inner_corners": [3, 3], "square_mm": 1}}')
    with pytest.raises(etlcal.Error, match="etlcal.dataset/2"):
        etlcal.Dataset.load(bad)
    with pytest.raises(etlcal.FileError):
        etlcal.Dataset.load(tmp_path / "missing.json")
