"""etlcal.rig: the rig's devices and the capture procedures (docs/RIG.md, "Capture").

- `Camera.open(spec)`: a camera from its spec, "sim" (the simulated paper rig),
  "files:DIR" (a folder replayed in name order) or "aravis:NAME" (a GigE Vision or USB3
  Vision camera through aravis; "aravis:Fake_1" is aravis's fake camera), with `grab()`
  (a 2-D uint8/uint16 numpy array), `grab_frame()` ((array, timestamp_ns)),
  `set_exposure_us`, `set_gain_db` and `info()`.
- `capture_views(plan, out=..., camera=..., lens=..., stage=...)`: an `etlcal.plan/1`
  (path or dict) captured into `out/dataset.json` with its images, resumably; each device
  is a spec or your own object: a camera with `grab()` (e.g. around pypylon, Spinnaker or
  IDS), a stage with `move_mm(z_mm)`, a lens with `set_current_ma(e_in_ma)` and
  `temperature_c()` (your own driver; see `Lens` below), or the specs "virtual",
  "ld4:/dev/ttyACM0".
- `capture_offstate(...)`: the plan's lens-off views only.
- `capture_thermal(...)`: the temperature procedure over the plan's `thermal` grid into
  `out/thermal.csv` and `out/thermal.json`, resumably.

An exception a Python device raises ends the capture and comes back as it is, with a note
(`__notes__`) naming the device; what was taken stays whole on disk.
"""
from os import PathLike
from typing import Any, Dict, Optional, Protocol, Tuple, Union

from ._etlcal import RigCamera as Camera
from ._etlcal import rig_capture_offstate, rig_capture_thermal, rig_capture_views

__all__ = ["Camera", "Lens", "capture_views", "capture_offstate", "capture_thermal"]

Plan = Union[str, "PathLike[str]", Dict[str, Any]]


class Lens(Protocol):
    """What a lens object passed as `lens=` needs (your own driver; `current_ma()` and
    `limits_ma()` are optional: without them the current is the last one commanded, and
    each approach goes the full 10 mA below its current)."""

    def set_current_ma(self, e_in_ma: float) -> Optional[float]:
        """Commands the driver current, mA; returns the current actually commanded (after
        the driver's clamping and quantisation), or None for the one asked."""
        ...

    def temperature_c(self) -> float:
        """The lens temperature, degC."""
        ...


def capture_views(
    plan: Plan,
    *,
    out: Union[str, "PathLike[str]"],
    camera: Any,
    lens: Union[str, Lens],
    stage: Any,
    settle_tolerance_px: float = 0.05,
    settle_timeout_s: float = 10.0,
    max_temperature_change_c: float = 0.5,
    autofocus_range_ma: Optional[Tuple[float, float]] = None,
    seed: int = 1,
) -> Dict[str, Any]:
    """Captures the plan's lens-off views (if it asks for them), then its ETL views, into
    `out/dataset.json` with the images (mm, mA, degC as the plan gives them); a second call
    resumes what the first left. Returns {"dataset", "offstate_kept", "offstate_taken",
    "views_kept", "views_taken", "stopped"}. Raises InputError for a bad plan or spec
    (nothing written), DeviceError / DeviceTimeoutError naming the device that failed."""
    return rig_capture_views(
        plan, out, camera, lens, stage, settle_tolerance_px=settle_tolerance_px,
        settle_timeout_s=settle_timeout_s, max_temperature_change_c=max_temperature_change_c,
        autofocus_range_ma=autofocus_range_ma, seed=seed,
    )


def capture_offstate(
    plan: Plan,
    *,
    out: Union[str, "PathLike[str]"],
    camera: Any,
    lens: Union[str, Lens],
    stage: Any,
    settle_tolerance_px: float = 0.05,
    settle_timeout_s: float = 10.0,
    max_temperature_change_c: float = 0.5,
    seed: int = 1,
) -> Dict[str, Any]:
    """The plan's lens-off views only (its `offstate_views`, lens at 0 mA), as
    `capture_views` takes them; the same return value and errors."""
    return rig_capture_offstate(
        plan, out, camera, lens, stage, settle_tolerance_px=settle_tolerance_px,
        settle_timeout_s=settle_timeout_s, max_temperature_change_c=max_temperature_change_c, seed=seed,
    )


def capture_thermal(
    plan: Plan,
    *,
    out: Union[str, "PathLike[str]"],
    camera: Any,
    lens: Union[str, Lens],
    stage: Any,
    settle_timeout_s: float = 10.0,
    max_temperature_change_c: float = 0.5,
    sim_roi: Optional[Tuple[int, int, int, int]] = None,
    seed: int = 1,
) -> Dict[str, Any]:
    """The temperature procedure (section 4.1) over the plan's `thermal` grid: for each of
    its `currents_ma` (the stage at the matching `stage_mm`), for each temperature, the lens
    brought there (the virtual lens's mount set; a real lens waited for), refocused by
    sharpness, E_T recorded into `out/thermal.csv`; the fitted surface into
    `out/thermal.json` once the grid is done. A second call resumes. `sim_roi` (x, y, width,
    height) px: the sim camera renders only that window. Returns {"table", "thermal",
    "samples_kept", "samples_taken", "evaluations", "rms_ma", "stopped"} ("thermal" and "rms_ma"
    None until done). Raises as `capture_views`."""
    return rig_capture_thermal(
        plan, out, camera, lens, stage, settle_timeout_s=settle_timeout_s,
        max_temperature_change_c=max_temperature_change_c, sim_roi=sim_roi, seed=seed,
    )
