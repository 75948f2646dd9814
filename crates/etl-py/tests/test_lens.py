"""`Lens` against `VirtualLens` through a pseudo-terminal, from Python."""
import math
import pathlib
import time
from typing import List, Optional

import numpy as np
import numpy.typing as npt
import pytest

import etlcal


def test_lens_talks_to_the_virtual_lens() -> None:
    device = etlcal.VirtualLens()
    with etlcal.Lens(device.port) as lens:
        info = lens.info()
        assert isinstance(info, etlcal.LensInfo)
        assert info.lens_serial == "ETLV0001" and info.firmware_type == "C"
        assert info.firmware_version == "3.8.1.5"  # the virtual driver's (etl-hw VirtualLensConfig)
        assert info.upper_limit_ma == pytest.approx(292.84) and info.lower_limit_ma == pytest.approx(-292.84)
        assert info.max_current_ma == pytest.approx(292.84)
        assert info.temperature_c is not None and abs(info.temperature_c - device.state().temperature_c) < 0.2
        # Dict access, as when info() returned a dict.
        assert info["lens_serial"] == "ETLV0001" and info["upper_limit_ma"] == info.upper_limit_ma
        assert set(info) == {"firmware_type", "firmware_version", "lens_serial", "max_current_ma",
                             "upper_limit_ma", "lower_limit_ma", "temperature_c"}
        assert repr(info).startswith("LensInfo(firmware_type='C', firmware_version='3.8.1.5'")
        got = lens.set_current_ma(150.0)
        assert abs(got - 150.0) < 0.04  # 12-bit quantisation
        assert lens.current_ma() == pytest.approx(got)
        assert device.state().e_in_ma == pytest.approx(got)
        device.set_temperature_c(32.0)
        assert abs(lens.temperature_c() - 32.0) < 0.1
        # E_com = E_in - E_T(T, E_in) inside the device follows the paper's surface.
        s = device.state()
        assert isinstance(s, etlcal.LensState)
        assert s.e_com_ma == pytest.approx(s.e_in_ma - s.e_t_ma)
        assert s.e_t_ma == pytest.approx(etlcal.ThermalSurface.paper().e_t(s.e_in_ma, s.temperature_c), abs=1e-9)
        # f_com at E_com (Eq. 10) of the paper's lens, which the device simulates.
        assert s.f_com_mm == pytest.approx(etlcal.physics.f_com_mm(s.e_com_ma), rel=1e-12)
        assert s["e_com_ma"] == s.e_com_ma and dict(s) == s.to_dict()


def test_no_current_outside_the_limits_reaches_the_wire() -> None:
    device = etlcal.VirtualLens()
    lo, hi = device.limits_ma
    with etlcal.Lens(device.port) as lens:
        for request in [1e9, -1e9, 300.0, -300.0, 291.0]:
            got = lens.set_current_ma(request)
            assert lo <= got <= hi
        with pytest.raises(etlcal.InputError):
            lens.set_current_ma(math.nan)
    assert all(-4095 <= c <= 4095 for c in device.received_current_codes())


def test_errors_are_device_errors() -> None:
    with pytest.raises(etlcal.DeviceError):
        etlcal.Lens("/dev/no-such-port")
    device = etlcal.VirtualLens()
    lens = etlcal.Lens(device.port)
    lens.close()
    with pytest.raises(etlcal.DeviceError):
        lens.current_ma()


