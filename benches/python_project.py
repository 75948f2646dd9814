"""Per-point time of `CameraAt.project` against `Calibration.project`, both in one run.

10^5 world points of the paper rig (boards at 40..120 mm, inside the image), projected at
E_com = 150 mA through both paths: `cal.project(world, 150.0)` and
`cal.at_e_com(150.0).project(world)` (the camera built once, as a service holds it; also
`cal.at(E_in, T).project(world)`). Each timing is the best of `--repeat` runs of
`--number` calls (the least disturbed by other jobs), in ns per point; the two paths
alternate within each repeat so that a change of machine load hits both.

    maturin build --release --manifest-path crates/etl-py/Cargo.toml --out /tmp/wheels
    pip install /tmp/wheels/etlcal-*.whl
    python benches/python_project.py

Prints one line per path and the ratio (docs/BENCHMARKS.md, "Python: CameraAt.project").
"""
import argparse
import json
import platform
import timeit

import numpy as np

import etlcal


def world_points(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    z = rng.uniform(40.0, 120.0, n)
    # Within the paper rig's field of view at each depth (about +-0.18 z by +-0.13 z).
    x = rng.uniform(-0.15, 0.15, n) * z + 7.0
    y = rng.uniform(-0.1, 0.1, n) * z + 5.0
    return np.column_stack([x, y, z])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=100_000)
    parser.add_argument("--number", type=int, default=20)
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()

    cal = etlcal.Calibration.paper_rig()
    world = world_points(args.points)
    e_com_ma = 150.0
    at = cal.at(e_com_ma, 30.0)
    paths = {
        "Calibration.project(world, e_com_ma)": lambda: cal.project(world, e_com_ma),
        "CameraAt.project(world) [at(E_in, T)]": lambda: at.project(world),
    }
    # The same pixels to the bit, before timing anything (a build of before issue 26,
    # which had no at_e_com, is measured on the two paths it has).
    assert np.array_equal(cal.project(world, at.e_com_ma), at.project(world))
    if hasattr(cal, "at_e_com"):
        at_e_com = cal.at_e_com(e_com_ma)
        assert np.array_equal(cal.project(world, e_com_ma), at_e_com.project(world))
        paths["CameraAt.project(world) [at_e_com]"] = lambda: at_e_com.project(world)
    best = {name: float("inf") for name in paths}
    for _ in range(args.repeat):
        for name, call in paths.items():
            t = timeit.timeit(call, number=args.number) / args.number
            best[name] = min(best[name], t)
    if args.json:
        print(json.dumps({"points": args.points, "ns_per_point": {n: t / args.points * 1e9 for n, t in best.items()}}))
        return
    print(f"{args.points} points, best of {args.repeat} x {args.number} calls; "
          f"Python {platform.python_version()}, numpy {np.__version__}, etlcal {etlcal.__version__}")
    base = best["Calibration.project(world, e_com_ma)"]
    for name, t in best.items():
        print(f"{name:<40} {t / args.points * 1e9:8.2f} ns/point  ({t / base:.2f}x Calibration.project)")


if __name__ == "__main__":
    main()
