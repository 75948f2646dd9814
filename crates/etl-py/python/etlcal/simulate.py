"""Synthetic data: the paper rig (section 5.1.2) with the paper's noise model, and the
strong-distortion rig (issue 16)."""
from typing import Mapping, Optional, Union

from ._etlcal import Simulation, simulate_paper_rig, simulate_strong_rig
from .options import NoisePreset

__all__ = ["Simulation", "paper_rig", "strong_rig"]


def paper_rig(
    seed: int = 0, noise: Optional[Union[NoisePreset, Mapping[str, float]]] = None, setting_views: bool = False
) -> Simulation:
    """The paper rig's 15 views (2311 corners of a 14 x 12 board, 1.5 mm squares, at stage
    positions 75..2 mm and E_com 80..225 mA), seeded.

    Args:
        seed: random seed (an int >= 0); the same seed gives the same data as
            `etlcal simulate --seed`.
        noise: "paper" (default: 1 um on corners, 10 um on the stage, 0.4 mA on the
            current, 0.2 px on pixels, 0.3 % on A0's kf0 and 1 px on its principal
            point), "none", or a dict overriding some of xy_mm, z_mm, e_ma, px, kf0_rel,
            pp_px.
        setting_views: also simulate the per-setting baseline's views (section 5.2.3:
            15 free views of the board at each of 80, 100, 125, ..., 225 mA, tilted as far
            as the depth of field allows; `observations.setting_count`), for
            `etlcal.calibrate(obs, method="per-setting")`.

    Returns:
        a `Simulation` with `observations`, `a0`, `truth` (a `Calibration`),
        `true_dz_mm` and `true_de_ma`.
    """
    return simulate_paper_rig(seed, noise, setting_views)


def strong_rig(seed: int = 0, noise: Optional[Union[NoisePreset, Mapping[str, float]]] = None) -> Simulation:
    """The strong-distortion rig: a short prime behind the ETL (fx about 1375..1247 px over
    80..225 mA on the paper rig's 1936 x 1458 sensor) whose lens distorts in OpenCV's
    family with k1 about -0.3 and k2 about 0.15 (normalised units), both varying with focus;
    the paper's 15 currents, a 19 x 15 board of 16 mm squares moving from 80 to -70 mm on
    the stage, 10 lens-off views of a 17 x 12 board of 25 mm squares. Seeded; `noise` as
    `paper_rig`'s. The same data as `etlcal simulate --config` with `"rig": "strong"`.

    Returns:
        a `Simulation`; its `truth` is in the opencv distortion family.
    """
    return simulate_strong_rig(seed, noise)
