"""`Lens` against `VirtualLens` through a pseudo-terminal, from Python."""
import math

import pytest

import etlcal


def test_lens_talks_to_the_virtual_lens():
    device = etlcal.VirtualLens()
    with etlcal.Lens(device.port) as lens:
        info = lens.info()
        assert info["lens_serial"] == "ETLV0001" and info["firmware_type"] == "C"
        assert info["upper_limit_ma"] == pytest.approx(292.84)
        got = lens.set_current_ma(150.0)
        assert abs(got - 150.0) < 0.04  # 12-bit quantisation
        assert lens.current_ma() == pytest.approx(got)
        assert device.state()["e_in_ma"] == pytest.approx(got)
        device.set_temperature_c(32.0)
        assert abs(lens.temperature_c() - 32.0) < 0.1
        # E_com = E_in - E_T(T, E_in) inside the device follows the paper's surface.
        s = device.state()
        assert s["e_com_ma"] == pytest.approx(s["e_in_ma"] - s["e_t_ma"])


def test_no_current_outside_the_limits_reaches_the_wire():
    device = etlcal.VirtualLens()
    lo, hi = device.limits_ma
    with etlcal.Lens(device.port) as lens:
        for request in [1e9, -1e9, 300.0, -300.0, 291.0]:
            got = lens.set_current_ma(request)
            assert lo <= got <= hi
        with pytest.raises(etlcal.InputError):
            lens.set_current_ma(math.nan)
    assert all(-4095 <= c <= 4095 for c in device.received_current_codes())


def test_errors_are_device_errors():
    with pytest.raises(etlcal.DeviceError):
        etlcal.Lens("/dev/no-such-port")
    device = etlcal.VirtualLens()
    lens = etlcal.Lens(device.port)
    lens.close()
    with pytest.raises(etlcal.DeviceError):
        lens.current_ma()


def test_thermal_calibration_with_a_python_camera():
    """The section 4.1 procedure with the camera and the climate as Python callables: a
    numpy camera whose blur grows with the distance of the lens's true E_com from the one
    the board was placed at, looking through the virtual lens."""
    import numpy as np

    device = etlcal.VirtualLens()
    yy, xx = np.mgrid[0:96, 0:96]
    board = np.where(((xx // 12) + (yy // 12)) % 2 == 0, 200.0, 40.0)
    f = np.fft.fft2(board)
    k2 = (2 * np.pi * np.fft.fftfreq(96))[None, :] ** 2 + (2 * np.pi * np.fft.fftfreq(96))[:, None] ** 2
    state = {"focus": None}
    calls = {"capture": 0, "place": 0, "temps": []}

    def capture():
        calls["capture"] += 1
        sigma = 0.5 + 0.3 * abs(device.state()["e_com_ma"] - state["focus"])
        img = np.real(np.fft.ifft2(f * np.exp(-0.5 * sigma**2 * k2)))
        return np.clip(np.round(img), 0, 255).astype(np.uint8)

    def place_board():
        calls["place"] += 1
        state["focus"] = device.state()["e_com_ma"]

    def set_temperature(t):
        calls["temps"].append(t)
        device.set_temperature_c(t)

    with etlcal.Lens(device.port) as lens:
        r = etlcal.thermal_calibration(
            lens, capture, set_temperature, place_board,
            e_in_grid_ma=[60.0, 110.0, 160.0, 210.0], temperatures_c=[27.0, 30.5, 34.0, 37.0], search_ma=15.0,
        )
    assert calls["place"] == 4 and calls["capture"] == r["frames"]
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

    def broken():
        raise RuntimeError("camera unplugged")

    with etlcal.Lens(device.port) as lens:
        with pytest.raises(RuntimeError, match="camera unplugged"):
            etlcal.thermal_calibration(lens, broken, set_temperature, e_in_grid_ma=[100.0], temperatures_c=[27.0, 30.0])
        with pytest.raises(etlcal.InputError):
            etlcal.thermal_calibration(lens, capture, set_temperature, temperatures_c=[27.0])
