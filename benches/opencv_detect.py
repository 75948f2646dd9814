#!/usr/bin/env python3
"""Checkerboard detection: etlcal vs OpenCV on the same images, in the same run.

Renders 1936 x 1458 views of a 14x12 board (4 poses x blur sigma 0.5 / 1.5 / 3 px, dark 40,
light 210, Gaussian noise sigma 2 grey levels, 8-bit PNG) with an independent numpy renderer
(exact homography, 8 x 8 area supersampling, then Gaussian blur: the true corners are the
projected board corners), and measures on every image:
  - OpenCV findChessboardCorners + cornerSubPix (11x11 and 21x21 windows),
  - OpenCV findChessboardCornersSB with CALIB_CB_ACCURACY (slow: --sb to include),
  - etlcal (`etlcal detect --json`, corners matched to the truth up to the board's half turn).
Reports found rate, RMS error against the truth, and time per image (OpenCV in process, best
of 5 for the classic detector;
etlcal's time is the criterion bench `cargo bench -p etl-image --features bench --bench detect`, the CLI time
here includes process start and PNG decoding).

Then the real photographs (fixtures/detect, or --real DIR...): found rate of both at the
right size and at one column more (which must find nothing).

    python3 -m venv /work/venv-det && /work/venv-det/bin/pip install opencv-python-headless numpy
    /work/venv-det/bin/python benches/opencv_detect.py --etlcal target/release/etlcal [--sb]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import cv2
import numpy as np

W, H = 1936, 1458
COLS, ROWS = 14, 12
POSES = [(0.0, 0.0, 0.05), (0.35, -0.25, 0.1), (-0.3, 0.4, -0.3), (0.1, 0.45, 2.0)]
BLURS = [0.5, 1.5, 3.0]


def homography(rot, square_px):
    f = 3000.0
    z = f / square_px  # in squares
    r, _ = cv2.Rodrigues(np.array(rot, dtype=np.float64))
    centre = np.array([(COLS - 1) / 2.0, (ROWS - 1) / 2.0, 0.0])
    t = np.array([0.0, 0.0, z]) - r @ centre
    k = np.array([[f, 0, (W - 1) / 2.0], [0, f, (H - 1) / 2.0], [0, 0, 1.0]])
    m = np.column_stack([r[:, 0], r[:, 1], t])
    return k @ m


def render(hm, blur, seed, ss=8):
    """Reflectance of the board (square [i,i+1]x[j,j+1] dark when i+j even, squares -1..cols,
    one square of white margin, grey background beyond), area-sampled ss x ss per pixel."""
    hinv = np.linalg.inv(hm)
    acc = np.zeros((H, W), dtype=np.float64)
    ys, xs = np.mgrid[0:H, 0:W].astype(np.float64)
    for sy in range(ss):
        for sx in range(ss):
            u = xs + (sx + 0.5) / ss - 0.5
            v = ys + (sy + 0.5) / ss - 0.5
            w = hinv[2, 0] * u + hinv[2, 1] * v + hinv[2, 2]
            x = (hinv[0, 0] * u + hinv[0, 1] * v + hinv[0, 2]) / w
            y = (hinv[1, 0] * u + hinv[1, 1] * v + hinv[1, 2]) / w
            inside = (x >= -1) & (y >= -1) & (x < COLS) & (y < ROWS)
            margin = (x >= -2) & (y >= -2) & (x < COLS + 1) & (y < ROWS + 1)
            dark = ((np.floor(x) + np.floor(y)) % 2 == 0) & inside
            refl = np.where(margin, 1.0, 0.6)
            refl = np.where(dark, 0.0, refl)
            acc += refl
    img = 40.0 + 170.0 * acc / (ss * ss)
    img = cv2.GaussianBlur(img, (0, 0), blur, borderType=cv2.BORDER_REPLICATE)
    rng = np.random.default_rng(seed)
    img = img + rng.normal(0.0, 2.0, img.shape)
    return np.clip(np.round(img), 0, 255).astype(np.uint8)


def truth(hm):
    pts = np.array([[i, j, 1.0] for j in range(ROWS) for i in range(COLS)]).T
    p = hm @ pts
    return (p[:2] / p[2]).T


def match_err(est, tru):
    """Per-corner errors with the estimate matched to the truth up to the order (each
    estimated corner to its nearest true corner; a wrong order shows as a large error)."""
    est = np.asarray(est, dtype=np.float64).reshape(-1, 2)
    d = np.linalg.norm(est[:, None, :] - tru[None, :, :], axis=2)
    return d.min(axis=1)


def opencv_classic(img, win, repeats=5):
    best = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        ok, c = cv2.findChessboardCorners(img, (COLS, ROWS), cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE)
        if ok:
            c = cv2.cornerSubPix(img, c, (win, win), (-1, -1), (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 40, 0.001))
        dt = time.perf_counter() - t0
        best = dt if best is None else min(best, dt)
    return ok, (c if ok else None), best


def opencv_sb(img):
    t0 = time.perf_counter()
    ok, c = cv2.findChessboardCornersSB(img, (COLS, ROWS), cv2.CALIB_CB_ACCURACY)
    return ok, (c if ok else None), time.perf_counter() - t0


def etlcal(binary, paths, pattern):
    t0 = time.perf_counter()
    out = subprocess.run([binary, "detect", *paths, "--pattern", pattern, "--json"], capture_output=True, text=True)
    dt = time.perf_counter() - t0
    res = json.loads(out.stdout)["images"]
    return res, dt


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--etlcal", default="target/release/etlcal")
    ap.add_argument("--sb", action="store_true", help="include findChessboardCornersSB (1-2 s per image)")
    ap.add_argument("--real", nargs="*", default=None, help="real images: NAME:CxR pairs")
    ap.add_argument("--square", type=float, default=66.0)
    ap.add_argument("--json", action="store_true", help="print the results as one JSON object instead")
    args = ap.parse_args()
    out = {"opencv": cv2.__version__, "synthetic": {}, "real": []}
    say = (lambda *a: None) if args.json else print
    methods = ["cv 11x11", "cv 21x21"] + (["cv SB accurate"] if args.sb else []) + ["etlcal"]
    say(f"OpenCV {cv2.__version__}, threads {cv2.getNumThreads()}, 2-core machine")
    with tempfile.TemporaryDirectory() as tmp:
        for blur in BLURS:
            errs = {m: [] for m in methods}
            found = {m: 0 for m in methods}
            times = {m: [] for m in methods}
            paths, truths = [], []
            for k, rot in enumerate(POSES):
                hm = homography(rot, args.square)
                img = render(hm, blur, 100 + k)
                p = os.path.join(tmp, f"b{blur}_p{k}.png")
                cv2.imwrite(p, img)
                paths.append(p)
                tru = truth(hm)
                truths.append(tru)
                for m in methods[:-1]:
                    if m == "cv SB accurate":
                        ok, c, dt = opencv_sb(img)
                    else:
                        ok, c, dt = opencv_classic(img, 11 if "11" in m else 21)
                    times[m].append(dt)
                    if ok:
                        found[m] += 1
                        errs[m].extend(match_err(c, tru))
            res, dt = etlcal(args.etlcal, paths, f"{COLS}x{ROWS}")
            times["etlcal"].append(dt / len(paths))
            for r, tru in zip(res, truths):
                if r["found"]:
                    found["etlcal"] += 1
                    errs["etlcal"].extend(match_err(r["corners_px"], tru))
            for m in methods:
                e = np.array(errs[m])
                rms = np.sqrt(np.mean(e**2)) if len(e) else float("nan")
                mx = e.max() if len(e) else float("nan")
                out["synthetic"].setdefault(str(blur), {})[m] = {
                    "found": found[m], "images": len(POSES), "rms_px": float(rms), "max_px": float(mx),
                    "ms_per_image": float(1000 * np.mean(times[m]))}
                say(
                    f"blur {blur}: {m:15s} found {found[m]}/{len(POSES)}  rms {rms:.4f} px  max {mx:.3f} px  "
                    f"time {1000 * np.mean(times[m]):.1f} ms/image"
                )
    here = os.path.dirname(os.path.abspath(__file__))
    fixtures = os.path.join(here, "..", "fixtures", "detect")
    real = args.real
    if real is None:
        real = [os.path.join(fixtures, f) + (":9x6" if f.startswith("stereo") else ":7x7") for f in sorted(os.listdir(fixtures)) if f.endswith(".jpg")]
    groups = {}
    for item in real:
        path, pat = item.rsplit(":", 1)
        groups.setdefault(pat, []).append(path)
    for pat, paths in groups.items():
        c, r = map(int, pat.split("x"))
        for cc, rr, label in [(c, r, "right size"), (c + 1, r, "one column more")]:
            cv_found = 0
            for p in paths:
                g = cv2.imread(p, cv2.IMREAD_GRAYSCALE)
                ok, _ = cv2.findChessboardCorners(g, (cc, rr), cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE)
                cv_found += int(ok)
            res, _ = etlcal(args.etlcal, paths, f"{cc}x{rr}")
            et_found = sum(int(x["found"]) for x in res)
            out["real"].append({"pattern": pat, "asked": f"{cc}x{rr}", "label": label, "images": len(paths),
                                "opencv_found": cv_found, "etlcal_found": et_found})
            say(f"real {pat} boards, asking {cc}x{rr} ({label}): OpenCV found {cv_found}/{len(paths)}, etlcal {et_found}/{len(paths)}")
    if args.json:
        print(json.dumps(out))


if __name__ == "__main__":
    sys.exit(main())
