"""The Python paths as safe as the CLI's: objects used from other threads raise
`etlcal.Error` (never PanicException or a builtin RuntimeError), the readers refuse what
the CLI's refuse, and requests sized by the caller are refused before they allocate."""
import os
import threading
from pathlib import Path
from typing import Any, Callable, List, Tuple

import numpy as np
import pytest

import etlcal

ROOT = Path(__file__).resolve().parents[3]
CALIBRATION = ROOT / "fixtures" / "service" / "calibration.json"


def run_in_thread(f: Callable[[], Any]) -> Tuple[str, Any]:
    """Runs f() on another thread; returns ("ok", value) or ("raised", exception)."""
    out: List[Tuple[str, Any]] = []

    def target() -> None:
        try:
            out.append(("ok", f()))
        except BaseException as e:  # noqa: BLE001 - the point is to see what escapes
            out.append(("raised", e))

    t = threading.Thread(target=target)
    t.start()
    t.join(30)
    assert not t.is_alive() and len(out) == 1
    return out[0]


def test_a_virtual_lens_and_a_lens_work_from_another_thread() -> None:
    device = etlcal.VirtualLens()
    kind, state = run_in_thread(device.state)
    assert kind == "ok" and isinstance(state, etlcal.LensState), state
    lens = etlcal.Lens(device.port)
    kind, got = run_in_thread(lambda: lens.set_current_ma(120.0))
    assert kind == "ok" and abs(got - 120.0) < 0.04, got
    assert abs(device.state().e_in_ma - got) < 1e-9
    lens.close()
    kind, _ = run_in_thread(device.disconnect)
    assert kind == "ok"


def test_a_call_during_a_hold_on_another_thread_is_an_etlcal_error_naming_the_rule() -> None:
    device = etlcal.VirtualLens()
    cal = etlcal.ThermalCalibration.paper()
    seen: List[Tuple[str, Any]] = []
    with etlcal.Lens(device.port) as lens:
        def observer(step: etlcal.HoldStep) -> bool:
            if step.index == 0:
                seen.append(run_in_thread(lens.current_ma))
            return step.index < 2

        r = lens.hold(cal, 120.0, on_step=observer)
        assert r.commands_sent == 3
        kind, err = seen[0]
        assert kind == "raised" and isinstance(err, etlcal.DeviceError), err
        assert "busy" in str(err) and "another thread" in str(err)
        # After the hold the lens serves every thread again.
        kind, got = run_in_thread(lens.current_ma)
        assert kind == "ok" and abs(got - device.state().e_in_ma) < 0.04


