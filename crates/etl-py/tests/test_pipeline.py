"""Observations, A0, simulate.paper_rig, calibrate and solve_pnp."""
import json
import math
import pathlib
import pickle
from typing import List, Optional, Tuple

import numpy as np
import numpy.typing as npt
import pytest

import etlcal


@pytest.fixture(scope="module")
def sim() -> etlcal.Simulation:
    return etlcal.simulate.paper_rig(seed=1)


def test_simulation_matches_the_paper_rig(sim: etlcal.Simulation) -> None:
    obs = sim.observations
    assert len(obs) == 15 and obs.point_count == 2311
    assert obs.image_size == (1936, 1458)
    assert sim.truth.kf_x.tolist() == [5380.0, -7.0, 0.02, -3e-5]
    assert len(sim.true_dz_mm) == 15 and len(sim.true_de_ma) == 15
    assert obs.e_com_ma()[0] == 80.0 and obs.e_com_ma()[-1] == 225.0
    assert sim.seed == 1 and sim.noise["px"] == 0.2
    # Noise-free: every pixel is the projection of its world point.
    clean = etlcal.simulate.paper_rig(seed=0, noise="none")
    v = clean.observations.view(3)
    assert np.max(np.abs(clean.truth.project(v["world_mm"], v["e_com_ma"]) - v["pixels"])) < 1e-9
    assert clean.a0 == etlcal.A0(5380.0, 5430.0, 900.0, 550.0)
    # Same seed, same data.
    assert etlcal.simulate.paper_rig(1).observations == obs
    assert pickle.loads(pickle.dumps(sim)).observations == obs
    only_px = etlcal.simulate.paper_rig(2, noise={"z_mm": 0.0, "e_ma": 0.0})
    assert only_px.true_dz_mm == [0.0] * 15
    with pytest.raises(etlcal.InputError, match="unknown noise key"):
        etlcal.simulate.paper_rig(0, noise={"pixels": 1.0})
    # Each standard deviation in its documented range (the simulation file's), named.
    for key, bad in [("px", -1.0), ("px", 1e308), ("z_mm", float("nan")), ("e_ma", float("inf")), ("pp_px", 1e4)]:
        with pytest.raises(etlcal.InputError, match=rf'noise\["{key}"\] .* is outside \[0, '):
            etlcal.simulate.paper_rig(0, noise={key: bad})
        with pytest.raises(etlcal.InputError, match=rf'noise\["{key}"\]'):
            etlcal.simulate.strong_rig(0, noise={key: bad})
    with pytest.raises(etlcal.InputError, match='noise must be "paper"'):
        etlcal.simulate.paper_rig(0, noise="loud")  # type: ignore[arg-type]  # the run-time check under test
    assert repr(sim) == "Simulation(views=15, points=2311)"


def test_calibrate_recovers_the_rig(sim: etlcal.Simulation) -> None:
    cal = etlcal.calibrate(sim.observations, sim.a0, estimator="paper")
    assert cal.estimator == "paper" and cal.iterations > 0
    assert 0.25 < cal.rms_px < 0.5 and cal.initial_rms_px > cal.rms_px
    truth = sim.truth
    e = np.linspace(80, 225, 30)
    fx = np.polyval(cal.kf_x[::-1], e)
    fx_true = np.polyval(truth.kf_x[::-1], e)
    assert np.max(np.abs(fx / fx_true - 1)) < 0.02
    assert cal.std["kf_x"].shape == (4,) and np.all(cal.std["kf_x"] > 0)
    assert len(cal.views) == 15 and cal.views[0]["points"] == 141
    # Every key of the file's views, with the file's values (fx_px, fy_px included).
    file_views = json.loads(cal.to_json())["views"]
    assert cal.views == file_views and {"fx_px", "fy_px"} <= set(cal.views[0])
    assert abs(cal.views[0]["fx_px"] / np.polyval(cal.kf_x[::-1], cal.views[0]["e_com_ma"]) - 1) < 0.01
    eiv = etlcal.calibrate(sim.observations, sim.a0, estimator="eiv")
    assert eiv.estimator == "eiv"
    dz = [v["dz_mm"] for v in eiv.views]
    assert np.corrcoef(dz, sim.true_dz_mm)[0, 1] > 0.5
    assert np.max(np.abs(np.polyval(eiv.kf_x[::-1], e) / fx_true - 1)) < 0.005
    held = etlcal.calibrate(sim.observations, sim.a0, hold_a0=True, robust="huber", robust_k_px=1.0)
    assert abs(held.kf_x[0] - sim.a0.kf0x) < 1e-3
    assert etlcal.Calibration.from_json(cal.to_json()) == cal


