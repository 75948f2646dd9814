"""docs/RIG.md, every code block in order, on the virtual lens and a simulated rig: the
port `/dev/ttyACM0` is the virtual lens (`--virtual` on the command line, a `VirtualLens`
from Python), `camera`, `chamber` and `stage` a simulated camera, climate chamber and
stage looking through it, and the images those of `etlcal simulate`. Then what the blocks
wrote is checked against the virtual lens's truth."""
import json
import os
import pathlib
import re
import shutil
import subprocess
from typing import Any, Dict, List, Tuple

import numpy as np
import numpy.typing as npt
import pytest

import etlcal

ROOT = pathlib.Path(__file__).resolve().parents[3]
RIG = ROOT / "docs" / "RIG.md"
RIG_FIXTURE = ROOT / "fixtures" / "rig"
PORT = "/dev/ttyACM0"


def code_blocks(path: pathlib.Path) -> List[Tuple[str, str]]:
    """(language, code) of every fenced block of a markdown file, in order, with the
    indentation of blocks inside list items removed."""
    pattern = re.compile(r"^( *)```(\w+)\n(.*?)^\1```$", re.S | re.M)
    blocks = []
    for m in pattern.finditer(path.read_text(encoding="utf-8")):
        indent = len(m.group(1))
        blocks.append((m.group(2), "".join(line[indent:] for line in m.group(3).splitlines(keepends=True))))
    return blocks


