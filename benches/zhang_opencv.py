#!/usr/bin/env python3
"""Zhang's monofocal calibration: `etlcal zhang` against OpenCV's calibrateCamera on real
image sets, both sides in the same run.

Two modes.

Default (issue 5): fixtures/zhang (25 photographs of a 9x6 board by one 640 x 512 camera;
source in fixtures/zhang/SOURCE.md) with the paper's model: OpenCV is made to match it
(radial k1 and the two decentering terms, no k2, k3): flags CALIB_FIX_K2 | CALIB_FIX_K3,
tangential terms free.

--wide (issue 16): the two wide-lens sets of fixtures/wide (SOURCE.md there; k1 < -0.25)
with OpenCV's own model on both sides (`etlcal zhang --model opencv`, calibrateCamera with
k1, k2, p1, p2, k3 free; --fix-k3 and --zero-tangent set CALIB_FIX_K3 and
CALIB_ZERO_TANGENT_DIST on both sides). Per set it checks the issue's acceptance:
  * views: etlcal uses every view OpenCV uses;
  * RMS: etlcal end to end (its corners, its solver) is at most OpenCV end to end;
  * same corners: on etlcal's corners, etlcal and cv2.calibrateCamera agree, every one of
    fx, fy, cx, cy, k1, k2, p1, p2, k3 within 0.01 of OpenCV's standard deviation of it
    (calibrateCameraExtended's stdDeviationsIntrinsics).
It exits 1 when a check fails.

Three calibrations per set in both modes:
  1. OpenCV end to end (findChessboardCorners + cornerSubPix 11x11, calibrateCamera),
  2. etlcal end to end (`etlcal zhang --json`: its detector, its LM),
  3. OpenCV's calibrateCamera on etlcal's corners (`etlcal detect --json`): the solver
     difference alone, without the detectors' difference.
--json prints everything as one object.

    /work/venv/bin/python benches/zhang_opencv.py --etlcal target/release/etlcal
    /work/venv/bin/python benches/zhang_opencv.py --wide --etlcal target/release/etlcal
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
SQUARE_MM = 1.0  # unknown for these sets; intrinsics do not depend on it
# OpenCV's LM run to convergence (its default stops after 30 iterations).
CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 500, 1e-15)
SUBPIX = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 100, 1e-4)
# (directory under fixtures/, inner corners)
WIDE_SETS = {"opencv_left": ("wide/opencv_left", (9, 6)), "stereo752_left": ("wide/stereo752_left", (11, 8))}
NAMES = ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3")


def board(cols, rows):
    obj = np.zeros((rows * cols, 3), np.float32)
    obj[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * SQUARE_MM
    return obj


def opencv_corners(paths, pattern):
    """OpenCV's detector: {path: corners (N, 1, 2) float32} for the images it finds."""
    found, size = {}, None
    for p in paths:
        g = cv2.imread(p, cv2.IMREAD_GRAYSCALE)
        size = (g.shape[1], g.shape[0])
        ok, c = cv2.findChessboardCorners(g, pattern)
        if ok:
            found[p] = cv2.cornerSubPix(g, c, (11, 11), (-1, -1), SUBPIX)
    return found, size


def opencv_calibrate(corner_sets, size, pattern, flags):
    obj = [board(*pattern) for _ in corner_sets]
    rms, k, dist, _, _, std, _, per_view = cv2.calibrateCameraExtended(
        obj, corner_sets, size, None, None, flags=flags, criteria=CRITERIA)
    dist = dist.ravel()
    values = [k[0, 0], k[1, 1], k[0, 2], k[1, 2], *dist[:5]]
    return {"fx": k[0, 0], "fy": k[1, 1], "u0": k[0, 2], "v0": k[1, 2], "k1_opencv": dist[0], "k2_opencv": dist[1],
            "p1_opencv": dist[2], "p2_opencv": dist[3], "k3_opencv": dist[4], "rms_px": rms,
            "views_used": len(corner_sets), "values": dict(zip(NAMES, values)),
            "std": dict(zip(NAMES, std.ravel()[:9])), "per_view_rms_px": per_view.ravel().tolist()}


