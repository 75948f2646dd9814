"""etlcal.rig: the rig's devices and the capture procedures (docs/RIG.md, "Capture").

- `Camera.open(spec)`: a camera from its spec, "sim" (the simulated paper rig),
  "files:DIR" (a folder replayed in name order) or "aravis:NAME" (a GigE Vision or USB3
  Vision camera through aravis; "aravis:Fake_1" is aravis's fake camera), with `grab()`
  (a 2-D uint8/uint16 numpy array), `grab_frame()` ((array, timestamp_ns)),
  `set_exposure_us`, `set_gain_db` and `info()`.
- `capture_views(plan, out=..., camera=..., lens=..., stage=...)`: an `etlcal.plan/1`
  (path or dict) captured into `out/dataset.json` with its images, resumably; the camera
  and the stage are specs or your own objects (a camera with `grab()`, e.g. around
  pypylon, Spinnaker or IDS; a stage with `move_mm(z_mm)`), the lens a spec ("virtual",
  "ld4:/dev/ttyACM0").
- `capture_offstate(...)`: the plan's lens-off views only.
"""
from os import PathLike
from typing import Any, Dict, Optional, Tuple, Union

from ._etlcal import RigCamera as Camera
from ._etlcal import rig_capture_offstate, rig_capture_views

__all__ = ["Camera", "capture_views", "capture_offstate"]

Plan = Union[str, "PathLike[str]", Dict[str, Any]]


def capture_views(
    plan: Plan,
    *,
    out: Union[str, "PathLike[str]"],
    camera: Any,
    lens: str,
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
    lens: str,
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
