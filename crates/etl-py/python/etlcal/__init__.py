"""etlcal: calibration and control of cameras focused by an electrically tunable lens.

Units everywhere: lengths in mm, currents in mA, temperatures in degC, pixels with (0, 0)
the centre of the top-left pixel. Arrays in and out are numpy arrays: (N, 3) world
points, (N, 2) pixels, 3 x 3 matrices.

Main nouns:
- `Calibration`: a calibrated camera (load / save / e_com / intrinsics / distortion /
  project / undistort / ray / solve_pnp / to_opencv), and `CameraAt`, the camera at one
  setting (`cal.at(e_in_ma, temperature_c)`, or `cal.at_e_com(e_com_ma)` at a known E_com,
  e.g. for a calibration without temperature compensation), which holds the run-time
  operations; `Calibration`'s methods taking `e_com_ma` are `at_e_com(e_com_ma)`'s.
- `Rig`: a multi-camera rig (etlcal.rig/1; `etlcal.rig` is the capture module):
  `Rig.load(path).at(settings, temperatures_c)` gives a `RigAt` (each camera's `CameraAt`
  and pose at those settings) with `triangulate(pixels, sigma_px)` (the point and its
  covariance) and `stereo_rectify_maps(left, right)` (R1, R2, P1, P2, Q and cv2.remap maps).
- `Observations`, `A0`: the input of `calibrate(...)`.
- `ThermalSurface`, `ThermalCalibration`: temperature compensation (E_com = E_in - E_T).
- `LensPhysics` and `etlcal.physics`: the lens's physical model.
- `etlcal.simulate.paper_rig(seed)`: the paper's simulated rig.
- Hardware: `Lens(port)` (Optotune Lens Driver 4; a context manager; `Lens.hold(...)`
  keeps E_com while the lens warms) and `VirtualLens()` (the simulated device on a
  pseudo-terminal: `Lens(VirtualLens().port)`, with fault injection);
  `thermal_calibration(lens, capture, set_temperature)` (section 4.1 with your camera).
- Images (2-D uint8/uint16 numpy arrays): `detect_corners(image, board)` (an `etlcal.Board`:
  a `BoardDetection` with `corners_px`, `ids`, `board_mm`; a ChArUco board gives the
  corners seen, each with its id) or `detect_corners(image, "14x12")` (a whole checkerboard),
  `sharpness(image, "cpbd")`, `render(e_com_ma=...)` (the synthetic camera),
  `autofocus(callable)`; `zhang(views, image_size)` (fixed-focus calibration, e.g. A0);
  `stereo(pairs, image_size)` (a fixed-focus pair, as cv2.stereoCalibrate);
  `Dataset` (images + what was recorded; `.detect()` gives Observations).
- `Board`: the calibration target (etlcal.board/1): `Board.charuco(squares, square_mm,
  marker_mm, dictionary)` (OpenCV's layout and ids; partial views need no hints) or
  `Board.checkerboard(inner_corners, square_mm)`; `load`, `save`, `to_svg()` (print at
  true size), `to_image(dpi)`.
- `etlcal.studies.fig5()`, `.fig6(trials)`, `.subsets()`, `.baseline()`, `.crlb(trials)`
  (also `study(name)`): the paper's simulation studies.

Results are typed objects (`etlcal.results`: `ZhangResult`, `AutofocusResult`,
`PaperDistortion` / `OpenCvDistortion` (what `distortion` gives, by family),
`Compensation`, `ModelStd`, `View`, `StudyResult`, `LensInfo`, `HoldReport`, ...):
attributes with a short repr, and read-only mappings too (`r["key"]`, `"key" in r`,
`r.keys()`), as the dicts they replace. `etlcal.options` names the words each option accepts (`typing.Literal`).
`Observations` is a sequence of `View`s (`obs[i]`, `obs[-1]`, `for v in obs`).
The per-current model functions (`focal_lengths`, `intrinsics`, `distortion`,
`to_opencv`) take a number or an array of currents (results stacked on leading axes);
`ThermalCalibration.compensate` and `.e_in_for_e_com` take numbers or arrays (broadcast;
a `CompensationArray` for arrays).

Every exception derives from `etlcal.Error`: `InputError` (also a ValueError),
`NotConvergedError`, `BoardNotFoundError`, `FileError` (also an OSError), `DeviceError`,
`DeviceTimeoutError` (also a TimeoutError). An `InputError` names what to change in `what`
(a file key, field or argument: `"views[3].points"`, `"square_mm"`) and the offending
value in `value` (text, numbers compact), each None when the error names none.
"""
from . import _etlcal, _guard

# Before any name is taken from the extension: a Rust panic becomes etlcal.Error.
_guard.install(_etlcal)

from ._etlcal import (
    __version__,
    A0,
    Board,
    BoardNotFoundError,
    BoardPose,
    Calibration,
    CameraAt,
    Dataset,
    DeviceError,
    DeviceTimeoutError,
    Error,
    FileError,
    InputError,
    Lens,
    LensPhysics,
    NotConvergedError,
    Observations,
    Rig,
    RigAt,
    Simulation,
    ThermalCalibration,
    ThermalSurface,
    VirtualLens,
    autofocus,
    calibrate,
    calibrate_rig,
    cramer_rao_std,
    detect_corners,
    diff,
    render,
    sharpness,
    stereo,
    study,
    thermal_calibration,
    zhang,
)
# The result classes: every name of etlcal.results.__all__ (re-exported by the star import,
# which type checkers follow too; listed once, there).
from .results import *  # noqa: F401,F403
from . import options, physics, results, rig, simulate, studies

__all__ = [
    "__version__",
    "A0",
    "Board",
    "BoardNotFoundError",
    "BoardPose",
    "Calibration",
    "CameraAt",
    "Dataset",
    "DeviceError",
    "DeviceTimeoutError",
    "Error",
    "FileError",
    "InputError",
    "Lens",
    "LensPhysics",
    "NotConvergedError",
    "Observations",
    "Rig",
    "RigAt",
    "Simulation",
    "ThermalCalibration",
    "ThermalSurface",
    "VirtualLens",
    "autofocus",
    "calibrate",
    "calibrate_rig",
    "cramer_rao_std",
    "detect_corners",
    "diff",
    "render",
    "sharpness",
    "stereo",
    "study",
    "thermal_calibration",
    "zhang",
    "options",
    "physics",
    "results",
    "rig",
    "simulate",
    "studies",
]
# The result classes, as etlcal.results lists them (one list to keep).
__all__ += results.__all__
