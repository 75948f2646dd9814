"""etlcal.rig: a camera opened from its spec, and a capture on the simulated rig with the
specs and with Python objects for the camera and the stage (as a pypylon or Spinnaker user
plugs in theirs)."""
import json
import pathlib
from typing import Any, Dict, List, Tuple

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


class FakeLens:
    """A Python lens driver: records the currents commanded (quantised to 0.07 mA steps, as a
    Lens Driver 4 does) and reads a fixed temperature; raises on command `fail_at`."""

    def __init__(self, fail_at: int = -1) -> None:
        self.commands: List[float] = []
        self.fail_at = fail_at

    def set_current_ma(self, e_in_ma: float) -> float:
        if len(self.commands) == self.fail_at:
            raise OSError("the lens driver stopped answering")
        self.commands.append(round(e_in_ma / 0.07) * 0.07)
        return self.commands[-1]

    def temperature_c(self) -> float:
        return 31.25

    def limits_ma(self) -> Tuple[float, float]:
        return (0.0, 290.0)


def test_capture_views_with_a_python_lens(tmp_path: pathlib.Path) -> None:
    sim = tmp_path / "S"
    etlcal.rig.capture_views(small_plan(), out=sim, camera="sim", lens="virtual", stage="sim")
    replay = etlcal.rig.Camera.open(f"files:{sim / 'views'}")
    images = [replay.grab(), replay.grab()]
    lens = FakeLens()
    out = tmp_path / "D"
    r = etlcal.rig.capture_views(small_plan(), out=out, camera=ReplayCamera(images), lens=lens, stage=HandStage())
    assert r["views_taken"] == 2
    # Each current approached from 10 mA below, recorded as the driver quantised it.
    assert lens.commands == pytest.approx([139.72, 149.73, 159.67, 169.68], abs=1e-9)
    views = json.loads((out / "dataset.json").read_text())["views"]
    assert [v["e_in_ma"] for v in views] == pytest.approx([149.73, 169.68], abs=1e-9)
    assert [v["temperature_c"] for v in views] == [31.25, 31.25]


def test_a_python_lens_that_raises_is_named_and_the_dataset_stays_whole(tmp_path: pathlib.Path) -> None:
    sim = tmp_path / "S"
    etlcal.rig.capture_views(small_plan(), out=sim, camera="sim", lens="virtual", stage="sim")
    replay = etlcal.rig.Camera.open(f"files:{sim / 'views'}")
    images = [replay.grab(), replay.grab()]
    out = tmp_path / "D"
    # The third command (the second view's approach) raises.
    with pytest.raises(OSError, match="stopped answering") as raised:
        etlcal.rig.capture_views(small_plan(), out=out, camera=ReplayCamera(images), lens=FakeLens(fail_at=2),
                                 stage=HandStage())
    notes = getattr(raised.value, "__notes__", [])
    assert any("lens (Python object)" in n for n in notes), notes
    assert len(json.loads((out / "dataset.json").read_text())["views"]) == 1
    # The same call with the lens back resumes: view 0 kept, view 1 taken.
    r = etlcal.rig.capture_views(small_plan(), out=out, camera=ReplayCamera(images[1:]), lens=FakeLens(),
                                 stage=HandStage())
    assert (r["views_kept"], r["views_taken"]) == (1, 1)


def test_a_lens_object_that_returns_no_temperature_is_refused_in_one_line(tmp_path: pathlib.Path) -> None:
    class NoSensor(FakeLens):
        def temperature_c(self) -> Any:
            return None

    sim = tmp_path / "S"
    etlcal.rig.capture_views(small_plan(), out=sim, camera="sim", lens="virtual", stage="sim")
    image = etlcal.rig.Camera.open(f"files:{sim / 'views'}").grab()
    with pytest.raises(etlcal.DeviceError, match=r"^lens \(Python object\): temperature_c\(\) returned None"):
        etlcal.rig.capture_views(small_plan(), out=tmp_path / "D", camera=ReplayCamera([image]), lens=NoSensor(),
                                 stage=HandStage())
    assert not (tmp_path / "D" / "dataset.json").exists()


def test_capture_thermal_on_the_sim_rig_fits_and_resumes(tmp_path: pathlib.Path) -> None:
    plan = ROOT / "fixtures" / "plan-thermal.json"
    out = tmp_path / "T"
    roi = (1018, 449, 240, 180)
    r = etlcal.rig.capture_thermal(plan, out=out, camera="sim", lens="virtual", stage="sim", sim_roi=roi)
    assert (r["samples_taken"], r["stopped"]) == (16, False) and r["rms_ma"] < 0.5, r
    thermal = etlcal.ThermalCalibration.load(out / "thermal.json")
    truth = etlcal.ThermalSurface.paper()
    for e in [100.0, 150.0, 200.0]:
        for t in [30.0, 36.0]:
            # The fitted E_T since 27 degC against the virtual lens's true one, at the E_in
            # that holds E_com.
            got = thermal.compensate(e, t).e_t_ma - thermal.compensate(e, 27.0).e_t_ma
            want = truth.e_t(e, t) - truth.e_t(e, 27.0)
            assert abs(got - want) < 0.5, (e, t, got, want)
    again = etlcal.rig.capture_thermal(plan, out=out, camera="sim", lens="virtual", stage="sim", sim_roi=roi)
    assert (again["samples_kept"], again["samples_taken"]) == (16, 0)
    bad: Dict[str, Any] = json.loads(plan.read_text())
    del bad["thermal"]
    with pytest.raises(etlcal.InputError, match="the plan has no \"thermal\" keys"):
        etlcal.rig.capture_thermal(bad, out=tmp_path / "B", camera="sim", lens="virtual", stage="sim", sim_roi=roi)
    assert not (tmp_path / "B").exists()