def test_the_default_estimator_is_errors_in_variables(sim: etlcal.Simulation) -> None:
    # No estimator: errors-in-variables with the paper's priors (10 um, 0.4 mA), the same
    # calibration as asking for it; "paper" (Eq. 24) stays available and differs.
    default = etlcal.calibrate(sim.observations, sim.a0)
    assert default.estimator == "eiv"
    assert default == etlcal.calibrate(sim.observations, sim.a0, estimator="eiv", sigma_z_mm=0.010, sigma_e_ma=0.4)
    assert any(v["dz_mm"] != 0.0 for v in default.views)
    paper = etlcal.calibrate(sim.observations, sim.a0, estimator="paper")
    assert paper.estimator == "paper" and paper != default
    assert all(v["dz_mm"] == 0.0 for v in paper.views)


def test_the_covariance_says_what_noise_it_accounts_for(sim: etlcal.Simulation) -> None:
    # Both estimators' covariances include the recorded stage and current errors (the
    # paper's takes them as exact in its fit, not in its uncertainty); the spreads are the
    # same sigma_z_mm / sigma_e_ma for both, the paper's by default.
    eiv = etlcal.calibrate(sim.observations, sim.a0)
    paper = etlcal.calibrate(sim.observations, sim.a0, estimator="paper")
    for cal in (eiv, paper):
        noise = cal.covariance_noise
        assert noise is not None and noise["sigma_z_mm"] == 0.010 and noise["sigma_e_ma"] == 0.4
        assert 0.15 < noise["sigma_px"] < 0.25, noise  # the simulation's 0.2 px (and 1 um corners)
        assert json.loads(cal.to_json())["covariance_noise"] == noise
    # The paper estimator's stds grow with the stage spread it is told of; its estimate does not move.
    loose = etlcal.calibrate(sim.observations, sim.a0, estimator="paper", sigma_z_mm=0.05)
    assert np.array_equal(loose.kf_x, paper.kf_x)
    assert np.all(loose.std["kf_x"] > 1.5 * paper.std["kf_x"])
    # A model given, not estimated, records none.
    assert etlcal.Calibration.paper_rig().covariance_noise is None


def test_the_centre_fixed_moving_and_bad(sim: etlcal.Simulation, tmp_path: pathlib.Path) -> None:
    # centre="fixed" is the default; "moving" fits dz(E) and the principal point's move
    # (Eq. C1-C3), recorded as the file's "centre"; a bad word is refused naming centre=.
    fixed = etlcal.calibrate(sim.observations, sim.a0, estimator="paper")
    assert fixed.centre is None
    assert fixed == etlcal.calibrate(sim.observations, sim.a0, estimator="paper", centre="fixed")
    moving = etlcal.calibrate(sim.observations, sim.a0, estimator="paper", centre="moving")
    c = moving.centre
    assert c is not None and c["dz_mm"][0] == 0.0 and len(c["dz_mm"]) == 3
    assert c["principal_point_px"][0][0] == moving.principal_point[0]
    # The paper rig's centre does not move: noise-free, the move over 80..225 mA is 0. The
    # stage positions and currents are exact too, and the covariance is told so (with the
    # paper's 10 um and 0.4 mA it would say the move is undetermined, as it is on that rig).
    clean = etlcal.simulate.paper_rig(seed=0, noise="none")
    exact = etlcal.calibrate(
        clean.observations, clean.a0, estimator="paper", centre="moving", sigma_z_mm=1e-9, sigma_e_ma=1e-9
    )
    still = exact.centre
    assert still is not None
    assert not any("centre's move" in w for w in exact.warnings), exact.warnings
    move = still["dz_mm"][1] * 145.0 + still["dz_mm"][2] * (225.0**2 - 80.0**2)
    assert abs(move) < 1e-6, move
    path = tmp_path / "moving.json"
    moving.save(path)
    assert etlcal.Calibration.load(path) == moving
    with pytest.raises(etlcal.InputError, match='centre must be "fixed", "moving" or "auto"'):
        etlcal.calibrate(sim.observations, sim.a0, centre="sideways")  # type: ignore[arg-type]  # the run-time check under test


def test_calibrate_bad_inputs(sim: etlcal.Simulation) -> None:
    obs = sim.observations
    with pytest.raises(etlcal.InputError, match='estimator must be "paper" or "eiv"'):
        etlcal.calibrate(obs, sim.a0, estimator="best")  # type: ignore[arg-type]  # the run-time check under test
    with pytest.raises(etlcal.InputError, match="robust must be"):
        etlcal.calibrate(obs, sim.a0, robust="l1")  # type: ignore[arg-type]  # the run-time check under test
    two = etlcal.Observations((1936, 1458))
    for i in (0, 1):
        v = obs.view(i)
        two.add_view(v["world_mm"], v["pixels"], v["e_in_ma"], v["temperature_c"], v["e_com_ma"])
    with pytest.raises(etlcal.InputError) as info:
        etlcal.calibrate(two, sim.a0)
    assert "distinct currents" in str(info.value)
    with pytest.raises(etlcal.InputError) as info:
        etlcal.calibrate(etlcal.Observations((10, 10)), sim.a0)
    assert str(info.value) == "invalid input: observations hold no views"


