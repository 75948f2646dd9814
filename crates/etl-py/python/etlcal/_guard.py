"""The binding boundary's catch-all: a Rust panic never reaches the user as pyo3's
PanicException (a BaseException, which neither ``except etlcal.Error`` nor
``except Exception`` catches), but as ``etlcal.Error`` naming the call, the panic's
message and a report file (the traceback and versions) to attach to a bug report.

Installed once, on import, over the extension module itself: every function of the
module, and every method, static method, class method and property of its classes is
wrapped. A panic is a bug in etlcal, so the message says so. Not wrapped: the
constructors (a Python ``__new__`` over an extension type's fails CPython's safety check
of ``tp_new``) and the special methods (``__repr__``, ``__eq__``, ``__len__``, ...), whose
slots a Python function would slow down for every container use: those catch their panics
in Rust (``errors::guarded``) and come here for the same error (`_panic_error`).
Exceptions other than a panic pass through untouched (KeyboardInterrupt included).
"""
import functools
import itertools
import os
import platform
import sys
import tempfile
import traceback
from types import BuiltinFunctionType, ModuleType
from typing import Any, Callable

_reports = itertools.count(1)


def _is_panic(e: BaseException) -> bool:
    t = type(e)
    return t.__name__ == "PanicException" and t.__module__ == "pyo3_runtime"


def _write_report(qualname: str, e: BaseException, version: str) -> str:
    """The report's path, or why it could not be written."""
    path = os.path.join(tempfile.gettempdir(), f"etlcal-panic-{os.getpid()}-{next(_reports)}.txt")
    if e.__traceback__ is not None:
        trace = "".join(traceback.format_exception(type(e), e, e.__traceback__))
    else:
        # Caught in Rust (a constructor or a special method): no traceback of its own, so
        # the Python stack that made the call.
        trace = "Traceback (most recent call last):\n" + "".join(traceback.format_stack()[:-2]) + f"{e!r}\n"
    text = (
        f"etlcal {version}, Python {sys.version.split()[0]}, {platform.platform()}\n"
        f"call: {qualname}\npanic: {e}\n\n" + trace
    )
    try:
        # O_EXCL: never through a planted symlink, never over another process's report.
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(fd, "w") as f:
            f.write(text)
    except OSError as w:
        return f"no report written: {w.strerror}"
    return f"report: {path}"


def _guarded(
    f: Callable[..., Any], qualname: str, error: type, version: str, like: Any = None
) -> Callable[..., Any]:
    """`f` with a panic turned into `error`; named, documented and signed as `like`
    (default: `f`)."""

    @functools.wraps(like if like is not None else f)
    def call(*args: Any, **kwargs: Any) -> Any:
        try:
            return f(*args, **kwargs)
        except BaseException as e:
            if not _is_panic(e):
                raise
            raise _panic_error(qualname, e, error, version) from None

    return call


def _panic_error(qualname: str, e: BaseException, error: type, version: str) -> BaseException:
    """The `error` a panic `e` in `qualname` becomes, its report written (also called from
    Rust, for the panics of constructors and special methods)."""
    where = _write_report(qualname, e, version)
    return error(f"internal error in {qualname}: {e} (a bug in etlcal; {where})")  # type: ignore[no-any-return]


def _class_call(raw: Any) -> Callable[..., Any]:
    """The class method descriptor `raw` as a function of the class (for `classmethod`)."""

    def call(cls: type, *args: Any, **kwargs: Any) -> Any:
        return raw.__get__(None, cls)(*args, **kwargs)

    return call


def _guarded_property(raw: Any, qualname: str, error: type, version: str) -> property:
    """The getter/setter descriptor `raw` as a property whose panics are `error`."""
    fget = _guarded(raw.__get__, qualname, error, version)
    fset = _guarded(raw.__set__, qualname, error, version)

    def get(self: Any) -> Any:
        return fget(self)

    def set_(self: Any, value: Any) -> None:
        fset(self, value)

    return property(get, set_, doc=raw.__doc__)


def _guard_class(cls: type, error: type, version: str) -> None:
    for name, raw in list(vars(cls).items()):
        qualname = f"{cls.__name__}.{name}"
        if name.startswith("__"):
            continue
        elif isinstance(raw, staticmethod):
            setattr(cls, name, staticmethod(_guarded(raw.__func__, qualname, error, version)))
        elif type(raw).__name__ == "classmethod_descriptor":
            setattr(cls, name, classmethod(_guarded(_class_call(raw), qualname, error, version, like=raw)))
        elif type(raw).__name__ == "method_descriptor":
            setattr(cls, name, _guarded(raw, qualname, error, version))
        elif type(raw).__name__ == "getset_descriptor":
            setattr(cls, name, _guarded_property(raw, qualname, error, version))


def install(module: ModuleType) -> None:
    """Wraps the functions and classes of the extension `module` (see the module doc)."""
    error = module.Error
    version = module.__version__
    for name, value in list(vars(module).items()):
        if isinstance(value, BuiltinFunctionType):
            setattr(module, name, _guarded(value, name, error, version))
        elif isinstance(value, type) and not issubclass(value, BaseException):
            _guard_class(value, error, version)