def test_thermal_calibration_with_a_python_camera() -> None:
    """The section 4.1 procedure with the camera and the climate as Python callables: a
    numpy camera whose blur grows with the distance of the lens's true E_com from the one
    the board was placed at, looking through the virtual lens."""
    device = etlcal.VirtualLens()
    yy, xx = np.mgrid[0:96, 0:96]
    board = np.where(((xx // 12) + (yy // 12)) % 2 == 0, 200.0, 40.0)
    f = np.fft.fft2(board)
    k2 = (2 * np.pi * np.fft.fftfreq(96))[None, :] ** 2 + (2 * np.pi * np.fft.fftfreq(96))[:, None] ** 2
    focus_ma: List[float] = []  # E_com at each placement of the board
    captures: List[int] = []
    temps: List[float] = []

    def capture() -> npt.NDArray[np.uint8]:
        captures.append(1)
        sigma = 0.5 + 0.3 * abs(device.state().e_com_ma - focus_ma[-1])
        img = np.real(np.fft.ifft2(f * np.exp(-0.5 * sigma**2 * k2)))
        frame: npt.NDArray[np.uint8] = np.clip(np.round(img), 0, 255).astype(np.uint8)
        return frame

    def place_board() -> None:
        focus_ma.append(device.state().e_com_ma)

    def set_temperature(t: float) -> None:
        temps.append(t)
        device.set_temperature_c(t)

    with etlcal.Lens(device.port) as lens:
        r = etlcal.thermal_calibration(
            lens, capture, set_temperature, place_board,
            e_in_grid_ma=[60.0, 110.0, 160.0, 210.0], temperatures_c=[27.0, 30.5, 34.0, 37.0], search_ma=15.0,
        )
    assert len(focus_ma) == 4 and len(captures) == r["frames"]
    samples = r["samples"]
    assert samples.shape == (16, 3)
    truth = etlcal.ThermalSurface.paper()
    # Each sample's E_T is the truth's change of E_T since the first temperature.
    for k in range(4):
        t0, e0, _ = samples[4 * k]
        for t, e, et in samples[4 * k : 4 * k + 4]:
            want = truth.e_t(e, t) - truth.e_t(e0, t0)
            assert abs(et - want) < 0.3, (t, e, et, want)
    assert isinstance(r["calibration"], etlcal.ThermalCalibration)

    def broken() -> npt.NDArray[np.uint8]:
        raise RuntimeError("camera unplugged")

    with etlcal.Lens(device.port) as lens:
        with pytest.raises(RuntimeError, match="camera unplugged"):
            etlcal.thermal_calibration(lens, broken, set_temperature, e_in_grid_ma=[100.0], temperatures_c=[27.0, 30.0])
        with pytest.raises(etlcal.InputError):
            etlcal.thermal_calibration(lens, capture, set_temperature, temperatures_c=[27.0])


def test_a_lens_timeout_inside_the_temperature_procedure_is_a_device_timeout() -> None:
    """The procedure is library code between Python and the lens: the failure keeps its
    kind on the way, so it is DeviceTimeoutError, not InputError."""
    device = etlcal.VirtualLens()
    frame = np.full((64, 64), 128, dtype=np.uint8)

    def set_temperature(t: float) -> None:
        # The lens stops answering once the climate moves: the next lens call times out.
        device.set_temperature_c(t)
        device.inject_faults(silence_next=1000)

    with etlcal.Lens(device.port, timeout_ms=150) as lens:
        with pytest.raises(etlcal.DeviceTimeoutError, match=r"^lens: no reply to \w+ within 150ms$"):
            etlcal.thermal_calibration(
                lens, lambda: frame, set_temperature, e_in_grid_ma=[100.0], temperatures_c=[27.0, 30.0]
            )
    device.inject_faults()


def test_link_faults_surface_as_device_exceptions_with_the_rust_message() -> None:
    device = etlcal.VirtualLens()
    with etlcal.Lens(device.port, timeout_ms=150) as lens:
        assert lens.port == device.port and lens.limits_ma == device.limits_ma
        device.inject_faults(silence_next=1)
        with pytest.raises(etlcal.DeviceTimeoutError, match=r"^no reply to \w+ within 150ms$") as timeout:
            lens.current_ma()
        assert isinstance(timeout.value, TimeoutError) and isinstance(timeout.value, etlcal.DeviceError)
        # The next call resynchronises first (a probe takes the next reply, faults included).
        lens.current_ma()
        device.inject_faults(error_frame_next=3)
        with pytest.raises(etlcal.DeviceError, match=r"answered \w+ with error 3") as e:
            lens.current_ma()
        assert not isinstance(e.value, etlcal.DeviceTimeoutError)
        device.inject_faults(reply_delay_ms=400.0)
        with pytest.raises(etlcal.DeviceTimeoutError):
            lens.current_ma()
        device.inject_faults()
        # The late reply arrives after the timeout and is discarded by the resynchronisation.
        time.sleep(0.3)
        got = lens.set_current_ma(100.0)
        assert lens.current_ma() == pytest.approx(got)
        with pytest.raises(etlcal.InputError, match="reply_delay_ms"):
            device.inject_faults(reply_delay_ms=-1.0)


def test_a_pulled_cable_is_a_device_error_and_reconnect_keeps_the_current() -> None:
    device = etlcal.VirtualLens()
    # A generous timeout: with 200 ms a reply delayed by a stalled machine timed out during
    # the reconnection's own queries (a late reply is now discarded by the resynchronisation,
    # docs/RELIABILITY.md, "Device faults"; not what this test is about).
    with etlcal.Lens(device.port, timeout_ms=1000) as lens:
        got = lens.set_current_ma(120.0)
        device.disconnect()
        with pytest.raises(etlcal.DeviceError):
            lens.current_ma()
        device.reconnect()
        lens.reconnect()
        assert lens.current_ma() == pytest.approx(got)
        assert device.state().e_in_ma == pytest.approx(got)


def test_hold_keeps_the_true_e_com_while_the_lens_warms() -> None:
    # The virtual lens's true surface is the paper's, so holding with the paper's
    # calibration must keep its true E_com at the wanted value to the DAC's resolution
    # (292.84 / 4095 = 0.0715 mA per code: half a code), at any temperature.
    device = etlcal.VirtualLens()
    cal = etlcal.ThermalCalibration.paper()
    with etlcal.Lens(device.port) as lens:
        lens.set_current_ma(120.0)
        e_in: List[float] = []
        for t in [27.0, 32.0, 36.5]:
            device.set_temperature_c(t)
            r = lens.hold(cal, 120.0, steps=3)
            assert isinstance(r, etlcal.HoldReport) and r.last is not None
            assert r.commands_sent == 3 and r.worst_e_com_error_ma < 0.036 and r.extrapolated_steps == 0
            assert r.last.index == 2 and not r.last.extrapolated
            # The step's E_com is the calibration's at its temperature and commanded current.
            assert r.last.e_com_ma == pytest.approx(cal.compensate(r.last.e_in_ma, r.last.temperature_c).e_com_ma)
            assert r.last.error_ma == pytest.approx(abs(r.last.e_com_ma - 120.0))
            lo_c, hi_c = r.temperature_range_c
            assert lo_c <= r.last.temperature_c <= hi_c
            # Dict access, as when hold() returned a dict.
            assert r["commands_sent"] == 3 and r["last"]["index"] == 2
            s = device.state()
            assert abs(s.e_com_ma - 120.0) < 0.036
            # The lens self-heats from t (time constant tau_s), faster in wall time on a
            # loaded machine: the hold must have compensated at the temperature the lens
            # had, whatever that was by then.
            assert abs(s.temperature_c - r.last.temperature_c) < 0.2
            assert t - 0.2 < s.temperature_c < t + 3.0
            e_in.append(s.e_in_ma)
        # E_T grows with temperature: the held E_in rises with it.
        assert e_in[0] < e_in[1] < e_in[2]


def test_hold_observer_and_bad_input() -> None:
    device = etlcal.VirtualLens()
    cal = etlcal.ThermalCalibration.paper()
    seen: List[etlcal.HoldStep] = []

    def stop_after_five(step: etlcal.HoldStep) -> bool:
        seen.append(step)
        return step.index < 4

    with etlcal.Lens(device.port) as lens:
        r = lens.hold(cal, 100.0, on_step=stop_after_five)
        assert r.commands_sent == 5 and [s.index for s in seen] == [0, 1, 2, 3, 4]
        assert all(isinstance(s, etlcal.HoldStep) for s in seen) and r.last == seen[-1]
        # Dict access to a step, as when on_step was given a dict.
        assert set(seen[0]) == {"index", "temperature_c", "e_in_ma", "e_com_ma", "error_ma", "extrapolated"}
        assert seen[0]["index"] == 0 and repr(seen[0]).startswith("HoldStep(index=0, temperature_c=")
        r = lens.hold(cal, 100.0, duration_s=0.05, rate_hz=100.0)
        assert 1 <= r.commands_sent <= 7 and r.elapsed_s >= 0.05
        assert r.achieved_rate_hz == pytest.approx(r.commands_sent / r.elapsed_s, rel=1e-9)

        def broken(step: etlcal.HoldStep) -> bool:
            raise RuntimeError("observer failed")

        with pytest.raises(RuntimeError, match="observer failed"):
            lens.hold(cal, 100.0, on_step=broken)
        with pytest.raises(etlcal.InputError, match="steps, duration_s or on_step"):
            lens.hold(cal, 100.0)
        with pytest.raises(etlcal.InputError, match="steps must be >= 1"):
            lens.hold(cal, 100.0, steps=0)
        with pytest.raises(etlcal.InputError, match="duration_s"):
            lens.hold(cal, 100.0, duration_s=-1.0)
        with pytest.raises(etlcal.InputError, match="e_com_ma"):
            lens.hold(cal, math.nan, steps=1)
        with pytest.raises(etlcal.InputError, match="rate"):
            lens.hold(cal, 100.0, steps=1, rate_hz=-1.0)
    with pytest.raises(etlcal.DeviceError, match="closed"):
        lens.hold(cal, 100.0, steps=1)


def test_thermal_calibration_bad_input() -> None:
    device = etlcal.VirtualLens()
    frame = np.zeros((96, 96), np.uint8)
    with etlcal.Lens(device.port) as lens:
        with pytest.raises(etlcal.InputError, match="uint8"):
            etlcal.thermal_calibration(lens, lambda: frame.astype(np.float32), lambda t: None,
                                       e_in_grid_ma=[100.0], temperatures_c=[27.0, 30.0])
        with pytest.raises(etlcal.InputError, match="sharpest"):
            etlcal.thermal_calibration(lens, lambda: frame, lambda t: None,
                                       metric="sharpest")  # type: ignore[arg-type]  # the run-time check under test
    with pytest.raises(etlcal.DeviceError, match="closed"):
        etlcal.thermal_calibration(lens, lambda: frame, lambda t: None)


def test_after_a_timeout_a_late_reply_never_answers_a_later_query() -> None:
    """Issue 19: the reply to a timed-out query (the lens at 50 mA) must not be taken for
    the answer to a later one (the lens at 150 mA)."""
    device = etlcal.VirtualLens()
    with etlcal.Lens(device.port, timeout_ms=150) as lens:
        lens.set_current_ma(50.0)
        device.inject_faults(reply_delay_ms=200.0)
        with pytest.raises(etlcal.DeviceTimeoutError):
            lens.current_ma()
        device.inject_faults()
        # The next call resynchronises first; on a stalled machine the late reply may come
        # after the probe's wait, which is a timeout again, never a wrong answer.
        got: Optional[float] = None
        for _ in range(5):
            try:
                got = lens.set_current_ma(150.0)
                break
            except etlcal.DeviceTimeoutError:
                time.sleep(0.2)
        assert got is not None and got == pytest.approx(150.0, abs=0.04)
        assert lens.current_ma() == pytest.approx(got)
        assert device.state().e_in_ma == pytest.approx(got)


def test_a_current_the_driver_rejects_is_an_error_not_applied() -> None:
    device = etlcal.VirtualLens()
    with etlcal.Lens(device.port, timeout_ms=1000) as lens:
        before = lens.set_current_ma(80.0)
        device.inject_faults(error_frame_next=2)
        with pytest.raises(etlcal.DeviceError, match=r"^lens driver answered Aw with error 2: ") as e:
            lens.set_current_ma(120.0)
        assert not isinstance(e.value, etlcal.DeviceTimeoutError)
        assert lens.current_ma() == pytest.approx(before)
        assert device.state().e_in_ma == pytest.approx(before)


def test_huge_durations_rates_delays_and_timeouts_are_input_errors_not_panics() -> None:
    device = etlcal.VirtualLens()
    cal = etlcal.ThermalCalibration.paper()
    with pytest.raises(etlcal.InputError, match=r"^reply_delay_ms must lie in 0\.\.=60000 ms, got 1e30$"):
        device.inject_faults(reply_delay_ms=1e30)
    with pytest.raises(etlcal.InputError, match=r"reply timeout must lie in 1\.\.=60000 ms"):
        etlcal.Lens(device.port, timeout_ms=0)
    with etlcal.Lens(device.port) as lens:
        with pytest.raises(etlcal.InputError, match=r"^duration_s must lie in 0\.\.=1e7 s, got 1e30$"):
            lens.hold(cal, 100.0, duration_s=1e30)
        with pytest.raises(etlcal.InputError, match=r"hold rate must be 0 \(as fast as possible\) or lie in 1e-3\.\.=1e4 Hz"):
            lens.hold(cal, 100.0, steps=1, rate_hz=1e-30)
    assert device.received_current_codes() == []


def test_virtual_lens_temperatures_and_time_steps_are_range_checked() -> None:
    device = etlcal.VirtualLens()
    before = device.state().temperature_c
    for bad in (1e308, float("nan"), -41.0, 126.0):
        with pytest.raises(etlcal.InputError, match=r"^t_c must lie in -40\.\.=125 degC, got "):
            device.set_temperature_c(bad)
        with pytest.raises(etlcal.InputError, match=r"^t_c must lie in -40\.\.=125 degC, got "):
            device.set_ambient_c(bad)
    for bad in (-1.0, 1e30, float("inf"), float("nan")):
        with pytest.raises(etlcal.InputError, match=r"^dt_s must lie in 0\.\.=1e7 s, got "):
            device.advance_s(bad)
    assert device.state().temperature_c == before
    device.set_temperature_c(40.0)
    assert device.state().temperature_c == pytest.approx(40.0, abs=0.05)


def test_a_virtual_lens_with_dynamics_lags_its_current_and_bad_dynamics_are_refused(tmp_path: pathlib.Path) -> None:
    fixture = pathlib.Path(__file__).resolve().parents[3] / "fixtures" / "lens-dynamics" / "el-10-30-published.json"
    device = etlcal.VirtualLens(dynamics=fixture)
    with etlcal.Lens(device.port) as lens:
        got = lens.set_current_ma(150.0)
        device.advance_s(30.0)  # past the ringing and the creep (2 s)
        s = device.state()
        # Approached from below: the loop's lower branch, half its 0.5 mA width under.
        assert s.e_in_ma == pytest.approx(got)
        assert s.effective_ma == pytest.approx(got - 0.25, abs=1e-6)
        assert s.e_com_ma == pytest.approx(s.effective_ma - s.e_t_ma)
    assert etlcal.VirtualLens().state().effective_ma == etlcal.VirtualLens().state().e_in_ma
    bad = tmp_path / "bad.json"
    bad.write_text(fixture.read_text().replace('"damping": 0.28', '"damping": 0'))
    with pytest.raises(etlcal.Error, match="damping"):
        etlcal.VirtualLens(dynamics=bad)