def test_observations_build_save_load(sim: etlcal.Simulation, tmp_path: pathlib.Path) -> None:
    obs = sim.observations
    views = [obs.view(i) for i in range(len(obs))]
    again = etlcal.Observations.from_arrays(
        obs.image_size,
        [v["world_mm"] for v in views],
        [v["pixels"] for v in views],
        [v["e_in_ma"] for v in views],
        [v["temperature_c"] for v in views],
        [v["e_com_ma"] for v in views],
    )
    # The simulation includes lens-off views (for Zhang's A0); from_arrays takes ETL views
    # only, so add them back.
    for i in range(obs.offstate_count):
        off = obs.offstate_view(i)
        again.add_offstate_view(off["world_mm"], off["pixels"])
    assert obs.offstate_count == 10
    assert again == obs
    path = tmp_path / "obs.json"
    obs.save(path)
    assert etlcal.Observations.load(path) == obs
    assert etlcal.Observations.from_json(obs.to_json()) == obs
    assert pickle.loads(pickle.dumps(obs)) == obs
    assert obs.view(-1)["e_com_ma"] == 225.0
    with pytest.raises(IndexError):
        obs.view(15)
    # Without recorded E_com, it is compensated through the thermal surface.
    o = etlcal.Observations((100, 100))
    o.add_view([[0, 0, 10], [1, 0, 10]], [[1, 2], [3, 4]], e_in_ma=120.0, temperature_c=33.0)
    assert o.view(0)["e_com_ma"] is None
    # None is assumed: the thermal calibration must be chosen ("paper" names the paper's).
    with pytest.raises(etlcal.InputError, match="view 0 has no e_com_ma and no thermal calibration"):
        o.e_com_ma()
    assert o.e_com_ma("paper")[0] == pytest.approx(etlcal.ThermalSurface.paper().e_com(120.0, 33.0), abs=1e-12)
    with pytest.raises(etlcal.InputError, match='only word accepted is "paper"'):
        o.e_com_ma("papr")  # type: ignore[arg-type]
    hot = etlcal.ThermalCalibration(etlcal.ThermalSurface([1.0] + [0.0] * 9), e_in_range_ma=(0, 250), t_range_c=(20, 40))
    assert o.e_com_ma(hot) == [119.0]
    o.add_offstate_view([[0, 0, 0], [4, 0, 0]], [[10, 10], [50, 10]])
    assert o.offstate_count == 1 and o.offstate_view(0)["pixels"].shape == (2, 2)
    assert "offstate_views=1" in repr(o)


def test_observations_bad_inputs() -> None:
    o = etlcal.Observations((100, 100))
    with pytest.raises(etlcal.InputError) as info:
        o.add_view([[0, 0, 10]], [[1, 2]], e_in_ma=math.nan, temperature_c=30.0)
    assert str(info.value) == "invalid input: view 0: current or temperature is not finite"
    assert len(o) == 0
    with pytest.raises(etlcal.InputError) as info:
        o.add_view([[0, 0, math.inf]], [[1, 2]], e_in_ma=100.0, temperature_c=30.0)
    assert str(info.value) == "invalid input: view 0: a point is not finite"
    with pytest.raises(etlcal.InputError) as info:
        o.add_view(np.zeros((0, 3)), np.zeros((0, 2)), e_in_ma=100.0, temperature_c=30.0)
    assert str(info.value) == "invalid input: view 0 has no points"
    with pytest.raises(etlcal.InputError, match="differ in length"):
        o.add_view([[0, 0, 1]], [[1, 2], [3, 4]], 100.0, 30.0)
    with pytest.raises(etlcal.InputError, match="one entry per view"):
        etlcal.Observations.from_arrays((10, 10), [[[0, 0, 1]]], [], [1.0], [1.0])
    with pytest.raises(etlcal.InputError, match="image_size"):
        etlcal.Observations((0, 10))
    with pytest.raises(etlcal.InputError) as info:
        etlcal.Observations.from_json('{"format": "etlcal.observations/1", "image_size": [4, 4], "views": []}')
    assert str(info.value) == "<json>: invalid input: observations hold no views"
    with pytest.raises(etlcal.InputError, match="not supported"):
        etlcal.Observations.from_json('{"format": "etlcal.dataset/1"}')


