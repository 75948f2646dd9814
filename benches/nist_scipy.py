#!/usr/bin/env python3
"""NIST StRD: etlcal's LM against scipy.optimize.least_squares, in one run.

Ours: `cargo test --release -p etl-core --test it nist:: -- --nocapture` (exact Jacobians by
forward-mode dual numbers). Scipy: least_squares with method 'lm' (MINPACK) and 'trf',
finite-difference Jacobians (its default), tight tolerances. Both start from NIST's
start 1 and start 2 and are scored by the LRE of the parameters (capped at 11).

    python3 -m venv /tmp/venv-nist && /tmp/venv-nist/bin/pip install scipy
    /tmp/venv-nist/bin/python benches/nist_scipy.py
"""
import math
import pathlib
import re
import subprocess
import sys

import numpy as np
from scipy.optimize import least_squares

ROOT = pathlib.Path(__file__).resolve().parent.parent
PI = math.pi
MODELS = {
    "Misra1a": lambda b, x: b[0] * (1 - np.exp(-b[1] * x)),
    "BoxBOD": lambda b, x: b[0] * (1 - np.exp(-b[1] * x)),
    "Chwirut1": lambda b, x: np.exp(-b[0] * x) / (b[1] + b[2] * x),
    "Chwirut2": lambda b, x: np.exp(-b[0] * x) / (b[1] + b[2] * x),
    "Lanczos1": lambda b, x: b[0] * np.exp(-b[1] * x) + b[2] * np.exp(-b[3] * x) + b[4] * np.exp(-b[5] * x),
    "Lanczos2": lambda b, x: b[0] * np.exp(-b[1] * x) + b[2] * np.exp(-b[3] * x) + b[4] * np.exp(-b[5] * x),
    "Lanczos3": lambda b, x: b[0] * np.exp(-b[1] * x) + b[2] * np.exp(-b[3] * x) + b[4] * np.exp(-b[5] * x),
    "Gauss1": lambda b, x: b[0] * np.exp(-b[1] * x) + b[2] * np.exp(-((x - b[3]) / b[4]) ** 2) + b[5] * np.exp(-((x - b[6]) / b[7]) ** 2),
    "Gauss2": lambda b, x: b[0] * np.exp(-b[1] * x) + b[2] * np.exp(-((x - b[3]) / b[4]) ** 2) + b[5] * np.exp(-((x - b[6]) / b[7]) ** 2),
    "Gauss3": lambda b, x: b[0] * np.exp(-b[1] * x) + b[2] * np.exp(-((x - b[3]) / b[4]) ** 2) + b[5] * np.exp(-((x - b[6]) / b[7]) ** 2),
    "Misra1b": lambda b, x: b[0] * (1 - (1 + b[1] * x / 2) ** (-2)),
    "Kirby2": lambda b, x: (b[0] + b[1] * x + b[2] * x**2) / (1 + b[3] * x + b[4] * x**2),
    "Hahn1": lambda b, x: (b[0] + b[1] * x + b[2] * x**2 + b[3] * x**3) / (1 + b[4] * x + b[5] * x**2 + b[6] * x**3),
    "Thurber": lambda b, x: (b[0] + b[1] * x + b[2] * x**2 + b[3] * x**3) / (1 + b[4] * x + b[5] * x**2 + b[6] * x**3),
    "MGH17": lambda b, x: b[0] + b[1] * np.exp(-x * b[3]) + b[2] * np.exp(-x * b[4]),
    "Misra1c": lambda b, x: b[0] * (1 - (1 + 2 * b[1] * x) ** (-0.5)),
    "Misra1d": lambda b, x: b[0] * b[1] * x / (1 + b[1] * x),
    "Roszman1": lambda b, x: b[0] - b[1] * x - np.arctan(b[2] / (x - b[3])) / PI,
    "ENSO": lambda b, x: (b[0] + b[1] * np.cos(2 * PI * x / 12) + b[2] * np.sin(2 * PI * x / 12)
                          + b[4] * np.cos(2 * PI * x / b[3]) + b[5] * np.sin(2 * PI * x / b[3])
                          + b[7] * np.cos(2 * PI * x / b[6]) + b[8] * np.sin(2 * PI * x / b[6])),
    "MGH09": lambda b, x: b[0] * (x**2 + x * b[1]) / (x**2 + x * b[2] + b[3]),
    "Rat42": lambda b, x: b[0] / (1 + np.exp(b[1] - b[2] * x)),
    "MGH10": lambda b, x: b[0] * np.exp(b[1] / (x + b[2])),
    "Eckerle4": lambda b, x: (b[0] / b[1]) * np.exp(-0.5 * ((x - b[2]) / b[1]) ** 2),
    "Rat43": lambda b, x: b[0] / ((1 + np.exp(b[1] - b[2] * x)) ** (1 / b[3])),
    "Bennett5": lambda b, x: b[0] * (b[1] + x) ** (-1 / b[2]),
    "DanWood": lambda b, x: b[0] * x ** b[1],
}
ORDER = ["Misra1a", "Chwirut2", "Chwirut1", "Lanczos3", "Gauss1", "Gauss2", "DanWood", "Misra1b", "Kirby2", "Hahn1",
         "Nelson", "MGH17", "Lanczos1", "Lanczos2", "Gauss3", "Misra1c", "Misra1d", "Roszman1", "ENSO", "MGH09",
         "Thurber", "BoxBOD", "Rat42", "MGH10", "Eckerle4", "Rat43", "Bennett5"]


