#!/usr/bin/env bash
# Every comparison of docs/BENCHMARKS.md rerun in one run, and the document rewritten from
# benches/BENCHMARKS.md.in with the figures measured now (benches/all.py says how).
#
#   benches/all.sh [--only SECTION ...] [--quick]
#
# Makes what it needs: the release binaries and benches (built before anything is timed,
# so no compilation overlaps a measurement), and a venv in target/bench-venv with numpy,
# scipy, OpenCV and a release wheel of etlcal. Run it on an otherwise idle machine: the
# load average is printed and recorded before and after each section.
set -euo pipefail
cd "$(dirname "$0")/.."
target="${CARGO_TARGET_DIR:-target}"
venv="$target/bench-venv"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
    "$venv/bin/python" -m pip install --quiet --upgrade pip
    "$venv/bin/python" -m pip install --quiet "maturin>=1.5,<2" numpy scipy opencv-python-headless
fi
echo "building (release binaries, examples and benches) ..."
cargo build --quiet --release -p etlcal
cargo build --quiet --release -p etl-sim --example ba_problem
cargo build --quiet --release -p etl-py --example detect_timing
cargo bench --quiet --no-run -p etl-core -p etl-calib -p etl-image -p etl-sim --features bench
cargo bench --quiet --no-run -p etl-hw
cargo test --quiet --release --no-run -p etl-core --test it
rm -rf "$target/wheels-bench"
"$venv/bin/maturin" build --quiet --release --manifest-path crates/etl-py/Cargo.toml \
    --out "$target/wheels-bench" --interpreter "$venv/bin/python"
"$venv/bin/python" -m pip install --quiet --force-reinstall --no-deps "$target"/wheels-bench/*.whl
exec "$venv/bin/python" benches/all.py "$@"
