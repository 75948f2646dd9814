#!/usr/bin/env bash
# The whole test suite: Rust (every crate, doctests included), the no-alloc gate, and the
# Python package (wheel built by maturin, installed into a fresh virtualenv, pytest).
# Prints the time of each stage and the total.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
export CARGO_TERM_COLOR=never
# Cargo's output directory: CARGO_TARGET_DIR when set (the binaries the Python tests run
# are taken from there), else target/ here.
target="${CARGO_TARGET_DIR:-$root/target}"
case "$target" in /*) ;; *) target="$root/$target" ;; esac
start=$SECONDS
stage_start=$SECONDS
# Prints how long the stage that just ended took, and the time so far.
stage_done() {
  echo "-- $1: $((SECONDS - stage_start)) s (total $((SECONDS - start)) s)"
  stage_start=$SECONDS
}

# The Python test environment, created and installed in the background while Rust compiles
# (network and disk, not the CPU the build needs); first, when .ci/run installs Debian
# packages in the background too (ETLCAL_APT_STATUS), it waits for them.
venv="$target/test-venv"
rm -rf "$venv" "$target/wheels-test"
mkdir -p "$target"
(
  if [ -n "${ETLCAL_APT_STATUS:-}" ]; then
    while [ ! -s "$ETLCAL_APT_STATUS" ]; do sleep 1; done
    if [ "$(cat "$ETLCAL_APT_STATUS")" != 0 ]; then
      cat "${ETLCAL_APT_LOG:-/dev/null}"
      echo "apt-get failed (log above)"
      exit 1
    fi
  fi
  python3 -m venv "$venv" &&
    "$venv/bin/python" -m pip install --quiet --upgrade pip &&
    "$venv/bin/python" -m pip install --quiet "maturin>=1.5,<2" "pytest>=7" "numpy>=1.21" \
      opencv-python-headless mypy pyyaml types-PyYAML
) >"$target/test-venv.log" 2>&1 &
venv_job=$!

# The no-alloc, no-panic gate (etl-core linked into a #![no_std] cdylib: no allocator,
# panics unresolvable) is a workspace of its own with its own target directory: it builds
# beside the Rust tests and fills the gaps of their build.
cargo build --release --locked --manifest-path tests/no-alloc-gate/Cargo.toml \
  --target-dir "$root/tests/no-alloc-gate/target" >"$target/no-alloc-gate.log" 2>&1 &
gate_job=$!

echo "== Rust tests (workspace)"
# etl-py is built here too: the features it unifies into the crates it shares are then
# those of the wheel's build below (crates/etl-py/Cargo.toml), which reuses them.
if cargo nextest --version >/dev/null 2>&1; then
  # nextest runs the tests of every binary in one pool, so no binary waits for another's
  # slowest test; it does not run doctests: cargo does, after.
  cargo nextest run --workspace --locked --no-fail-fast --status-level fail \
    --final-status-level slow
  # (--doc runs etl-py's too, doctest = false or not: its doc comments hold no code.)
  cargo test --workspace --locked --doc
else
  cargo test --workspace --locked
fi
stage_done "Rust tests"

echo "== no-alloc, no-panic gate"
if ! wait "$gate_job"; then
  cat "$target/no-alloc-gate.log" >&2
  echo "test.sh: the no-alloc, no-panic gate failed to build (log above)" >&2
  exit 1
fi
tail -1 "$target/no-alloc-gate.log"
stage_done "no-alloc gate (built during the Rust tests)"

echo "== Python package"
if ! wait "$venv_job"; then
  cat "$target/test-venv.log" >&2
  echo "test.sh: the Python test environment could not be installed (log above)" >&2
  exit 1
fi
stage_done "Python test environment (installed during the Rust tests)"
"$venv/bin/maturin" build --quiet --profile dev --manifest-path crates/etl-py/Cargo.toml \
  --out "$target/wheels-test" --interpreter "$venv/bin/python"
"$venv/bin/python" -m pip install --quiet "$target"/wheels-test/*.whl
stage_done "Python package built and installed"
cd crates/etl-py/tests
# The Rust programs the Python tests compare with, as `cargo test` built them.
export ETLCAL_TEST_RUST_REFERENCE="$target/debug/examples/rust_reference"
export ETLCAL_TEST_BINARY="$target/debug/etlcal"
"$venv/bin/python" -m pytest -q --durations=10
stage_done "pytest"
cd "$root"
# docs/BENCHMARKS.md is benches/all.sh's output, never edited by hand.
"$venv/bin/python" -m pytest -q benches/test_benchdoc.py
stage_done "benchmark document"

echo "== hostile-user battery (fast part)"
# The wide net of docs/RELIABILITY.md: the fast part of scripts/hostile/ (its README); a
# case that loses data, dies uncatchably, hangs or leaks fails the run.
"$venv/bin/python" scripts/hostile/battery.py --fast --binary "$target/debug/etlcal"
stage_done "hostile-user battery (fast)"
echo "== all tests passed in $((SECONDS - start)) s"
