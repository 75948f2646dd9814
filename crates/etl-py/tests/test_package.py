"""The package surface: version, stubs covering every public name, docstrings, help."""
import ast
import inspect
import pathlib
from typing import Dict, Set, Tuple

import etlcal
import etlcal._etlcal as native

STUB = pathlib.Path(etlcal.__file__).with_name("_etlcal.pyi")


def test_version_is_the_crate_version() -> None:
    assert etlcal.__version__ == "0.1.0"


def test_py_typed_marker_ships() -> None:
    assert STUB.with_name("py.typed").exists()


def stub_names() -> Tuple[Set[str], Dict[str, Set[str]]]:
    tree = ast.parse(STUB.read_text())
    top: Set[str] = set()
    members: Dict[str, Set[str]] = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            top.add(node.name)
            members[node.name] = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
        elif isinstance(node, ast.FunctionDef):
            top.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) and node.target.id != "__all__":
            top.add(node.target.id)
    return top, members


def test_stubs_cover_every_public_name_and_method() -> None:
    top, members = stub_names()
    runtime = {n for n in dir(native) if not n.startswith("__") or n == "__version__"}
    assert runtime - top == set(), f"missing from the stub: {runtime - top}"
    assert top - runtime == set(), f"in the stub, not at run time: {top - runtime}"
    for cls, names in members.items():
        obj = getattr(native, cls)
        if issubclass(obj, BaseException):
            continue
        public = {n for n in vars(obj) if not n.startswith("_")}
        assert public - names == set(), f"{cls}: missing from the stub: {public - names}"
        assert {n for n in names if not n.startswith("_")} - public == set()


def test_every_public_callable_has_a_docstring_with_units() -> None:
    for name in etlcal.__all__:
        obj = getattr(etlcal, name)
        if name.startswith("__") or inspect.ismodule(obj):
            continue
        assert obj.__doc__, name
        if inspect.isclass(obj) and not issubclass(obj, BaseException):
            for m, member in vars(obj).items():
                if not m.startswith("_"):
                    assert member.__doc__, f"{name}.{m}"
    for mod in (etlcal.physics, etlcal.simulate, etlcal.studies):
        for name in mod.__all__:
            assert getattr(mod, name).__doc__, f"{mod.__name__}.{name}"


def test_help_of_calibrate_reads_well() -> None:
    doc = etlcal.calibrate.__doc__
    assert doc is not None
    assert "observations" in doc and "Raises" in doc and "mA" in doc and "px" in doc
    assert inspect.signature(etlcal.calibrate).parameters["estimator"].default is None
    assert '"eiv"' in doc and "None (the default)" in doc
    assert "e_com_ma" in inspect.signature(etlcal.Calibration.project).parameters


def test_classes_live_in_the_etlcal_namespace() -> None:
    for name in ("Calibration", "Observations", "ThermalSurface", "LensPhysics", "A0", "BoardPose"):
        assert getattr(etlcal, name).__module__ == "etlcal"


def test_quickstart_runs(tmp_path: pathlib.Path) -> None:
    import subprocess
    import sys

    script = pathlib.Path(__file__).resolve().parents[3] / "examples" / "quickstart.py"
    out = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert "measured stage move" in out.stdout


def test_stubs_agree_with_the_runtime_signatures() -> None:
    """mypy's stubtest over the native module (names, parameters, defaults); runs when mypy
    is installed in the test environment."""
    import subprocess
    import sys

    import pytest

    pytest.importorskip("mypy.stubtest")
    out = subprocess.run([sys.executable, "-m", "mypy.stubtest", "etlcal._etlcal"], capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stdout + out.stderr
