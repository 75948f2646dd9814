"""Type stubs of the native module etlcal._etlcal (units: mm, mA, degC, px)."""
import os
import pathlib
from typing import Any, Callable, Dict, Iterator, List, Literal, Mapping, Optional, Sequence, Tuple, Union, final, overload

import numpy as np
import numpy.typing as npt
from numpy.polynomial import Polynomial

from etlcal.options import (
    DistortionChoice,
    Estimator,
    ExportFormat,
    FocalDegreeChoice,
    Method,
    NoisePreset,
    RobustLoss,
    SharpnessMetric,
    StudyName,
)
from etlcal.results import (
    AutofocusResult,
    BoardDetection,
    Compensation,
    CompensationArray,
    DetectionSummary,
    Distortion,
    ExportResult,
    FocusLaw,
    HoldReport,
    HoldStep,
    LensInfo,
    LensState,
    ModelStd,
    OffstateView,
    OpenCvCamera,
    ProjectionDiff,
    SettingViewSummary,
    StereoRectifyMaps,
    StereoResult,
    StudyResult,
    ThermalCalibrationResult,
    Triangulated,
    View,
    ViewSummary,
    ZhangOpenCvResult,
    ZhangResult,
)

_Path = Union[str, "os.PathLike[str]"]
_F64 = npt.NDArray[np.float64]
_F32 = npt.NDArray[np.float32]
_Image = Union[npt.NDArray[np.uint8], npt.NDArray[np.uint16], npt.NDArray[np.float32]]
_ArrayLike = npt.ArrayLike
_FloatOrArray = Union[float, _F64]
# An array of currents (any shape S): the vectorised per-current functions stack their
# results on leading axes S.
_Currents = Union[_F64, Sequence[float]]

__all__ = [
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
    "__version__",
    "autofocus",
    "calibrate",
    "calibrate_rig",
    "cramer_rao_std",
    "detect_corners",
    "diff",
    "render",
    "sharpness",
    "simulate_paper_rig",
    "simulate_strong_rig",
    "stereo",
    "study",
    "thermal_calibration",
    "zhang",
    "RigCamera",
    "rig_capture_offstate",
    "rig_capture_thermal",
    "rig_capture_views",
]
__version__: str

class Error(Exception): ...
class InputError(Error, ValueError):
    # The flag, file key, field or argument to change ("views[3].points", "square_mm",
    # "search_ma"), and the offending value as text (numbers compact: "1e308", "NaN");
    # None when the error names none.
    what: Optional[str]
    value: Optional[str]

class NotConvergedError(Error): ...
class BoardNotFoundError(Error): ...
class FileError(Error, OSError): ...
class DeviceError(Error): ...
class DeviceTimeoutError(DeviceError, TimeoutError): ...

def _raise_rust_error(kind: str) -> None: ...
def _panic(message: str, in_pool: bool = False) -> None: ...

@final
class _ZhangProjection:
    def projection_std(self, pixels: _ArrayLike, distance_mm: Optional[float] = None) -> _F64: ...
    @staticmethod
    def _from_json(text: str) -> _ZhangProjection: ...

@final
class _PanicProbe:
    def __new__(cls, panic_now: bool) -> _PanicProbe: ...
    def method(self) -> None: ...
    @staticmethod
    def static_method() -> None: ...
    @property
    def property(self) -> bool: ...
    def __len__(self) -> int: ...

# Numbers given as an array (any numeric dtype) or a list: the elementwise functions
# return an array for them (two numbers give a number).
_Numbers = Union[npt.NDArray[Any], Sequence[float]]

@final
class ThermalSurface:
    def __new__(cls, coefficients: _ArrayLike) -> ThermalSurface: ...
    @staticmethod
    def paper() -> ThermalSurface: ...
    @property
    def coefficients(self) -> _F64: ...
    @overload
    def e_t(self, e_in_ma: float, temperature_c: float) -> float: ...
    @overload
    def e_t(self, e_in_ma: _Numbers, temperature_c: Union[float, _Numbers]) -> _F64: ...
    @overload
    def e_t(self, e_in_ma: float, temperature_c: _Numbers) -> _F64: ...
    @overload
    def e_t(self, e_in_ma: _ArrayLike, temperature_c: _ArrayLike) -> _FloatOrArray: ...
    @overload
    def e_com(self, e_in_ma: float, temperature_c: float) -> float: ...
    @overload
    def e_com(self, e_in_ma: _Numbers, temperature_c: Union[float, _Numbers]) -> _F64: ...
    @overload
    def e_com(self, e_in_ma: float, temperature_c: _Numbers) -> _F64: ...
    @overload
    def e_com(self, e_in_ma: _ArrayLike, temperature_c: _ArrayLike) -> _FloatOrArray: ...
    @overload
    def e_in_for_e_com(self, e_com_ma: float, temperature_c: float) -> float: ...
    @overload
    def e_in_for_e_com(self, e_com_ma: _Numbers, temperature_c: Union[float, _Numbers]) -> _F64: ...
    @overload
    def e_in_for_e_com(self, e_com_ma: float, temperature_c: _Numbers) -> _F64: ...
    @overload
    def e_in_for_e_com(self, e_com_ma: _ArrayLike, temperature_c: _ArrayLike) -> _FloatOrArray: ...
    @staticmethod
    def fit(
        e_in_ma: _ArrayLike, temperature_c: _ArrayLike, e_t_ma: _ArrayLike, weights: Optional[_ArrayLike] = None
    ) -> ThermalCalibration: ...