def test_a0(tmp_path: pathlib.Path) -> None:
    a = etlcal.A0(5380.0, 5430.0, 900.0, 550.0)
    assert (a.kf0x, a.kf0y, a.u0, a.v0) == (5380.0, 5430.0, 900.0, 550.0)
    a.save(tmp_path / "a0.json")
    assert etlcal.A0.load(tmp_path / "a0.json") == a
    assert etlcal.A0.from_json(a.to_json()) == a
    assert pickle.loads(pickle.dumps(a)) == a
    assert repr(a) == "A0(kf0x=5380.0, kf0y=5430.0, u0=900.0, v0=550.0)"
    with pytest.raises(etlcal.InputError, match="kf0x, kf0y must be positive"):
        etlcal.A0(-1.0, 5430.0, 900.0, 550.0)
    (tmp_path / "bad.json").write_text('{"format": "etlcal.a0/1", "kf0x": 0, "kf0y": 1, "u0": 0, "v0": 0}')
    with pytest.raises(etlcal.InputError) as info:
        etlcal.A0.load(tmp_path / "bad.json")
    assert str(info.value) == f"{tmp_path / 'bad.json'}: kf0x, kf0y must be positive and u0, v0 finite"


def test_solve_pnp_measures_a_stage_move() -> None:
    cal = etlcal.Calibration.paper_rig()
    board = np.array([[1.5 * i, 1.5 * j, 0.0] for j in range(12) for i in range(14)])
    e = 140.0
    poses = []
    for z in (28.0, 30.0):
        px = cal.project(board + [0, 0, z], e)
        poses.append(cal.solve_pnp(board, px, e))
    assert poses[0].rms_px < 1e-6 and poses[0].iterations >= 0
    move = poses[0].displacement_mm(poses[1])
    assert abs(np.linalg.norm(move) - 2.0) < 1e-6
    # The board origin in camera coordinates is R (0, 0, z) + T.
    expect = cal.rotation_matrix @ [0, 0, 28.0] + cal.translation_mm
    assert np.max(np.abs(poses[0].translation_mm - expect)) < 1e-6
    assert np.allclose(poses[0].rotation_matrix, cal.rotation_matrix, atol=1e-9)
    assert np.allclose(poses[0].rotation_rodrigues, [0.2, 0.2, 0.2], atol=1e-9)
    assert pickle.loads(pickle.dumps(poses[0])) == poses[0]
    assert repr(poses[0]).startswith("BoardPose(")


def test_solve_pnp_bad_inputs() -> None:
    cal = etlcal.Calibration.paper_rig()
    board = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    px = cal.project(board + [0, 0, 40.0], 120.0)
    cases: List[Tuple[Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]], Optional[str]]] = [
        ((board[:3], px[:3]), "too few points for PnP: the method needs at least 4, got 3"),
        ((board, px[:3]), "invalid argument: board points and pixels differ in number"),
        ((board + [0, 0, 1.0], px), "invalid argument: board points must lie on Z = 0 of the board frame"),
        ((np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]]), px), None),
        ((board, px * np.nan), "pixel is NaN or infinite; pass finite numbers"),
    ]
    for (b, p), message in cases:
        with pytest.raises(etlcal.InputError) as info:
            cal.solve_pnp(b, p, 120.0)
        if message:
            assert str(info.value) == message
        else:
            assert str(info.value).startswith("degenerate input:")


def test_cramer_rao_bound_of_the_paper_rig() -> None:
    sim = etlcal.simulate.paper_rig(0, noise="none")
    plain = etlcal.cramer_rao_std(sim.observations, sim.truth, 0.2)
    # docs/METHOD.md: with 0.2 px of pixel noise alone the bound of kf3 is about 3 %.
    rel = plain["kf_x"][3] / 3e-5
    assert 0.015 < rel < 0.06, rel
    eiv = etlcal.cramer_rao_std(sim.observations, sim.truth, 0.2, sigma_z_mm=0.010, sigma_e_ma=0.4)
    assert np.all(eiv["kf_x"] > plain["kf_x"])
    # Twice the noise, twice the bound.
    double = etlcal.cramer_rao_std(sim.observations, sim.truth, 0.4)
    assert np.allclose(double["kf_y"], 2 * plain["kf_y"], rtol=1e-9)
    with pytest.raises(etlcal.InputError, match="give both"):
        etlcal.cramer_rao_std(sim.observations, sim.truth, 0.2, sigma_z_mm=0.01)
    with pytest.raises(etlcal.InputError, match="sigma_px"):
        etlcal.cramer_rao_std(sim.observations, sim.truth, 0.0)
    # The request's ranges: a sigma whose square overflows once gave a bound of 0.
    with pytest.raises(etlcal.InputError, match="^invalid input: sigma_px must be positive and finite, at most 100 px"):
        etlcal.cramer_rao_std(sim.observations, sim.truth, 1e155)
    with pytest.raises(etlcal.InputError, match="^invalid input: sigma_e_ma .* at most 50 mA"):
        etlcal.cramer_rao_std(sim.observations, sim.truth, 0.2, sigma_z_mm=0.01, sigma_e_ma=1e200)


