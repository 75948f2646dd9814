"""Real ChArUco photographs have no truth: which detector is closer to it? A proxy: a
printed board seen by a lens maps board -> image through a smooth function (a homography
and the lens distortion), so the corners of the more accurate detector lie closer to the
best smooth surface. Fits a 2-D polynomial of degree 3..6 in the board coordinates to each
detector's pixels (the ids both find) and prints the residual RMS per coordinate (px,
corrected for the fitted coefficients) for etlcal and for OpenCV 5's CharucoDetector
(its corners as recorded in fixtures/charuco/opencv.json).

    cargo build --release -p etlcal
    python benches/charuco_photo_smoothness.py [--etlcal target/release/etlcal]

The fit's own misfit (a board not quite flat, a distortion of higher order) adds the same
to both sides; what differs is each detector's noise.
"""
import argparse
import json
import pathlib
import subprocess
import tempfile

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
FIXTURES = ROOT / "fixtures" / "charuco"


def smooth_residual_px(board_mm: np.ndarray, pixels: np.ndarray, degree: int) -> float:
    x = (board_mm[:, 0] - board_mm[:, 0].mean()) / board_mm[:, 0].std()
    y = (board_mm[:, 1] - board_mm[:, 1].mean()) / board_mm[:, 1].std()
    a = np.stack([x**i * y**j for i in range(degree + 1) for j in range(degree + 1 - i)], 1)
    res = np.concatenate([pixels[:, c] - a @ np.linalg.lstsq(a, pixels[:, c], rcond=None)[0] for c in range(2)])
    return float(np.sqrt((res**2).sum() / (res.size - 2 * a.shape[1])))


def etlcal_corners(exe: str, board: dict, image: pathlib.Path) -> dict:
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
        json.dump({"format": "etlcal.board/1", "type": "charuco", **board}, f)
    out = subprocess.run([exe, "detect", "--board", f.name, "--json", str(image)],
                         capture_output=True, text=True, check=True).stdout
    r = json.loads(out)
    r = r[0] if isinstance(r, list) else r
    r = r["images"][0] if "images" in r else r
    return dict(zip(r["ids"], r["corners_px"]))


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--etlcal", default=str(ROOT / "target" / "release" / "etlcal"))
    p.add_argument("--json", action="store_true")
    args = p.parse_args()
    rows = []
    recorded = json.loads((FIXTURES / "opencv.json").read_text())
    if not args.json:
        print(f"OpenCV {recorded['opencv']} (recorded); etlcal {args.etlcal}")
        print("| photograph | corners | etlcal - OpenCV RMS | degree | etlcal residual | OpenCV residual |")
        print("|---|---|---|---|---|---|")
    for im in recorded["images"]:
        if im["source"] != "photograph" or len(im["ids"]) < 30:
            continue
        ours = etlcal_corners(args.etlcal, im["board"], FIXTURES / im["file"])
        theirs = dict(zip(im["ids"], im["corners_px"]))
        board = dict(zip(im["ids"], im["board_mm"]))
        ids = sorted(set(ours) & set(theirs))
        b = np.array([board[i] for i in ids], float)
        po, pc = np.array([ours[i] for i in ids]), np.array([theirs[i] for i in ids])
        diff = float(np.sqrt(((po - pc) ** 2).sum(1).mean()))
        for degree in (3, 4, 5, 6):
            rows.append({"photograph": im["file"], "corners": len(ids), "difference_rms_px": diff, "degree": degree,
                         "etlcal_residual_px": smooth_residual_px(b, po, degree),
                         "opencv_residual_px": smooth_residual_px(b, pc, degree)})
            if args.json:
                continue
            print(f"| {im['file']} | {len(ids)} | {diff:.3f} px | {degree} | "
                  f"{smooth_residual_px(b, po, degree):.4f} px | {smooth_residual_px(b, pc, degree):.4f} px |")
    if args.json:
        print(json.dumps({"opencv": recorded["opencv"], "rows": rows}))


if __name__ == "__main__":
    main()
