"""The focus law of a calibration: Calibration.focus_law, focus_e_in, focus_distance_mm
(through the thermal surface), and the refusals (no law, out-of-range distance, current or
temperature), each an InputError naming the quantity."""
import json
import warnings
from typing import Callable, List, Tuple

import pytest

import etlcal

# The simulated rig's lens (etl_sim::rig::PAPER_FOCUS_LAW_MA): E = c0 + c1 V + c2 V^2.
RIG_LAW = (-2.0889218690457646e1, 1.1308537646717632e1, 4.255592823755981e-2)


def rig_current(distance_mm: float) -> float:
    v = 1000.0 / distance_mm
    return RIG_LAW[0] + RIG_LAW[1] * v + RIG_LAW[2] * v * v


@pytest.fixture(scope="module")
def cal() -> etlcal.Calibration:
    sim = etlcal.simulate.paper_rig(seed=1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return etlcal.calibrate(sim.observations, sim.a0, thermal="paper")


def test_the_law_is_stored_and_predicts_the_rig_lens(cal: etlcal.Calibration) -> None:
    law = cal.focus_law
    assert law is not None and law["views"] == 15
    assert set(law) == {"coefficients_ma", "distance_range_mm", "e_com_range_ma", "rms_ma", "views"}
    lo, hi = law["distance_range_mm"]
    assert 49.0 < lo < 50.0 and 120.0 < hi < 121.0
    assert law["e_com_range_ma"] == (80.0, 225.0)
    assert 2.6 < law["rms_ma"] < 2.8  # the paper's whole-mm stage positions
    for d, t in [(60.0, 27.0), (85.0, 31.5), (115.0, 36.0)]:
        e_in = cal.focus_e_in(d, t)
        e_com = cal.e_com(e_in, t)
        # Within 0.3 mA of the lens's best focus at 60..115 mm (etl-sim tests/focus_law.rs).
        assert abs(e_com - rig_current(d)) < 0.3, (d, e_com, rig_current(d))
        assert cal.focus_distance_mm(e_in, t) == pytest.approx(d, abs=1e-8)
    # The file keeps it.
    back = etlcal.Calibration.from_json(cal.to_json())
    assert back.focus_law == law
    assert "focus_law" in json.loads(cal.to_json())


def test_out_of_range_inputs_name_the_quantity(cal: etlcal.Calibration) -> None:
    cases: List[Tuple[Callable[[], object], str]] = [
        (lambda: cal.focus_e_in(300.0, 27.0), "distance_mm"),
        (lambda: cal.focus_e_in(30.0, 27.0), "distance_mm"),
        (lambda: cal.focus_e_in(80.0, 500.0), "temperature_c"),
        (lambda: cal.focus_e_in(80.0, 80.0), r"temperature_c = 80 is outside \[26, 38\]"),
        (lambda: cal.focus_distance_mm(270.0, 27.0), "e_in_ma"),
        (lambda: cal.focus_distance_mm(270.0, 27.0, allow_extrapolation=True), "e_com_ma"),
        (lambda: cal.focus_distance_mm(150.0, float("nan")), "temperature_c"),
    ]
    for call, name in cases:
        with pytest.raises(etlcal.InputError, match=name):
            call()


def test_a_calibration_without_a_focus_law_says_so() -> None:
    rig = etlcal.Calibration.paper_rig()
    assert rig.focus_law is None
    with pytest.raises(etlcal.InputError, match="this calibration has no focus law"):
        rig.focus_e_in(80.0, 27.0)
    with pytest.raises(etlcal.InputError, match="this calibration has no focus law"):
        rig.focus_distance_mm(150.0, 27.0)


def test_calibrate_warns_when_the_views_allow_no_focus_law() -> None:
    sim = etlcal.simulate.paper_rig(seed=1)
    doc = json.loads(sim.observations.to_json())
    doc["views"] = [doc["views"][k] for k in (0, 7, 14)]  # three currents: a law needs four
    obs = etlcal.Observations.from_json(json.dumps(doc))
    with pytest.warns(UserWarning, match="no focus law: too few calibration views at distinct currents"):
        cal = etlcal.calibrate(obs, sim.a0, thermal="paper")
    assert cal.focus_law is None
