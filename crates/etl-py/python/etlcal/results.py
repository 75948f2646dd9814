"""Typed result objects of etlcal's functions (units: mm, mA, degC, px).

Each is a frozen dataclass with one attribute per result and a short ``repr``; each is
also a read-only mapping (``result["key"]``, ``"key" in result``, ``keys()``,
``items()``, ``dict(result)``) so code written when these were dicts still runs.
``to_dict()`` gives a plain dict (e.g. for ``json.dumps`` after converting arrays).
"""
from __future__ import annotations

import dataclasses
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

_F64 = npt.NDArray[np.float64]
_Bool = npt.NDArray[np.bool_]

__all__ = [
    "AutofocusResult",
    "BoardDetection",
    "Compensation",
    "CompensationArray",
    "DetectionSummary",
    "Distortion",
    "ExportResult",
    "FocusLaw",
    "HoldReport",
    "HoldStep",
    "LensInfo",
    "LensState",
    "ModelStd",
    "OffstateView",
    "OpenCvCamera",
    "OpenCvDistortion",
    "ProjectionDiff",
    "PaperDistortion",
    "SettingViewSummary",
    "StereoRectifyMaps",
    "StereoResult",
    "StudyResult",
    "ThermalCalibrationResult",
    "Triangulated",
    "View",
    "ViewSummary",
    "ZhangOpenCvResult",
    "ZhangResult",
]


def _short(value: Any) -> str:
    # Arrays of points would flood a repr: their shape says what they are.
    if isinstance(value, np.ndarray) and value.size > 9:
        return f"<array {value.shape}>"
    if isinstance(value, list) and len(value) > 9:
        return f"<list of {len(value)}>"
    return repr(value)


@dataclass(frozen=True, eq=False, repr=False)
class _Result(Mapping[str, Any]):
    """Attributes and read-only dict access to the same fields."""

    def __getitem__(self, key: str) -> Any:
        if key not in self._names():
            raise KeyError(key)
        return getattr(self, key)

    def __iter__(self) -> Iterator[str]:
        return iter(self._names())

    def __len__(self) -> int:
        return len(self._names())

    def __contains__(self, key: object) -> bool:
        return key in self._names()

    def __eq__(self, other: object) -> bool:
        # Key by key, as the dicts these once were (so `result == {...}` still holds);
        # arrays compared elementwise, NaN equal to NaN.
        if not isinstance(other, Mapping):
            return NotImplemented
        if set(self) != set(other.keys()):
            return False
        return all(_same(self[k], other[k]) for k in self)

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        inner = ", ".join(f"{k}={_short(getattr(self, k))}" for k in self._names())
        return f"{type(self).__name__}({inner})"

    def to_dict(self) -> Dict[str, Any]:
        """The fields as a plain dict (values as they are: arrays stay arrays)."""
        return {k: getattr(self, k) for k in self._names()}

    @classmethod
    def _names(cls) -> Tuple[str, ...]:
        return tuple(f.name for f in dataclasses.fields(cls))


def _error() -> Any:
    from . import _etlcal  # the extension, imported when needed (this module loads first)

    return _etlcal.Error


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return bool(np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True))
    return bool(a == b)


@dataclass(frozen=True, eq=False, repr=False)
class ZhangResult(_Result):
    """`zhang(...)`: intrinsics fx, fy, u0, v0 (px), distortion k1 (1/px^2), p1, p2 (1/px),
    `std` (one standard deviation of those seven, same order), `rms_px`, `iterations`,
    `views_used`, `poses` (per view: (rodrigues (rad), translation_mm))."""

    fx: float
    fy: float
    u0: float
    v0: float
    k1: float
    p1: float
    p2: float
    std: List[float]
    rms_px: float
    iterations: int
    views_used: int
    poses: List[Tuple[List[float], List[float]]]
    # The Rust result behind `projection_std`, set by `zhang` after construction: not a
    # field (no key, no repr, no comparison), absent (None) in a result built by hand.
    _projection: ClassVar[Any] = None

    def projection_std(self, pixels: npt.ArrayLike, distance_mm: Optional[float] = None) -> _F64:
        """The projection uncertainty in mrcal's sense: the standard deviations of u and v
        (px) of where a calibration re-solved from new corner noise projects the point seen
        at each pixel, at `distance_mm` along its viewing ray (None: in its direction, a
        point at infinity), the point held in the boards' frames (mrcal's
        `projection_uncertainty`; docs/METHOD.md, "Projection uncertainty of a Zhang
        calibration"). First order, with the result's noise estimate (its `std`'s).

        Args:
            pixels: an (N, 2) array of pixels, or one pixel of shape (2,).
            distance_mm: a finite distance > 0, or None.

        Returns: an (N, 2) float64 array (or (2,)).

        Raises: InputError for a bad distance or a pixel outside the distortion's domain;
        etlcal.Error for a result built by hand (no covariance blocks).
        """
        if self._projection is None:
            raise _error()("this ZhangResult was built by hand: it carries no covariance blocks")
        out: _F64 = self._projection.projection_std(pixels, distance_mm)
        return out


