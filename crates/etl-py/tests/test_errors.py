"""The exception hierarchy, and every variant of the Rust error types mapped to its class
with the Rust message unchanged."""
import pickle

import numpy as np
import pytest

import etlcal


def test_hierarchy() -> None:
    assert issubclass(etlcal.Error, Exception)
    assert issubclass(etlcal.InputError, etlcal.Error)
    assert issubclass(etlcal.InputError, ValueError)
    assert issubclass(etlcal.NotConvergedError, etlcal.Error)
    assert not issubclass(etlcal.NotConvergedError, ValueError)
    assert issubclass(etlcal.BoardNotFoundError, etlcal.Error)
    assert issubclass(etlcal.FileError, etlcal.Error)
    assert issubclass(etlcal.FileError, OSError)
    assert issubclass(etlcal.DeviceError, etlcal.Error)
    assert issubclass(etlcal.DeviceTimeoutError, etlcal.DeviceError)
    assert issubclass(etlcal.DeviceTimeoutError, TimeoutError)
    for cls in (etlcal.Error, etlcal.InputError, etlcal.DeviceTimeoutError):
        assert cls.__module__ == "etlcal"
        assert cls.__doc__


# (variant, class, message exactly as etl_core / etl_calib format it)
RUST_ERRORS = [
    ("core:NotFinite", "InputError", "x is NaN or infinite; pass finite numbers"),
    ("core:OutOfRange", "InputError", "x = 5 is outside [0, 1]"),
    ("core:TooFew", "InputError", "too few views: the method needs at least 3, got 1"),
    ("core:Degenerate", "InputError", "degenerate input: all points on one line"),
    (
        "core:BehindCamera",
        "InputError",
        "point is at or behind the camera (Z_C <= 0); check the pose and units (mm)",
    ),
    ("core:NotConverged", "NotConvergedError", "solver did not converge in 7 iterations"),
    (
        "core:BufferTooSmall",
        "InputError",
        "buffer out too small: needs 4 elements, got 2 (see its *_scratch function)",
    ),
    ("core:InvalidArgument", "InputError", "invalid argument: bad"),
    ("calib:Io", "FileError", "x.json: not there"),
    ("calib:Parse", "InputError", "x.json: line 1"),
    ("calib:Format", "InputError", 'x.json: format "a/1" is not supported (expected "b/1")'),
    ("calib:Image", "InputError", "x.json: cannot read image: truncated"),
    ("calib:BoardNotFound", "BoardNotFoundError", "board not found: img.png"),
    ("calib:InvalidInput", "InputError", "invalid input: negative"),
    ("calib:Core", "NotConvergedError", "ba did not converge in 3 iterations"),
    # A lens timeout inside a library procedure keeps its class.
    ("calib:LensTimeout", "DeviceTimeoutError", "lens: no reply to GetTemperature within 500ms"),
]


@pytest.mark.parametrize("variant,cls,message", RUST_ERRORS)
def test_every_rust_error_variant_maps_to_its_class_with_the_same_message(variant: str, cls: str, message: str) -> None:
    with pytest.raises(getattr(etlcal, cls)) as info:
        etlcal._etlcal._raise_rust_error(variant)
    assert type(info.value) is getattr(etlcal, cls)
    assert str(info.value) == message


def test_unknown_variant_is_an_input_error() -> None:
    with pytest.raises(etlcal.InputError, match="unknown error kind"):
        etlcal._etlcal._raise_rust_error("core:Nope")


def test_exceptions_pickle() -> None:
    e = etlcal.InputError("t_c is NaN or infinite; pass finite numbers")
    back = pickle.loads(pickle.dumps(e))
    assert type(back) is etlcal.InputError and str(back) == str(e)


# (variant, InputError.what, InputError.value): the fields of the Rust error.
INPUT_FIELDS = [
    ("calib:InvalidInput", "square_mm", "-1.5"),
    ("calib:InvalidInputNoValue", "views", None),
    ("core:OutOfRange", "x", "5"),
    ("core:NotFinite", "x", None),
    ("core:TooFew", None, None),
    ("calib:Parse", None, None),
]


@pytest.mark.parametrize("variant,what,value", INPUT_FIELDS)
def test_input_error_names_what_and_value(variant, what, value):
    with pytest.raises(etlcal.InputError) as info:
        etlcal._etlcal._raise_rust_error(variant)
    assert (info.value.what, info.value.value) == (what, value)


def test_input_error_fields_default_to_none_and_survive_pickling():
    e = etlcal.InputError("made in Python")
    assert (e.what, e.value) == (None, None)
    with pytest.raises(etlcal.InputError) as info:
        etlcal._etlcal._raise_rust_error("calib:InvalidInput")
    back = pickle.loads(pickle.dumps(info.value))
    assert (back.what, back.value, str(back)) == ("square_mm", "-1.5", "invalid input: negative")


def test_input_errors_of_real_calls_name_the_key_or_argument():
    o = etlcal.Observations((100, 100))
    with pytest.raises(etlcal.InputError) as info:
        o.add_view([[0, 0, 10]], [[1, 2]], e_in_ma=float("nan"), temperature_c=30.0)
    assert (info.value.what, info.value.value) == ("views[0].e_in_ma", "NaN")
    with pytest.raises(etlcal.InputError) as info:
        o.add_view([[0, 0, 1e308]], [[1, 2]], e_in_ma=100.0, temperature_c=30.0)
    assert (info.value.what, info.value.value) == ("views[0].points[0].world_mm", "1e308")
    assert str(info.value) == (
        "invalid input: view 0 point 0: world coordinate 1e308 mm is outside [-10000, 10000] mm"
    )
    # An argument of the bindings themselves, and an option word.
    with pytest.raises(etlcal.InputError) as info:
        etlcal.Observations((0, 10))
    assert (info.value.what, info.value.value) == ("image_size", "[0, 10]")
    with pytest.raises(etlcal.InputError) as info:
        etlcal.sharpness(np.zeros((8, 8), np.uint8), "sharpest")
    assert (info.value.what, info.value.value) == ("metric", "sharpest")
