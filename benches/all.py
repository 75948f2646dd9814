#!/usr/bin/env python3
"""Every comparison of docs/BENCHMARKS.md rerun in one run, and the document rewritten.

Run through `benches/all.sh`, which makes the environment (a venv with numpy, scipy,
OpenCV and a release wheel of etlcal; the release binaries) and then calls

    python benches/all.py [--only SECTION ...] [--quick]

Each section runs its benchmarks (criterion for the Rust side, the scripts of benches/ for
the comparisons with OpenCV and scipy, which interleave the two sides' calls in one
process where both are callable from Python) and returns its tables. The load average is
printed and recorded before and after each section. The figures go to docs/benchmarks.json,
and docs/BENCHMARKS.md is rendered from benches/BENCHMARKS.md.in (benches/benchdoc.py).
`--only` reruns some sections and keeps the others' last figures (each section records its
own commit and date, printed in the document). `--quick` shortens every measurement, to
try the command; its figures are marked as such and must not be committed.
"""
import argparse
import datetime
import json
import os
import pathlib
import platform
import subprocess
import sys
import time

import benchdoc
import bench_sections

ROOT = benchdoc.ROOT


def git_commit() -> str:
    out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True)
    # The run's own outputs (written after each section) do not make the code dirty.
    own = [":!docs/benchmarks.json", ":!docs/BENCHMARKS.md"]
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", ".", *own], cwd=ROOT,
                           capture_output=True, text=True).stdout.strip()
    return out.stdout.strip() + ("+changes" if dirty else "")


def machine() -> dict:
    cpu = "unknown"
    for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines() if pathlib.Path("/proc/cpuinfo").exists() else []:
        if line.startswith("model name"):
            cpu = line.split(":", 1)[1].strip()
            break
    rustc = subprocess.run(["rustc", "--version"], capture_output=True, text=True).stdout.strip()
    import cv2
    import numpy
    import scipy

    return {"cpu": cpu, "cores": os.cpu_count(), "rustc": rustc, "python": platform.python_version(),
            "numpy": numpy.__version__, "scipy": scipy.__version__, "opencv": cv2.__version__,
            "os": f"{platform.system()} {platform.release()}"}


def run_section(name: str, quick: bool) -> dict:
    before = os.getloadavg()[0]
    print(f"== {name}: load average {before:.2f}", flush=True)
    t0 = time.perf_counter()
    out = bench_sections.SECTIONS[name](bench_sections.Settings(quick))
    seconds = time.perf_counter() - t0
    after = os.getloadavg()[0]
    print(f"   {name}: {seconds:.0f} s, load average {after:.2f}", flush=True)
    out.update({"load_average": [before, after], "seconds": seconds, "commit": git_commit(),
                "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
                "quick": quick})
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="+", choices=list(bench_sections.SECTIONS), help="rerun these sections only")
    ap.add_argument("--quick", action="store_true", help="short measurements, to try the command (not for the docs)")
    ap.add_argument("--results", type=pathlib.Path, default=benchdoc.RESULTS)
    ap.add_argument("--out", type=pathlib.Path, default=benchdoc.DOCUMENT)
    args = ap.parse_args()
    names = args.only or list(bench_sections.SECTIONS)
    results = benchdoc.load_results(args.results) if args.only and args.results.exists() else {"sections": {}}
    results["meta"] = machine()
    for name in names:
        results["sections"][name] = run_section(name, args.quick)
        args.results.write_text(json.dumps(results, indent=1) + "\n")
    missing = [n for n in bench_sections.SECTIONS if n not in results["sections"]]
    if missing:
        print(f"sections never run (the document cannot be rendered): {', '.join(missing)}", file=sys.stderr)
        return 1
    benchdoc.write(results, out=args.out)
    print(f"wrote {args.results} and {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