def test_a0_from_the_lens_off_views_when_not_given(sim: etlcal.Simulation) -> None:
    # Without a0, Zhang's method on the simulation's 10 lens-off views gives A0 (as
    # `etlcal calibrate` without --a0): the fx(E) curve stays within the demo's tolerance.
    cal = etlcal.calibrate(sim.observations)
    e = np.linspace(80, 225, 30)
    fx = np.polyval(cal.kf_x[::-1], e)
    fx_true = np.polyval(sim.truth.kf_x[::-1], e)
    assert np.max(np.abs(fx / fx_true - 1)) < 0.02
    no_offstate = etlcal.Observations((1936, 1458))
    for i in range(len(sim.observations)):
        v = sim.observations.view(i)
        no_offstate.add_view(v["world_mm"], v["pixels"], v["e_in_ma"], v["temperature_c"], v["e_com_ma"])
    with pytest.raises(etlcal.InputError, match="no lens-off views"):
        etlcal.calibrate(no_offstate)


def test_per_setting_baseline_from_python() -> None:
    sim = etlcal.simulate.paper_rig(seed=3, setting_views=True)
    obs = sim.observations
    assert obs.setting_count == 7 * 15 and len(obs) == 15
    s = obs.setting_view(-1)
    assert s["world_mm"].shape[1] == 3 and np.all(s["world_mm"][:, 2] == 0.0)
    assert pickle.loads(pickle.dumps(sim)).observations == obs
    base = etlcal.calibrate(obs, method="per-setting")
    assert base.estimator == "per-setting"
    # The baseline's fx(E) is a cubic through per-setting Zhang estimates: close to the
    # truth over the calibrated currents, but the paper's method is closer (Fig. 12(a)).
    e = np.linspace(80, 225, 30)
    truth = np.polyval(sim.truth.kf_x[::-1], e)
    base_err = np.max(np.abs(np.polyval(base.kf_x[::-1], e) / truth - 1))
    assert base_err < 0.05
    with pytest.raises(etlcal.InputError, match="takes no a0, estimator"):
        etlcal.calibrate(obs, sim.a0, method="per-setting")
    # The estimator left at its default (None) is accepted above; one passed explicitly,
    # even the proposed method's default "eiv", is refused: the baseline has no BA.
    for est in ("paper", "eiv"):
        with pytest.raises(etlcal.InputError, match="takes no a0, estimator"):
            etlcal.calibrate(obs, estimator=est, method="per-setting")
    assert etlcal.calibrate(obs, estimator=None, method="per-setting") == base
    with pytest.raises(etlcal.InputError, match='method must be "proposed" or "per-setting"'):
        etlcal.calibrate(obs, method="zhang")  # type: ignore[arg-type]  # the run-time check under test
    # Too few settings: the Rust message, unchanged.
    few = etlcal.Observations((1936, 1458))
    for i in range(obs.setting_count):
        v = obs.setting_view(i)
        if v["e_com_ma"] < 110:
            few.add_setting_view(v["world_mm"], v["pixels"], v["e_in_ma"], v["temperature_c"], v["e_com_ma"])
    with pytest.raises(etlcal.InputError, match=r"needs views at >= 3 distinct currents, got 2"):
        etlcal.calibrate(few, method="per-setting")
    with pytest.raises(etlcal.InputError, match="needs setting_views"):
        etlcal.calibrate(etlcal.simulate.paper_rig(seed=3).observations, method="per-setting")
    with pytest.raises(etlcal.InputError, match="not finite"):
        few.add_setting_view([[0.0, 0.0, 0.0]] * 4, [[1.0, 1.0]] * 4, math.nan, 27.0)
    assert few.setting_count == 2 * 15


