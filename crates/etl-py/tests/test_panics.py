"""A Rust panic at the binding boundary becomes etlcal.Error (with a report file), never
pyo3's PanicException, which neither `except etlcal.Error` nor `except Exception` catches.
The panics come from private test hooks (`_etlcal._panic`, `_etlcal._PanicProbe`)."""
import os
import re
import threading
from pathlib import Path
from typing import Callable, List

import pytest

import etlcal
from etlcal import _etlcal

REPORT = re.compile(r"report: (\S+etlcal-panic-\d+-\d+\.txt)\)$")


def _caught(call: Callable[[], object], where: str, message: str) -> str:
    with pytest.raises(etlcal.Error) as info:
        call()
    text = str(info.value)
    assert text.startswith(f"internal error in {where}: {message} (a bug in etlcal; report: "), text
    m = REPORT.search(text)
    assert m, text
    report = Path(m.group(1)).read_text()
    assert f"call: {where}\npanic: {message}\n" in report and "Traceback" in report
    os.unlink(m.group(1))
    return text


def test_a_panic_in_a_function_or_in_a_worker_thread_is_an_etlcal_error() -> None:
    _caught(lambda: _etlcal._panic("boom"), "_panic", "boom")
    _caught(lambda: _etlcal._panic("in a worker", in_pool=True), "_panic", "in a worker")
    # also `except Exception`, as users write it
    try:
        _etlcal._panic("plain")
    except Exception as e:
        assert isinstance(e, etlcal.Error)
        os.unlink(REPORT.search(str(e)).group(1))  # type: ignore[union-attr]


def test_a_panic_in_a_method_static_method_or_property_is_an_etlcal_error() -> None:
    probe = _etlcal._PanicProbe(False)
    _caught(probe.method, "_PanicProbe.method", "the method panicked")
    _caught(_etlcal._PanicProbe.static_method, "_PanicProbe.static_method", "the static method panicked")
    _caught(lambda: probe.property, "_PanicProbe.property", "the property panicked")


def test_a_panic_in_a_constructor_or_a_special_method_is_an_etlcal_error() -> None:
    _caught(lambda: _etlcal._PanicProbe(True), "_PanicProbe.__new__", "the constructor panicked")
    probe = _etlcal._PanicProbe(False)
    _caught(lambda: repr(probe), "_PanicProbe.__repr__", "the repr panicked")
    _caught(lambda: len(probe), "_PanicProbe.__len__", "the len panicked")
    # the report's traceback is the Python stack of the call
    with pytest.raises(etlcal.Error) as info:
        _etlcal._PanicProbe(True)
    path = REPORT.search(str(info.value)).group(1)  # type: ignore[union-attr]
    report = Path(path).read_text()
    os.unlink(path)
    assert "test_a_panic_in_a_constructor_or_a_special_method_is_an_etlcal_error" in report, report


def test_a_panic_on_other_threads_is_an_etlcal_error_on_each() -> None:
    errors: List[BaseException] = []

    def run() -> None:
        try:
            _etlcal._panic("threaded", in_pool=True)
        except BaseException as e:
            errors.append(e)

    threads = [threading.Thread(target=run) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(errors) == 4 and all(isinstance(e, etlcal.Error) for e in errors), errors
    paths = {REPORT.search(str(e)).group(1) for e in errors}  # type: ignore[union-attr]
    assert len(paths) == 4, "one report each"
    for p in paths:
        os.unlink(p)


def test_the_guard_keeps_names_docs_signatures_and_other_errors() -> None:
    assert etlcal.calibrate.__name__ == "calibrate" and etlcal.calibrate.__doc__
    assert etlcal.Calibration.load.__doc__ == _etlcal.Calibration.load.__doc__
    with pytest.raises(etlcal.InputError, match="trials 100000000 must lie"):
        etlcal.study("fig6", trials=10**8)
    with pytest.raises(etlcal.FileError):
        etlcal.Calibration.load("/nonexistent/c.json")
    with pytest.raises(TypeError):
        etlcal.Calibration.load()  # type: ignore[call-arg]
