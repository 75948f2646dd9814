"""The paper's simulation studies (`etlcal study NAME` on the command line), one function
each. Every function returns a StudyResult: the study's table (the command line's `--json`),
its keys also the result's keys and attributes, and,
given `out` (an existing directory), also writes NAME.json, NAME.md and the plots there.
The trials run in parallel without the GIL; results are the same for the same seed.
`trials=None` runs the study's own default count, the same as `etlcal study NAME`
(fig6 100 per level, subsets 5, baseline 200, crlb 300): the defaults live in Rust only."""
import os
from typing import Optional, Union

from ._etlcal import study
from .results import StudyResult

__all__ = ["fig5", "fig6", "subsets", "baseline", "crlb"]

_Out = Optional[Union[str, "os.PathLike[str]"]]


def fig5(out: _Out = None) -> StudyResult:
    """Fig. 5: RMSE of polynomial fits (degrees 1..6) of the physics model's focal length
    f_com(E) over the current range, mm ("fit_rmse_mm"; the cubic's is ~1.09e-3 mm).
    Deterministic (no trials)."""
    return study("fig5", 0, 1, out)


def fig6(trials: Optional[int] = None, seed: int = 1, out: _Out = None) -> StudyResult:
    """Fig. 6: the calibration's spread against pixel noise (px), current noise (mA) and the
    number of images, for the paper's bundle adjustment and errors-in-variables;
    `trials` Monte Carlo data sets per level (31 levels: ~30 s of CPU at 100)."""
    return study("fig6", trials or 0, seed, out)


def subsets(trials: Optional[int] = None, seed: int = 1, out: _Out = None) -> StudyResult:
    """The paper's Tables 1-2 and Fig. 11: from 9 views of the paper rig, calibrations with
    the first 6..9 views and with each of the 84 six-view subsets: parameters (mean, std),
    BA iterations, RMS before and after (px); `trials` fresh data sets (the tables show the
    first)."""
    return study("subsets", trials or 0, seed, out)


def baseline(trials: Optional[int] = None, seed: int = 1, out: _Out = None) -> StudyResult:
    """The paper's Fig. 12: the existing method (Zhang at each of 7 currents, a cubic through
    fx(E), fy(E)) against the proposed one (paper BA and errors-in-variables): relative error
    of fx(E) ("fx_curve", means with their standard errors `*_se`) and the PnP error of a
    2 mm stage move at 100..250 mA, um ("pnp", "baseline_over_proposed_at_250ma"), over
    `trials` data sets."""
    return study("baseline", trials or 0, seed, out)


def crlb(trials: Optional[int] = None, seed: int = 1, out: _Out = None, rig: str = "paper") -> StudyResult:
    """Cramer-Rao bound of every parameter against the Monte Carlo spread of the estimates
    over `trials` data sets: {"parameters": [{"name", "truth", "crlb_std", "mc_std",
    "mc_std_se", "efficiency", "efficiency_se", ...}, ...], "fx_curve": [...]} (each
    observed std and efficiency with its standard error over the trials). `rig="strong"`:
    the strong-distortion rig, OpenCV's distortion family against its bound (pixel noise
    only), and the paper family's bias in the principal point and fx(E) there ("bias");
    the study "crlb-strong"."""
    if rig not in ("paper", "strong"):
        raise ValueError(f'rig must be "paper" or "strong", got {rig!r}')
    return study("crlb" if rig == "paper" else "crlb-strong", trials or 0, seed, out)
