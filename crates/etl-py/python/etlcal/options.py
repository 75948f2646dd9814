"""The words etlcal's options accept, as `typing.Literal` types (for annotations; each
function also checks its option at run time and names the allowed words in the error)."""
from typing import Literal, Union

__all__ = [
    "DistortionChoice",
    "Estimator",
    "ExportFormat",
    "FocalDegreeChoice",
    "Method",
    "NoisePreset",
    "RobustLoss",
    "SharpnessMetric",
    "StudyName",
    "ZhangModel",
]

Estimator = Literal["paper", "eiv"]
"""`calibrate(estimator=...)`: the paper's bundle adjustment or errors-in-variables."""
RobustLoss = Literal["huber", "cauchy"]
"""`calibrate(robust=...)`: the robust loss on each point's error."""
Method = Literal["proposed", "per-setting"]
"""`calibrate(method=...)`: the paper's method or the per-setting baseline."""
SharpnessMetric = Literal["cpbd", "tenengrad", "laplacian", "brenner", "normvar"]
"""`sharpness(metric=...)`, `thermal_calibration(metric=...)`."""
StudyName = Literal["fig5", "fig6", "subsets", "baseline", "crlb", "crlb-strong"]
"""`study(name)`: the paper's studies."""
NoisePreset = Literal["paper", "none"]
"""`simulate.paper_rig(noise=...)`: the paper's noise model or none."""
ExportFormat = Literal["opencv", "ros", "mrcal"]
"""`Calibration.export(format=...)`."""
ZhangModel = Literal["paper", "opencv"]
"""`zhang(model=...)`: the paper's distortion (k1, p1, p2 in centred pixels) or OpenCV's."""
DistortionChoice = Literal["paper", "opencv", "auto"]
"""`calibrate(distortion=...)`: a distortion family, or chosen by held-out views."""
FocalDegreeChoice = Union[Literal[1, 2, 3, 4, 5], Literal["auto"]]
"""`calibrate(focal_degree=...)`: the degree of fx(E), fy(E), or chosen by held-out views."""