class Rig:
    """A camera looking at a checkerboard through the virtual lens: the image blurs with the
    distance of the lens's true E_com from the E_com the board was placed in focus at."""

    def __init__(self, device: etlcal.VirtualLens) -> None:
        self.device = device
        yy, xx = np.mgrid[0:96, 0:96]
        self.board_spectrum = np.fft.fft2(np.where(((xx // 12) + (yy // 12)) % 2 == 0, 200.0, 40.0))
        w = 2 * np.pi * np.fft.fftfreq(96)
        self.k2 = w[None, :] ** 2 + w[:, None] ** 2
        self.focus_e_com_ma: List[float] = []
        self.temperatures_c: List[float] = []

    def grab(self) -> npt.NDArray[np.uint8]:
        sigma = 0.5 + 0.3 * abs(self.device.state().e_com_ma - self.focus_e_com_ma[-1])
        image = np.real(np.fft.ifft2(self.board_spectrum * np.exp(-0.5 * sigma**2 * self.k2)))
        frame: npt.NDArray[np.uint8] = np.clip(np.round(image), 0, 255).astype(np.uint8)
        return frame

    def set(self, t_c: float) -> None:
        self.temperatures_c.append(t_c)
        self.device.set_temperature_c(t_c)

    def place_board(self) -> None:
        self.focus_e_com_ma.append(self.device.state().e_com_ma)


def run_shell(code: str, cwd: pathlib.Path, etlcal_binary: str) -> str:
    """A shell block with `etlcal` on the PATH and the virtual lens for the port."""
    assert PORT in code or "--port" not in code, code
    env = dict(os.environ, PATH=f"{pathlib.Path(etlcal_binary).parent}{os.pathsep}{os.environ['PATH']}")
    script = "set -euo pipefail\n" + code.replace(f"--port {PORT}", "--virtual")
    out = subprocess.run(["bash", "-c", script], cwd=cwd, env=env, capture_output=True, text=True)
    assert out.returncode == 0, f"{code}\nstdout: {out.stdout}\nstderr: {out.stderr}"
    return out.stdout


def test_every_rig_snippet_runs_on_the_virtual_lens(
    tmp_path: pathlib.Path, monkeypatch: pytest.MonkeyPatch, etlcal_binary: str
) -> None:
    blocks = code_blocks(RIG)
    languages = [language for language, _ in blocks]
    # A new snippet must be added here with what the test gives it.
    assert languages == ["sh", "json", "sh", "python", "sh", "sh", "json", "sh", "python", "sh", "python", "sh",
                         "json", "sh", "python", "json", "sh", "json", "sh"], languages
    # The rig's data: images of the simulated rig (views/, offstate/, dataset.json) and the
    # lens-off board's file that the zhang snippet names.
    subprocess.run([etlcal_binary, "simulate", "--out", str(tmp_path), "--quiet"], check=True, capture_output=True)
    dataset = json.loads((tmp_path / "dataset.json").read_text())
    (tmp_path / "offstate-board.json").write_text(json.dumps(dataset["offstate_board"]))
    # The rig snippets' rig.json: the synthetic two-camera rig of fixtures/rig.
    for name in ["rig.json", "left.json", "right.json"]:
        shutil.copy(RIG_FIXTURE / name, tmp_path / name)
    # The calibrate-rig snippets' rig/rig_dataset.json: a simulated 2-camera rig's points.
    rig_sim = [etlcal_binary, "simulate", "--rig", "2", "--observations-only", "--out", str(tmp_path / "rig"), "--quiet"]
    subprocess.run(rig_sim, check=True, capture_output=True)
    device = etlcal.VirtualLens()
    rig = Rig(device)
    namespace: Dict[str, Any] = {"camera": rig, "chamber": rig, "stage": rig}
    monkeypatch.chdir(tmp_path)
    for language, code in blocks:
        if "thermal-cam1.json" in code and not (tmp_path / "thermal-cam1.json").exists():
            # The second lens's surface: the virtual lens's again (one virtual lens here).
            shutil.copy(tmp_path / "thermal.json", tmp_path / "thermal-cam1.json")
        if language == "sh":
            run_shell(code, tmp_path, etlcal_binary)
        elif language == "python":
            assert f'"{PORT}"' in code or PORT not in code, code
            exec(compile(code.replace(f'"{PORT}"', repr(device.port)), str(RIG), "exec"), namespace)
        elif '"etlcal.plan/1"' in code:
            (tmp_path / "plan.json").write_text(code)  # the text names it plan.json
        elif '"etlcal.rig-dataset/1"' in code:
            (tmp_path / "example-rig-dataset.json").write_text(code)
        elif '"etlcal.board/1"' in code:
            (tmp_path / "board.json").write_text(code)  # the text names it board.json
        else:
            (tmp_path / "example-dataset.json").write_text(code)
    # The board file as written in RIG, printed at true size: 15 x 13 squares of 1.5 mm and
    # a margin of one square.
    assert etlcal.Board.load(tmp_path / "board.json").squares == (15, 13)
    svg = (tmp_path / "board.svg").read_text()
    assert 'width="25.5mm"' in svg and 'height="22.5mm"' in svg, svg[:300]
    assert (tmp_path / "board.png").stat().st_size > 0
    # The example dataset is a valid etlcal.dataset/1 (its images are the reader's own).
    example = etlcal.Dataset.load(tmp_path / "example-dataset.json")
    assert len(example) == 2 and example.image_size == (1936, 1458)
    thermal_surface_follows_the_virtual_lens(tmp_path, rig, namespace)
    # The calibration of the simulated images: within 1 % of the truth's fx(E) over the range.
    cal = etlcal.Calibration.load(tmp_path / "calibration.json")
    truth = etlcal.simulate.paper_rig(0).truth
    for e in [80.0, 150.0, 225.0]:
        assert abs(cal.intrinsics(e)[0, 0] / truth.intrinsics(e)[0, 0] - 1.0) < 0.01
    assert (tmp_path / "observations.json").is_file() and (tmp_path / "report" / "index.html").is_file()
    # The run-time snippets at (150 mA, 31 degC): E_com through the surface just measured.
    e_com = namespace["cal"].thermal_calibration.compensate(150.0, 31.0).e_com_ma
    assert namespace["cam"].e_com_ma == pytest.approx(e_com, abs=1e-9)
    assert "camera_matrix" in (tmp_path / "camera.yaml").read_text()
    # The rig snippets: a point triangulated in front of both cameras, with its std, and the
    # rectification written in the formats asked for.
    point = namespace["p"]
    assert 100.0 < point.point_mm[2] < 2000.0 and all(0.0 < s < 10.0 for s in point.std_mm)
    for name in ["stereo.yaml", "left.yaml", "right.yaml"]:
        assert (tmp_path / "rectified" / name).is_file(), name
    # The rig calibrated from the simulated points, by the CLI and by Python alike; the
    # example rig dataset reads, and is refused for its images that are not there.
    assert len(etlcal.Rig.load(tmp_path / "rig.json").names) == 2
    # Camera 1's own flags: its calibration in OpenCV's family, camera 0's in the paper's.
    families = [c.distortion_model for c in etlcal.Rig.load(tmp_path / "rig.json").calibrations]
    assert families == ["paper", "opencv"], families
    assert len(namespace["at"].cameras) == 2
    # (With its lenses' surface: a camera without one is refused first, before any image.)
    example_rig = [etlcal_binary, "calibrate-rig", "--dataset", "example-rig-dataset.json", "--thermal",
                   "thermal.json", "--out", "x.json"]
    refused = subprocess.run(example_rig, cwd=tmp_path, capture_output=True, text=True)
    assert refused.returncode != 0 and "images/cam0/view00.png" in refused.stderr, refused.stderr
    assert not (tmp_path / "x.json").exists()
    # The capture on the simulated rig: the plan's views, calibrated.
    captured = etlcal.Dataset.load(tmp_path / "capture" / "dataset.json")
    assert len(captured) == 15
    assert (tmp_path / "capture" / "calibration.json").is_file()
    # The temperature capture on the simulated rig: its 4 x 4 grid, fitted close to the
    # virtual lens's surface (E_T since 27 degC at the same E_in).
    table = (tmp_path / "thermal-capture" / "thermal.csv").read_text().splitlines()
    assert table[0] == "temperature_c,e_in_ma,e_t_ma" and len(table) == 17
    fitted = etlcal.ThermalCalibration.load(tmp_path / "thermal-capture" / "thermal.json")
    surface = etlcal.ThermalSurface.paper()
    got = fitted.compensate(150.0, 33.0).e_t_ma - fitted.compensate(150.0, 27.0).e_t_ma
    assert abs(got - (surface.e_t(150.0, 33.0) - surface.e_t(150.0, 27.0))) < 0.5


def thermal_surface_follows_the_virtual_lens(tmp_path: pathlib.Path, rig: Rig, namespace: Dict[str, Any]) -> None:
    """The thermal snippet placed the board once per grid current, stepped the default
    temperatures, and fitted the virtual lens's surface: each sample's E_T is the paper
    surface's change since the first temperature."""
    result = namespace["result"]
    assert len(rig.focus_e_com_ma) == 11 and rig.temperatures_c[:11] == [27.0 + k for k in range(11)]
    thermal = etlcal.ThermalCalibration.load(tmp_path / "thermal.json")
    assert thermal.rms_ma == pytest.approx(result.rms_ma)
    truth = etlcal.ThermalSurface.paper()
    samples = result.samples
    for k in range(11):
        t0, e0, _ = samples[11 * k]
        for t, e, e_t in samples[11 * k : 11 * k + 11]:
            assert abs(e_t - (truth.e_t(e, t) - truth.e_t(e0, t0))) < 0.3, (t, e, e_t)


def test_the_temperature_procedure_without_place_board_names_the_python_argument() -> None:
    """RIG's warning: without `place_board` the board is in focus at one current only, so a
    refocus away from it ends at the edge of its window, and the error names `search_ma`,
    the argument to change."""
    device = etlcal.VirtualLens()
    rig = Rig(device)
    rig.focus_e_com_ma.append(85.0)  # the board, fixed, is in focus at E_com 85 mA
    with etlcal.Lens(device.port) as lens:
        with pytest.raises(etlcal.InputError, match="edge of its window") as raised:
            etlcal.thermal_calibration(lens, capture=rig.grab, set_temperature=rig.set,
                                       e_in_grid_ma=[60.0], temperatures_c=[27.0, 30.0])
    assert raised.value.what == "search_ma" and raised.value.value == "20"