@final
class ThermalCalibration:
    def __new__(
        cls,
        surface: ThermalSurface,
        *,
        e_in_range_ma: Tuple[float, float],
        t_range_c: Tuple[float, float],
        rms_ma: float = 0.0,
    ) -> ThermalCalibration: ...
    @staticmethod
    def paper() -> ThermalCalibration: ...
    @classmethod
    def load(cls, path: _Path) -> ThermalCalibration: ...
    def save(self, path: _Path) -> None: ...
    def to_json(self) -> str: ...
    @staticmethod
    def from_json(text: str) -> ThermalCalibration: ...
    @property
    def surface(self) -> ThermalSurface: ...
    @property
    def t_range_c(self) -> Tuple[float, float]: ...
    @property
    def e_in_range_ma(self) -> Tuple[float, float]: ...
    @property
    def rms_ma(self) -> float: ...
    @overload
    def compensate(self, e_in_ma: float, temperature_c: float) -> Compensation: ...
    @overload
    def compensate(self, e_in_ma: _Numbers, temperature_c: Union[float, _Numbers]) -> CompensationArray: ...
    @overload
    def compensate(self, e_in_ma: float, temperature_c: _Numbers) -> CompensationArray: ...
    @overload
    def compensate(
        self, e_in_ma: _ArrayLike, temperature_c: _ArrayLike
    ) -> Union[Compensation, CompensationArray]: ...
    @overload
    def e_in_for_e_com(self, e_com_ma: float, temperature_c: float) -> Compensation: ...
    @overload
    def e_in_for_e_com(self, e_com_ma: _Numbers, temperature_c: Union[float, _Numbers]) -> CompensationArray: ...
    @overload
    def e_in_for_e_com(self, e_com_ma: float, temperature_c: _Numbers) -> CompensationArray: ...
    @overload
    def e_in_for_e_com(
        self, e_com_ma: _ArrayLike, temperature_c: _ArrayLike
    ) -> Union[Compensation, CompensationArray]: ...
    def contains(self, e_in_ma: float, temperature_c: float) -> bool: ...

@final
class LensPhysics:
    def __new__(
        cls,
        young_modulus_pa: float = 3.0e6,
        membrane_radius_mm: float = 5.0,
        membrane_thickness_mm: float = 0.1,
        poisson_ratio: float = 0.48,
        prestrain: float = 0.05,
        n_liq: float = 1.4,
        n_0: float = 1.0,
        p0_pa: float = 1200.0,
        k_e0_pa: float = 2.061e-13,
        k_e1_pa_per_ma: float = 7.8,
        k_e2_pa_per_ma2: float = -0.004,
        f_pri_mm: float = 30.0,
        d_lens_mm: float = 3.0,
    ) -> LensPhysics: ...
    @staticmethod
    def paper() -> LensPhysics: ...
    def to_dict(self) -> Dict[str, float]: ...
    @overload
    def applied_pressure_pa(self, e_ma: float) -> float: ...
    @overload
    def applied_pressure_pa(self, e_ma: _Numbers) -> _F64: ...
    @overload
    def applied_pressure_pa(self, e_ma: _ArrayLike) -> _FloatOrArray: ...
    @overload
    def membrane_pressure_pa(self, e_ma: float) -> float: ...
    @overload
    def membrane_pressure_pa(self, e_ma: _Numbers) -> _F64: ...
    @overload
    def membrane_pressure_pa(self, e_ma: _ArrayLike) -> _FloatOrArray: ...
    def hemisphere_pressure_pa(self) -> float: ...
    @overload
    def peak_deflection_mm(self, e_ma: float) -> float: ...
    @overload
    def peak_deflection_mm(self, e_ma: _Numbers) -> _F64: ...
    @overload
    def peak_deflection_mm(self, e_ma: _ArrayLike) -> _FloatOrArray: ...
    @overload
    def radius_of_curvature_mm(self, e_ma: float) -> float: ...
    @overload
    def radius_of_curvature_mm(self, e_ma: _Numbers) -> _F64: ...
    @overload
    def radius_of_curvature_mm(self, e_ma: _ArrayLike) -> _FloatOrArray: ...
    @overload
    def f_liq_mm(self, e_ma: float) -> float: ...
    @overload
    def f_liq_mm(self, e_ma: _Numbers) -> _F64: ...
    @overload
    def f_liq_mm(self, e_ma: _ArrayLike) -> _FloatOrArray: ...
    @overload
    def f_com_mm(self, e_ma: float) -> float: ...
    @overload
    def f_com_mm(self, e_ma: _Numbers) -> _F64: ...
    @overload
    def f_com_mm(self, e_ma: _ArrayLike) -> _FloatOrArray: ...
    @overload
    def f_com_for_f_liq_mm(self, f_liq_mm: float) -> float: ...
    @overload
    def f_com_for_f_liq_mm(self, f_liq_mm: _Numbers) -> _F64: ...
    @overload
    def f_com_for_f_liq_mm(self, f_liq_mm: _ArrayLike) -> _FloatOrArray: ...
    @overload
    def gravity_error_mm(self, e_ma: float, dp_gravity_pa: float) -> float: ...
    @overload
    def gravity_error_mm(self, e_ma: _Numbers, dp_gravity_pa: float) -> _F64: ...
    @overload
    def gravity_error_mm(self, e_ma: _ArrayLike, dp_gravity_pa: float) -> _FloatOrArray: ...
    @overload
    def gravity_coefficient(self, e_ma: float, rho_liq_kg_m3: float, rho_sur_kg_m3: float) -> float: ...
    @overload
    def gravity_coefficient(self, e_ma: _Numbers, rho_liq_kg_m3: float, rho_sur_kg_m3: float) -> _F64: ...
    @overload
    def gravity_coefficient(self, e_ma: _ArrayLike, rho_liq_kg_m3: float, rho_sur_kg_m3: float) -> _FloatOrArray: ...
    def polynomial_fit_rmse_mm(self, e_from_ma: float = 0.0, e_to_ma: float = 260.0, step_ma: float = 0.1) -> List[float]: ...

