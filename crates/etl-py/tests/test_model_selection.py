"""calibrate(distortion=..., focal_degree=...) (issue 16): the opencv family, the choice
by held-out views (`model_selection`), and the bad inputs, each a one-line InputError
naming the argument, with nothing returned."""
from typing import Any, Dict

import pytest

import etlcal


@pytest.fixture(scope="module")
def strong() -> etlcal.simulate.Simulation:
    return etlcal.simulate.strong_rig(2)


def test_auto_chooses_opencv_on_the_strong_rig_and_records_the_table(strong: etlcal.simulate.Simulation) -> None:
    cal = etlcal.calibrate(strong.observations, thermal="paper", distortion="auto")
    assert cal.distortion_model == "opencv" and cal.focal_degree == 3
    sel = cal.model_selection
    assert sel is not None
    assert sel["method"] == "leave-one-view-out" and sel["rule"] == "one-standard-error"
    rows = {(c["distortion_model"], c["focal_degree"]): c for c in sel["candidates"]}
    assert set(rows) == {("paper", 3), ("opencv", 3)}
    assert rows[("opencv", 3)]["chosen"] and not rows[("paper", 3)]["chosen"]
    # The paper's distortion cannot follow k2: its held-out error is several times larger.
    assert rows[("paper", 3)]["prediction_rms_px"] > 3 * rows[("opencv", 3)]["prediction_rms_px"]
    assert rows[("opencv", 3)]["parameters"] == 31 and rows[("paper", 3)]["parameters"] == 25
    # The chosen model is the calibration: the principal point within 2 px of the truth.
    assert abs(cal.principal_point - strong.truth.principal_point).max() < 2.0


def test_given_models_and_defaults(strong: etlcal.simulate.Simulation) -> None:
    cal = etlcal.calibrate(strong.observations, thermal="paper", distortion="opencv", focal_degree=2)
    assert (cal.distortion_model, cal.focal_degree, cal.model_selection) == ("opencv", 2, None)
    assert len(cal.kf_x) == 3 and len(cal.distortion_a) == 15
    paper = etlcal.simulate.paper_rig(1)
    default = etlcal.calibrate(paper.observations, thermal="paper")
    assert (default.distortion_model, default.focal_degree, default.model_selection) == ("paper", 3, None)


@pytest.mark.parametrize(
    "kwargs, words",
    [
        ({"distortion": "brown"}, 'distortion must be "paper", "opencv" or "auto", got "brown"'),
        ({"focal_degree": 7}, 'focal_degree must be 1..5 or "auto", got 7'),
        ({"focal_degree": "cubic"}, 'focal_degree must be 1..5 or "auto", got cubic'),
        ({"fix_k3": True}, "fix_k3=True is an OpenCV flag"),
        ({"distortion": "paper", "zero_tangent": True}, "zero_tangent=True is an OpenCV flag"),
        ({"method": "per-setting", "distortion": "opencv"}, 'method="per-setting" takes no distortion'),
    ],
)
def test_bad_model_options_are_one_line_errors(strong: etlcal.simulate.Simulation, kwargs: Dict[str, Any],
                                              words: str) -> None:
    with pytest.raises(etlcal.InputError) as e:
        etlcal.calibrate(strong.observations, thermal="paper", **kwargs)
    assert words in str(e.value) and "\n" not in str(e.value)
