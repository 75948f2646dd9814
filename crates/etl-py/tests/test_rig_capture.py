"""etlcal.rig: a camera opened from its spec, and a capture on the simulated rig with the
specs and with Python objects for the camera and the stage (as a pypylon or Spinnaker user
plugs in theirs)."""
import json
import pathlib
from typing import Any, Dict, List

import numpy as np
import numpy.typing as npt
import pytest

import etlcal
import etlcal.rig

ROOT = pathlib.Path(__file__).resolve().parents[3]


def small_plan() -> Dict[str, Any]:
    plan: Dict[str, Any] = json.loads((ROOT / "fixtures" / "plan.json").read_text())
    plan.update(stage_mm=[22.0, 16.0], currents_ma=[149.7, 169.7], frames=1)
    del plan["offstate_views"], plan["offstate_board"]
    return plan


def test_a_camera_opens_from_its_spec_and_grabs_frames() -> None:
    camera = etlcal.rig.Camera.open("sim")
    spec, model, size = camera.info()
    assert spec == "sim" and size == (1936, 1458), (spec, model, size)
    image, timestamp_ns = camera.grab_frame()
    assert image.shape == (1458, 1936) and image.dtype == np.uint8 and timestamp_ns >= 0
    with pytest.raises(etlcal.InputError, match="camera webcam: unknown camera spec"):
        etlcal.rig.Camera.open("webcam")


def test_capture_views_with_specs_writes_a_dataset_and_resumes(tmp_path: pathlib.Path) -> None:
    out = tmp_path / "D"
    r = etlcal.rig.capture_views(small_plan(), out=out, camera="sim", lens="virtual", stage="sim")
    assert (r["views_taken"], r["views_kept"], r["stopped"]) == (2, 0, False)
    again = etlcal.rig.capture_views(small_plan(), out=out, camera="sim", lens="virtual", stage="sim")
    assert (again["views_taken"], again["views_kept"]) == (0, 2)
    dataset = etlcal.Dataset.load(out / "dataset.json")
    assert len(dataset) == 2 and dataset.image_size == (1936, 1458)


class ReplayCamera:
    """A Python camera: replays images (each three times: two to settle, one to keep)."""

    def __init__(self, images: List[npt.NDArray[np.uint8]]) -> None:
        self.frames = [im for im in images for _ in range(3)]
        self.image_size = (images[0].shape[1], images[0].shape[0])

    def grab(self) -> npt.NDArray[np.uint8]:
        if not self.frames:
            raise RuntimeError("the camera is unplugged")
        return self.frames.pop(0)


class HandStage:
    """A Python stage: records where it was asked to go."""

    def __init__(self) -> None:
        self.moves: List[float] = []

    def move_mm(self, z_mm: float) -> float:
        self.moves.append(z_mm)
        return z_mm + 0.001  # what the micrometer reads


def test_capture_views_with_python_objects(tmp_path: pathlib.Path) -> None:
    # The Python camera shows the sim rig's images of the two views.
    sim = tmp_path / "S"
    etlcal.rig.capture_views(small_plan(), out=sim, camera="sim", lens="virtual", stage="sim")
    replay = etlcal.rig.Camera.open(f"files:{sim / 'views'}")
    images = [replay.grab(), replay.grab()]
    stage = HandStage()
    out = tmp_path / "D"
    r = etlcal.rig.capture_views(small_plan(), out=out, camera=ReplayCamera(images), lens="virtual", stage=stage)
    assert r["views_taken"] == 2 and stage.moves == [22.0, 16.0]
    dataset = json.loads((out / "dataset.json").read_text())
    assert [v["z_w_mm"] for v in dataset["views"]] == [22.001, 16.001]
    # A Python camera's own exception comes back as it is; the dataset stays whole.
    with pytest.raises(RuntimeError, match="unplugged"):
        etlcal.rig.capture_views(small_plan(), out=tmp_path / "E", camera=ReplayCamera(images[:1]), lens="virtual",
                                 stage=HandStage())
    assert len(json.loads((tmp_path / "E" / "dataset.json").read_text())["views"]) == 1


def test_bad_plans_are_refused_before_anything_is_written(tmp_path: pathlib.Path) -> None:
    plan = small_plan()
    plan["frames"] = 0
    with pytest.raises(etlcal.InputError, match="frames"):
        etlcal.rig.capture_views(plan, out=tmp_path / "D", camera="sim", lens="virtual", stage="sim")
    plan = small_plan()
    plan["stage_mm"] = [22.0, 400.0]
    with pytest.raises(etlcal.InputError, match="outside the travel of stage sim"):
        etlcal.rig.capture_views(plan, out=tmp_path / "D", camera="sim", lens="virtual", stage="sim")
    assert not (tmp_path / "D").exists()