@final
class BoardPose:
    def __new__(
        cls,
        rotation_rodrigues: Tuple[float, float, float],
        translation_mm: Tuple[float, float, float],
        rms_px: float = 0.0,
        iterations: int = 0,
    ) -> BoardPose: ...
    @property
    def rotation_rodrigues(self) -> _F64: ...
    @property
    def rotation_matrix(self) -> _F64: ...
    @property
    def translation_mm(self) -> _F64: ...
    @property
    def rms_px(self) -> float: ...
    @property
    def iterations(self) -> int: ...
    @property
    def sigma_px(self) -> Optional[float]: ...
    @property
    def covariance(self) -> Optional[_F64]: ...
    def displacement_mm(self, other: BoardPose) -> _F64: ...
    def displacement_std_mm(self, other: BoardPose, pixel_noise_only: bool = False) -> _F64: ...

@final
class Calibration:
    def __new__(
        cls,
        rotation_rodrigues: _ArrayLike,
        translation_mm: _ArrayLike,
        kf_x: _ArrayLike,
        kf_y: _ArrayLike,
        principal_point: _ArrayLike,
        distortion_a: _ArrayLike,
        image_size: Tuple[int, int] = (1936, 1458),
        e_com_range_ma: Tuple[float, float] = (0.0, 250.0),
        thermal: Union[ThermalCalibration, ThermalSurface, Literal["paper"], None] = None,
        rms_px: float = 0.0,
    ) -> Calibration: ...
    @staticmethod
    def paper_rig() -> Calibration: ...
    @classmethod
    def load(cls, path: _Path) -> Calibration: ...
    def save(self, path: _Path) -> None: ...
    def to_json(self) -> str: ...
    @staticmethod
    def from_json(text: str) -> Calibration: ...
    @property
    def rotation_rodrigues(self) -> _F64: ...
    @property
    def rotation_matrix(self) -> _F64: ...
    @property
    def translation_mm(self) -> _F64: ...
    @property
    def kf_x(self) -> _F64: ...
    @property
    def kf_y(self) -> _F64: ...
    @property
    def principal_point(self) -> _F64: ...
    @property
    def centre(self) -> Optional[Dict[str, Any]]: ...
    @property
    def fx_poly(self) -> Polynomial: ...
    @property
    def fy_poly(self) -> Polynomial: ...
    @property
    def distortion_a(self) -> _F64: ...
    @property
    def image_size(self) -> Tuple[int, int]: ...
    @property
    def e_com_range_ma(self) -> Tuple[float, float]: ...
    @property
    def thermal(self) -> Optional[ThermalSurface]: ...
    @property
    def thermal_calibration(self) -> Optional[ThermalCalibration]: ...
    @property
    def thermal_source(self) -> Optional[str]: ...
    @property
    def outliers(self) -> List[Tuple[int, int, float]]: ...
    @property
    def setting_outliers(self) -> List[Tuple[int, int, float]]: ...
    @property
    def setting_views(self) -> List[SettingViewSummary]: ...
    @property
    def warnings(self) -> List[str]: ...
    @property
    def distortion_model(self) -> Literal["paper", "opencv"]: ...
    @property
    def focal_degree(self) -> int: ...
    @property
    def model_selection(self) -> Optional[Dict[str, Any]]:
        """How distortion="auto" / focal_degree="auto" chose the model: {"method", "rule",
        "candidates": [...]}; None when the model was given."""
        ...
    def at(
        self,
        e_in_ma: Optional[float] = None,
        temperature_c: Optional[float] = None,
        *,
        focal_power_dpt: Optional[float] = None,
        allow_extrapolation: bool = False,
    ) -> CameraAt: ...
    @property
    def setting(self) -> Literal["current", "focal_power"]: ...
    @property
    def focal_power_range_dpt(self) -> Optional[Tuple[float, float]]: ...
    def focus_focal_power_dpt(
        self, distance_mm: float, temperature_c: float, *, allow_extrapolation: bool = False
    ) -> float: ...
    def at_e_com(self, e_com_ma: float, *, allow_extrapolation: bool = False) -> CameraAt:
        """The camera at a known E_com (a calibration without temperature compensation)."""
        ...
    @property
    def temperature_compensation(self) -> Optional[Literal["none"]]: ...
    @property
    def rms_px(self) -> float: ...
    @property
    def initial_rms_px(self) -> float: ...
    @property
    def estimator(self) -> Optional[str]: ...
    @property
    def covariance_noise(self) -> Optional[Dict[str, float]]: ...
    @property
    def iterations(self) -> int: ...
    @property
    def views(self) -> List[ViewSummary]: ...
    @property
    def std(self) -> ModelStd: ...
    @overload
    def e_com(self, e_in_ma: float, temperature_c: float, *, allow_extrapolation: bool = False) -> float: ...
    @overload
    def e_com(
        self, e_in_ma: _Numbers, temperature_c: Union[float, _Numbers], *, allow_extrapolation: bool = False
    ) -> _F64: ...
    @overload
    def e_com(
        self, e_in_ma: float, temperature_c: _Numbers, *, allow_extrapolation: bool = False
    ) -> _F64: ...
    @overload
    def e_com(
        self, e_in_ma: _ArrayLike, temperature_c: _ArrayLike, *, allow_extrapolation: bool = False
    ) -> _FloatOrArray: ...
    @overload
    def e_in_for_e_com(self, e_com_ma: float, temperature_c: float, *, allow_extrapolation: bool = False) -> float: ...
    @overload
    def e_in_for_e_com(
        self, e_com_ma: _Numbers, temperature_c: Union[float, _Numbers], *, allow_extrapolation: bool = False
    ) -> _F64: ...
    @overload
    def e_in_for_e_com(
        self, e_com_ma: float, temperature_c: _Numbers, *, allow_extrapolation: bool = False
    ) -> _F64: ...
    @overload
    def e_in_for_e_com(
        self, e_com_ma: _ArrayLike, temperature_c: _ArrayLike, *, allow_extrapolation: bool = False
    ) -> _FloatOrArray: ...
    @property
    def focus_law(self) -> Optional[FocusLaw]: ...
    @overload
    def focus_e_in(self, distance_mm: float, temperature_c: float, *, allow_extrapolation: bool = False) -> float: ...
    @overload
    def focus_e_in(
        self, distance_mm: _Numbers, temperature_c: Union[float, _Numbers], *, allow_extrapolation: bool = False
    ) -> _F64: ...
    @overload
    def focus_e_in(
        self, distance_mm: float, temperature_c: _Numbers, *, allow_extrapolation: bool = False
    ) -> _F64: ...
    @overload
    def focus_e_in(
        self, distance_mm: _ArrayLike, temperature_c: _ArrayLike, *, allow_extrapolation: bool = False
    ) -> _FloatOrArray: ...
    @overload
    def focus_distance_mm(
        self, e_in_ma: float, temperature_c: float, *, allow_extrapolation: bool = False
    ) -> float: ...
    @overload
    def focus_distance_mm(
        self, e_in_ma: _Numbers, temperature_c: Union[float, _Numbers], *, allow_extrapolation: bool = False
    ) -> _F64: ...
    @overload
    def focus_distance_mm(
        self, e_in_ma: float, temperature_c: _Numbers, *, allow_extrapolation: bool = False
    ) -> _F64: ...
    @overload
    def focus_distance_mm(
        self, e_in_ma: _ArrayLike, temperature_c: _ArrayLike, *, allow_extrapolation: bool = False
    ) -> _FloatOrArray: ...
    @overload
    def focal_lengths(self, e_com_ma: float, *, allow_extrapolation: bool = False) -> Tuple[float, float]: ...
    @overload
    def focal_lengths(self, e_com_ma: _Currents, *, allow_extrapolation: bool = False) -> Tuple[_F64, _F64]: ...
    def intrinsics(self, e_com_ma: Union[float, _Currents], *, allow_extrapolation: bool = False) -> _F64: ...
    def distortion(self, e_com_ma: Union[float, _Currents], *, allow_extrapolation: bool = False) -> Distortion:
        """A PaperDistortion (k1, p1, p2) or an OpenCvDistortion (k1, k2, p1, p2, k3), by
        `distortion_model`; floats for a number, arrays for an array of currents."""
        ...
    def project(self, world_mm: _ArrayLike, e_com_ma: float, *, allow_extrapolation: bool = False) -> _F64: ...
    def undistort(self, pixels: _ArrayLike, e_com_ma: float, *, allow_extrapolation: bool = False) -> _F64: ...
    def ray(
        self, pixel: Tuple[float, float], e_com_ma: float, *, allow_extrapolation: bool = False
    ) -> Tuple[_F64, _F64]: ...
    def solve_pnp(
        self,
        board_mm: _ArrayLike,
        pixels: _ArrayLike,
        e_com_ma: float,
        sigma_px: Optional[float] = None,
        *,
        allow_extrapolation: bool = False,
    ) -> BoardPose: ...
    @property
    def covariance(self) -> Optional[_F64]: ...
    def projection_std(self, world_mm: _ArrayLike, e_com_ma: float, *, allow_extrapolation: bool = False) -> _F64: ...
    def pixel_projection_std(
        self, pixels: _ArrayLike, e_com_ma: float, distance_mm: Optional[float] = None, *, allow_extrapolation: bool = False
    ) -> _F64: ...
    def to_opencv(
        self, e_com_ma: Union[float, _Currents], *, allow_extrapolation: bool = False
    ) -> OpenCvCamera:
        """(K, dist) for cv2, exact for the opencv family; `fit_rms_px`, `fit_max_px`,
        `exact` say the paper family's fit error."""
        ...
    def undistort_maps(
        self,
        e_com_ma: float,
        new_camera_matrix: Optional[_ArrayLike] = None,
        size: Optional[Tuple[int, int]] = None,
        *,
        allow_extrapolation: bool = False,
    ) -> Tuple[_F32, _F32]: ...
    def undistort_image(self, image: _Image, e_com_ma: float, *, allow_extrapolation: bool = False) -> _Image: ...
    def export(
        self,
        path: _Path,
        e_in_ma: float,
        temperature_c: float,
        format: ExportFormat,
        *,
        allow_extrapolation: bool = False,
    ) -> ExportResult: ...

