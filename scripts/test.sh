#!/usr/bin/env bash
# The whole test suite: Rust (every crate, doctests included), the no-alloc gate, and the
# Python package (wheel built by maturin, installed into a fresh virtualenv, pytest).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
export CARGO_TERM_COLOR=never
start=$SECONDS
stage_start=$SECONDS
# Prints how long the stage that just ended took, and the time so far.
stage_done() {
  echo "-- $1: $((SECONDS - stage_start)) s (total $((SECONDS - start)) s)"
  stage_start=$SECONDS
}

echo "== Rust tests (workspace)"
cargo test --workspace --locked
stage_done "Rust tests"

echo "== no-alloc, no-panic gate (etl-core linked into a #![no_std] cdylib: no allocator, panics unresolvable)"
cargo build --release --locked --manifest-path tests/no-alloc-gate/Cargo.toml
stage_done "no-alloc gate"

echo "== Python package"
venv="$root/target/test-venv"
rm -rf "$venv" "$root/target/wheels-test"
python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --upgrade pip
"$venv/bin/python" -m pip install --quiet "maturin>=1.5,<2" "pytest>=7" "numpy>=1.21" opencv-python-headless mypy pyyaml types-PyYAML
stage_done "Python test environment"
"$venv/bin/maturin" build --quiet --profile dev --manifest-path crates/etl-py/Cargo.toml \
  --out "$root/target/wheels-test" --interpreter "$venv/bin/python"
"$venv/bin/python" -m pip install --quiet "$root"/target/wheels-test/*.whl
stage_done "Python package built and installed"
cd crates/etl-py/tests
"$venv/bin/python" -m pytest -q --durations=10
stage_done "pytest"
echo "== all tests passed in $((SECONDS - start)) s"