@dataclass(frozen=True, eq=False, repr=False)
class ZhangOpenCvResult(ZhangResult):
    """`zhang(..., model="opencv")`: OpenCV's camera, the model and least-squares problem of
    `cv2.calibrateCamera`. `fx`, `fy`, `u0`, `v0` (px); `k1`, `k2`, `p1`, `p2`, `k3`
    (dimensionless, OpenCV's); `camera_matrix` (3 x 3) and `dist_coeffs` ([k1, k2, p1, p2,
    k3]) for cv2 as they are; `std`: one standard deviation of fx, fy, u0, v0, k1, k2, p1,
    p2, k3 (cv2.calibrateCameraExtended's `stdDeviationsIntrinsics`; 0 for a coefficient a
    flag holds); `per_view_rms_px` (its `perViewErrors`); `model` is "opencv"."""

    model: str
    k2: float
    k3: float
    camera_matrix: _F64
    dist_coeffs: _F64
    per_view_rms_px: List[float]


@dataclass(frozen=True, eq=False, repr=False)
class AutofocusResult(_Result):
    """`autofocus(...)`: `best_ma` (mA), `best_sharpness`, `evaluations` (calls made),
    `bracket_ma` (the final bracket, mA), `converged` (bracket below the tolerance)."""

    best_ma: float
    best_sharpness: float
    evaluations: int
    bracket_ma: Tuple[float, float]
    converged: bool


@dataclass(frozen=True, eq=False, repr=False)
class Compensation(_Result):
    """`ThermalCalibration.compensate` / `.e_in_for_e_com`: `e_in_ma`, `e_t_ma`,
    `e_com_ma` (mA; E_com = E_in - E_T) and `extrapolated` (outside the calibrated ranges)."""

    e_in_ma: float
    e_t_ma: float
    e_com_ma: float
    extrapolated: bool


@dataclass(frozen=True, eq=False, repr=False)
class CompensationArray(_Result):
    """`ThermalCalibration.compensate` / `.e_in_for_e_com` over arrays: the fields of a
    `Compensation` as arrays of the arguments' broadcast shape: `e_in_ma`, `e_t_ma`,
    `e_com_ma` (float64, mA) and `extrapolated` (bool, per reading)."""

    e_in_ma: _F64
    e_t_ma: _F64
    e_com_ma: _F64
    extrapolated: _Bool


@dataclass(frozen=True, eq=False, repr=False)
class LensInfo(_Result):
    """`Lens.info()`: `firmware_type` (the letter of the `H` reply), `firmware_version`
    ("major.minor.build.revision"), `lens_serial`, the driver's `max_current_ma` and its
    software limits `upper_limit_ma`, `lower_limit_ma` (mA), and `temperature_c` (degC, None
    when the lens has no temperature sensor)."""

    firmware_type: str
    firmware_version: str
    lens_serial: str
    max_current_ma: float
    upper_limit_ma: float
    lower_limit_ma: float
    temperature_c: Optional[float]


@dataclass(frozen=True, eq=False, repr=False)
class HoldStep(_Result):
    """One step of `Lens.hold` (given to `on_step`, and the report's `last`): `index` (from
    0), `temperature_c` (degC, read), `e_in_ma` (mA, commanded after clamping and
    quantisation), `e_com_ma` (mA, the surface's E_com at that current), `error_ma`
    (|E_com - wanted|, mA) and `extrapolated` (outside the calibrated ranges)."""

    index: int
    temperature_c: float
    e_in_ma: float
    e_com_ma: float
    error_ma: float
    extrapolated: bool