@final
class CameraAt:
    """The camera at one setting (``Calibration.at``, ``Calibration.at_e_com``): every
    run-time operation; ``Calibration``'s methods taking ``e_com_ma`` are these."""
    @property
    def e_in_ma(self) -> Optional[float]: ...
    @property
    def temperature_c(self) -> Optional[float]: ...
    @property
    def e_com_ma(self) -> float: ...
    @property
    def focal_power_dpt(self) -> Optional[float]: ...
    @property
    def setting(self) -> Literal["current", "focal_power"]: ...
    @property
    def calibration(self) -> Calibration: ...
    @property
    def extrapolated(self) -> bool: ...
    @property
    def extrapolated_quantities(self) -> List[str]: ...
    @property
    def focal_lengths(self) -> Tuple[float, float]: ...
    @property
    def camera_matrix(self) -> _F64: ...
    @property
    def distortion(self) -> Distortion: ...
    def to_opencv(self) -> OpenCvCamera: ...
    def project(self, world_mm: _ArrayLike) -> _F64: ...
    def undistort(self, pixels: _ArrayLike) -> _F64: ...
    def ray(self, pixel: Tuple[float, float]) -> Tuple[_F64, _F64]: ...
    def solve_pnp(self, board_mm: _ArrayLike, pixels: _ArrayLike, sigma_px: Optional[float] = None) -> BoardPose: ...
    def projection_std(self, world_mm: _ArrayLike) -> _F64: ...
    def undistort_maps(
        self, new_camera_matrix: Optional[_ArrayLike] = None, size: Optional[Tuple[int, int]] = None
    ) -> Tuple[_F32, _F32]: ...
    def undistort_image(self, image: _Image) -> _Image: ...
    def export(self, path: _Path, format: ExportFormat) -> ExportResult: ...

