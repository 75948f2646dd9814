"""One request behind both front ends (issue 26): `etlcal calibrate` / `etlcal zhang` (the
binary) and `etlcal.calibrate(...)` / `etlcal.zhang(...)` parse their options into the same
etl-calib request (`etl_calib::request`), so the same request must give the same result.

Each case is one request written both ways, flag for keyword (`--hold-a0` is `hold_a0`),
on small simulated observations (`etlcal simulate --observations-only`, the paper rig: 15
views) or, for Zhang, on 6 of the fixtures/zhang images. The calibration files are compared
as JSON values, exactly: no field differs (nothing in the file names its front end or a
time), and the warnings the CLI prints on stderr are those Python raises as UserWarning.
"""
import json
import pathlib
import subprocess
import warnings
from typing import Any, Dict, List, Tuple

import pytest

import etlcal

ROOT = pathlib.Path(__file__).resolve().parents[3]
ZHANG_IMAGES = sorted((ROOT / "fixtures" / "zhang").glob("left0*.jpg"))[:6]


@pytest.fixture(scope="module")
def rigs(tmp_path_factory: pytest.TempPathFactory, etlcal_binary: str) -> Dict[str, pathlib.Path]:
    """The paper rig's corners (seed 7) with and without per-setting views."""
    out = {}
    for name, extra in [("plain", []), ("setting", ["--setting-views"])]:
        d = tmp_path_factory.mktemp(name)
        subprocess.run([etlcal_binary, "simulate", "--out", str(d), "--observations-only", "--seed", "7", *extra],
                       check=True, capture_output=True)
        out[name] = d
    return out


# (id, rig, CLI flags, Python keywords, with the simulation's A0): the matrix of issue 26.
CASES: List[Tuple[str, str, List[str], Dict[str, Any], bool]] = [
    ("defaults, A0 by Zhang", "plain", [], {}, False),
    ("paper estimator", "plain", ["--estimator", "paper"], {"estimator": "paper"}, True),
    ("eiv, sigma_z in um on the CLI, mm in Python", "plain",
     ["--estimator", "eiv", "--sigma-z-um", "20", "--sigma-e-ma", "0.3"],
     {"estimator": "eiv", "sigma_z_mm": 0.020, "sigma_e_ma": 0.3}, True),
    ("sigma_z in mm on the CLI, um in Python; sigma_px", "plain",
     ["--sigma-z-mm", "0.005", "--sigma-px", "0.25"], {"sigma_z_um": 5.0, "sigma_px": 0.25}, True),
    ("hold A0, huber", "plain", ["--hold-a0", "--robust", "huber", "--robust-k-px", "1.5"],
     {"hold_a0": True, "robust": "huber", "robust_k_px": 1.5}, True),
    ("--huber-px, the alias", "plain", ["--huber-px", "0.8"], {"robust": "huber", "robust_k_px": 0.8}, True),
    ("cauchy, its default k", "plain", ["--robust", "cauchy"], {"robust": "cauchy"}, True),
    ("opencv with fix_k3 and zero_tangent, A0 by Zhang in that family", "plain",
     ["--distortion", "opencv", "--fix-k3", "--zero-tangent"],
     {"distortion": "opencv", "fix_k3": True, "zero_tangent": True}, False),
    ("focal degree 2, paper estimator", "plain", ["--focal-degree", "2", "--estimator", "paper"],
     {"focal_degree": 2, "estimator": "paper"}, True),
    ("per-setting baseline", "setting", ["--method", "per-setting"], {"method": "per-setting"}, False),
    ("auto family at degree 3", "plain", ["--distortion", "auto", "--focal-degree", "3", "--estimator", "paper"],
     {"distortion": "auto", "focal_degree": 3, "estimator": "paper"}, True),
]