@dataclass(frozen=True, eq=False, repr=False)
class HoldReport(_Result):
    """`Lens.hold(...)`: `commands_sent`, `elapsed_s` (s), `achieved_rate_hz` (Hz),
    `worst_e_com_error_ma` (mA), `temperature_range_c` ((min, max) read, degC),
    `extrapolated_steps` and `last` (the last HoldStep, None when no step ran)."""

    commands_sent: int
    elapsed_s: float
    achieved_rate_hz: float
    worst_e_com_error_ma: float
    temperature_range_c: Tuple[float, float]
    extrapolated_steps: int
    last: Optional[HoldStep]


@dataclass(frozen=True, eq=False, repr=False)
class ProjectionDiff(_Result):
    """`diff(a, b)`: how far apart two cameras project the same directions over the image:
    `grid` (columns, rows), `rms_px` and `max_px` (intrinsics only), `rotated_rms_px` and
    `rotated_max_px` (after the best rotation, `rotation_rodrigues`, rad), `unmapped`
    (pixels that did not map through both), `diff_px` and `rotated_diff_px` ((rows,
    columns) arrays, px; NaN where unmapped)."""

    grid: Tuple[int, int]
    rms_px: float
    max_px: float
    rotated_rms_px: float
    rotated_max_px: float
    rotation_rodrigues: List[float]
    unmapped: int
    diff_px: _F64
    rotated_diff_px: _F64


@dataclass(frozen=True, eq=False, repr=False)
class LensState(_Result):
    """`VirtualLens.state()`, the simulated lens's truth: `e_in_ma` (the current the driver
    outputs, mA), `effective_ma` (the current the optics follow: `e_in_ma` itself, or with
    dynamics where the membrane has got to, mA), `temperature_c` (the true lens
    temperature, degC), `e_t_ma`, `e_com_ma` (E_T(T, E) and E_com = E - E_T of the
    effective current E, mA) and `f_com_mm` (the ETL group's focal length f_com(E_com),
    mm)."""

    e_in_ma: float
    effective_ma: float
    temperature_c: float
    e_t_ma: float
    e_com_ma: float
    f_com_mm: float


@dataclass(frozen=True, eq=False, repr=False)
class ViewSummary(_Result):
    """One entry of `Calibration.views`: `e_com_ma` (mA), `points`, `rms_px` (px), `dz_mm`
    (mm) and `de_ma` (mA) (errors-in-variables corrections; 0 for the paper's estimator),
    `fx_px`, `fy_px` (px: the focal lengths refitted to that view alone; 0 if not computed)."""

    e_com_ma: float
    points: int
    rms_px: float
    dz_mm: float
    de_ma: float
    fx_px: float
    fy_px: float


@dataclass(frozen=True, eq=False, repr=False)
class SettingViewSummary(_Result):
    """One entry of `Calibration.setting_views` (`setting_views="joint"`): `e_com_ma` (mA),
    `points`, `rms_px` (px), `de_ma` (mA: its current correction, 0 for the paper's
    estimator), and the board's pose, board to camera: `rotation_rodrigues` (3, rad) and
    `translation_mm` (3, mm); with a moving centre a board point P is at
    R P + t - dz(E) e_z in the camera."""

    e_com_ma: float
    points: int
    rms_px: float
    de_ma: float
    rotation_rodrigues: _F64
    translation_mm: _F64


@dataclass(frozen=True, eq=False, repr=False)
class ModelStd(_Result):
    """One standard deviation of each model number (`Calibration.std`, `cramer_rao_std`):
    float64 arrays in the numbers' units: `rotation_rodrigues` (3, rad), `translation_mm`
    (3, mm), `kf_x`, `kf_y` (4 each, px / mA^k), `principal_point` (2, px), `distortion_a` (9)."""

    rotation_rodrigues: _F64
    translation_mm: _F64
    kf_x: _F64
    kf_y: _F64
    principal_point: _F64
    distortion_a: _F64