@final
class A0:
    def __new__(cls, kf0x: float, kf0y: float, u0: float, v0: float) -> A0: ...
    @classmethod
    def load(cls, path: _Path) -> A0: ...
    def save(self, path: _Path) -> None: ...
    def to_json(self) -> str: ...
    @staticmethod
    def from_json(text: str) -> A0: ...
    @property
    def kf0x(self) -> float: ...
    @property
    def kf0y(self) -> float: ...
    @property
    def u0(self) -> float: ...
    @property
    def v0(self) -> float: ...

@final
class Observations:
    def __new__(cls, image_size: Tuple[int, int]) -> Observations: ...
    @staticmethod
    def from_arrays(
        image_size: Tuple[int, int],
        world_mm: Sequence[_ArrayLike],
        pixels: Sequence[_ArrayLike],
        e_in_ma: Sequence[float],
        temperature_c: Sequence[float],
        e_com_ma: Optional[Sequence[float]] = None,
    ) -> Observations: ...
    @classmethod
    def load(cls, path: _Path) -> Observations: ...
    def save(self, path: _Path) -> None: ...
    def to_json(self) -> str: ...
    @staticmethod
    def from_json(text: str) -> Observations: ...
    @property
    def image_size(self) -> Tuple[int, int]: ...
    def add_view(
        self,
        world_mm: _ArrayLike,
        pixels: _ArrayLike,
        e_in_ma: Optional[float] = None,
        temperature_c: Optional[float] = None,
        e_com_ma: Optional[float] = None,
        *,
        focal_power_dpt: Optional[float] = None,
    ) -> None: ...
    def add_offstate_view(self, world_mm: _ArrayLike, pixels: _ArrayLike) -> None: ...
    def add_setting_view(
        self,
        world_mm: _ArrayLike,
        pixels: _ArrayLike,
        e_in_ma: float,
        temperature_c: float,
        e_com_ma: Optional[float] = None,
    ) -> None: ...
    @property
    def setting_count(self) -> int: ...
    def setting_view(self, index: int) -> View: ...
    def __len__(self) -> int: ...
    def __getitem__(self, index: int, /) -> View: ...
    def __iter__(self) -> Iterator[View]: ...
    @property
    def offstate_count(self) -> int: ...
    @property
    def point_count(self) -> int: ...
    def view(self, index: int) -> View: ...
    def offstate_view(self, index: int) -> OffstateView: ...
    def e_com_ma(self, thermal: Union[ThermalCalibration, Literal["paper"], None] = None) -> List[float]: ...

@final
class Simulation:
    @property
    def observations(self) -> Observations: ...
    @property
    def a0(self) -> A0: ...
    @property
    def truth(self) -> Calibration: ...
    @property
    def true_dz_mm(self) -> List[float]: ...
    @property
    def true_de_ma(self) -> List[float]: ...
    @property
    def seed(self) -> int: ...
    @property
    def noise(self) -> Dict[str, float]: ...

def simulate_paper_rig(
    seed: int = 0, noise: Optional[Union[NoisePreset, Mapping[str, float]]] = None, setting_views: bool = False
) -> Simulation: ...
def simulate_strong_rig(
    seed: int = 0, noise: Optional[Union[NoisePreset, Mapping[str, float]]] = None
) -> Simulation: ...
def calibrate(
    observations: Observations,
    a0: Optional[A0] = None,
    thermal: Union[ThermalCalibration, Literal["paper"], None] = None,
    estimator: Optional[Estimator] = None,
    hold_a0: bool = False,
    robust: Optional[RobustLoss] = None,
    robust_k_px: Optional[float] = None,
    sigma_z_mm: Optional[float] = None,
    sigma_e_ma: Optional[float] = None,
    sigma_px: Optional[float] = None,
    method: Method = "proposed",
    distortion: Optional[DistortionChoice] = None,
    focal_degree: Optional[FocalDegreeChoice] = None,
    fix_k3: bool = False,
    zero_tangent: bool = False,
    sigma_z_um: Optional[float] = None,
    accept_ill_conditioned: bool = False,
    centre: Optional[Literal["fixed", "moving", "auto"]] = None,
    sigma_p_dpt: Optional[float] = None,
    model: Optional[Literal["auto"]] = None,
    setting_views: Optional[Literal["ignored", "joint"]] = None,
) -> Calibration:
    """The paper's calibration (or the per-setting baseline) from observations; every
    keyword is the `etlcal calibrate` flag of the same name (hold_a0: --hold-a0). None
    robust_k_px is 1 px; None sigmas take the paper's (sigma_z 10 um, sigma_e 0.4 mA,
    sigma_px estimated); give the stage prior as sigma_z_mm or sigma_z_um, not both."""
    ...
def calibrate_rig(
    dataset: Union[str, os.PathLike[str]],
    solver: Literal["auto", "dense", "sparse"] = "auto",
    a0: Optional[A0] = None,
    thermal: Union[ThermalCalibration, Literal["paper"], None] = None,
    estimator: Optional[Estimator] = None,
    hold_a0: bool = False,
    robust: Optional[RobustLoss] = None,
    robust_k_px: Optional[float] = None,
    sigma_z_mm: Optional[float] = None,
    sigma_e_ma: Optional[float] = None,
    sigma_px: Optional[float] = None,
    method: Method = "proposed",
    distortion: Optional[DistortionChoice] = None,
    focal_degree: Optional[FocalDegreeChoice] = None,
    fix_k3: bool = False,
    zero_tangent: bool = False,
    sigma_z_um: Optional[float] = None,
    accept_ill_conditioned: bool = False,
    centre: Optional[Literal["fixed", "moving", "auto"]] = None,
    sigma_p_dpt: Optional[float] = None,
    model: Optional[Literal["auto"]] = None,
    setting_views: Optional[Literal["ignored", "joint"]] = None,
    per_camera: Optional[Mapping[str, Mapping[str, Any]]] = None,
) -> "Rig":
    """A multi-camera rig calibrated jointly from an etlcal.rig-dataset/1 file (points or
    images, detected first), as `etlcal calibrate-rig --dataset`: the keywords are
    calibrate's (every camera's) and --solver's; `per_camera` gives a camera (by name)
    its own keywords of calibrate on top of those, e.g. its lens's surface
    `{"cam1": {"thermal": ThermalCalibration.load(...), "distortion": "opencv"}}`
    (`--thermal CAM=FILE`, `--camera-flags CAM="FLAGS"`); an unknown camera or keyword
    raises InputError (a ValueError) naming it. Returns the run-time Rig."""
    ...
