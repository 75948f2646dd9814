#!/usr/bin/env python3
"""Why etl-image's FocusMaps computes the maps at each new current instead of interpolating
cached ones: the error of maps cached at n equally spaced currents over the paper
rig's calibrated range 80..225 mA and interpolated linearly in E, against the exact maps, on
every 5th pixel of the 1936 x 1458 image (and its last row and column), at 581 currents.

The maps are the paper's model (Eq. 15-18, Weng's decentering term) with the default output
camera K(E): map = distort_E(x - u0, y - v0) + (u0, v0), evaluated here with numpy in
float64. Prints n and the worst error, px.

    python benches/undistort_interpolation.py
"""
import numpy as np

A = [-0.067, -5.19e-5, 1.09e-8, -0.0077, 0.103, -1.93e-5, 0.11, -0.0257, 5.6e-6]
KF_X = [5380.0, -7.0, 0.02, -3e-5]
KF_Y = [5430.0, -7.0, 0.02, -3e-5]
U0, V0 = 900.0, 550.0
W, H = 1936, 1458
E_LO, E_HI = 80.0, 225.0

XS = np.append(np.arange(0, W, 5.0), W - 1)
YS = np.append(np.arange(0, H, 5.0), H - 1)
X, Y = np.meshgrid(XS, YS)


def maps(e_ma):
    fx, fy = np.polyval(KF_X[::-1], e_ma), np.polyval(KF_Y[::-1], e_ma)
    w = 2.0 / (fx + fy)
    k1 = A[0] * w * w + A[1] * w + A[2]
    p1 = A[3] * w * w + A[4] * w + A[5]
    p2 = A[6] * w * w + A[7] * w + A[8]
    u, v = X - U0, Y - V0
    r2 = u * u + v * v
    return (u + k1 * u * r2 + p1 * (3 * u * u + v * v) + 2 * p2 * u * v + U0,
            v + k1 * v * r2 + 2 * p1 * u * v + p2 * (u * u + 3 * v * v) + V0)


def measure():
    """{cached currents n: worst error in px} over 581 currents."""
    currents = np.linspace(E_LO, E_HI, 581)
    exact = [maps(e) for e in currents]
    out = {}
    for n in [2, 3, 4, 5, 6, 8, 10, 12, 16]:
        nodes = np.linspace(E_LO, E_HI, n)
        cached = [maps(e) for e in nodes]
        step = (E_HI - E_LO) / (n - 1)
        worst = 0.0
        for e, (mx, my) in zip(currents, exact):
            i = min(int((e - E_LO) / step), n - 2)
            t = (e - nodes[i]) / (nodes[i + 1] - nodes[i])
            ix = (1 - t) * cached[i][0] + t * cached[i + 1][0]
            iy = (1 - t) * cached[i][1] + t * cached[i + 1][1]
            worst = max(worst, np.abs(ix - mx).max(), np.abs(iy - my).max())
        out[n] = float(worst)
    return out


def main():
    import json
    import sys

    res = measure()
    if "--json" in sys.argv[1:]:
        print(json.dumps({"worst_px": res}))
        return
    print("cached currents, worst linear-interpolation error (px)")
    for n, worst in res.items():
        print(f"{n:3d} {worst:.4f}")


if __name__ == "__main__":
    main()
