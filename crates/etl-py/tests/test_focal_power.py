"""A focal-power calibration from Python: observations whose views carry
`focal_power_dpt` (written by `etlcal simulate --focal-power`: the paper rig in the lens
driver's focal-power mode at 25, 30 and 35 degC), `calibrate` with no thermal part, the
camera at `focal_power_dpt=`, the focus law in dioptres; and the refusals."""
import pathlib
import subprocess

import numpy as np
import pytest

import etlcal


@pytest.fixture(scope="module")
def focal_power_observations(etlcal_binary: str, tmp_path_factory: pytest.TempPathFactory) -> pathlib.Path:
    out = tmp_path_factory.mktemp("fp") / "sim"
    cmd = [etlcal_binary, "simulate", "--focal-power", "--observations-only", "--out", str(out), "--seed", "4"]
    subprocess.run(cmd, check=True, capture_output=True)
    return out / "observations.json"


def test_a_focal_power_calibration_from_python(focal_power_observations: pathlib.Path) -> None:
    obs = etlcal.Observations.load(str(focal_power_observations))
    assert obs[0].focal_power_dpt is not None and obs[0].e_in_ma is None
    cal = etlcal.calibrate(obs)
    assert cal.setting == "focal_power"
    noise = cal.covariance_noise
    assert noise is not None and noise["sigma_p_dpt"] == 0.05 and "sigma_e_ma" not in noise
    own = etlcal.calibrate(obs, sigma_p_dpt=0.1).covariance_noise
    assert own is not None and own["sigma_p_dpt"] == 0.1
    power_range = cal.focal_power_range_dpt
    assert power_range is not None
    lo, hi = power_range
    assert 12.0 < lo < hi < 19.0
    cam = cal.at(focal_power_dpt=15.0, temperature_c=30.0)
    assert (cam.setting, cam.focal_power_dpt, cam.temperature_c, cam.e_in_ma) == ("focal_power", 15.0, 30.0, None)
    # fx at 15 dpt is the paper rig's at the current where its liquid lens has 15 dpt
    # (between its 150 and 175 mA views), within 1 %.
    assert 4600.0 < cam.focal_lengths[0] < 4800.0
    # The focus law in dioptres: 80 mm is in focus at 127.1 mA, 1000 / f_liq = 14.55 dpt.
    assert cal.focus_focal_power_dpt(80.0, 30.0) == pytest.approx(14.55, abs=0.1)
    # The same camera through the file.
    again = etlcal.Calibration.from_json(cal.to_json())
    assert again.setting == "focal_power"
    assert np.allclose(again.at(focal_power_dpt=15.0, temperature_c=30.0).focal_lengths, cam.focal_lengths)
    assert cal.at(focal_power_dpt=19.5, temperature_c=36.5, allow_extrapolation=True).extrapolated_quantities == [
        "temperature_c",
        "focal_power_dpt",
    ]


def test_the_refusals(focal_power_observations: pathlib.Path) -> None:
    obs = etlcal.Observations.load(str(focal_power_observations))
    cal = etlcal.calibrate(obs)
    with pytest.raises(etlcal.InputError, match="setting is the focal power"):
        cal.at(150.0, 30.0)
    with pytest.raises(etlcal.InputError, match="exactly one of e_in_ma"):
        cal.at(150.0, 30.0, focal_power_dpt=15.0)
    with pytest.raises(etlcal.InputError, match="focal_power_dpt"):
        cal.at(focal_power_dpt=25.0, temperature_c=30.0)
    with pytest.raises(etlcal.InputError, match="does not apply to views at a focal power"):
        etlcal.calibrate(obs, thermal="paper")
    with pytest.raises(etlcal.InputError, match="sigma_e_ma does not apply to views at a focal power"):
        etlcal.calibrate(obs, sigma_e_ma=0.4)
    view = obs[0]
    with pytest.raises(etlcal.InputError, match="exactly one of e_in_ma"):
        obs.add_view(view.world_mm, view.pixels, 150.0, 30.0, focal_power_dpt=15.0)
    with pytest.raises(etlcal.InputError, match="is set by a current"):
        obs.add_view(view.world_mm, view.pixels, 150.0, 30.0)
    assert len(obs) == 15, "a refused view is not kept"
    obs.add_view(view.world_mm, view.pixels, temperature_c=30.0, focal_power_dpt=15.0)
    assert len(obs) == 16 and obs[15].focal_power_dpt == 15.0


def test_model_auto_chooses_everything_and_stands_alone(focal_power_observations: pathlib.Path) -> None:
    obs = etlcal.Observations.load(str(focal_power_observations))
    cal = etlcal.calibrate(obs, model="auto")
    assert cal.setting == "focal_power"
    selection = cal.model_selection
    assert selection is not None and len(selection["candidates"]) == 20
    with pytest.raises(etlcal.InputError, match='model="auto" chooses the distortion family.*drop centre'):
        etlcal.calibrate(obs, model="auto", centre="fixed")
    with pytest.raises(etlcal.InputError, match="model must be"):
        etlcal.calibrate(obs, model="opencv")  # type: ignore[arg-type]