def cramer_rao_std(
    observations: Observations,
    truth: Calibration,
    sigma_px: float,
    sigma_z_mm: Optional[float] = None,
    sigma_e_ma: Optional[float] = None,
    thermal: Union[ThermalCalibration, Literal["paper"], None] = None,
) -> ModelStd: ...


@overload
def detect_corners(image: np.ndarray, board: Union[Board, Mapping[str, Any]], *, pattern: None = None) -> BoardDetection:
    """A board's corners, sub-pixel, with their ids: `corners_px` (N, 2), `ids` (N,),
    `board_mm` (N, 2). A ChArUco board gives the corners seen (partial views need no hint),
    a checkerboard all of them. `image`: 2-D uint8/uint16. Raises BoardNotFoundError with
    the reason."""
    ...
@overload
def detect_corners(image: np.ndarray, board: Union[str, Tuple[int, int]], *, pattern: None = None) -> np.ndarray:
    """Inner corners of a checkerboard "CxR", sub-pixel: (cols*rows, 2) float64 pixels, row by
    row. `image`: 2-D uint8/uint16. Raises BoardNotFoundError (absent, partial, other size)."""
    ...
@overload
def detect_corners(image: np.ndarray, board: None = None, *, pattern: Union[str, Tuple[int, int]]) -> np.ndarray: ...

def sharpness(image: np.ndarray, metric: SharpnessMetric = "cpbd") -> float:
    """Sharpness (larger is sharper): "cpbd" (bit-exact with the cpbd package), "tenengrad",
    "laplacian", "brenner", "normvar"."""
    ...

def render(
    e_com_ma: float = 150.0,
    z_mm: Optional[float] = None,
    pattern: Union[str, Tuple[int, int], None] = None,
    square_mm: float = 1.5,
    aperture_mm: float = 2.5,
    blur_px: float = 0.0,
    noise: float = 2.0,
    bit_depth: int = 8,
    seed: int = 1,
) -> Tuple[np.ndarray, np.ndarray]:
    """A synthetic image of a board on the paper rig (mm, mA, px) and its true corners (N, 2)."""
    ...

def autofocus(
    sharpness_at: Callable[[float], float],
    range_ma: Tuple[float, float] = (75.0, 240.0),
    coarse_points: int = 7,
    max_evaluations: int = 15,
    tolerance_ma: float = 0.1,
) -> AutofocusResult:
    """Current of best focus: coarse scan then Brent; returns best_ma, best_sharpness,
    evaluations, bracket_ma, converged."""
    ...


@final
class Lens:
    """An Optotune Lens Driver 4 on `port` (or a VirtualLens's port); a context manager.
    The current never leaves the driver's limits (clamped); NaN raises InputError;
    timeout_ms lies in 1..=60000. After a DeviceTimeoutError the next call resynchronises
    (a late reply never answers a later query); set_current_ma reads the current back, so
    a current the driver rejects raises DeviceError."""
    def __new__(cls, port: _Path, handshake: bool = False, timeout_ms: int = 500) -> Lens: ...
    def info(self) -> LensInfo: ...
    def set_current_ma(self, e_in_ma: float) -> float: ...
    def current_ma(self) -> float: ...
    def temperature_c(self) -> float: ...
    @property
    def limits_ma(self) -> Tuple[float, float]: ...
    @property
    def port(self) -> str: ...
    def reconnect(self) -> None: ...
    def hold(
        self,
        calibration: ThermalCalibration,
        e_com_ma: float,
        steps: Optional[int] = None,
        duration_s: Optional[float] = None,
        rate_hz: float = 0.0,
        on_step: Optional[Callable[[HoldStep], Optional[bool]]] = None,
    ) -> HoldReport:
        """Holds E_com (mA) while the temperature changes (reads T, sends E_in solving
        E_in - E_T(T, E_in) = E_com), until `steps`, `duration_s` (s) or `on_step` (given
        each HoldStep) returns False; returns a HoldReport: commands_sent, elapsed_s,
        achieved_rate_hz, worst_e_com_error_ma, temperature_range_c, extrapolated_steps,
        last."""
        ...
    def close(self) -> None: ...
    def __enter__(self) -> "Lens": ...
    def __exit__(self, *args: Any) -> bool: ...

@final
class VirtualLens:
    """The simulated lens and driver on a pseudo-terminal (paper physics and thermal surface);
    `dynamics`: an etlcal.lens-dynamics/1 file (step response, creep, hysteresis, self-heating)."""
    def __new__(cls, dynamics: Optional[Union[str, "os.PathLike[str]"]] = None) -> VirtualLens: ...
    @property
    def port(self) -> str: ...
    @property
    def limits_ma(self) -> Tuple[float, float]: ...
    def state(self) -> LensState: ...
    def set_temperature_c(self, t_c: float) -> None: ...
    def received_current_codes(self) -> List[int]: ...
    def set_ambient_c(self, t_c: float) -> None: ...
    def advance_s(self, dt_s: float) -> None: ...
    def inject_faults(
        self,
        reply_delay_ms: float = 0.0,
        silence_next: int = 0,
        corrupt_next: int = 0,
        crc_error_next: int = 0,
        error_frame_next: Optional[int] = None,
        drop_rx_bytes_next: int = 0,
        garbage_before_next: bytes = b"",
    ) -> None:
        """Faults on the link (replacing any before): reply delay (0..=60000 ms), silenced or corrupted
        replies, commands failing their CRC, an error frame E<id>, lost host bytes, garbage."""
        ...
    def disconnect(self) -> None: ...
    def reconnect(self) -> None: ...