@dataclass(frozen=True, eq=False, repr=False)
class FocusLaw(_Result):
    """`Calibration.focus_law`: E_com = c0 + c1 V + c2 V^2 with V = 1000 / distance_mm
    (`coefficients_ma`: c0 mA, c1 mA/dpt, c2 mA/dpt^2), the fitted views'
    `distance_range_mm` and `e_com_range_ma` (min, max), `rms_ma` (mA), `views` (count)."""

    coefficients_ma: Tuple[float, float, float]
    distance_range_mm: Tuple[float, float]
    e_com_range_ma: Tuple[float, float]
    rms_ma: float
    views: int


@dataclass(frozen=True, eq=False, repr=False)
class ExportResult(_Result):
    """`Calibration.export`: `e_com_ma` (mA; NaN at a focal power), `extrapolated`,
    `camera_matrix` (3 x 3, px), `dist_coeffs` (k1, k2, p1, p2, k3), the fit's error
    `fit_rms_px`, `fit_max_px` (px), and `focal_power_dpt` (dpt; None at a current)."""

    e_com_ma: float
    extrapolated: bool
    camera_matrix: _F64
    dist_coeffs: _F64
    fit_rms_px: float
    fit_max_px: float
    focal_power_dpt: Optional[float]


@dataclass(frozen=True, eq=False, repr=False)
class Triangulated(_Result):
    """`RigAt.triangulate`: `point_mm` (3,) in camera 0's frame at its setting, its
    `covariance_mm2` (3 x 3) = `from_pixels_mm2` (the pixel noise's) + `from_calibration_mm2`
    (the calibrations' and poses', None when pixel-only), `calibration_covariance`
    (`"joint"`: from the rig file's joint covariance, cross-covariances kept;
    `"independent"`: each calibration and pose as an independent group, which over-states
    the depth sigma of a rig calibrated jointly; None when pixel-only), `std_mm` (the
    square roots of its diagonal), `cameras_used`, `rms_px` (reprojection),
    `extrapolated`."""

    point_mm: _F64
    covariance_mm2: _F64
    std_mm: _F64
    from_pixels_mm2: _F64
    from_calibration_mm2: Optional[_F64]
    calibration_covariance: Optional[str]
    cameras_used: List[int]
    rms_px: float
    extrapolated: bool


@dataclass(frozen=True, eq=False, repr=False)
class StereoRectifyMaps(_Result):
    """`Rig.stereo_rectify_maps`, `RigAt.stereo_rectify_maps`: Bouguet's rectification of a
    pair at its settings, as cv2.stereoRectify returns it (`R1`, `R2` 3 x 3, `P1`, `P2` 3 x 4,
    `Q` 4 x 4), the pair's pose `R`, `T` (X_right = R X_left + T, mm) and `baseline_mm`, and
    each image's maps `left_maps`, `right_maps` ((map_x, map_y), (h, w) float32: for
    `cv2.remap`); `pair` (left, right) and `image_size` (w, h)."""

    pair: Tuple[int, int]
    image_size: Tuple[int, int]
    R: _F64
    T: _F64
    baseline_mm: float
    R1: _F64
    R2: _F64
    P1: _F64
    P2: _F64
    Q: _F64
    left_maps: Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]
    right_maps: Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]


@dataclass(frozen=True, eq=False, repr=False)
class StereoResult(_Result):
    """`stereo(...)`: `left`, `right` (each camera's `ZhangResult` or `ZhangOpenCvResult`),
    `rotation_rodrigues` (rad), `rotation_matrix`, `translation_mm` (X_right = R X_left + T),
    `covariance` (6 x 6 over (om, T)), `std`, `rms_px`, `per_view_rms_px` ([left, right] per
    pair used), `pairs_used`, `baseline_mm`, `intrinsics` ("fixed" or "joint")."""

    left: ZhangResult
    right: ZhangResult
    rotation_rodrigues: _F64
    rotation_matrix: _F64
    translation_mm: _F64
    covariance: _F64
    std: _F64
    rms_px: float
    per_view_rms_px: List[List[float]]
    pairs_used: List[int]
    baseline_mm: float
    intrinsics: str


