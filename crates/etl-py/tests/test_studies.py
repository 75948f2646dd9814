"""The paper's studies from Python: fig5 against the paper's figure, crlb's table shape and
efficiency on a few trials, files written, bad input."""
import pathlib

import pytest

import etlcal


def test_fig5_matches_the_paper(tmp_path: pathlib.Path) -> None:
    r = etlcal.study("fig5", out=tmp_path)
    rmse = r["fit_rmse_mm"]
    assert len(rmse) == 6
    assert abs(rmse[2] / 1.09e-3 - 1.0) < 0.1  # the cubic, paper Fig. 5
    assert rmse[0] > rmse[1] > rmse[2]
    assert (tmp_path / "fig5.json").exists() and (tmp_path / "fig5.md").exists()


def test_crlb_table() -> None:
    r = etlcal.study("crlb", trials=40, seed=3)
    names = [p["name"] for p in r["parameters"]]
    assert names[:3] == ["om1", "om2", "om3"] and len(names) == 25
    for p in r["parameters"]:
        assert p["crlb_std"] > 0 and 0.4 < p["efficiency"] < 2.5, p


def test_bad_study_input(tmp_path: pathlib.Path) -> None:
    with pytest.raises(etlcal.InputError, match="fig5"):
        etlcal.study("fig7")  # type: ignore[arg-type]  # the run-time check under test
    with pytest.raises(etlcal.InputError, match="does not exist"):
        etlcal.study("fig5", out=tmp_path / "missing")


def test_the_studies_module_calls_the_same_studies() -> None:
    assert etlcal.studies.fig5() == etlcal.study("fig5")
    assert etlcal.studies.crlb(trials=20, seed=3) == etlcal.study("crlb", trials=20, seed=3)
    with pytest.raises(etlcal.InputError, match="does not exist"):
        etlcal.studies.fig6(trials=1, out="/no/such/dir")


def test_study_defaults_are_rusts_own() -> None:
    """trials=None is the command line's default count (one owner: Rust), not a second one."""
    import inspect

    for name in ["fig6", "subsets", "baseline", "crlb"]:
        assert inspect.signature(getattr(etlcal.studies, name)).parameters["trials"].default is None