@overload
def zhang(
    views: Sequence[Tuple[npt.ArrayLike, npt.ArrayLike]],
    image_size: Tuple[int, int],
    model: Literal["paper"] = "paper",
    fix_k3: Literal[False] = False,
    zero_tangent: Literal[False] = False,
) -> ZhangResult:
    """Zhang's monofocal calibration from (board_mm (N,2), pixels (N,2)) views: fx, fy, u0, v0
    (px), k1, p1, p2, std, rms_px, iterations, views_used, poses."""
    ...
@overload
def zhang(
    views: Sequence[Tuple[npt.ArrayLike, npt.ArrayLike]],
    image_size: Tuple[int, int],
    model: Literal["opencv"],
    fix_k3: bool = False,
    zero_tangent: bool = False,
) -> ZhangOpenCvResult:
    """The same in OpenCV's model (cv2.calibrateCamera's): also k2, k3, camera_matrix,
    dist_coeffs, per_view_rms_px; std of fx, fy, u0, v0, k1, k2, p1, p2, k3."""
    ...

def stereo(
    pairs: Sequence[Tuple[Optional[Tuple[npt.ArrayLike, npt.ArrayLike]], Optional[Tuple[npt.ArrayLike, npt.ArrayLike]]]],
    image_size: Tuple[int, int],
    model: Literal["paper", "opencv"] = "paper",
    fix_k3: bool = False,
    zero_tangent: bool = False,
    intrinsics: Literal["fixed", "joint"] = "fixed",
    right_image_size: Optional[Tuple[int, int]] = None,
) -> StereoResult:
    """A fixed-focus pair from synchronised board views (left, right), each (board_mm,
    pixels) or None: each camera by Zhang, then R, T as cv2.stereoCalibrate."""
    ...

@final
class Rig:
    """A multi-camera ETL rig (etlcal.rig/1): calibrations and poses relative to camera 0."""
    @classmethod
    def load(cls, path: Union[str, os.PathLike[str]]) -> "Rig": ...
    def save(self, path: Union[str, os.PathLike[str]]) -> None:
        """Writes the rig as etlcal.rig/1, each calibration inline (atomically)."""
        ...
    def __len__(self) -> int: ...
    @property
    def names(self) -> List[str]: ...
    @property
    def calibrations(self) -> List[Calibration]: ...
    def at(
        self,
        settings: Sequence[Union[float, str]],
        temperatures_c: Sequence[float],
        allow_extrapolation: bool = False,
    ) -> "RigAt":
        """The rig at one setting (each calibration's unit: mA or dpt) and temperature per camera."""
        ...
    def stereo_rectify_maps(
        self,
        setting_left: Union[float, str],
        setting_right: Union[float, str],
        temperatures_c: Sequence[float],
        alpha: float = -1.0,
        allow_extrapolation: bool = False,
    ) -> StereoRectifyMaps:
        """A two-camera rig's rectification at two settings, with cv2.remap maps."""
        ...

@final
class RigAt:
    """The rig at one setting per camera: cameras, poses, triangulation, rectification."""
    def __len__(self) -> int: ...
    @property
    def cameras(self) -> List[CameraAt]: ...
    @property
    def poses(self) -> List[Tuple[_F64, _F64]]: ...
    @property
    def extrapolated(self) -> bool: ...
    def triangulate(
        self,
        pixels: Sequence[Optional[Tuple[float, float]]],
        sigma_px: float,
        pixel_only: bool = False,
    ) -> Triangulated:
        """The point seen at one pixel per camera (None where unseen) and its covariance."""
        ...
    def stereo_rectify_maps(self, left: int = 0, right: int = 1, alpha: float = -1.0) -> StereoRectifyMaps:
        """Bouguet's rectification of (left, right) at these settings, with cv2.remap maps."""
        ...
    def export_pair(
        self,
        out_dir: Union[str, os.PathLike[str]],
        left: int = 0,
        right: int = 1,
        formats: Optional[Sequence[ExportFormat]] = None,
        maps: bool = False,
        alpha: float = -1.0,
    ) -> List[pathlib.Path]:
        """stereo.yaml, and ROS / mrcal exports and .npy maps, into out_dir as one set."""
        ...

def thermal_calibration(
    lens: Lens,
    capture: Callable[[], np.ndarray],
    set_temperature: Callable[[float], None],
    place_board: Optional[Callable[[], None]] = None,
    e_in_grid_ma: Optional[Sequence[float]] = None,
    temperatures_c: Optional[Sequence[float]] = None,
    search_ma: float = 20.0,
    metric: SharpnessMetric = "tenengrad",
) -> ThermalCalibrationResult:
    """The section 4.1 temperature procedure with your camera and climate as callables:
    returns calibration (ThermalCalibration), rms_ma, samples ((N, 3): T, E_in, E_T), frames."""
    ...