@dataclass(frozen=True, eq=False, repr=False)
class View(_Result):
    """An ETL view of `Observations` (`obs[i]`, `obs.view(i)`, `obs.setting_view(i)`):
    `world_mm` ((N, 3), mm), `pixels` ((N, 2), px), `e_in_ma` (mA; None at a focal power),
    `temperature_c` (degC), `e_com_ma` (mA, None when not recorded), `focal_power_dpt`
    (dpt; None at a current)."""

    world_mm: _F64
    pixels: _F64
    e_in_ma: Optional[float]
    temperature_c: float
    e_com_ma: Optional[float]
    focal_power_dpt: Optional[float]


@dataclass(frozen=True, eq=False, repr=False)
class OffstateView(_Result):
    """A lens-off view of `Observations` (`obs.offstate_view(i)`): `world_mm` ((N, 3), mm)
    and `pixels` ((N, 2), px)."""

    world_mm: _F64
    pixels: _F64


@dataclass(frozen=True, eq=False, repr=False)
class BoardDetection(_Result):
    """`detect_corners(image, board)` for an `etlcal.Board`: `corners_px` ((N, 2), px),
    `ids` ((N,) int64, increasing: OpenCV's ChArUco corner ids, a checkerboard's row-major
    index), `board_mm` ((N, 2), each corner on the board, mm), `image_size` ((width,
    height), px)."""

    corners_px: _F64
    ids: npt.NDArray[np.int64]
    board_mm: _F64
    image_size: Tuple[int, int]


@dataclass(frozen=True, eq=False, repr=False)
class DetectionSummary(_Result):
    """`Dataset.detect()`'s summary: `images` (count), `detected` (boards found),
    `views_detected`, `skipped` (list of (image, kind, reason))."""

    images: int
    detected: int
    views_detected: int
    skipped: List[Tuple[str, str, str]]


@dataclass(frozen=True, eq=False, repr=False)
class ThermalCalibrationResult(_Result):
    """`thermal_calibration(...)`: `calibration` (a ThermalCalibration), `rms_ma` (mA),
    `samples` ((N, 3): T degC, E_in mA, E_T mA), `frames` (images captured)."""

    calibration: Any
    rms_ma: float
    samples: _F64
    frames: int


@dataclass(frozen=True, eq=False, repr=False)
class StudyResult(_Result):
    """`study(name)`: `name` (the study) and `table` (the command line's --json object).
    As a mapping it is the table itself (``result["parameters"]``, ``dict(result)``, as
    when `study` returned the dict); the table's keys are also attributes
    (``result.parameters``); which keys depends on the study."""

    name: str
    table: Dict[str, Any]

    def __getitem__(self, key: str) -> Any:
        return self.table[key]

    def __getattr__(self, key: str) -> Any:
        # Only called for names that are not fields: the table's keys.
        table = self.__dict__.get("table", {})
        if key in table:
            return table[key]
        raise AttributeError(f"the {self.__dict__.get('name')!r} study has no {key!r}")

    def __iter__(self) -> Iterator[str]:
        return iter(self.table)

    def __len__(self) -> int:
        return len(self.table)

    def __contains__(self, key: object) -> bool:
        return key in self.table

    def __repr__(self) -> str:
        return f"StudyResult(name={self.name!r}, keys={list(self.table)})"

    def to_dict(self) -> Dict[str, Any]:
        """The table as a plain dict (the command line's --json object)."""
        return dict(self.table)


class OpenCvCamera(Tuple[_F64, _F64]):
    """`Calibration.to_opencv(...)`: the tuple (camera_matrix, dist_coeffs) for cv2, as it
    always was (`K, dist = cal.to_opencv(E)`), saying how exact it is: `exact` is True for
    the opencv distortion family (OpenCV's own model: `cv2.projectPoints` reproduces the
    calibration), False for the paper family, whose coefficients are the least-squares fit
    over the image; `fit_rms_px`, `fit_max_px` are the fit's error (0 when exact; arrays
    over an array of currents)."""

    camera_matrix: _F64
    dist_coeffs: _F64
    fit_rms_px: Any
    fit_max_px: Any
    exact: bool

    def __new__(cls, camera_matrix: _F64, dist_coeffs: _F64, fit_rms_px: Any, fit_max_px: Any,
                exact: bool) -> "OpenCvCamera":
        self = super().__new__(cls, (camera_matrix, dist_coeffs))
        self.camera_matrix, self.dist_coeffs = camera_matrix, dist_coeffs
        self.fit_rms_px, self.fit_max_px, self.exact = fit_rms_px, fit_max_px, exact
        return self

    def __repr__(self) -> str:
        how = "exact" if self.exact else f"least-squares fit, error {_short(self.fit_rms_px)} px RMS"
        return (f"OpenCvCamera(camera_matrix={_short(self.camera_matrix)}, "
                f"dist_coeffs={_short(self.dist_coeffs)}, {how})")


