#!/usr/bin/env python3
"""Zhang's monofocal calibration: `etlcal zhang` against OpenCV's calibrateCamera on a real
image set, in the same run.

The set: fixtures/zhang (25 photographs of a 9x6 board by one 640 x 512 camera; source in
fixtures/zhang/SOURCE.md). OpenCV's model is made to match etlcal's (the paper's section 4.2
model: radial k1 and the two decentering terms, no k2, k3): flags CALIB_FIX_K2 | CALIB_FIX_K3,
tangential terms free. Three calibrations:
  1. OpenCV end to end (findChessboardCorners + cornerSubPix 11x11, calibrateCamera),
  2. etlcal end to end (`etlcal zhang --json`: its detector, its LM),
  3. OpenCV's calibrateCamera on etlcal's corners (`etlcal detect --json`): the model and
     solver difference alone, without the detectors' difference.
Prints fx, fy, u0, v0, RMS and the relative differences; --json prints them as one object.

    /work/venv-det/bin/python benches/zhang_opencv.py --etlcal target/release/etlcal
"""
import argparse
import glob
import json
import os
import subprocess
import sys

import cv2
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
COLS, ROWS = 9, 6
SQUARE_MM = 1.0  # unknown for this set; intrinsics do not depend on it


def board():
    obj = np.zeros((ROWS * COLS, 3), np.float32)
    obj[:, :2] = np.mgrid[0:COLS, 0:ROWS].T.reshape(-1, 2) * SQUARE_MM
    return obj


def opencv_calibrate(corner_sets, size):
    flags = cv2.CALIB_FIX_K2 | cv2.CALIB_FIX_K3
    crit = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 200, 1e-12)
    obj = [board() for _ in corner_sets]
    rms, k, dist, _, _ = cv2.calibrateCamera(obj, corner_sets, size, None, None, flags=flags, criteria=crit)
    return {"fx": k[0, 0], "fy": k[1, 1], "u0": k[0, 2], "v0": k[1, 2], "k1_opencv": dist[0, 0],
            "p1_opencv": dist[0, 2], "p2_opencv": dist[0, 3], "rms_px": rms, "views_used": len(corner_sets)}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--etlcal", default=os.path.join(ROOT, "target/release/etlcal"))
    ap.add_argument("--images", default=os.path.join(ROOT, "fixtures/zhang"))
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    paths = sorted(glob.glob(os.path.join(a.images, "*.jpg")))
    size = None
    cv_sets = []
    for p in paths:
        g = cv2.imread(p, cv2.IMREAD_GRAYSCALE)
        size = (g.shape[1], g.shape[0])
        ok, c = cv2.findChessboardCorners(g, (COLS, ROWS))
        if ok:
            c = cv2.cornerSubPix(g, c, (11, 11), (-1, -1), (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 100, 1e-4))
            cv_sets.append(c)
    out = {"images": len(paths), "opencv": opencv_calibrate(cv_sets, size)}
    run = lambda args: json.loads(subprocess.run([a.etlcal, *args], check=True, capture_output=True, text=True).stdout)
    out["etlcal"] = run(["zhang", *paths, "--pattern", f"{COLS}x{ROWS}", "--square", str(SQUARE_MM), "--json"])
    det = run(["detect", *paths, "--pattern", f"{COLS}x{ROWS}", "--json"])
    et_sets = [np.array(i["corners_px"], np.float32).reshape(-1, 1, 2) for i in det["images"] if i["found"]]
    out["opencv_on_etlcal_corners"] = opencv_calibrate(et_sets, size)
    for key in ("etlcal", "opencv_on_etlcal_corners"):
        out[f"{key}_vs_opencv"] = {n: out[key][n] / out["opencv"][n] - 1.0 for n in ("fx", "fy", "u0", "v0")}
    out["etlcal_vs_opencv_same_corners"] = {
        n: out["etlcal"][n] / out["opencv_on_etlcal_corners"][n] - 1.0 for n in ("fx", "fy", "u0", "v0")}
    if a.json:
        print(json.dumps(out, indent=1, default=float))
        return
    print(f"{len(paths)} images of a {COLS}x{ROWS} board, {size[0]} x {size[1]} px")
    print(f"{'':28} {'fx':>9} {'fy':>9} {'u0':>9} {'v0':>9} {'rms px':>7} views")
    for key in ("opencv", "etlcal", "opencv_on_etlcal_corners"):
        r = out[key]
        print(f"{key:28} {r['fx']:9.2f} {r['fy']:9.2f} {r['u0']:9.2f} {r['v0']:9.2f} {r['rms_px']:7.4f} {r['views_used']}")
    for key in ("etlcal_vs_opencv", "opencv_on_etlcal_corners_vs_opencv", "etlcal_vs_opencv_same_corners"):
        d = out[key]
        print(f"{key:36} " + " ".join(f"{100 * d[n]:9.4f}%" for n in ("fx", "fy", "u0", "v0")))


if __name__ == "__main__":
    sys.exit(main())
