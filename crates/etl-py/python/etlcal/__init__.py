"""etlcal: calibration and control of cameras focused by an electrically tunable lens."""
from ._etlcal import __version__

__all__ = ["__version__"]
