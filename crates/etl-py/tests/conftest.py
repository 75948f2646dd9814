"""Shared fixtures: the Rust reference values (printed by the `rust_reference` example of
etl-core) and the `etlcal` command line, each built by cargo once per session, or taken
ready-built from the paths in ETLCAL_TEST_RUST_REFERENCE and ETLCAL_TEST_BINARY
(scripts/test.sh passes the ones `cargo test` has just built: building them again here
would rebuild pyo3 and a part of the workspace under another configuration)."""
import json
import os
import pathlib
import shutil
import subprocess
from typing import Any, Dict

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def rust_reference() -> Dict[str, Any]:
    built = os.environ.get("ETLCAL_TEST_RUST_REFERENCE")
    if built:
        command = [built]
    else:
        cargo = shutil.which("cargo") or os.path.expanduser("~/.cargo/bin/cargo")
        command = [cargo, "run", "-q", "-p", "etl-core", "--example", "rust_reference"]
    out = subprocess.run(
        command,
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    )
    reference: Dict[str, Any] = json.loads(out.stdout)
    return reference


@pytest.fixture(scope="session")
def etlcal_binary() -> str:
    """The `etlcal` command line (built by cargo once per session), to make test data."""
    built = os.environ.get("ETLCAL_TEST_BINARY")
    if built:
        return built
    cargo = shutil.which("cargo") or os.path.expanduser("~/.cargo/bin/cargo")
    subprocess.run([cargo, "build", "-q", "-p", "etlcal", "--bin", "etlcal"], cwd=ROOT, check=True)
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    if not target.is_absolute():
        target = ROOT / target
    return str(target / "debug" / "etlcal")
