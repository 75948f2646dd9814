"""Shared fixtures: the Rust reference values (printed by the `rust_reference` example of
etl-py, run through cargo once per session)."""
import json
import os
import pathlib
import shutil
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def rust_reference():
    cargo = shutil.which("cargo") or os.path.expanduser("~/.cargo/bin/cargo")
    out = subprocess.run(
        [cargo, "run", "-q", "-p", "etl-py", "--example", "rust_reference"],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(out.stdout)


@pytest.fixture(scope="session")
def etlcal_binary():
    """The `etlcal` command line (built by cargo once per session), to make test data."""
    cargo = shutil.which("cargo") or os.path.expanduser("~/.cargo/bin/cargo")
    subprocess.run([cargo, "build", "-q", "-p", "etlcal", "--bin", "etlcal"], cwd=ROOT, check=True)
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    if not target.is_absolute():
        target = ROOT / target
    return str(target / "debug" / "etlcal")