def load(name):
    lines = (ROOT / "fixtures" / "nist" / f"{name}.dat").read_text().splitlines()
    starts, cert, data = [[], []], [], []
    for n, line in enumerate(lines):
        t = line.strip()
        m = re.match(r"b(\d+)\s*=\s*(\S+)\s+(\S+)\s+(\S+)", t)
        if n < 59 and m:
            starts[0].append(float(m.group(2)))
            starts[1].append(float(m.group(3)))
            cert.append(float(m.group(4)))
        if n >= 60:
            v = [float(s) for s in t.split()]
            if len(v) >= 2:
                data.append(v)
    return starts, np.array(cert), np.array(data)


def lre(b, c):
    out = 11.0
    for bi, ci in zip(b, c):
        rel = abs(bi - ci) / abs(ci)
        v = 0.0 if not math.isfinite(rel) else (11.0 if rel == 0 else min(max(-math.log10(rel), 0.0), 11.0))
        out = min(out, v)
    return out


def scipy_lre(name, start, method):
    starts, cert, data = load(name)
    y = data[:, 0]
    if name == "Nelson":
        x1, x2 = data[:, 1], data[:, 2]
        f = lambda b: b[0] - b[1] * x1 * np.exp(-b[2] * x2) - np.log(y)
    else:
        x = data[:, 1]
        f = lambda b: MODELS[name](b, x) - y
    try:
        with np.errstate(all="ignore"):
            r = least_squares(f, np.array(starts[start]), method=method, xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=100000)
        return lre(r.x, cert)
    except Exception:
        return 0.0


def ours():
    out = subprocess.run(["cargo", "test", "--release", "-q", "-p", "etl-core", "--test", "it", "nist::", "--", "--nocapture", "--test-threads=1"],
                         cwd=ROOT, capture_output=True, text=True, check=True).stdout
    res = {}
    for line in out.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 7 and cells[0] in ORDER:
            res[cells[0]] = (float(cells[1]), float(cells[4]))
    return res


def measure():
    """LRE per problem and start: {problem: {"etlcal": [s1, s2], "lm": [...], "trf": [...]}}."""
    mine = ours()
    return {name: {"etlcal": list(mine[name]),
                   "lm": [scipy_lre(name, 0, "lm"), scipy_lre(name, 1, "lm")],
                   "trf": [scipy_lre(name, 0, "trf"), scipy_lre(name, 1, "trf")]} for name in ORDER}


def main():
    import argparse
    import json

    ap = argparse.ArgumentParser()
    ap.add_argument("--json", action="store_true", help="print the LREs as one JSON object")
    args = ap.parse_args()
    res = measure()
    if args.json:
        print(json.dumps({"problems": res, "order": ORDER}))
        return 0
    print("| problem | etlcal s1 | etlcal s2 | scipy lm s1 | scipy lm s2 | scipy trf s1 | scipy trf s2 |")
    print("|---|---|---|---|---|---|---|")
    for name in ORDER:
        row = res[name]["etlcal"] + res[name]["lm"] + res[name]["trf"]
        print(f"| {name} | " + " | ".join(f"{v:.1f}" for v in row) + " |")
    for k in ["etlcal", "lm", "trf"]:
        c6 = [sum(res[n][k][s] >= 6 for n in ORDER) for s in (0, 1)]
        c4 = [sum(res[n][k][s] >= 4 for n in ORDER) for s in (0, 1)]
        print(f"{k}: LRE >= 6 on {c6[0]}/27 (start 1), {c6[1]}/27 (start 2); LRE >= 4 on {c4[0]}/27, {c4[1]}/27")
    return 0


if __name__ == "__main__":
    sys.exit(main())
