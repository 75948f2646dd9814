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