def test_many_threads_share_one_lens_without_mixing_replies() -> None:
    device = etlcal.VirtualLens()
    with etlcal.Lens(device.port) as lens:
        errors: List[BaseException] = []

        def worker(k: int) -> None:
            try:
                for _ in range(10):
                    lens.temperature_c()
                    lens.set_current_ma(100.0 + k)
            except BaseException as e:  # noqa: BLE001
                errors.append(e)

        threads = [threading.Thread(target=worker, args=(k,)) for k in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(60)
        assert errors == []
        assert 100.0 - 0.04 < lens.current_ma() < 103.04


def test_calibration_load_refuses_a_fifo_a_device_and_a_directory_in_the_clis_words(tmp_path: Path) -> None:
    fifo = tmp_path / "fifo.json"
    os.mkfifo(fifo)
    for bad in [fifo, Path("/dev/zero"), tmp_path]:
        with pytest.raises(etlcal.Error, match="not a regular file"):
            etlcal.Calibration.load(bad)
    with pytest.raises(etlcal.Error, match="not a regular file"):
        etlcal.Observations.load(fifo)
    # The good file still reads.
    assert etlcal.Calibration.load(CALIBRATION).image_size == (1936, 1458)


def test_a_json_file_beyond_the_size_limit_is_refused_before_reading(tmp_path: Path) -> None:
    big = tmp_path / "big.json"
    with open(big, "wb") as f:
        f.truncate((1 << 30) + 1)  # sparse: no disk used
    with pytest.raises(etlcal.Error, match="more than the 1073741824"):
        etlcal.Calibration.load(big)


def test_caller_sized_requests_are_refused_before_they_allocate() -> None:
    with pytest.raises(etlcal.InputError, match="trials 100000000 must lie in 0..=100000"):
        etlcal.study("fig6", trials=10**8)
    cal = etlcal.Calibration.load(CALIBRATION)
    with pytest.raises(etlcal.InputError, match="width_px x height_px"):
        cal.at_e_com(150.0).undistort_maps(size=(100000, 100000))
    # A size within the limits works.
    mx, my = cal.at_e_com(150.0).undistort_maps(size=(64, 48))
    assert mx.shape == (48, 64) and my.shape == (48, 64)


def test_maps_beyond_the_memory_budget_are_refused_naming_the_option(monkeypatch: pytest.MonkeyPatch) -> None:
    # 4000 x 3000 px of two f32 maps: 96 MB, above a 10 MB budget, within the pixel cap.
    cal = etlcal.Calibration.load(CALIBRATION)
    monkeypatch.setenv("ETLCAL_MEMORY_BUDGET", "10M")
    with pytest.raises(etlcal.InputError, match=r"size needs about 0\.096 GB, above the memory budget of 0\.010 GB"):
        cal.at_e_com(150.0).undistort_maps(size=(4000, 3000))
    monkeypatch.setenv("ETLCAL_MEMORY_BUDGET", "ten megabytes")
    with pytest.raises(etlcal.InputError, match="is not a number of bytes"):
        cal.at_e_com(150.0).undistort_maps(size=(4000, 3000))
    monkeypatch.setenv("ETLCAL_MEMORY_BUDGET", "200M")
    mx, _ = cal.at_e_com(150.0).undistort_maps(size=(4000, 3000))
    assert mx.shape == (3000, 4000)


def test_arrays_of_other_than_real_numbers_are_refused_naming_the_dtype() -> None:
    cal = etlcal.Calibration.load(CALIBRATION)
    cam = cal.at_e_com(150.0)
    world = np.array([[0.0, 0.0, 0.0], [10.0, 5.0, 0.0]])
    # complex: numpy's cast would drop the imaginary part with only a warning
    for bad, dtype in [
        (world.astype(np.complex128), "complex128"),
        (world.astype(bool), "bool"),
        (world.astype(str), "<U32"),
        (world.astype(object), "object"),
    ]:
        with pytest.raises(etlcal.InputError, match=f"must hold real numbers \\(integer or float\\), got dtype {dtype}"):
            cam.project(bad)
    with pytest.raises(etlcal.InputError, match="got dtype complex128"):
        cal.e_com(np.array([100.0, 150.0], dtype=np.complex128), 30.0)
    with pytest.raises(etlcal.InputError, match="got dtype <U3"):
        cal.focal_lengths("1.5")  # type: ignore[arg-type]
    with pytest.raises(etlcal.InputError, match="got dtype <U5"):
        cal.focal_lengths(["100.0", "150.0"])  # type: ignore[list-item]
    # real numbers in any numeric dtype or as lists: accepted, the same result
    ref = cam.project(world)
    for ok in [world.astype(np.float32), world.astype(np.int64), world.tolist()]:
        assert np.allclose(cam.project(ok), ref, atol=1e-3)


def test_zhang_refuses_an_image_size_of_zero() -> None:
    obs = etlcal.simulate.paper_rig(1).observations
    views = [(obs.offstate_view(k)["world_mm"][:, :2], obs.offstate_view(k)["pixels"]) for k in range(4)]
    with pytest.raises(etlcal.InputError, match="image_size"):
        etlcal.zhang(views, (0, 0))
    assert etlcal.zhang(views, (1936, 1458)).rms_px < 1.0
    # a NaN pixel is refused, naming its view (it was dropped silently)
    bad = [(w, p.copy()) for w, p in views]
    bad[2][1][5, 0] = np.nan
    with pytest.raises(etlcal.InputError, match="view 2: pixels point 5 is not finite"):
        etlcal.zhang(bad, (1936, 1458))


def test_sizes_that_mean_nothing_are_refused() -> None:
    with pytest.raises(etlcal.InputError, match="more than 268435456 pixels"):
        etlcal.Observations((65536, 65536))
    with pytest.raises(etlcal.InputError, match="below the smallest board square, 1e-3 mm"):
        etlcal.Board.checkerboard((9, 7), 1e-300)
    with pytest.raises(etlcal.InputError, match="below the smallest board square"):
        etlcal.Board.charuco((12, 9), 1e-300, 0.7e-300, "DICT_5X5_100")
    assert etlcal.Observations((1936, 1458)).image_size == (1936, 1458)
    etlcal.Board.checkerboard((9, 7), 0.001)


def _huge(shape: Tuple[int, ...], dtype: Any = np.float64) -> "np.ndarray[Any, Any]":
    """An array declaring `shape` over one element (zero strides): no memory of its own."""
    return np.lib.stride_tricks.as_strided(np.ones(1, dtype=dtype), shape=shape, strides=(0,) * len(shape))


def test_an_array_too_large_to_copy_is_refused_by_its_shape_before_any_copy() -> None:
    # Each of these once aborted the interpreter (SIGABRT) when copied.
    cal = etlcal.Calibration.load(CALIBRATION)
    cam = cal.at_e_com(150.0)
    rows = 2**31
    with pytest.raises(etlcal.InputError, match=rf"^pixels has {rows * 2} elements .* more than the 67108864"):
        cam.undistort(_huge((rows, 2)))
    with pytest.raises(etlcal.InputError, match="more than the 67108864"):
        cal.focal_lengths(_huge((rows,)))
    with pytest.raises(etlcal.InputError, match="^image has 1073741824 elements .* more than the 268435456"):
        etlcal.detect_corners(_huge((2**15, 2**15), np.uint8), (9, 6))
    o = etlcal.Observations((1936, 1458))
    with pytest.raises(etlcal.InputError, match="more than the 67108864"):
        o.add_view(_huge((rows, 3)), _huge((rows, 2)), 150.0, 31.0)
    assert len(o) == 0
    # The limit is on what is copied, not on what is passed: a real array is read whole.
    fx, fy = cal.focal_lengths(np.linspace(100.0, 200.0, 1000))
    assert fx.shape == fy.shape == (1000,)


def test_views_added_while_another_thread_calibrates_are_not_an_error() -> None:
    # calibrate() once held a borrow of the Observations through the solve: add_view on
    # another thread raised a builtin RuntimeError("Already borrowed").
    sim = etlcal.simulate.paper_rig(seed=3)
    obs = sim.observations
    first = obs[0]
    errors: List[BaseException] = []
    before = len(obs)

    def add() -> None:
        try:
            for _ in range(300):
                obs.add_view(first.world_mm, first.pixels, first.e_in_ma, first.temperature_c)
        except BaseException as e:  # the test's point: nothing escapes
            errors.append(e)

    t = threading.Thread(target=add)
    t.start()
    for _ in range(3):
        etlcal.calibrate(obs, sim.a0, thermal="paper")
    t.join()
    assert errors == [] and len(obs) == before + 300
