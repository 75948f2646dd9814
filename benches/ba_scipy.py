#!/usr/bin/env python3
"""Bundle adjustment of the paper rig: etlcal against scipy.optimize.least_squares from the
same linear start, in one run. Prints both times, the ratio and both final costs.

    python3 -m venv /tmp/venv-ba && /tmp/venv-ba/bin/pip install scipy
    /tmp/venv-ba/bin/python benches/ba_scipy.py [--rounds 3] [--json]
"""
import argparse
import json
import os
import pathlib
import statistics
import subprocess
import time

import numpy as np
from scipy.optimize import least_squares

ROOT = pathlib.Path(__file__).resolve().parent.parent
TARGET = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))


def rodrigues(om):
    t = np.linalg.norm(om)
    k = np.array([[0, -om[2], om[1]], [om[2], 0, -om[0]], [-om[1], om[0], 0]])
    if t < 1e-12:
        return np.eye(3) + k
    return np.eye(3) + np.sin(t) / t * k + (1 - np.cos(t)) / t**2 * (k @ k)


def residuals(x, world, pix, e):
    """Eq. 13-18 as etlcal reads them (Weng's decentering term; centred pixels)."""
    r = rodrigues(x[0:3])
    pc = world @ r.T + x[3:6]
    powers = np.stack([np.ones_like(e), e, e**2, e**3], axis=1)
    fx, fy = powers @ x[6:10], powers @ x[10:14]
    u, v = fx * pc[:, 0] / pc[:, 2], fy * pc[:, 1] / pc[:, 2]
    w = 2.0 / (fx + fy)
    a = x[16:25]
    k1 = a[0] * w**2 + a[1] * w + a[2]
    p1 = a[3] * w**2 + a[4] * w + a[5]
    p2 = a[6] * w**2 + a[7] * w + a[8]
    r2 = u * u + v * v
    ud = u + k1 * u * r2 + p1 * (3 * u * u + v * v) + 2 * p2 * u * v
    vd = v + k1 * v * r2 + 2 * p1 * u * v + p2 * (u * u + 3 * v * v)
    return np.concatenate([ud + x[14] - pix[:, 0], vd + x[15] - pix[:, 1]])


def etlcal_problem():
    """One run of etl-sim's `ba_problem` example: the problem, etlcal's time, cost and iterations."""
    out = subprocess.run([str(TARGET / "release/examples/ba_problem")], capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def measure(rounds):
    """`rounds` interleaved rounds (etlcal's example, scipy 'lm', scipy 'trf'); medians of the rounds."""
    subprocess.run(["cargo", "build", "--release", "-q", "-p", "etl-sim", "--example", "ba_problem"], cwd=ROOT, check=True)
    prob = etlcal_problem()
    world, pix, e = [], [], []
    for v in prob["observations"]["views"]:
        for p in v["points"]:
            world.append(p["world_mm"])
            pix.append(p["pixel"])
            e.append(v["e_com_ma"])
    world, pix, e = np.array(world), np.array(pix), np.array(e)
    x0 = np.array(prob["start"])
    times = {"etlcal": [], "lm": [], "trf": []}
    costs = {}
    for _ in range(rounds):
        run = etlcal_problem()
        times["etlcal"].append(run["etlcal_seconds"])
        costs["etlcal"], iterations = run["etlcal_cost"], run["etlcal_iterations"]
        for method in ["lm", "trf"]:
            t = time.perf_counter()
            r = least_squares(residuals, x0, args=(world, pix, e), method=method, xtol=1e-15, ftol=1e-15,
                              gtol=1e-15, x_scale="jac")
            times[method].append(time.perf_counter() - t)
            costs[method] = float(np.sum(r.fun**2))
    return {"points": len(e), "rounds": rounds, "etlcal_iterations": iterations,
            "seconds": {k: statistics.median(v) for k, v in times.items()}, "cost": costs}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    res = measure(args.rounds)
    if args.json:
        print(json.dumps(res))
        return
    et = res["seconds"]["etlcal"]
    print(f"points: {res['points']}; etlcal {1e3 * et:.2f} ms, cost {res['cost']['etlcal']:.9f}, "
          f"{res['etlcal_iterations']} iterations")
    for method in ["lm", "trf"]:
        secs, cost = res["seconds"][method], res["cost"][method]
        rel = abs(cost - res["cost"]["etlcal"]) / res["cost"]["etlcal"]
        print(f"scipy {method}: {1e3 * secs:.1f} ms ({secs / et:.0f}x), cost {cost:.9f} ({rel:.1e} relative)")


if __name__ == "__main__":
    main()
