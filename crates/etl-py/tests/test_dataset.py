"""Dataset from Python: a rendered rig (written by `etlcal simulate`), detection into
Observations, calibration; bad files as the right exceptions; pickling."""
import json
import pathlib
import pickle
import subprocess

import pytest

import etlcal



def test_dataset_detect_and_calibrate(tmp_path: pathlib.Path, etlcal_binary: str) -> None:
    subprocess.run([etlcal_binary, "simulate", "--out", str(tmp_path), "--seed", "4", "--json"], check=True,
                   capture_output=True)
    ds = etlcal.Dataset.load(tmp_path / "dataset.json")
    assert len(ds) == 15 and ds.image_size == (1936, 1458)
    # The rig's ChArUco board: partial views, no per-view hints.
    assert ds.board["type"] == "charuco" and ds.board["squares"] == (15, 13)
    assert etlcal.Board.from_dict(ds.board).inner_corners == (14, 12)
    obs, summary = ds.detect()
    assert summary["views_detected"] == 15 and summary["skipped"] == []
    assert obs.offstate_count == 10
    cal = etlcal.calibrate(obs, etlcal.A0.load(tmp_path / "a0.json"), estimator="eiv")
    truth = etlcal.simulate.paper_rig(4).truth
    for e in [80.0, 150.0, 225.0]:
        assert abs(cal.intrinsics(e)[0, 0] / truth.intrinsics(e)[0, 0] - 1.0) < 0.01
    # The same file built view by view from Python (what a capture script does).
    truth = json.loads(ds.to_json())
    built = etlcal.Dataset(tuple(truth["image_size"]), board=etlcal.Board.from_dict(truth["board"]),
                           offstate_board=etlcal.Board.from_dict(truth["offstate_board"]), base_dir=tmp_path)
    for v in truth["views"]:
        built.add_view(v["image"], v["e_in_ma"], v["temperature_c"], v["z_w_mm"], v.get("e_com_ma"))
    for v in truth.get("offstate_views", []):
        built.add_offstate_view(v["image"])
    for v in truth.get("setting_views", []):
        built.add_setting_view(v["image"], v["e_in_ma"], v["temperature_c"], v.get("e_com_ma"))
    assert json.loads(built.to_json()) == truth
    assert built.images() == ds.images() and built.offstate_count == ds.offstate_count == 10
    again = pickle.loads(pickle.dumps(ds))
    assert again.to_json() == ds.to_json() and again.images() == ds.images()
    # A missing image is a FileError before any work.
    (tmp_path / "views" / "view02.png").unlink()
    with pytest.raises(etlcal.FileError, match="view02.png"):
        ds.detect()


def test_bad_dataset_files(tmp_path: pathlib.Path) -> None:
    bad = tmp_path / "d.json"
    bad.write_text('{"format": "etlcal.dataset/2", "image_size": [10, 10], "board": {"inner_corners": [3, 3], "square_mm": 1}}')
    with pytest.raises(etlcal.Error, match="etlcal.dataset/2"):
        etlcal.Dataset.load(bad)
    with pytest.raises(etlcal.FileError):
        etlcal.Dataset.load(tmp_path / "missing.json")


def test_dataset_json_round_trip_and_save(tmp_path: pathlib.Path) -> None:
    text = ('{"format": "etlcal.dataset/1", "image_size": [640, 480], '
            '"board": {"inner_corners": [9, 6], "square_mm": 2.5}, '
            '"views": [{"image": "a.png", "e_in_ma": 100.0, "temperature_c": 30.0, "z_w_mm": 40.0}]}')
    ds = etlcal.Dataset.from_json(text, base_dir=tmp_path)
    assert len(ds) == 1 and ds.image_size == (640, 480)
    assert ds.board == {"inner_corners": (9, 6), "square_mm": 2.5}
    assert [str(p) for p in ds.images()] == [str(tmp_path / "a.png")]
    assert "views=1" in repr(ds)
    out = tmp_path / "sub" / "d.json"
    out.parent.mkdir()
    ds.save(out)
    again = etlcal.Dataset.load(out)
    assert again.to_json() == ds.to_json()
    assert [str(p) for p in again.images()] == [str(out.parent / "a.png")]
    with pytest.raises(etlcal.FileError):
        ds.save(tmp_path / "missing-dir" / "d.json")
    with pytest.raises(etlcal.Error):
        etlcal.Dataset.from_json("{not json")


def test_dataset_built_in_python_and_its_bad_input(tmp_path: pathlib.Path) -> None:
    ds = etlcal.Dataset((640, 480), (9, 6), 2.5)
    with pytest.raises(etlcal.InputError, match="no views"):
        ds.save(tmp_path / "empty.json")
    ds.add_view("v0.png", 100.0, 30.0, 40.0)
    ds.add_view("v1.png", 150.0, 30.5, 30.0, e_com_ma=148.0)
    ds.add_offstate_view("off0.png")
    ds.add_setting_view("s0.png", 120.0, 29.0)
    assert (len(ds), ds.offstate_count, ds.setting_count) == (2, 1, 1)
    ds.save(tmp_path / "d.json")
    again = etlcal.Dataset.load(tmp_path / "d.json")
    assert again.to_json() == ds.to_json()
    assert [str(p) for p in again.images()] == [str(tmp_path / "v0.png"), str(tmp_path / "v1.png")]
    with pytest.raises(etlcal.InputError, match="e_in_ma must be finite"):
        ds.add_view("v2.png", float("nan"), 30.0, 40.0)
    with pytest.raises(etlcal.InputError, match="z_w_mm must be finite"):
        ds.add_view("v2.png", 100.0, 30.0, float("inf"))
    with pytest.raises(etlcal.InputError, match="temperature_c must be finite"):
        ds.add_setting_view("s1.png", 100.0, float("nan"))
    assert len(ds) == 2 and ds.setting_count == 1
    with pytest.raises(etlcal.InputError, match="image_size"):
        etlcal.Dataset((0, 480), (9, 6), 2.5)
    with pytest.raises(etlcal.InputError, match="3 x 3"):
        etlcal.Dataset((640, 480), (2, 6), 2.5)
    with pytest.raises(etlcal.InputError, match="square size"):
        etlcal.Dataset((640, 480), (9, 6), -1.0)
