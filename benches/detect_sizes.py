#!/usr/bin/env python3
"""Checkerboard detection time at three image sizes: etlcal's `detect_corners` against OpenCV's
findChessboardCorners + cornerSubPix 11x11 (the pair the issue names), both in this process,
on the same images, calls interleaved (etlcal, OpenCV, etlcal, ...) so that both see the same
load; the load average is printed with the results.

Images:
  - 640 x 480 / 640 x 512: the real photographs of fixtures/detect (webcam 7x7, stereo 9x6) and
    fixtures/wide/opencv_left (OpenCV's own sample set, 9x6); sources in their SOURCE.md;
  - 1280 x 960 and 1936 x 1458: renders of a 14x12 board (benches/opencv_detect.py's renderer:
    exact homography, 8 x 8 area sampling, blur sigma 1.5 px, noise 2 grey levels) in 3 poses,
    squares of 35-60 px.

ChArUco: etlcal's `detect_corners(image, Board.charuco(...))` against OpenCV 5's
`cv2.aruco.CharucoDetector.detectBoard` on renders of the 12 x 9 board of
benches/charuco_opencv.py (DICT_5X5_100, its renderer) at the three sizes, the whole board in
view, squares of 6 % of the width, 3 poses, blur 1.5 px.

Both checkerboard detectors must find every board (the script exits 1 otherwise); for ChArUco
the corners each finds are printed beside its time. Per image the median of
--repeat calls of each; per size the median over its images, and etlcal / OpenCV.

Then the first call in a fresh process against a warm call (etlcal only; its first call pays
for the allocator's first pages and the thread pool's start), median over --fresh processes.

    /work/venv-bench/bin/python benches/detect_sizes.py [--repeat 21] [--fresh 7] [--json]

(numpy, opencv-python-headless and a release build of the etlcal wheel in that venv:
`maturin build --release --manifest-path crates/etl-py/Cargo.toml`.)
"""
import argparse
import glob
import json
import os
import statistics
import subprocess
import sys
import time

import cv2
import numpy as np

import etlcal

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import charuco_opencv as co  # noqa: E402  (its ChArUco renderer, likewise)
import opencv_detect as od  # noqa: E402  (the renderer, with its size set per run)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 30, 0.01)
RENDER_POSES = [(0.0, 0.0, 0.05), (0.35, -0.25, 0.1), (0.1, 0.45, 2.0)]

FIRST_CALL = r"""
import sys, time, cv2, etlcal
img = cv2.imread(sys.argv[1], cv2.IMREAD_GRAYSCALE)
pattern = tuple(int(v) for v in sys.argv[2].split("x"))
t0 = time.perf_counter(); etlcal.detect_corners(img, pattern); first = time.perf_counter() - t0
warm = []
for _ in range(9):
    t0 = time.perf_counter(); etlcal.detect_corners(img, pattern); warm.append(time.perf_counter() - t0)
warm.sort()
print(first, warm[len(warm) // 2])
"""


def real_images():
    out = []
    for pattern, paths in [((7, 7), "fixtures/detect/webcam_*.jpg"), ((9, 6), "fixtures/detect/stereo_*.jpg"),
                           ((9, 6), "fixtures/wide/opencv_left/*.jpg")]:
        for p in sorted(glob.glob(os.path.join(ROOT, paths))):
            out.append((os.path.relpath(p, ROOT), cv2.imread(p, cv2.IMREAD_GRAYSCALE), pattern))
    return out


def renders(w, h):
    od.W, od.H = w, h
    square = 60.0 * w / 1936.0 * 1.3
    return [(f"render {w}x{h} pose {k}", od.render(od.homography(rot, square), 1.5, 100 + k), (od.COLS, od.ROWS))
            for k, rot in enumerate(RENDER_POSES)]


CHARUCO_POSES = [(0.05, -0.04, 0.03), (0.35, -0.25, 0.1), (-0.3, 0.4, -0.3)]


