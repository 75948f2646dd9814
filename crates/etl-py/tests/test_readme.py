"""The README's Python example, run as written in a fresh directory (it writes
calibration.json there), and what it computed checked against the simulation's truth."""
import pathlib
import re
from typing import Any, Dict, List

import numpy as np
import pytest

import etlcal

ROOT = pathlib.Path(__file__).resolve().parents[3]


def code_blocks(path: pathlib.Path, language: str) -> List[str]:
    """The fenced code blocks of `language` in a markdown file, in order (indented blocks,
    e.g. inside a list item, have their indentation removed)."""
    pattern = re.compile(r"^( *)```" + re.escape(language) + r"\n(.*?)^\1```$", re.S | re.M)
    blocks = []
    for m in pattern.finditer(path.read_text(encoding="utf-8")):
        indent = len(m.group(1))
        blocks.append("".join(line[indent:] for line in m.group(2).splitlines(keepends=True)))
    return blocks


def test_code_blocks_reads_fenced_and_indented_blocks(tmp_path: pathlib.Path) -> None:
    doc = tmp_path / "doc.md"
    doc.write_text("a\n```python\nx = 1\n```\n- item\n\n  ```python\n  y = 2\n  ```\n```sh\nls\n```\n")
    assert code_blocks(doc, "python") == ["x = 1\n", "y = 2\n"]
    assert code_blocks(doc, "sh") == ["ls\n"]


def test_the_readme_python_example_calibrates_the_simulated_rig(
    tmp_path: pathlib.Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    blocks = code_blocks(ROOT / "README.md", "python")
    assert len(blocks) == 1, "the README has one Python example"
    monkeypatch.chdir(tmp_path)
    namespace: Dict[str, Any] = {}
    exec(compile(blocks[0], str(ROOT / "README.md"), "exec"), namespace)
    printed = capsys.readouterr().out
    # It wrote the file it loaded: the errors-in-variables calibration with the paper's surface.
    saved = etlcal.Calibration.load(tmp_path / "calibration.json")
    assert saved.estimator == "eiv" and saved.thermal_calibration is not None
    sim, cam = namespace["sim"], namespace["cam"]
    # The focal length curve within 0.5 % of the truth over the calibrated currents (the
    # demo's errors-in-variables bound).
    e = np.linspace(80.0, 225.0, 30)
    fx, fx_true = np.polyval(saved.kf_x[::-1], e), np.polyval(sim.truth.kf_x[::-1], e)
    assert np.max(np.abs(fx / fx_true - 1.0)) < 0.005
    # The camera at (150 mA, 31 degC): E_com through the paper's surface, as printed.
    e_com = 150.0 - etlcal.ThermalSurface.paper().e_t(150.0, 31.0)
    assert cam.e_com_ma == pytest.approx(e_com, abs=1e-9)
    assert f"E_com {e_com:.2f} mA" in printed
    # Its projection of the world point against the true camera's at that E_com.
    pixel = cam.project([[3.0, 4.5, 20.0]])[0]
    true_pixel = sim.truth.project(np.array([[3.0, 4.5, 20.0]]), cam.e_com_ma)[0]
    assert np.hypot(*(pixel - true_pixel)) < 1.0, (pixel, true_pixel)