@final
class Board:
    """A calibration target (etlcal.board/1): a ChArUco board in OpenCV's layout and ids
    (views that see part of it need no hint) or a plain checkerboard."""
    @staticmethod
    def charuco(squares: Tuple[int, int], square_mm: float, marker_mm: float, dictionary: str) -> Board: ...
    @staticmethod
    def checkerboard(inner_corners: Tuple[int, int], square_mm: float) -> Board: ...
    @staticmethod
    def load(path: Union[str, os.PathLike[str]]) -> Board: ...
    def save(self, path: Union[str, os.PathLike[str]]) -> None: ...
    @staticmethod
    def from_dict(d: Union[Board, Mapping[str, Any]]) -> Board: ...
    def to_dict(self) -> Dict[str, Any]: ...
    def to_json(self) -> str: ...
    @staticmethod
    def from_json(text: str) -> Board: ...
    def to_svg(self, margin_mm: Optional[float] = None) -> str: ...
    def to_image(self, dpi: float, margin_mm: Optional[float] = None) -> npt.NDArray[np.uint8]: ...
    @property
    def type(self) -> Literal["charuco", "checkerboard"]: ...
    @property
    def squares(self) -> Optional[Tuple[int, int]]: ...
    @property
    def square_mm(self) -> float: ...
    @property
    def marker_mm(self) -> Optional[float]: ...
    @property
    def dictionary(self) -> Optional[str]: ...
    @property
    def inner_corners(self) -> Tuple[int, int]: ...
    @property
    def corner_count(self) -> int: ...
    @property
    def corners_mm(self) -> npt.NDArray[np.float64]: ...
    def __eq__(self, value: object, /) -> bool: ...
    def __hash__(self) -> int: ...

@final
class Dataset:
    """An etlcal.dataset/1 file: images with E_in, T and stage Z per view; `detect()` gives
    Observations."""
    def __new__(
        cls,
        image_size: Tuple[int, int],
        inner_corners: Optional[Tuple[int, int]] = None,
        square_mm: Optional[float] = None,
        base_dir: Union[str, os.PathLike[str], None] = None,
        offstate_board: Union[Board, Dict[str, Any], None] = None,
        board: Union[Board, Dict[str, Any], None] = None,
    ) -> Dataset: ...
    def add_view(
        self,
        image: Union[str, os.PathLike[str]],
        e_in_ma: float,
        temperature_c: float,
        z_w_mm: float,
        e_com_ma: Optional[float] = None,
        board: Union[Board, Dict[str, Any], None] = None,
        first_corner: Optional[Tuple[int, int]] = None,
    ) -> None: ...
    def add_offstate_view(
        self,
        image: Union[str, os.PathLike[str]],
        board: Union[Board, Dict[str, Any], None] = None,
        first_corner: Optional[Tuple[int, int]] = None,
    ) -> None: ...
    def add_setting_view(
        self,
        image: Union[str, os.PathLike[str]],
        e_in_ma: float,
        temperature_c: float,
        e_com_ma: Optional[float] = None,
        board: Union[Board, Dict[str, Any], None] = None,
        first_corner: Optional[Tuple[int, int]] = None,
    ) -> None: ...
    @property
    def offstate_count(self) -> int: ...
    @property
    def setting_count(self) -> int: ...
    @classmethod
    def load(cls, path: Union[str, os.PathLike[str]]) -> Dataset: ...
    def save(self, path: Union[str, os.PathLike[str]]) -> None: ...
    def to_json(self) -> str: ...
    @staticmethod
    def from_json(text: str, base_dir: Union[str, os.PathLike[str], None] = None) -> Dataset: ...
    def __len__(self) -> int: ...
    @property
    def image_size(self) -> Tuple[int, int]: ...
    @property
    def board(self) -> Dict[str, Any]: ...
    def images(self) -> List[str]: ...
    def detect(self) -> Tuple[Observations, DetectionSummary]: ...

def study(
    name: StudyName, trials: int = 0, seed: int = 1, out: Union[str, os.PathLike[str], None] = None
) -> StudyResult:
    """One of the paper's studies ("fig5", "fig6", "subsets", "baseline", "crlb") as the
    command line's --json table; `out` also writes its JSON, summary and plots."""
    ...


def diff(a: CameraAt, b: CameraAt, grid: Tuple[int, int] = (64, 48)) -> ProjectionDiff:
    """How far apart two cameras at a setting project the same directions over the image
    (intrinsics only, and after the best rotation), px; as `etlcal diff`."""
    ...


@final
class RigCamera:
    """A camera of the rig opened from its spec ("sim", "files:DIR", "aravis:NAME"):
    `etlcal.rig.Camera`."""
    @staticmethod
    def open(spec: str, seed: int = 1) -> RigCamera: ...
    def grab(self) -> npt.NDArray[Any]: ...
    def grab_frame(self) -> Tuple[npt.NDArray[Any], int]: ...
    def set_exposure_us(self, exposure_us: float) -> None: ...
    def set_gain_db(self, gain_db: float) -> None: ...
    def info(self) -> Tuple[str, str, Tuple[int, int]]: ...


def rig_capture_views(
    plan: Any,
    out: Union[str, os.PathLike[str]],
    camera: Any,
    lens: Any,
    stage: Any,
    *,
    settle_tolerance_px: float = 0.05,
    settle_timeout_s: float = 10.0,
    max_temperature_change_c: float = 0.5,
    autofocus_range_ma: Optional[Tuple[float, float]] = None,
    seed: int = 1,
) -> Dict[str, Any]:
    """A plan's lens-off and ETL views captured into `out` (`etlcal.rig.capture_views`)."""
    ...


def rig_capture_offstate(
    plan: Any,
    out: Union[str, os.PathLike[str]],
    camera: Any,
    lens: Any,
    stage: Any,
    *,
    settle_tolerance_px: float = 0.05,
    settle_timeout_s: float = 10.0,
    max_temperature_change_c: float = 0.5,
    seed: int = 1,
) -> Dict[str, Any]:
    """A plan's lens-off views captured into `out` (`etlcal.rig.capture_offstate`)."""
    ...


def rig_capture_thermal(
    plan: Any,
    out: Union[str, os.PathLike[str]],
    camera: Any,
    lens: Any,
    stage: Any,
    *,
    settle_timeout_s: float = 10.0,
    max_temperature_change_c: float = 0.5,
    sim_roi: Optional[Tuple[int, int, int, int]] = None,
    seed: int = 1,
) -> Dict[str, Any]:
    """A plan's temperature grid captured into `out` (`etlcal.rig.capture_thermal`)."""
    ...
