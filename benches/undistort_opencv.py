#!/usr/bin/env python3
"""Whole-image undistortion, 1936 x 1458 u8, in one run: OpenCV's
cv2.initUndistortRectifyMap (CV_32FC1) + cv2.remap (INTER_LINEAR, BORDER_CONSTANT) against
etlcal's Calibration.undistort_maps + undistort_image (the same maps and bilinear remap,
exact for the paper's model), interleaved, median of N runs each.

OpenCV is given the paper rig's camera at 150 mA in its own model (Calibration.to_opencv:
exact here up to fx != fy), so both do the same amount of work: a map per pixel and a
bilinear remap. etlcal's undistort_image computes its maps band by band (no full-size
maps stored); "etlcal maps + remap" times undistort_maps then undistort_image, i.e. the
maps twice, as a user who also wants the arrays would. Needs a release build of the wheel
(maturin build --release) and opencv-python-headless.

    python benches/undistort_opencv.py [--runs 30] [--json]
"""
import argparse
import json
import os
import statistics
import time

import cv2
import numpy as np

import etlcal

W, H = 1936, 1458
E_COM_MA = 150.0


def timed(f, runs):
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        f()
        times.append((time.perf_counter() - t0) * 1e3)
    return statistics.median(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=30)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    cal = etlcal.Calibration.paper_rig()
    k, dist = cal.to_opencv(E_COM_MA)
    y, x = np.mgrid[0:H, 0:W]
    img = ((x * 7 + y * 13) % 256).astype(np.uint8)

    def cv_maps():
        return cv2.initUndistortRectifyMap(k, dist, None, k, (W, H), cv2.CV_32FC1)

    cv_mx, cv_my = cv_maps()

    def cv_both():
        mx, my = cv_maps()
        return cv2.remap(img, mx, my, cv2.INTER_LINEAR)

    def ours_maps():
        return cal.undistort_maps(E_COM_MA)

    def ours_both():
        ours_maps()
        return cal.undistort_image(img, E_COM_MA)

    cases = {
        "opencv_maps_ms": cv_maps,
        "opencv_remap_ms": lambda: cv2.remap(img, cv_mx, cv_my, cv2.INTER_LINEAR),
        "opencv_maps_plus_remap_ms": cv_both,
        "etlcal_undistort_maps_ms": ours_maps,
        "etlcal_undistort_image_ms": lambda: cal.undistort_image(img, E_COM_MA),
        "etlcal_maps_plus_undistort_image_ms": ours_both,
    }
    for f in cases.values():  # warm-up: first-touch of the buffers, thread pools
        f()
    # Interleaved rounds, so that a load change on the shared machine hits both sides.
    samples = {name: [] for name in cases}
    rounds = max(1, args.runs // 5)
    for _ in range(rounds):
        for name, f in cases.items():
            samples[name].append(timed(f, 5))
    res = {name: statistics.median(v) for name, v in samples.items()}
    res.update({"threads_opencv": cv2.getNumThreads(), "cpus": os.cpu_count(), "opencv": cv2.__version__})
    if args.json:
        print(json.dumps(res))
    else:
        for name, v in res.items():
            print(f"{name:40s} {v:.2f}" if isinstance(v, float) else f"{name:40s} {v}")


if __name__ == "__main__":
    main()
