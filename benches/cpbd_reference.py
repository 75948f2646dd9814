#!/usr/bin/env python3
"""Reference values for etlcal's sharpness measures, computed by the PyPI package `cpbd`
1.0.7 (CPBD) and by NumPy (the simple measures), and a side-by-side comparison with
`etlcal sharpness` on the same images in the same run.

Setup (a private venv; the library never depends on these):
    python3 -m venv /work/venv-cpbd
    /work/venv-cpbd/bin/pip install cpbd scikit-image scipy numpy imageio

Usage:
    # (re)write fixtures/cpbd/: the synthetic boards and reference.json
    /work/venv-cpbd/bin/python benches/cpbd_reference.py --write-fixtures
    # compare etlcal with the package on every fixture (and any extra PNGs), timing both
    /work/venv-cpbd/bin/python benches/cpbd_reference.py --compare --etlcal target/release/etlcal [extra.png ...]

The natural images come from scikit-image's data directory (see fixtures/cpbd/SOURCE.md);
the boards are drawn here: a checkerboard rotated by 7 degrees (so that its edges are not
pixel-aligned, see SPEC.md A.3), anti-aliased by 8 x 8 supersampling, Gaussian-blurred
and given Gaussian noise with a fixed seed, quantised to 8 bits.
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np
import scipy.ndimage

# cpbd 1.0.7 imports a name SciPy removed in 1.2; it uses it only in its own CLI.
scipy.ndimage.imread = lambda *a, **k: None  # noqa: E731
import cpbd  # noqa: E402
import imageio.v3 as iio  # noqa: E402
import skimage  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FIXTURES = os.path.join(ROOT, "fixtures", "cpbd")
NATURAL = ["camera", "coins", "brick", "gravel"]
# (file stem, blur sigma px, noise sigma DN, width, height)
BOARDS = [
    ("board_s0.5_n0", 0.5, 0.0, 640, 480),
    ("board_s0.5_n2", 0.5, 2.0, 640, 480),
    ("board_s1.0_n1", 1.0, 1.0, 640, 480),
    ("board_s1.5_n2", 1.5, 2.0, 640, 480),
    ("board_s3.0_n2", 3.0, 2.0, 640, 480),
    ("board_s0.3_n3", 0.3, 3.0, 331, 203),
]


def board(sigma, noise, w, h, seed):
    """A rotated checkerboard, dark 40 / light 210, 36 px squares, white margin."""
    ss = 8
    ys, xs = np.mgrid[0:h * ss, 0:w * ss]
    x = (xs + 0.5) / ss - 0.5 - w / 2.0
    y = (ys + 0.5) / ss - 0.5 - h / 2.0
    a = np.deg2rad(7.0)
    u = np.cos(a) * x + np.sin(a) * y
    v = -np.sin(a) * x + np.cos(a) * y
    sq = 36.0
    inside = (np.abs(u) < 6 * sq) & (np.abs(v) < 4.5 * sq)
    dark = ((np.floor(u / sq) + np.floor(v / sq)) % 2 == 0) & inside
    hi = np.where(dark, 40.0, 210.0).reshape(h, ss, w, ss).mean(axis=(1, 3))
    if sigma > 0:
        hi = scipy.ndimage.gaussian_filter(hi, sigma, mode="nearest")
    rng = np.random.default_rng(seed)
    hi = hi + rng.normal(0.0, noise, hi.shape) if noise > 0 else hi
    return np.clip(np.round(hi), 0, 255).astype(np.uint8)


def simple_measures(img):
    """Tenengrad, variance of Laplacian, Brenner, normalised variance as etl-core defines them."""
    f = img.astype(np.float64)
    gx = (f[:-2, 2:] + 2 * f[1:-1, 2:] + f[2:, 2:]) - (f[:-2, :-2] + 2 * f[1:-1, :-2] + f[2:, :-2])
    gy = (f[2:, :-2] + 2 * f[2:, 1:-1] + f[2:, 2:]) - (f[:-2, :-2] + 2 * f[:-2, 1:-1] + f[:-2, 2:])
    lap = f[1:-1, :-2] + f[1:-1, 2:] + f[:-2, 1:-1] + f[2:, 1:-1] - 4 * f[1:-1, 1:-1]
    bren = np.mean((f[:, 2:] - f[:, :-2]) ** 2) + np.mean((f[2:, :] - f[:-2, :]) ** 2)
    return {
        "tenengrad": float(np.mean(gx * gx + gy * gy)),
        "laplacian": float(lap.var()),
        "brenner": float(bren),
        "normvar": float(f.var() / f.mean()),
    }


def write_fixtures():
    os.makedirs(FIXTURES, exist_ok=True)
    data = os.path.join(os.path.dirname(skimage.__file__), "data")
    files = []
    for name in NATURAL:
        img = iio.imread(os.path.join(data, name + ".png"))
        assert img.ndim == 2 and img.dtype == np.uint8
        iio.imwrite(os.path.join(FIXTURES, name + ".png"), img)
        files.append(name + ".png")
    rgb = iio.imread(os.path.join(data, "astronaut.png")).astype(np.float64)
    # ITU-R BT.601 luma, rounded: CPBD needs one 8-bit plane (SPEC.md A.1).
    gray = np.round(rgb[..., 0] * 0.299 + rgb[..., 1] * 0.587 + rgb[..., 2] * 0.114).astype(np.uint8)
    iio.imwrite(os.path.join(FIXTURES, "astronaut_gray.png"), gray)
    files.append("astronaut_gray.png")
    for k, (stem, sigma, noise, w, h) in enumerate(BOARDS):
        iio.imwrite(os.path.join(FIXTURES, stem + ".png"), board(sigma, noise, w, h, 1000 + k))
        files.append(stem + ".png")
    images = []
    for f in files:
        img = iio.imread(os.path.join(FIXTURES, f))
        entry = {"file": f, "width": int(img.shape[1]), "height": int(img.shape[0]), "cpbd": float(cpbd.compute(img))}
        entry.update(simple_measures(img))
        images.append(entry)
        print(f"{f}: cpbd {entry['cpbd']!r}", file=sys.stderr)
    out = {
        "about": "reference sharpness values: cpbd = cpbd.compute(img) of PyPI cpbd 1.0.7 "
        "(scikit-image 0.26, SciPy 1.17, NumPy 2.4); the rest by NumPy with etl-core's definitions "
        "(benches/cpbd_reference.py)",
        "versions": {"cpbd": "1.0.7", "scikit-image": skimage.__version__, "scipy": scipy.__version__,
                     "numpy": np.__version__},
        "images": images,
    }
    with open(os.path.join(FIXTURES, "reference.json"), "w") as fh:
        json.dump(out, fh, indent=1)
        fh.write("\n")


def compare(etlcal, extra):
    ref = json.load(open(os.path.join(FIXTURES, "reference.json")))
    paths = [os.path.join(FIXTURES, e["file"]) for e in ref["images"]] + list(extra)
    t0 = time.perf_counter()
    out = subprocess.run([etlcal, "sharpness", *paths, "--metric", "cpbd", "--json"], check=True,
                         capture_output=True, text=True).stdout
    t_rust = time.perf_counter() - t0
    ours = {os.path.abspath(i["path"]): i["value"] for i in json.loads(out)["images"]}
    worst, t_py = 0.0, 0.0
    print(f"{'image':<28} {'size':>11} {'cpbd (package)':>20} {'etlcal':>20} {'|diff|':>9} {'package s':>9}")
    for p in paths:
        img = iio.imread(p)
        t = time.perf_counter()
        want = float(cpbd.compute(img))
        t_py += time.perf_counter() - t
        got = ours[os.path.abspath(p)]
        worst = max(worst, abs(got - want))
        size = f"{img.shape[1]}x{img.shape[0]}"
        print(f"{os.path.basename(p):<28} {size:>11} {want:>20.17f} {got:>20.17f} {abs(got - want):>9.2e} "
              f"{time.perf_counter() - t:>9.2f}")
    print(f"max |diff| = {worst:.3e} over {len(paths)} images; package {t_py:.1f} s in total, "
          f"etlcal {t_rust:.2f} s in total (one process, decoding included)")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--write-fixtures", action="store_true")
    ap.add_argument("--compare", action="store_true")
    ap.add_argument("--etlcal", default=os.path.join(ROOT, "target", "release", "etlcal"))
    ap.add_argument("extra", nargs="*", help="more 8-bit grayscale PNGs to compare")
    a = ap.parse_args()
    if a.write_fixtures:
        write_fixtures()
    if a.compare:
        compare(a.etlcal, a.extra)


if __name__ == "__main__":
    main()