class Distortion(Tuple[Any, ...]):
    """`Calibration.distortion(e_com_ma)`, `CameraAt.distortion`: the distortion
    coefficients at one current, named for their family (`model`: "paper" or "opencv",
    the calibration's `distortion_model`). A tuple of the coefficients in the family's
    order (`names`), as the paper family's (k1, p1, p2) always was (`k1, p1, p2 =
    cal.distortion(E)`), with one attribute per coefficient and `to_dict()`. Over an array
    of currents each coefficient is an array of that shape. Frozen (a tuple)."""

    __slots__ = ()
    model: ClassVar[str] = ""
    names: ClassVar[Tuple[str, ...]] = ()

    def __new__(cls, *coefficients: Any) -> "Distortion":
        if not cls.names:
            raise TypeError("Distortion is abstract: use Distortion.of(model, ...) or a family's class")
        if len(coefficients) != len(cls.names):
            raise TypeError(f"{cls.__name__} takes {len(cls.names)} coefficients ({', '.join(cls.names)}), "
                            f"got {len(coefficients)}")
        return super().__new__(cls, coefficients)

    @staticmethod
    def of(model: str, *coefficients: Any) -> "Distortion":
        """The result of family `model` ("paper" or "opencv") with its coefficients."""
        for family in Distortion.__subclasses__():
            if family.model == model:
                return family(*coefficients)
        raise ValueError(f"no distortion family {model!r}: use \"paper\" or \"opencv\"")

    def __getnewargs__(self) -> Tuple[Any, ...]:
        # Pickling: the coefficients as __new__'s arguments (a tuple would pass one).
        return tuple(self)

    def to_dict(self) -> Dict[str, Any]:
        """The coefficients as a plain dict, keyed by their names (arrays stay arrays)."""
        return dict(zip(self.names, self))

    def __repr__(self) -> str:
        inner = ", ".join(f"{k}={_short(v)}" for k, v in zip(self.names, self))
        return f"{type(self).__name__}({inner})"


class PaperDistortion(Distortion):
    """The paper's family (Eq. 17-18), acting on pixel coordinates centred on the
    principal point: radial `k1` (1/px^2) and decentering `p1`, `p2` (1/px; Weng's term)."""

    __slots__ = ()
    model = "paper"
    names = ("k1", "p1", "p2")

    @property
    def k1(self) -> Any:
        """Radial k1, 1/px^2."""
        return self[0]

    @property
    def p1(self) -> Any:
        """Decentering p1 (paired with 3u^2 + v^2 in u_d), 1/px."""
        return self[1]

    @property
    def p2(self) -> Any:
        """Decentering p2 (paired with u^2 + 3v^2 in v_d), 1/px."""
        return self[2]


class OpenCvDistortion(Distortion):
    """OpenCV's family in normalised coordinates (x = (u - u0) / fx), OpenCV's order and
    meaning: radial `k1`, `k2`, `k3` and tangential `p1`, `p2`, dimensionless (the
    `dist_coeffs` cv2 takes, exactly)."""

    __slots__ = ()
    model = "opencv"
    names = ("k1", "k2", "p1", "p2", "k3")

    @property
    def k1(self) -> Any:
        """Radial k1 (r^2), dimensionless."""
        return self[0]

    @property
    def k2(self) -> Any:
        """Radial k2 (r^4), dimensionless."""
        return self[1]

    @property
    def p1(self) -> Any:
        """Tangential p1, dimensionless."""
        return self[2]

    @property
    def p2(self) -> Any:
        """Tangential p2, dimensionless."""
        return self[3]

    @property
    def k3(self) -> Any:
        """Radial k3 (r^6), dimensionless."""
        return self[4]