def cli_calibrate(binary: str, rig: pathlib.Path, flags: List[str], with_a0: bool,
                  out: pathlib.Path) -> Tuple[Dict[str, Any], List[str]]:
    a0 = ["--a0", str(rig / "a0.json")] if with_a0 else []
    run = subprocess.run([binary, "calibrate", "--observations", str(rig / "observations.json"), *a0, *flags,
                          "--out", str(out), "--json"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    written: Dict[str, Any] = json.loads(out.read_text())
    assert json.loads(run.stdout) == written, "--json prints the file written"
    said = [line.removeprefix("etlcal: warning: ") for line in run.stderr.splitlines()
            if line.startswith("etlcal: warning: ")]
    return written, said


@pytest.mark.parametrize("name, rig, flags, keywords, with_a0", CASES, ids=[c[0] for c in CASES])
def test_the_same_request_gives_the_same_file_through_the_cli_and_python(
        name: str, rig: str, flags: List[str], keywords: Dict[str, Any], with_a0: bool,
        rigs: Dict[str, pathlib.Path], etlcal_binary: str, tmp_path: pathlib.Path) -> None:
    d = rigs[rig]
    cli, cli_warnings = cli_calibrate(etlcal_binary, d, flags, with_a0, tmp_path / "cli.json")
    obs = etlcal.Observations.load(d / "observations.json")
    a0 = etlcal.A0.load(d / "a0.json") if with_a0 else None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        cal = etlcal.calibrate(obs, a0, **keywords)
    cal.save(tmp_path / "python.json")
    python = json.loads((tmp_path / "python.json").read_text())
    assert python == cli, name
    # The same warnings, each naming its own front end's way to give E_com.
    said = [str(w.message) for w in caught if issubclass(w.category, UserWarning)]
    assert said == [w.replace("use it with --e-com MA", "use it with at_e_com(e_com_ma)") for w in cli_warnings]
    # The options reached the solver (a case that changed nothing would prove nothing).
    if "estimator" in keywords or "method" in keywords:
        assert cli["estimator"] == keywords.get("estimator", "per-setting")
    if "distortion" in keywords and keywords["distortion"] != "auto":
        assert cli["distortion_model"] == keywords["distortion"]
    if "focal_degree" in keywords:
        assert len(cli["kf_x"]) == keywords["focal_degree"] + 1
    if keywords.get("distortion") == "auto":
        assert {c["distortion_model"] for c in cli["model_selection"]["candidates"]} == {"paper", "opencv"}


@pytest.mark.filterwarnings("ignore:the stage correction of view")
def test_the_options_change_the_result(rigs: Dict[str, pathlib.Path]) -> None:
    """The matrix's options are not ignored: each differs from the defaults it changes."""
    d = rigs["plain"]
    obs, a0 = etlcal.Observations.load(d / "observations.json"), etlcal.A0.load(d / "a0.json")
    base = json.loads(etlcal.calibrate(obs, a0).to_json())
    changes: List[Dict[str, Any]] = [{"sigma_z_mm": 0.020}, {"sigma_z_um": 5.0}, {"sigma_px": 0.25},
                                     {"sigma_e_ma": 0.3}, {"robust": "huber", "robust_k_px": 0.8},
                                     {"robust": "cauchy"}]
    for keywords in changes:
        other = json.loads(etlcal.calibrate(obs, a0, **keywords).to_json())
        assert other["kf_x"] != base["kf_x"], keywords
    # The same prior in both units is the same request.
    assert etlcal.calibrate(obs, a0, sigma_z_um=20.0) == etlcal.calibrate(obs, a0, sigma_z_mm=0.020)


@pytest.mark.parametrize("keywords, what, words", [
    ({"sigma_z_mm": 0.01, "sigma_z_um": 10.0}, "sigma_z_um", "give sigma_z_mm or sigma_z_um, not both"),
    ({"sigma_z_um": -1.0}, "sigma_z_um", "sigma_z_um must be positive and finite"),
    ({"sigma_px": 0.0}, "sigma_px", "sigma_px must be positive and finite"),
    ({"robust": "cauchy", "robust_k_px": -1.0}, "robust_k_px", "robust_k_px must be positive and finite"),
    ({"method": "per-setting", "robust": "huber"}, "robust",
     'method="per-setting" takes no a0, estimator, hold_a0 or robust'),
    ({"method": "per-setting", "fix_k3": True}, "fix_k3", 'method="per-setting" takes no fix_k3'),
    ({"fix_k3": True}, "fix_k3", 'fix_k3=True is an OpenCV flag: it needs distortion="opencv" or "auto"'),
])
def test_refusals_name_python_arguments(rigs: Dict[str, pathlib.Path], keywords: Dict[str, Any], what: str,
                                        words: str) -> None:
    obs = etlcal.Observations.load(rigs["plain"] / "observations.json")
    with pytest.raises(etlcal.InputError) as e:
        etlcal.calibrate(obs, **keywords)
    assert words in str(e.value) and "\n" not in str(e.value) and "--" not in str(e.value)
    assert e.value.what == what


def test_missing_data_is_refused_in_python_words(rigs: Dict[str, pathlib.Path]) -> None:
    obs = etlcal.Observations.load(rigs["plain"] / "observations.json")
    with pytest.raises(etlcal.InputError, match='method="per-setting" needs setting_views'):
        etlcal.calibrate(obs, method="per-setting")
    doc = json.loads(obs.to_json())
    del doc["offstate_views"]
    with pytest.raises(etlcal.InputError, match=r"no lens-off views .*: pass a0 \(the lens-off intrinsics\)"):
        etlcal.calibrate(etlcal.Observations.from_json(json.dumps(doc)))
    # A view without E_com and no thermal calibration: Python's argument, not the CLI's flag.
    doc = json.loads(obs.to_json())
    del doc["views"][2]["e_com_ma"]
    with pytest.raises(etlcal.InputError) as e:
        etlcal.calibrate(etlcal.Observations.from_json(json.dumps(doc)))
    message = str(e.value)
    assert "view 2 has no e_com_ma and no thermal calibration was chosen" in message, message
    assert 'thermal="paper"' in message and "--" not in message, message
    assert e.value.what == "views[2].e_com_ma"


@pytest.fixture(scope="module")
def zhang_views() -> Tuple[List[Tuple[Any, Any]], Tuple[int, int]]:
    """The corners of the Zhang images as Python gets them: a dataset of the images, detected
    by the same detector (and JPEG decoder) as `etlcal zhang`. A dataset needs ETL views: the
    images are added as views at placeholder settings (80, 90, ... mA, 25 degC, Z = 0: at
    least 3 currents, as a dataset needs), which detection does not use; each view's world points are then its board points at Z = 0."""
    assert len(ZHANG_IMAGES) == 6
    ds = etlcal.Dataset((640, 512), inner_corners=(9, 6), square_mm=1.0, base_dir=ZHANG_IMAGES[0].parent)
    for i, p in enumerate(ZHANG_IMAGES):
        ds.add_view(p.name, 80.0 + 10 * i, 25.0, 0.0, 80.0 + 10 * i)
    obs, summary = ds.detect()
    assert summary["skipped"] == [] and len(obs) == 6
    views = [obs.view(i) for i in range(len(obs))]
    assert all(float(abs(v["world_mm"][:, 2]).max()) == 0.0 for v in views)
    return [(v["world_mm"][:, :2], v["pixels"]) for v in views], obs.image_size


ZHANG_CASES: List[Tuple[List[str], Dict[str, Any]]] = [
    ([], {}),
    (["--model", "paper"], {"model": "paper"}),
    (["--model", "opencv"], {"model": "opencv"}),
    (["--model", "opencv", "--fix-k3"], {"model": "opencv", "fix_k3": True}),
    (["--model", "opencv", "--fix-k3", "--zero-tangent"], {"model": "opencv", "fix_k3": True, "zero_tangent": True}),
]


@pytest.mark.parametrize("flags, keywords", ZHANG_CASES, ids=[" ".join(c[0]) or "defaults" for c in ZHANG_CASES])
def test_the_same_zhang_request_gives_the_same_result(flags: List[str], keywords: Dict[str, Any],
                                                      zhang_views: Tuple[List[Tuple[Any, Any]], Tuple[int, int]],
                                                      etlcal_binary: str) -> None:
    run = subprocess.run([etlcal_binary, "zhang", *map(str, ZHANG_IMAGES), "--pattern", "9x6", "--square", "1",
                          *flags, "--json"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    cli = json.loads(run.stdout)
    views, size = zhang_views
    zhang: Any = etlcal.zhang  # the keywords vary by case: the overloads cannot tell
    r = zhang(views, size, **keywords)
    # Every number the CLI prints, as Python returns it (the CLI's std is keyed by name).
    # The paper family's --json has k1, p1, p2; OpenCV's has dist_coeffs in their place.
    opencv = keywords.get("model") == "opencv"
    for key in ["fx", "fy", "u0", "v0", "rms_px", "views_used"] + ([] if opencv else ["k1", "p1", "p2"]):
        assert cli[key] == r[key], key
    assert "outliers" not in cli
    if not opencv:
        assert "dist_coeffs" not in cli
        return
    assert cli["dist_coeffs"] == list(r.dist_coeffs) and cli["camera_matrix"] == r.camera_matrix.tolist()
    assert cli["per_view_rms_px"] == list(r.per_view_rms_px) and cli["model"] == r.model == "opencv"
    assert [cli["std"][n] for n in ["fx", "fy", "u0", "v0", "k1", "k2", "p1", "p2", "k3"]] == list(r.std)
    assert (cli["fix_k3"], cli["zero_tangent"]) == (keywords.get("fix_k3", False), keywords.get("zero_tangent", False))
    held = [r.k3] * keywords.get("fix_k3", False) + [r.p1, r.p2] * keywords.get("zero_tangent", False)
    assert all(x == 0.0 for x in held)


def test_zhang_refusals_name_python_arguments(zhang_views: Tuple[List[Tuple[Any, Any]], Tuple[int, int]]) -> None:
    views, size = zhang_views
    with pytest.raises(etlcal.InputError) as e:
        etlcal.zhang(views, size, zero_tangent=True)  # type: ignore[call-overload]  # the run-time check under test
    assert 'zero_tangent=True is an OpenCV flag: it needs model="opencv" (the' in str(e.value)
    assert e.value.what == "zero_tangent"
