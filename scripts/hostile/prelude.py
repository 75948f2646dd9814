"""What every Python case of the battery sees: etlcal, numpy and fresh objects built from
the fixtures (each call loads anew, so that no case sees another's mutations)."""
import os
import threading
import time
from typing import Any, Callable, List

import numpy as np

import etlcal

FX = ""
_cache: dict = {}


def fx(name: str) -> str:
    return os.path.join(FX, name)


def cal() -> "etlcal.Calibration":
    return etlcal.Calibration.load(fx("cal.json"))


def cal_ecom() -> "etlcal.Calibration":
    return etlcal.Calibration.load(fx("cal_ecom.json"))


def cam() -> "etlcal.CameraAt":
    return cal().at(150.0, 31.0)


def obs() -> "etlcal.Observations":
    return etlcal.Observations.load(fx("obs.json"))


def a0() -> "etlcal.A0":
    return etlcal.A0.load(fx("a0.json"))


def thermal() -> "etlcal.ThermalCalibration":
    return etlcal.ThermalCalibration.load(fx("thermal.json"))


def board() -> "etlcal.Board":
    return etlcal.Board.load(fx("charuco_sim.json"))


def img() -> np.ndarray:
    """The rendered 14x12 checkerboard at 150 mA (uint8, 1458 x 1936), a fresh copy."""
    if "img" not in _cache:
        _cache["img"], _cache["corners"] = etlcal.render()
    return _cache["img"].copy()


def corners() -> np.ndarray:
    img()
    return _cache["corners"].copy()


def board_mm() -> np.ndarray:
    """The 14x12 board's corners (mm, Z = 0), row by row, as render's corners."""
    j, i = np.mgrid[0:12, 0:14]
    return np.stack([i.ravel() * 1.5, j.ravel() * 1.5, np.zeros(168)], axis=1)


def world(n: int = 20) -> np.ndarray:
    g = np.linspace(0.0, 15.0, n)
    return np.stack([g, g[::-1], np.full(n, 60.0)], axis=1)


def huge(shape, dtype: Any = np.float64, fill: Any = 1.0) -> np.ndarray:
    """An array declaring a huge shape over one element (zero strides): no memory used."""
    base = np.full(1, fill, dtype=dtype)
    return np.lib.stride_tricks.as_strided(base, shape=tuple(shape), strides=(0,) * len(shape))


def in_thread(f: Callable[..., Any], *args: Any, **kw: Any) -> Any:
    """f(*args) on another thread; its exception (any) is raised again here."""
    box: List[Any] = []

    def run() -> None:
        try:
            box.append(("ok", f(*args, **kw)))
        except BaseException as e:  # noqa: BLE001
            box.append(("raised", e))

    t = threading.Thread(target=run)
    t.start()
    t.join()
    kind, v = box[0]
    if kind == "raised":
        raise v
    return v


def threads(f: Callable[[int], Any], n: int = 4) -> List[Any]:
    """f(k) on n threads at once; the first exception (any) is raised again here."""
    box: List[Any] = [None] * n
    errs: List[BaseException] = []
    barrier = threading.Barrier(n)

    def run(k: int) -> None:
        try:
            barrier.wait()
            box[k] = f(k)
        except BaseException as e:  # noqa: BLE001
            errs.append(e)

    ts = [threading.Thread(target=run, args=(k,)) for k in range(n)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    if errs:
        raise errs[0]
    return box


def namespace() -> dict:
    ns = {k: v for k, v in globals().items() if not k.startswith("_")}
    ns["__name__"] = "__hostile__"
    import gc
    import signal
    import sys
    import time
    import pathlib

    ns.update(np=np, etlcal=etlcal, os=os, threading=threading, gc=gc, signal=signal, sys=sys, time=time,
              pathlib=pathlib)
    return ns


def zhang_views():
    """Five synthetic views (board_mm (54, 2), pixels (54, 2)) of a 9x6 board of 25 mm
    squares, tilted, through a 640 x 512 pinhole camera (fx = fy = 500 px)."""
    j, i = np.mgrid[0:6, 0:9]
    bm = np.stack([i.ravel() * 25.0, j.ravel() * 25.0], axis=1)
    views = []
    for ax, ay in [(0.3, 0.0), (-0.3, 0.1), (0.0, 0.35), (0.2, -0.3), (-0.25, -0.2)]:
        cx, sx, cy, sy = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay)
        r = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]]) @ np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
        p = (r @ np.column_stack([bm - [100.0, 62.5], np.zeros(54)]).T).T + [0.0, 0.0, 500.0]
        px = np.column_stack([500 * p[:, 0] / p[:, 2] + 320, 500 * p[:, 1] / p[:, 2] + 256])
        views.append((bm.copy(), px))
    return views


def readonly(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


class Boom(Exception):
    """A user's own exception, raised from a callback: it must come back as itself."""


class HostileHang(Exception):
    """Raised by a case that watched something hang (a forked child): counted as a hang."""


def wait_child(pid: int, seconds: float = 15.0) -> int:
    """The exit code of a forked child; HostileHang (after killing it) past `seconds`."""
    deadline = time.monotonic() + seconds
    while True:
        r, status = os.waitpid(pid, os.WNOHANG)
        if r:
            return os.waitstatus_to_exitcode(status)
        if time.monotonic() > deadline:
            os.kill(pid, 9)
            os.waitpid(pid, 0)
            raise HostileHang(f"the forked child did not end within {seconds:.0f} s")
        time.sleep(0.05)
