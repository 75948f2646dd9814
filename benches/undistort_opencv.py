#!/usr/bin/env python3
"""Whole-image undistortion, 1936 x 1458 u8, both sides in one process: OpenCV's
cv2.initUndistortRectifyMap + cv2.remap (INTER_LINEAR, BORDER_CONSTANT) against etlcal's
Calibration.undistort_maps and undistort_image (exact maps, bilinear remap), interleaved
rounds, medians and spread.

Like with like:
- OpenCV is given the paper rig's camera at 150 mA in its own model (Calibration.to_opencv:
  exact here up to fx != fy), so both do the same work: a map per pixel and a bilinear
  remap, fresh output arrays each call (as cv2 returns them).
- Bilinear arithmetic: OpenCV 5's remap with float (CV_32FC1) maps interpolates in f32 at
  the exact position, as etlcal does; with fixed-point (CV_16SC2) maps it quantises the
  position to 1/32 px. The acceptance pair is the float one; the fixed one is shown too.
- Threads: OpenCV runs its thread pool (cv2.getNumThreads()), etlcal rayon's, both over
  every core unless --threads N sets both (cv2.setNumThreads, RAYON_NUM_THREADS).
- Time: wall clock per call, and the process's CPU time per call (every thread's), which
  a load from other processes inflates less.
etlcal's undistort_image computes its maps band by band (no full-size maps stored), so it
is "maps + remap" in one call; "etlcal maps + image" times undistort_maps then
undistort_image (the maps twice, as a user who also wants the arrays would).
Needs a release build of the wheel (maturin build --release) and opencv-python-headless.

    python benches/undistort_opencv.py [--rounds 10] [--calls 5] [--threads N] [--json]
"""
import argparse
import json
import os
import statistics
import time


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=10, help="interleaved rounds (each case once a round)")
    ap.add_argument("--calls", type=int, default=5, help="calls per case and round (the round's median)")
    ap.add_argument("--threads", type=int, default=0, help="threads for both sides (0: every core)")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    if args.threads:
        # Before rayon's pool starts (at etlcal's first parallel call).
        os.environ["RAYON_NUM_THREADS"] = str(args.threads)
    import cv2
    import numpy as np

    import etlcal

    if args.threads:
        cv2.setNumThreads(args.threads)
    w, h, e_com_ma = 1936, 1458, 150.0
    cal = etlcal.Calibration.paper_rig()
    k, dist = cal.to_opencv(e_com_ma)
    y, x = np.mgrid[0:h, 0:w]
    img = ((x * 7 + y * 13) % 256).astype(np.uint8)

    def cv_maps(kind):
        return cv2.initUndistortRectifyMap(k, dist, None, k, (w, h), kind)

    f1, f2 = cv_maps(cv2.CV_32FC1)
    q1, q2 = cv_maps(cv2.CV_16SC2)
    cases = {
        "opencv_maps_f32": lambda: cv_maps(cv2.CV_32FC1),
        "opencv_remap_f32_maps": lambda: cv2.remap(img, f1, f2, cv2.INTER_LINEAR),
        "opencv_maps_plus_remap_f32": lambda: cv2.remap(img, *cv_maps(cv2.CV_32FC1), cv2.INTER_LINEAR),
        "opencv_maps_fixed": lambda: cv_maps(cv2.CV_16SC2),
        "opencv_remap_fixed_maps": lambda: cv2.remap(img, q1, q2, cv2.INTER_LINEAR),
        "opencv_maps_plus_remap_fixed": lambda: cv2.remap(img, *cv_maps(cv2.CV_16SC2), cv2.INTER_LINEAR),
        "etlcal_undistort_maps": lambda: cal.undistort_maps(e_com_ma),
        "etlcal_undistort_image": lambda: cal.undistort_image(img, e_com_ma),
        "etlcal_maps_plus_image": lambda: (cal.undistort_maps(e_com_ma), cal.undistort_image(img, e_com_ma)),
    }
    # The same arithmetic as OpenCV's float path: cv2.remap through etlcal's own maps gives
    # etlcal's image up to the rounding of each level (so the race is fair).
    ours_x, ours_y = cal.undistort_maps(e_com_ma)
    diff = np.abs(cal.undistort_image(img, e_com_ma).astype(int) - cv2.remap(img, ours_x, ours_y, cv2.INTER_LINEAR))
    for f in cases.values():  # warm-up: first touch of buffers, thread pools, dispatch
        f()
    wall = {name: [] for name in cases}
    cpu = {name: [] for name in cases}
    for _ in range(args.rounds):
        for name, f in cases.items():
            ws, cs = [], []
            for _ in range(args.calls):
                t0, c0 = time.perf_counter(), time.process_time()
                f()
                ws.append((time.perf_counter() - t0) * 1e3)
                cs.append((time.process_time() - c0) * 1e3)
            wall[name].append(statistics.median(ws))
            cpu[name].append(statistics.median(cs))

    def summary(v):
        return {"median": statistics.median(v), "min": min(v), "max": max(v)}

    res = {
        "wall_ms": {n: summary(v) for n, v in wall.items()},
        "cpu_ms": {n: summary(v) for n, v in cpu.items()},
        "max_abs_diff_levels_vs_cv2_remap_of_our_maps": int(diff.max()),
        "threads_opencv": cv2.getNumThreads(),
        "threads_etlcal": int(os.environ.get("RAYON_NUM_THREADS", os.cpu_count())),
        "cpus": os.cpu_count(),
        "opencv": cv2.__version__,
        "load_average": os.getloadavg(),
    }
    if args.json:
        print(json.dumps(res))
        return
    print(f"{'case':32s} {'wall median [min, max] ms':>28s} {'cpu median [min, max] ms':>28s}")
    for n in cases:
        a, b = res["wall_ms"][n], res["cpu_ms"][n]
        print(
            f"{n:32s} {a['median']:8.2f} [{a['min']:6.2f}, {a['max']:6.2f}]"
            f"      {b['median']:8.2f} [{b['min']:6.2f}, {b['max']:6.2f}]"
        )
    for key in ("max_abs_diff_levels_vs_cv2_remap_of_our_maps", "threads_opencv", "threads_etlcal", "cpus", "opencv", "load_average"):
        print(f"{key}: {res[key]}")


if __name__ == "__main__":
    main()
