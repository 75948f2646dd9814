#!/usr/bin/env bash
# The whole test suite: Rust (every crate, doctests included), the no-alloc gate, and the
# Python package (wheel built by maturin, installed into a fresh virtualenv, pytest).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
export CARGO_TERM_COLOR=never

echo "== Rust tests (workspace)"
cargo test --workspace --locked

echo "== no-alloc, no-panic gate (etl-core linked into a #![no_std] cdylib: no allocator, panics unresolvable)"
cargo build --release --locked --manifest-path tests/no-alloc-gate/Cargo.toml

echo "== Python package"
venv="$root/target/test-venv"
rm -rf "$venv" "$root/target/wheels-test"
python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --upgrade pip
"$venv/bin/python" -m pip install --quiet "maturin>=1.5,<2" "pytest>=7" "numpy>=1.21" opencv-python-headless mypy pyyaml types-PyYAML
"$venv/bin/maturin" build --quiet --profile dev --manifest-path crates/etl-py/Cargo.toml \
  --out "$root/target/wheels-test" --interpreter "$venv/bin/python"
"$venv/bin/python" -m pip install --quiet "$root"/target/wheels-test/*.whl
cd crates/etl-py/tests
"$venv/bin/python" -m pytest -q