def _board_pixels(
    cal: etlcal.Calibration, z_mm: float, e_com_ma: float
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    board = np.array([[1.5 * i, 1.5 * j, 0.0] for j in range(12) for i in range(14)])
    return board, cal.project(board + [0, 0, z_mm], e_com_ma)


def test_solve_pnp_pixel_noise_covariance_matches_monte_carlo() -> None:
    """sigma^2 (J^T J)^-1 against the spread of 300 PnPs of noisy pixels (0.2 px), and the
    displacement's std of two poses against that of their differences."""
    cal = etlcal.Calibration.paper_rig()
    e = 140.0
    board, px_a = _board_pixels(cal, 28.0, e)
    _, px_b = _board_pixels(cal, 30.0, e)
    a = cal.solve_pnp(board, px_a, e, sigma_px=0.2)
    b = cal.solve_pnp(board, px_b, e, sigma_px=0.2)
    assert a.sigma_px == 0.2 and a.covariance is not None and a.covariance.shape == (6, 6)
    assert np.allclose(a.covariance, a.covariance.T, rtol=0, atol=1e-18)
    predicted = np.sqrt(np.diag(a.covariance))
    d_std = a.displacement_std_mm(b, pixel_noise_only=True)
    rng = np.random.default_rng(5)
    poses, moves = [], []
    for _ in range(300):
        pa = cal.solve_pnp(board, px_a + rng.normal(0, 0.2, px_a.shape), e)
        pb = cal.solve_pnp(board, px_b + rng.normal(0, 0.2, px_b.shape), e)
        poses.append(np.concatenate([pa.rotation_rodrigues, pa.translation_mm]))
        moves.append(pa.displacement_mm(pb))
    # 300 trials: the observed std is uncertain by 1 / sqrt(600), 4 %.
    observed = np.std(poses, axis=0, ddof=1)
    assert np.all(np.abs(observed / predicted - 1) < 0.15), (observed, predicted)
    observed_move = np.std(moves, axis=0, ddof=1)
    assert np.all(np.abs(observed_move / d_std - 1) < 0.15), (observed_move, d_std)
    # The residual estimate of sigma: ~0.2 px on noisy pixels, ~0 on exact ones.
    noisy = cal.solve_pnp(board, px_a + rng.normal(0, 0.2, px_a.shape), e)
    exact = cal.solve_pnp(board, px_a, e)
    assert noisy.sigma_px is not None and exact.sigma_px is not None
    assert abs(noisy.sigma_px / 0.2 - 1) < 0.15
    assert exact.sigma_px < 1e-6
    # Pickling keeps the uncertainty.
    back = pickle.loads(pickle.dumps(a))
    assert back.covariance is not None
    assert back == a and back.sigma_px == 0.2 and np.array_equal(back.covariance, a.covariance)


def test_displacement_std_refuses_what_it_cannot_know() -> None:
    cal = etlcal.Calibration.paper_rig()
    board, px = _board_pixels(cal, 28.0, 140.0)
    a = cal.solve_pnp(board, px, 140.0, sigma_px=0.2)
    with pytest.raises(etlcal.InputError) as info:
        a.displacement_std_mm(a)
    assert str(info.value) == (
        "the calibration has no covariance: pass pixel_noise_only=True for the pixel noise's part alone")
    by_hand = etlcal.BoardPose((0.0, 0.0, 0.0), (0.0, 0.0, 50.0))
    assert by_hand.sigma_px is None and by_hand.covariance is None
    with pytest.raises(etlcal.InputError, match="the other pose has no uncertainty"):
        a.displacement_std_mm(by_hand, pixel_noise_only=True)
    with pytest.raises(etlcal.InputError, match="sigma must be finite and >= 0"):
        cal.solve_pnp(board, px, 140.0, sigma_px=-1.0)
    with pytest.raises(etlcal.InputError, match="no covariance"):
        cal.projection_std(board, 140.0)


def _with_covariance(
    cal: etlcal.Calibration, cov: npt.NDArray[np.float64], std: npt.NDArray[np.float64]
) -> etlcal.Calibration:
    """The calibration with a covariance and the matching std written into its file."""
    d = json.loads(cal.to_json())
    names = [("rotation_rodrigues", 3), ("translation_mm", 3), ("kf_x", 4), ("kf_y", 4), ("principal_point", 2),
             ("distortion_a", 9)]
    k = 0
    for name, n in names:
        d["std"][name] = list(std[k:k + n])
        k += n
    d["covariance"] = cov.tolist()
    return etlcal.Calibration.from_json(json.dumps(d))


def test_projection_std_is_the_principal_points_for_its_covariance() -> None:
    """A covariance on (u0, v0) alone passes to every pixel as is: std (2, 0.5) px."""
    cov = np.zeros((25, 25))
    cov[14, 14], cov[15, 15], cov[14, 15], cov[15, 14] = 4.0, 0.25, 0.3, 0.3
    cal = _with_covariance(etlcal.Calibration.paper_rig(), cov, np.sqrt(np.diag(cov)))
    assert cal.covariance is not None and np.array_equal(cal.covariance, cov)
    pts = np.array([[5.0, 4.0, 40.0], [20.0, 15.0, 10.0]])
    assert np.array_equal(cal.projection_std(pts, 150.0), [[2.0, 0.5], [2.0, 0.5]])
    assert cal.projection_std(pts[0], 150.0).shape == (2,)
    bad = cov.copy()
    bad[14, 15] = 0.4
    with pytest.raises(etlcal.InputError, match="covariance is not symmetric"):
        _with_covariance(etlcal.Calibration.paper_rig(), bad, np.sqrt(np.diag(cov)))


def test_pixel_projection_std_is_that_of_the_point_seen_there(sim: etlcal.Simulation) -> None:
    """mrcal's sense: the point seen at a pixel at a distance along its ray is a world point,
    and a direction is the limit of far points; bad distances are refused by name."""
    cal = etlcal.calibrate(sim.observations, sim.a0)
    e = 150.0
    pixels = np.array([[968.0, 729.0], [150.0, 120.0], [1800.0, 1350.0]])
    for q in pixels:
        origin, direction = cal.ray((float(q[0]), float(q[1])), e)
        for d in (22.0, 300.0):
            world = origin + d * direction
            assert np.allclose(cal.pixel_projection_std(q, e, d), cal.projection_std(world, e), rtol=1e-9)
    far = cal.pixel_projection_std(pixels, e, 1e9)
    at_infinity = cal.pixel_projection_std(pixels, e)
    assert at_infinity.shape == (3, 2) and np.allclose(at_infinity, far, rtol=1e-6)
    # Near the board the translation's uncertainty adds to the pixel's.
    assert not np.allclose(cal.pixel_projection_std(pixels, e, 22.0), at_infinity, rtol=1e-3)
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(etlcal.InputError, match="distance_mm = .* must be a finite number > 0"):
            cal.pixel_projection_std(pixels, e, bad)
    with pytest.raises(etlcal.InputError, match="outside"):
        cal.pixel_projection_std(pixels, 400.0)
    with pytest.raises(etlcal.InputError, match="no covariance"):
        etlcal.Calibration.paper_rig().pixel_projection_std(pixels, e)


def test_calibrate_records_the_covariance_and_measures_with_it(sim: etlcal.Simulation) -> None:
    cal = etlcal.calibrate(sim.observations, sim.a0)
    c = cal.covariance
    assert c is not None and c.shape == (25, 25) and np.array_equal(c, c.T)
    std = np.concatenate([cal.std[k] for k in ("rotation_rodrigues", "translation_mm", "kf_x", "kf_y",
                                               "principal_point", "distortion_a")])
    assert np.array_equal(np.sqrt(np.diag(c)), std)
    # projection_std against J C J^T with J by central differences of the projection.
    w, e = np.array([10.0, 8.0, 22.0]), 150.0
    d = json.loads(cal.to_json())
    x = np.concatenate([d[k] for k in ("rotation_rodrigues", "translation_mm", "kf_x", "kf_y",
                                       "principal_point", "distortion_a")])
    jac = np.zeros((2, 25))
    for i in range(25):
        h = 1e-6 * max(abs(x[i]), 1e-3)
        p = []
        for s in (h, -h):
            xi = x.copy()
            xi[i] += s
            m = etlcal.Calibration(xi[0:3], xi[3:6], xi[6:10], xi[10:14], xi[14:16], xi[16:25])
            p.append(m.project(w, e))
        jac[:, i] = (p[0] - p[1]) / (2 * h)
    expect = np.sqrt(np.diag(jac @ c @ jac.T))
    assert np.allclose(cal.projection_std(w, e), expect, rtol=1e-4)
    # A 2 mm move: the displacement's std with the calibration's covariance is larger
    # than the pixel noise's alone, and the true move lies within 4 of them.
    board, px_a = _board_pixels(sim.truth, 22.0, e)
    _, px_b = _board_pixels(sim.truth, 20.0, e)
    rng = np.random.default_rng(3)
    a = cal.solve_pnp(board, px_a + rng.normal(0, 0.2, px_a.shape), e)
    b = cal.solve_pnp(board, px_b + rng.normal(0, 0.2, px_b.shape), e)
    s = a.displacement_std_mm(b)
    s_px = a.displacement_std_mm(b, pixel_noise_only=True)
    assert np.all(s >= s_px) and np.all(s > 0)
    truth = sim.truth.rotation_matrix @ [0, 0, -2.0]
    assert np.all(np.abs(a.displacement_mm(b) - truth) < 4 * s), (a.displacement_mm(b) - truth, s)


def test_calibrate_reports_outliers_and_warns(sim: etlcal.Simulation) -> None:
    # Issue 19: two corners moved far off are left out, listed as (view, point,
    # residual_px), and said as a UserWarning; a clean calibration has neither.
    clean = etlcal.calibrate(sim.observations, sim.a0)
    assert clean.outliers == [] and clean.warnings == []
    doc = json.loads(sim.observations.to_json())
    for v, p in [(1, 4), (8, 30)]:
        px = doc["views"][v]["points"][p]["pixel"]
        doc["views"][v]["points"][p]["pixel"] = [px[0] - 250.0, px[1] + 120.0]
    obs = etlcal.Observations.from_json(json.dumps(doc))
    with pytest.warns(UserWarning, match="2 of 2311 corners"):
        cal = etlcal.calibrate(obs, sim.a0)
    assert [(v, p) for v, p, _ in cal.outliers] == [(1, 4), (8, 30)]
    assert all(r > 200.0 for _, _, r in cal.outliers)
    assert cal.warnings[0].startswith("2 of 2311 corners")
    assert abs(cal.principal_point[0] - clean.principal_point[0]) < 0.5
    again = etlcal.Calibration.from_json(cal.to_json())
    assert again.outliers == cal.outliers and again.warnings == cal.warnings


def test_per_setting_baseline_names_zhangs_outliers_by_setting_view() -> None:
    # Issue 19: corners of setting views moved far off are left out by Zhang's method at
    # their setting and listed as (setting view, point, residual_px), the view counted in
    # the observations' setting_views; a clean baseline has none.
    sim = etlcal.simulate.paper_rig(seed=3, setting_views=True)
    doc = json.loads(sim.observations.to_json())
    clean = etlcal.calibrate(etlcal.Observations.from_json(json.dumps(doc)), method="per-setting")
    assert clean.setting_outliers == [] and clean.outliers == []
    last = len(doc["setting_views"]) - 1
    for v, p in [(2, 9), (last, 40)]:
        px = doc["setting_views"][v]["points"][p]["pixel"]
        doc["setting_views"][v]["points"][p]["pixel"] = [px[0] + 150.0, px[1] - 90.0]
    base = etlcal.calibrate(etlcal.Observations.from_json(json.dumps(doc)), method="per-setting")
    assert [(v, p) for v, p, _ in base.setting_outliers] == [(2, 9), (last, 40)]
    assert all(r > 100.0 for _, _, r in base.setting_outliers)
    assert etlcal.Calibration.from_json(base.to_json()).setting_outliers == base.setting_outliers


def test_a_calibration_the_data_do_not_determine_is_refused_unless_accepted(tmp_path: pathlib.Path) -> None:
    # Three views of six corners of the golden observations: the principal point is then
    # unknown to hundreds of px.
    root = pathlib.Path(__file__).resolve().parents[3]
    d = json.loads((root / "fixtures" / "golden" / "observations.json").read_text())
    d["views"] = [dict(v, points=v["points"][:6]) for v in d["views"][:3]]
    tiny = tmp_path / "tiny.json"
    tiny.write_text(json.dumps(d))
    obs = etlcal.Observations.load(tiny)
    with pytest.raises(etlcal.InputError, match=r"principal point's standard deviation .*accept_ill_conditioned=True"):
        etlcal.calibrate(obs)
    with pytest.warns(UserWarning, match="ill-conditioned, kept by accept_ill_conditioned=True"):
        cal = etlcal.calibrate(obs, accept_ill_conditioned=True)
    assert cal.warnings[0].startswith("ill-conditioned, kept by accept_ill_conditioned=True: the principal point")


def test_setting_views_joint_is_the_cli_s_and_refused_without_setting_views(
    etlcal_binary: str, tmp_path: pathlib.Path
) -> None:
    # setting_views="joint": the simulated setting views solved with the stage views,
    # the same calibration as `etlcal calibrate --setting-views joint`; "ignored" is the
    # default; refused naming setting_views without setting views or beside a robust loss.
    import subprocess

    sim_dir = tmp_path / "sim"
    subprocess.run([etlcal_binary, "simulate", "--out", str(sim_dir), "--observations-only", "--setting-views",
                    "--seed", "7"], check=True, capture_output=True)
    obs = etlcal.Observations.load(sim_dir / "observations.json")
    a0 = etlcal.A0.load(sim_dir / "a0.json")
    out = tmp_path / "joint.json"
    subprocess.run([etlcal_binary, "calibrate", "--observations", str(sim_dir / "observations.json"), "--a0",
                    str(sim_dir / "a0.json"), "--out", str(out), "--setting-views", "joint", "--centre", "moving"],
                   check=True, capture_output=True)
    with pytest.warns(UserWarning):
        joint = etlcal.calibrate(obs, a0, setting_views="joint", centre="moving")
    assert joint == etlcal.Calibration.load(out)
    # Each setting view's solved pose, as the file records it.
    recorded = json.loads(out.read_text())["setting_views"]
    assert len(joint.setting_views) == len(recorded) == obs.setting_count > 0
    for got, want in zip(joint.setting_views, recorded):
        assert isinstance(got, etlcal.SettingViewSummary) and got.points == want["points"]
        assert np.array_equal(got.translation_mm, want["translation_mm"])
        assert got.rms_px < 1.0 and got.translation_mm[2] > 0  # in front of the camera
    with pytest.warns(UserWarning):
        stage = etlcal.calibrate(obs, a0, centre="moving")
        ignored = etlcal.calibrate(obs, a0, centre="moving", setting_views="ignored")
    assert stage == ignored and stage != joint and stage.setting_views == []
    with pytest.raises(etlcal.InputError, match='setting_views="joint" does not go with robust'):
        etlcal.calibrate(obs, a0, setting_views="joint", robust="huber")
    with pytest.raises(etlcal.InputError, match="setting_views must be"):
        etlcal.calibrate(obs, a0, setting_views="tilted")  # type: ignore[arg-type]  # the run-time check under test
    stage_only = etlcal.simulate.paper_rig(seed=1)
    with pytest.raises(etlcal.InputError, match='setting_views="joint" needs setting_views'):
        etlcal.calibrate(stage_only.observations, stage_only.a0, setting_views="joint")