def run_etlcal(binary, args):
    out = subprocess.run([binary, *args], check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


def etlcal_corners(binary, paths, pattern):
    det = run_etlcal(binary, ["detect", *paths, "--pattern", f"{pattern[0]}x{pattern[1]}", "--json"])
    return {p: np.array(i["corners_px"], np.float32).reshape(-1, 1, 2)
            for p, i in zip(paths, det["images"]) if i["found"]}


def paper_model(a):
    """Issue 5's comparison on fixtures/zhang (the paper's model)."""
    pattern = (9, 6)
    paths = sorted(glob.glob(os.path.join(ROOT, "fixtures/zhang", "*.jpg")))
    flags = cv2.CALIB_FIX_K2 | cv2.CALIB_FIX_K3
    cv, size = opencv_corners(paths, pattern)
    out = {"images": len(paths), "opencv": opencv_calibrate(list(cv.values()), size, pattern, flags)}
    out["etlcal"] = run_etlcal(a.etlcal, ["zhang", *paths, "--pattern", "9x6", "--square", str(SQUARE_MM), "--json"])
    et = etlcal_corners(a.etlcal, paths, pattern)
    out["opencv_on_etlcal_corners"] = opencv_calibrate(list(et.values()), size, pattern, flags)
    for key in ("etlcal", "opencv_on_etlcal_corners"):
        out[f"{key}_vs_opencv"] = {n: out[key][n] / out["opencv"][n] - 1.0 for n in ("fx", "fy", "u0", "v0")}
    out["etlcal_vs_opencv_same_corners"] = {
        n: out["etlcal"][n] / out["opencv_on_etlcal_corners"][n] - 1.0 for n in ("fx", "fy", "u0", "v0")}
    if a.json:
        print(json.dumps(out, indent=1, default=float))
        return 0
    print(f"{len(paths)} images of a 9x6 board, {size[0]} x {size[1]} px")
    print(f"{'':28} {'fx':>9} {'fy':>9} {'u0':>9} {'v0':>9} {'rms px':>7} views")
    for key in ("opencv", "etlcal", "opencv_on_etlcal_corners"):
        r = out[key]
        print(f"{key:28} {r['fx']:9.2f} {r['fy']:9.2f} {r['u0']:9.2f} {r['v0']:9.2f} {r['rms_px']:7.4f} {r['views_used']}")
    for key in ("etlcal_vs_opencv", "opencv_on_etlcal_corners_vs_opencv", "etlcal_vs_opencv_same_corners"):
        d = out[key]
        print(f"{key:36} " + " ".join(f"{100 * d[n]:9.4f}%" for n in ("fx", "fy", "u0", "v0")))
    return 0


def etlcal_values(z):
    k, d = z["camera_matrix"], z["dist_coeffs"]
    return dict(zip(NAMES, [k[0][0], k[1][1], k[0][2], k[1][2], *d]))


def wide_set(a, name, flags, model_flags):
    sub, pattern = WIDE_SETS[name]
    paths = sorted(glob.glob(os.path.join(ROOT, "fixtures", sub, "*.jpg")))
    cv, size = opencv_corners(paths, pattern)
    et = etlcal_corners(a.etlcal, paths, pattern)
    r = {"images": len(paths), "pattern": list(pattern), "image_size": list(size),
         "opencv_found": len(cv), "etlcal_found": len(et)}
    r["opencv"] = opencv_calibrate(list(cv.values()), size, pattern, flags)
    r["etlcal"] = run_etlcal(a.etlcal, ["zhang", *paths, "--pattern", f"{pattern[0]}x{pattern[1]}", "--square",
                                        str(SQUARE_MM), "--model", "opencv", *model_flags, "--json"])
    r["opencv_on_etlcal_corners"] = opencv_calibrate(list(et.values()), size, pattern, flags)
    same, ref = etlcal_values(r["etlcal"]), r["opencv_on_etlcal_corners"]
    # A held coefficient has no standard deviation (OpenCV reports 0): its values must be equal.
    r["same_corners_in_std"] = {
        n: abs(same[n] - ref["values"][n]) / ref["std"][n] if ref["std"][n] > 0 else abs(same[n] - ref["values"][n])
        for n in NAMES}
    r["checks"] = {
        "every_opencv_view_used": set(cv) <= set(et) and r["etlcal"]["views_used"] == len(et),
        "rms_at_most_opencv": r["etlcal"]["rms_px"] <= r["opencv"]["rms_px"],
        "same_corners_within_0.01_std": max(r["same_corners_in_std"].values()) <= 0.01,
    }
    return r


def print_wide(name, r):
    w, h = r["image_size"]
    print(f"\n{name}: {r['images']} images, {r['pattern'][0]}x{r['pattern'][1]} board, {w} x {h} px; "
          f"found by OpenCV {r['opencv_found']}, by etlcal {r['etlcal_found']}")
    print(f"{'':26} " + " ".join(f"{n:>9}" for n in NAMES) + f" {'rms px':>7} views")
    rows = [("opencv", r["opencv"]["values"], r["opencv"]), ("etlcal", etlcal_values(r["etlcal"]), r["etlcal"]),
            ("opencv_on_etlcal_corners", r["opencv_on_etlcal_corners"]["values"], r["opencv_on_etlcal_corners"])]
    for key, v, full in rows:
        print(f"{key:26} " + " ".join(f"{v[n]:9.4f}" for n in NAMES) + f" {full['rms_px']:7.4f} {full['views_used']}")
    print(f"{'std (OpenCV, same corners)':26} " + " ".join(f"{r['opencv_on_etlcal_corners']['std'][n]:9.2e}" for n in NAMES))
    print(f"{'|etlcal - cv| / std':26} " + " ".join(f"{r['same_corners_in_std'][n]:9.2e}" for n in NAMES))
    for k, ok in r["checks"].items():
        print(f"  {k}: {'pass' if ok else 'FAIL'}")


def wide(a):
    flags = (cv2.CALIB_FIX_K3 if a.fix_k3 else 0) | (cv2.CALIB_ZERO_TANGENT_DIST if a.zero_tangent else 0)
    model_flags = (["--fix-k3"] if a.fix_k3 else []) + (["--zero-tangent"] if a.zero_tangent else [])
    out = {name: wide_set(a, name, flags, model_flags) for name in WIDE_SETS}
    ok = all(all(r["checks"].values()) for r in out.values())
    if a.json:
        print(json.dumps(out, indent=1, default=float))
    else:
        print(f"OpenCV {cv2.__version__}, flags: {' '.join(model_flags) or 'none (k1, k2, p1, p2, k3 free)'}")
        for name, r in out.items():
            print_wide(name, r)
        print("\nacceptance:", "pass" if ok else "FAIL")
    return 0 if ok else 1


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--etlcal", default=os.path.join(ROOT, "target/release/etlcal"))
    ap.add_argument("--wide", action="store_true", help="the wide-lens sets with OpenCV's model (issue 16)")
    ap.add_argument("--fix-k3", action="store_true", help="--wide: hold k3 = 0 on both sides")
    ap.add_argument("--zero-tangent", action="store_true", help="--wide: hold p1 = p2 = 0 on both sides")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    return wide(a) if a.wide else paper_model(a)


if __name__ == "__main__":
    sys.exit(main())