def charuco_renders(w, h):
    co.W, co.H = w, h
    bits = co.marker_bits(co.SQUARES[0] * co.SQUARES[1] // 2)
    centre = (co.SQUARES[0] * co.SQUARE_MM / 2, co.SQUARES[1] * co.SQUARE_MM / 2)
    return [(f"charuco {w}x{h} pose {k}", co.render(co.homography(rot, 0.06 * w, centre, (0.5, 0.5)), 1.5, 7 + k, bits))
            for k, rot in enumerate(CHARUCO_POSES)]


def measure_charuco(name, img, board, detector, repeat):
    etl, ocv, n = [], [], [0, 0]
    for _ in range(repeat):
        dt, d = timed(lambda: etlcal.detect_corners(img, board))
        etl.append(dt)
        dt, (cc, _, _, _) = timed(lambda: detector.detectBoard(img))
        ocv.append(dt)
        n = [len(d.corners_px), 0 if cc is None else len(cc)]
    return {"image": name, "size": [img.shape[1], img.shape[0]], "etlcal_ms": 1e3 * statistics.median(etl),
            "opencv_ms": 1e3 * statistics.median(ocv), "corners": {"etlcal": n[0], "opencv": n[1]}}


def opencv(img, pattern):
    ok, c = cv2.findChessboardCorners(img, pattern)
    if ok:
        cv2.cornerSubPix(img, c, (11, 11), (-1, -1), CRITERIA)
    return ok


def timed(f):
    t0 = time.perf_counter()
    r = f()
    return time.perf_counter() - t0, r


def measure(name, img, pattern, repeat):
    etl, ocv = [], []
    for _ in range(repeat):
        dt, _ = timed(lambda: etlcal.detect_corners(img, pattern))
        etl.append(dt)
        dt, ok = timed(lambda: opencv(img, pattern))
        if not ok:
            raise SystemExit(f"{name}: OpenCV did not find the board")
        ocv.append(dt)
    return {"image": name, "size": [img.shape[1], img.shape[0]], "etlcal_ms": 1e3 * statistics.median(etl),
            "opencv_ms": 1e3 * statistics.median(ocv)}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=21)
    ap.add_argument("--fresh", type=int, default=7)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    cv2.setNumThreads(2)
    load_before = os.getloadavg()
    groups = {"640 x 480": real_images(), "1280 x 960": renders(1280, 960), "1936 x 1458": renders(1936, 1458)}
    rows = {g: [measure(n, img, p, args.repeat) for n, img, p in imgs] for g, imgs in groups.items()}
    board = etlcal.Board.charuco(co.SQUARES, co.SQUARE_MM, co.MARKER_MM, co.DICT)
    detector = co.opencv_detector()
    for w, h in [(640, 480), (1280, 960), (1936, 1458)]:
        rows[f"ChArUco {w} x {h}"] = [measure_charuco(n, img, board, detector, args.repeat)
                                      for n, img in charuco_renders(w, h)]
    fresh = []
    name, _, pattern = groups["640 x 480"][0]
    for _ in range(args.fresh):
        out = subprocess.run([sys.executable, "-c", FIRST_CALL, os.path.join(ROOT, name), "%dx%d" % pattern],
                             capture_output=True, text=True, check=True)
        first, warm = (float(v) for v in out.stdout.split())
        fresh.append(first / warm)
    result = {"load_average": [load_before, os.getloadavg()], "sizes": {}, "first_call_over_warm": {
        "image": name, "median": statistics.median(fresh), "all": fresh}}
    for g, rs in rows.items():
        e = statistics.median(r["etlcal_ms"] for r in rs)
        o = statistics.median(r["opencv_ms"] for r in rs)
        slower = [r["image"] for r in rs if r["etlcal_ms"] > r["opencv_ms"]]
        result["sizes"][g] = {"images": len(rs), "etlcal_ms": e, "opencv_ms": o, "ratio": e / o,
                              "images_where_etlcal_is_slower": slower, "per_image": rs}
    if args.json:
        print(json.dumps(result, indent=1))
    else:
        print(f"load average before {load_before}, after {os.getloadavg()}")
        for g, s in result["sizes"].items():
            print(f"{g}: {s['images']} images, median etlcal {s['etlcal_ms']:.2f} ms, OpenCV {s['opencv_ms']:.2f} ms, "
                  f"etlcal / OpenCV {s['ratio']:.2f}; etlcal slower on {len(s['images_where_etlcal_is_slower'])}")
            for r in s["per_image"]:
                if "corners" in r:
                    print(f"    {r['image']}: corners etlcal {r['corners']['etlcal']}, OpenCV {r['corners']['opencv']}")
        f = result["first_call_over_warm"]
        print(f"first call in a fresh process / warm call: median {f['median']:.2f} over {len(f['all'])} processes")
    return 0


if __name__ == "__main__":
    sys.exit(main())
