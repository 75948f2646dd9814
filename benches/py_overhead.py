"""Per-call overhead of the Python bindings over the Rust functions, both measured in one run.

Rust side: the criterion benches of etl-core (`cargo bench -p etl-core --features bench --bench model`),
read from criterion's JSON estimates (median). Python side: the same work through
`etlcal` (timeit, best of 7 repeats of the median-ish mean), with a wheel built in release:

    maturin build --release --manifest-path crates/etl-py/Cargo.toml --out /tmp/wheels
    pip install /tmp/wheels/etlcal-*.whl
    python benches/py_overhead.py

Prints a Markdown table (the numbers of docs/BENCHMARKS.md, "Python bindings").
"""
import json
import os
import pathlib
import subprocess
import sys
import timeit

import numpy as np

import etlcal

ROOT = pathlib.Path(__file__).resolve().parents[1]
TARGET = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))


RUN_BENCHES = True


def rust_median_ns(bench: str, name: str, package: str = "etl-core") -> float:
    """Criterion's median of one bench; run here unless `--no-bench` (benches/all.py has just run it)."""
    if RUN_BENCHES:
        subprocess.run(
            ["cargo", "bench", "-q", "-p", package, "--features", "bench", "--bench", bench, "--", name, "--exact"],
            cwd=ROOT,
            check=True,
            stdout=subprocess.DEVNULL,
        )
    est = json.loads((TARGET / "criterion" / name / "new" / "estimates.json").read_text())
    return est["median"]["point_estimate"]


def python_ns(stmt, number: int) -> float:
    # Best of the repeats: the least disturbed by the other jobs on the machine.
    times = timeit.repeat(stmt, number=number, repeat=7)
    return min(times) / number * 1e9


def rust_detect_ms(png: pathlib.Path, warm: bool) -> float:
    """Best per-call time of the `detect_timing` example of etl-py (a fresh process)."""
    args = [str(TARGET / "release" / "examples" / "detect_timing"), str(png)]
    out = subprocess.run(args + (["--warm"] if warm else []), cwd=ROOT, check=True, capture_output=True, text=True)
    return float(out.stdout.split()[0])


PY_DETECT = """
import sys, timeit
import cv2, numpy as np, etlcal
if sys.argv[2] == "warm":
    a = np.ones(16 << 20, np.uint8)
    del a
img = cv2.imread(sys.argv[1], cv2.IMREAD_GRAYSCALE)
etlcal.detect_corners(img, "14x12")
t = timeit.repeat(lambda: etlcal.detect_corners(img, "14x12"), number=5, repeat=7)
print(min(t) / 5 * 1e3)
"""


def python_detect_ms(png: pathlib.Path, warm: bool) -> float:
    """The same loop as `rust_detect_ms` through etlcal, in a fresh interpreter."""
    args = [sys.executable, "-c", PY_DETECT, str(png), "warm" if warm else "cold"]
    return float(subprocess.run(args, check=True, capture_output=True, text=True).stdout)


def measure() -> list:
    """Rows (call, Rust ns, Python ns), both sides measured now."""
    subprocess.run(["cargo", "build", "-q", "--release", "-p", "etl-py", "--example", "detect_timing"], cwd=ROOT, check=True)
    cal = etlcal.Calibration.paper_rig()
    board = np.array([[1.5 * i, 1.5 * j, 48.0] for j in range(12) for i in range(14)])
    pixels = cal.project(board, 100.0)
    rows = []
    rust = rust_median_ns("model", "project_168_points")
    py = python_ns(lambda: cal.project(board, 100.0), 20000)
    rows.append(("Calibration.project, 168 points", rust, py))
    rust = rust_median_ns("model", "undistort_168_points")
    py = python_ns(lambda: cal.undistort(pixels, 100.0), 2000)
    rows.append(("Calibration.undistort, 168 points", rust, py))
    s = etlcal.ThermalSurface.paper()
    rust = rust_median_ns("model", "e_com_one")
    py = python_ns(lambda: s.e_com(143.2, 31.7), 200000)
    rows.append(("ThermalSurface.e_com, one float", rust, py))
    rust = rust_median_ns("detect", "detect_1936x1458_14x12/blur_1.5", package="etl-image")
    png = TARGET / "criterion" / "detect_view_blur_1.5.png"
    for warm in [False, True]:
        r_ms = rust_detect_ms(png, warm)
        p_ms = python_detect_ms(png, warm)
        state = "malloc warmed (one 16 MiB block freed first)" if warm else "fresh process"
        rows.append((f"detect_corners, 1936 x 1458, {state}", r_ms * 1e6, p_ms * 1e6))
    import cv2

    img = cv2.imread(str(png), cv2.IMREAD_GRAYSCALE)
    py = python_ns(lambda: etlcal.detect_corners(img, "14x12"), 5)
    rows.append(("detect_corners, 1936 x 1458, this process against criterion", rust, py))
    return rows


def main() -> None:
    import argparse

    global RUN_BENCHES
    ap = argparse.ArgumentParser()
    ap.add_argument("--no-bench", action="store_true", help="read criterion's last results instead of running it")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    RUN_BENCHES = not args.no_bench
    rows = measure()
    if args.json:
        print(json.dumps({"rows": [{"call": n, "rust_ns": r, "python_ns": p} for n, r, p in rows],
                          "python": sys.version.split()[0], "numpy": np.__version__}))
        return
    print(f"python {sys.version.split()[0]}, numpy {np.__version__}, etlcal {etlcal.__version__}")
    print("| call | Rust | Python (best of 7) | overhead |")
    print("|---|---|---|---|")

    def fmt(ns: float) -> str:
        return f"{ns:.0f} ns" if abs(ns) < 1000 else f"{ns / 1000:.2f} us"

    for name, r, p in rows:
        print(f"| {name} | {fmt(r)} | {fmt(p)} | {fmt(p - r)} ({100 * (p - r) / r:+.1f} %) |")


if __name__ == "__main__":
    main()
