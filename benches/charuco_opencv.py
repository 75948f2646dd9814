#!/usr/bin/env python3
"""ChArUco detection: etlcal vs OpenCV 5's cv2.aruco.CharucoDetector on the same images, in the
same run.

Renders 1936 x 1458 views of a 12 x 9 ChArUco board (1.5 mm squares, 1.1 mm markers,
DICT_5X5_100) whose corners overflow the frame (squares of 150-200 px, a quarter to three
quarters of the board in view), POSES x blur sigma 0.5 / 1.5 / 3 px, dark 40, light 210,
Gaussian noise sigma 2 grey levels, 8-bit PNG, with an independent numpy renderer: the board's
reflectance (OpenCV's layout; the marker bits from cv2.aruco's own dictionary) through an exact
homography, pixels straddling an edge area-sampled 16 x 16, then Gaussian blur and noise. The
truth is the homography applied to the board's corners.

On every image it measures, for OpenCV's CharucoDetector (default parameters) and for etlcal
(`etlcal detect --board FILE --json`): the fraction of the corners inside the frame that are
found, the RMS distance to the truth, wrong ids (a corner farther than 2 px from its id's
truth), and OpenCV's time per image (median and spread over --repeat calls in this process).
etlcal's time is the criterion bench `cargo bench -p etl-image --features bench --bench charuco`, which reads
the very PNGs written here (--out, default target/charuco-views).

    /work/venv/bin/python benches/charuco_opencv.py --etlcal target/release/etlcal [--repeat 7]
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time

import cv2
import numpy as np

W, H = 1936, 1458
SQUARES = (12, 9)
SQUARE_MM, MARKER_MM = 1.5, 1.1
DICT = "DICT_5X5_100"
# (Rodrigues rotation, square size at the board point in view, px; that board point, mm,
# put at the image point (fraction of the frame)).
POSES = [
    ((0.05, -0.04, 0.03), 170.0, (13.5, 10.0), (0.5, 0.5)),
    ((0.35, -0.25, 0.1), 175.0, (4.0, 3.5), (0.5, 0.5)),
    ((-0.3, 0.4, -0.3), 185.0, (14.0, 9.5), (0.45, 0.5)),
    ((0.1, 0.45, 2.0), 165.0, (13.0, 3.0), (0.5, 0.5)),
    ((-0.4, -0.2, 0.6), 190.0, (5.0, 10.0), (0.55, 0.5)),
    ((0.2, 0.3, -1.0), 180.0, (2.0, 2.0), (0.5, 0.5)),
]
BLURS = [0.5, 1.5, 3.0]
# Sharp views of smaller squares, sharpened and JPEG-compressed (--phone).
PHONE_POSES = [
    ((0.2, -0.15, 0.05), 80.0, (9.0, 6.75), (0.5, 0.5)),
    ((-0.3, 0.25, 0.3), 90.0, (9.0, 6.75), (0.5, 0.5)),
]
DARK, LIGHT, NOISE = 40.0, 210.0, 2.0


def homography(rot, square_px, board_pt, image_frac):
    """Board mm -> image px for a pinhole camera (f = 3000 px) looking at the board rotated by
    `rot`, scaled so that a square near `board_pt` is about `square_px` px wide, with
    `board_pt` at `image_frac` of the frame."""
    f = 3000.0
    r, _ = cv2.Rodrigues(np.array(rot, dtype=np.float64))
    z = f * SQUARE_MM / square_px
    k = np.array([[f, 0, (W - 1) / 2.0], [0, f, (H - 1) / 2.0], [0, 0, 1.0]])
    target = np.array([(image_frac[0] * W - (W - 1) / 2.0) / f, (image_frac[1] * H - (H - 1) / 2.0) / f, 1.0]) * z
    t = target - r @ np.array([board_pt[0], board_pt[1], 0.0])
    return k @ np.column_stack([r[:, 0], r[:, 1], t])


def marker_bits(n_markers):
    d = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, DICT))
    n = d.markerSize
    bits = np.zeros((n_markers, n + 2, n + 2), dtype=bool)
    for i in range(n_markers):
        bits[i] = d.generateImageMarker(i, n + 2) > 127
    return bits


def reflectance(x, y, bits):
    """Reflectance at board points (mm): OpenCV's layout (square (0,0) black, markers in the
    white squares row by row), white paper one square beyond the board, grey 0.6 further."""
    cols, rows = SQUARES
    s = SQUARE_MM
    c = np.floor(x / s).astype(np.int64)
    r = np.floor(y / s).astype(np.int64)
    on = (c >= 0) & (r >= 0) & (c < cols) & (r < rows)
    paper = (x >= -s) & (y >= -s) & (x < (cols + 1) * s) & (y < (rows + 1) * s)
    out = np.where(paper, 1.0, 0.6)
    black = on & ((c + r) % 2 == 0)
    out[black] = 0.0
    white = on & ~black
    cells = bits.shape[1]
    cell = MARKER_MM / cells
    inset = 0.5 * (s - MARKER_MM)
    mx = x - c * s - inset
    my = y - r * s - inset
    i = np.floor(mx / cell).astype(np.int64)
    j = np.floor(my / cell).astype(np.int64)
    inm = white & (i >= 0) & (j >= 0) & (i < cells) & (j < cells)
    ids = (r * cols + c) // 2
    out[inm] = bits[ids[inm], j[inm], i[inm]].astype(np.float64)
    return out


def to_board(hinv, u, v):
    w = hinv[2, 0] * u + hinv[2, 1] * v + hinv[2, 2]
    return (hinv[0, 0] * u + hinv[0, 1] * v + hinv[0, 2]) / w, (hinv[1, 0] * u + hinv[1, 1] * v + hinv[1, 2]) / w


def render(hm, blur, seed, bits, ss=16):
    hinv = np.linalg.inv(hm)
    # Reflectance at the pixel corners and centres: a pixel whose five agree is uniform.
    ys, xs = np.mgrid[0 : H + 1, 0 : W + 1].astype(np.float64) - 0.5
    corner = reflectance(*to_board(hinv, xs, ys), bits)
    yc, xc = np.mgrid[0:H, 0:W].astype(np.float64)
    centre = reflectance(*to_board(hinv, xc, yc), bits)
    img = centre.copy()
    mixed = ~(
        (corner[:-1, :-1] == centre) & (corner[1:, :-1] == centre) & (corner[:-1, 1:] == centre) & (corner[1:, 1:] == centre)
    )
    my, mx = np.nonzero(mixed)
    acc = np.zeros(my.shape, dtype=np.float64)
    for sy in range(ss):
        for sx in range(ss):
            u = mx + (sx + 0.5) / ss - 0.5
            v = my + (sy + 0.5) / ss - 0.5
            acc += reflectance(*to_board(hinv, u, v), bits)
    img[my, mx] = acc / (ss * ss)
    img = DARK + (LIGHT - DARK) * img
    img = cv2.GaussianBlur(img, (0, 0), blur, borderType=cv2.BORDER_REPLICATE)
    rng = np.random.default_rng(seed)
    img = img + rng.normal(0.0, NOISE, img.shape)
    return np.clip(np.round(img), 0, 255).astype(np.uint8)


def truth(hm):
    cols, rows = SQUARES
    pts = np.array([[(c + 1) * SQUARE_MM, (r + 1) * SQUARE_MM, 1.0] for r in range(rows - 1) for c in range(cols - 1)]).T
    p = hm @ pts
    return (p[:2] / p[2]).T


def in_frame(t):
    return (t[:, 0] >= 0) & (t[:, 1] >= 0) & (t[:, 0] <= W - 1) & (t[:, 1] <= H - 1)


def score(ids, corners, t):
    """(found in frame, wrong ids, squared errors of the right ones)."""
    inside = in_frame(t)
    found, wrong, sq = 0, 0, []
    for i, p in zip(ids, corners):
        e = np.hypot(*(np.asarray(p) - t[i]))
        if e > 2.0:
            wrong += 1
            continue
        sq.append(e * e)
        found += int(inside[i])
    return found, wrong, sq


def opencv_detector():
    d = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, DICT))
    board = cv2.aruco.CharucoBoard(SQUARES, SQUARE_MM, MARKER_MM, d)
    return cv2.aruco.CharucoDetector(board)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--etlcal", help="the etlcal binary (detect --board)")
    ap.add_argument("--example", help="instead of --etlcal: etl-image's charuco_detect example (same JSON)")
    ap.add_argument("--out", default="target/charuco-views")
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--reuse", action="store_true", help="reuse the PNGs already in --out")
    ap.add_argument("--phone", action="store_true",
                    help="also two sharp views of 80-90 px squares processed as a phone does (unsharp mask 0.8, "
                         "JPEG quality 90)")
    ap.add_argument("--json", action="store_true", help="print the per-blur summary as one JSON object instead")
    args = ap.parse_args()
    say = (lambda *a, **k: None) if args.json else print
    os.makedirs(args.out, exist_ok=True)
    cv2.setNumThreads(2)
    bits = marker_bits(SQUARES[0] * SQUARES[1] // 2)
    board_file = os.path.join(args.out, "board.json")
    with open(board_file, "w") as f:
        json.dump({"format": "etlcal.board/1", "type": "charuco", "squares": list(SQUARES), "square_mm": SQUARE_MM,
                   "marker_mm": MARKER_MM, "dictionary": DICT}, f)
    views = []
    for pi, (rot, spx, bpt, frac) in enumerate(POSES):
        hm = homography(rot, spx, bpt, frac)
        for blur in BLURS:
            path = os.path.join(args.out, f"charuco_pose{pi}_blur{blur}.png")
            if not (args.reuse and os.path.exists(path)):
                cv2.imwrite(path, render(hm, blur, 100 * pi + int(10 * blur), bits))
            views.append((path, pi, blur, truth(hm)))
    if args.phone:
        for k, pose in enumerate(PHONE_POSES):
            hm = homography(*pose)
            path = os.path.join(args.out, f"charuco_phone{k}.jpg")
            if not (args.reuse and os.path.exists(path)):
                img = render(hm, 0.6, 7 + k, bits).astype(np.float64)
                sharp = np.clip(img + 0.8 * (img - cv2.GaussianBlur(img, (0, 0), 1.0)), 0, 255).astype(np.uint8)
                cv2.imwrite(path, sharp, [cv2.IMWRITE_JPEG_QUALITY, 90])
            views.append((path, 10 + k, "phone", truth(hm)))
    detector = opencv_detector()
    results = {}
    etl = {}
    if args.etlcal or args.example:
        cmd = [args.example, board_file] if args.example else [args.etlcal, "detect", "--board", board_file, "--json"]
        out = subprocess.run(cmd + [v[0] for v in views], capture_output=True, text=True)
        for e in json.loads(out.stdout)["images"]:
            etl[e["path"]] = e
    say(f"{'view':<28} {'in frame':>8} | {'OpenCV found':>12} {'RMS px':>8} {'wrong':>5} {'ms med [min-max]':>20} | "
          f"{'etlcal found':>12} {'RMS px':>8} {'wrong':>5}")
    for path, pi, blur, t in views:
        img = cv2.imread(path, cv2.IMREAD_GRAYSCALE)
        times = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            cc, ci, _, _ = detector.detectBoard(img)
            times.append(1e3 * (time.perf_counter() - t0))
        ocv_ids = [] if ci is None else ci.ravel().tolist()
        ocv_pts = [] if cc is None else cc.reshape(-1, 2).tolist()
        n_in = int(in_frame(t).sum())
        o = score(ocv_ids, ocv_pts, t)
        row = {"blur": blur, "in_frame": n_in, "opencv": o, "opencv_ms": times}
        line = (f"{os.path.basename(path):<28} {n_in:>8} | {o[0]:>5} ({100 * o[0] / n_in:4.1f}%) "
                f"{np.sqrt(np.mean(o[2])) if o[2] else float('nan'):>8.4f} {o[1]:>5} "
                f"{statistics.median(times):>7.1f} [{min(times):.1f}-{max(times):.1f}]")
        if path in etl:
            e = etl[path]
            s = score(e.get("ids", []), e.get("corners_px", []), t)
            row["etlcal"] = s
            line += (f" | {s[0]:>5} ({100 * s[0] / n_in:4.1f}%) "
                     f"{np.sqrt(np.mean(s[2])) if s[2] else float('nan'):>8.4f} {s[1]:>5}")
        results[path] = row
        say(line)
    say("\nper blur (all poses):")
    summary = {"opencv": cv2.__version__, "blurs": {}, "views": {}}
    for path, row in results.items():
        summary["views"][os.path.basename(path)] = {"opencv_ms": statistics.median(row["opencv_ms"])}
    for blur in BLURS + (["phone"] if args.phone else []):
        rows = [r for r in results.values() if r["blur"] == blur]
        n_in = sum(r["in_frame"] for r in rows)
        for who in ["opencv", "etlcal"]:
            if who not in rows[0]:
                continue
            found = sum(r[who][0] for r in rows)
            wrong = sum(r[who][1] for r in rows)
            sq = [x for r in rows for x in r[who][2]]
            s = {"found": found, "in_frame": n_in, "wrong_ids": wrong, "rms_px": float(np.sqrt(np.mean(sq))),
                 "max_px": float(np.sqrt(max(sq)))}
            extra = ""
            if who == "opencv":
                med = [statistics.median(r["opencv_ms"]) for r in rows]
                s["ms_median_of_views"] = statistics.median(med)
                extra = f", {statistics.median(med):.1f} ms per image (median of the views' medians; views {min(med):.1f}-{max(med):.1f})"
            summary["blurs"].setdefault(str(blur), {})[who] = s
            say(f"  blur {blur}: {who:<7} {found}/{n_in} = {100 * found / n_in:.1f} % of the in-frame corners, "
                  f"RMS {s['rms_px']:.4f} px, max {s['max_px']:.4f} px, wrong ids {wrong}{extra}")
    if args.json:
        sys.stdout.write(json.dumps(summary) + "\n")


if __name__ == "__main__":
    sys.exit(main())
