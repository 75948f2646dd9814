"""The command line's cases: fixtures, then every verb with bad numbers, bad input files,
bad outputs, mutated files, hostile environments, misuse, kills and the lens server."""
import copy
import glob
import json
import os
import random
import re
import shutil
import signal
import subprocess
import time
import zlib
from typing import Callable, Dict, List, Optional, Tuple

import battery as B
import hostile_files as H

# ---------------------------------------------------------------------------------------
# Fixtures

CHARUCO_SIM = {"format": "etlcal.board/1", "type": "charuco", "squares": [15, 13], "square_mm": 1.5,
               "marker_mm": 1.1, "dictionary": "DICT_5X5_100"}
CHECKER = {"format": "etlcal.board/1", "type": "checkerboard", "inner_corners": [14, 12], "square_mm": 1.5}
CHECKER96 = {"format": "etlcal.board/1", "type": "checkerboard", "inner_corners": [9, 6], "square_mm": 1.0}
SIMCONFIG = {"format": "etlcal.simconfig/1", "seed": 3, "rig": "paper",
             "noise": {"xy_mm": 0.001, "z_mm": 0.01, "e_ma": 0.4, "px": 0.2, "kf0_rel": 0.003, "pp_px": 1.0},
             "setting_rig": {"e_com_ma": [80, 150, 225], "views_per_setting": 3, "blur_px": 2.0,
                             "aperture_mm": 2.5, "max_tilt_deg": 25.0}}


def build_fixtures(ctx: B.Ctx) -> None:
    if ctx.info.get("built"):
        return
    ctx.info["built"] = True
    fx = ctx.fx

    def run(*argv: str, env: Optional[dict] = None, cwd: str = fx) -> None:
        pr = B.run_proc(ctx, [ctx.binary] + list(argv), cwd, env or {}, 300)
        if pr.rc != 0:
            raise SystemExit(f"battery: building the fixtures failed: etlcal {' '.join(argv)}: "
                             f"exit {pr.rc}: {pr.stderr[-800:]}")

    def dump(name: str, obj) -> None:
        with open(os.path.join(fx, name), "w") as f:
            json.dump(obj, f, indent=1)

    dump("charuco_sim.json", CHARUCO_SIM)
    dump("checker.json", CHECKER)
    dump("checker96.json", CHECKER96)
    dump("simconfig.json", SIMCONFIG)
    run("simulate", "--out", "sim1", "--observations-only", "--seed", "1")
    run("simulate", "--out", "sim2", "--observations-only", "--seed", "2")
    for n in ("observations.json", "a0.json", "truth.json"):
        shutil.copy(os.path.join(fx, "sim1", n), os.path.join(fx, {"observations.json": "obs.json"}.get(n, n)))
    shutil.copy(os.path.join(fx, "sim2", "observations.json"), os.path.join(fx, "obs2.json"))
    run("calibrate", "--observations", "obs.json", "--thermal", "paper", "--out", "cal.json", "--quiet")
    run("calibrate", "--observations", "obs.json", "--out", "cal_ecom.json", "--quiet")
    run("calibrate", "--observations", "obs.json", "--thermal", "paper", "--estimator", "paper",
        "--out", "cal_paper.json", "--quiet")
    run("render", "--out", "img.png")
    run("render", "--out", "img2.png", "--seed", "2")
    run("render", "--out", "img16.png", "--bit-depth", "16")
    run("render", "--out", "img.jpg")
    run("render", "--out", "img.tif")
    run("render", "--out", "rcharuco.png", "--board", "charuco_sim.json")
    run("thermal", "calibrate", "--virtual", "--quick", "--out", "thermal.json", "--table", "table.csv", "--quiet")
    for k in range(1, 6):
        shutil.copy(os.path.join(B.REPO, "fixtures", "zhang", f"left0{k}.jpg"), os.path.join(fx, f"z{k}.jpg"))
    shutil.copy(os.path.join(B.REPO, "fixtures", "optics", "cooke-16mm-centred.json"), os.path.join(fx, "optics.json"))
    # The images' dataset: its images stay in the fixtures (absolute paths), checked at the end.
    run("simulate", "--out", "simimg", "--quiet")
    with open(os.path.join(fx, "simimg", "dataset.json")) as f:
        ds = json.load(f)
    for key in ("views", "offstate_views", "setting_views"):
        for v in ds.get(key, []):
            v["image"] = os.path.join(fx, "simimg", v["image"])
    dump("dataset.json", ds)
    # Earlier sets, copied where a case replaces one.
    env0 = {"SOURCE_DATE_EPOCH": "0"}
    run("simulate", "--out", "set_sim", "--observations-only", "--seed", "5")
    run("report", "--calibration", "cal_paper.json", "--out", "set_rep", env=env0)
    run("study", "fig5", "--out", "set_study", "--quiet")
    run("demo", "--no-images", "--out", "set_demo", "--seed", "2", "--quiet", env=env0)
    run("undistort", "img2.png", "--calibration", "cal.json", "--e-in", "150", "--t", "31", "--out", "set_und")
    # Timings of the kill cases' writers, measured once.
    ctx.info["fixtures"] = sorted(os.listdir(fx))


# ---------------------------------------------------------------------------------------
# The valid commands every family mutates

SDE = {"SOURCE_DATE_EPOCH": "0"}

# name: (argv, fixture files copied in, outputs, env, timeout)
BASES: Dict[str, tuple] = {
    "simulate": (["simulate", "--out", "out", "--observations-only"], [], ["out"], {}, None),
    "simulate-images": (["simulate", "--out", "out", "--quiet"], [], ["out"], {}, 60),
    "simulate-config": (["simulate", "--config", "simconfig.json", "--out", "out", "--observations-only"],
                        ["simconfig.json"], ["out"], {}, None),
    "simulate-optics": (["simulate", "--optics", "optics.json", "--out", "out", "--quiet"], ["optics.json"], ["out"], {}, 60),
    "calibrate": (["calibrate", "--observations", "obs.json", "--out", "cal_out.json"], ["obs.json"],
                  ["cal_out.json"], {}, None),
    "calibrate-full": (["calibrate", "--observations", "obs.json", "--a0", "a0.json", "--thermal", "thermal.json",
                        "--out", "cal_out.json"], ["obs.json", "a0.json", "thermal.json"], ["cal_out.json"], {}, None),
    "calibrate-dataset": (["calibrate", "--dataset", "dataset.json", "--out", "cal_out.json", "--observations-out",
                           "obs_out.json", "--quiet"], ["dataset.json"], ["cal_out.json", "obs_out.json"], {}, 60),
    "zhang": (["zhang", "z1.jpg", "z2.jpg", "z3.jpg", "z4.jpg", "z5.jpg", "--pattern", "9x6", "--square", "1"],
              ["z1.jpg", "z2.jpg", "z3.jpg", "z4.jpg", "z5.jpg"], [], {}, None),
    "zhang-board": (["zhang", "z1.jpg", "z2.jpg", "z3.jpg", "z4.jpg", "z5.jpg", "--board", "checker96.json",
                     "--model", "opencv"], ["z1.jpg", "z2.jpg", "z3.jpg", "z4.jpg", "z5.jpg", "checker96.json"], [], {}, None),
    "stereo": (["stereo", "z1.jpg", "z2.jpg", "z3.jpg", "z4.jpg", "--right", "z2.jpg", "z3.jpg", "z4.jpg", "z5.jpg",
                "--pattern", "9x6", "--square", "1", "--model", "opencv"],
               ["z1.jpg", "z2.jpg", "z3.jpg", "z4.jpg", "z5.jpg"], [], {}, None),
    "report": (["report", "--calibration", "cal.json", "--observations", "obs.json", "--out", "rep"],
               ["cal.json", "obs.json"], ["rep"], SDE, None),
    "report-thermal": (["report", "--calibration", "cal_ecom.json", "--thermal", "thermal.json", "--out", "rep"],
                       ["cal_ecom.json", "thermal.json"], ["rep"], SDE, None),
    "export": (["export", "--calibration", "cal.json", "--e-in", "150", "--t", "31", "--format", "opencv",
                "--out", "cam.yaml"], ["cal.json"], ["cam.yaml"], {}, None),
    "export-ecom": (["export", "--calibration", "cal_ecom.json", "--e-com", "150", "--format", "ros", "--out",
                     "cam.yaml"], ["cal_ecom.json"], ["cam.yaml"], {}, None),
    "export-mrcal": (["export", "--calibration", "cal.json", "--e-in", "150", "--t", "31", "--format", "mrcal",
                      "--out", "cam.cameramodel"], ["cal.json"], ["cam.cameramodel"], {}, None),
    "measure": (["measure", "--calibration", "cal.json", "--e-in", "150", "--t", "31", "img.png", "img2.png",
                 "--pattern", "14x12", "--square", "1.5"], ["cal.json", "img.png", "img2.png"], [], {}, None),
    "measure-board": (["measure", "--calibration", "cal.json", "--e-in", "150", "--t", "31", "rcharuco.png",
                       "rcharuco.png", "--board", "charuco_sim.json"], ["cal.json", "rcharuco.png", "charuco_sim.json"],
                      [], {}, None),
    "undistort": (["undistort", "img.png", "--calibration", "cal.json", "--e-in", "150", "--t", "31", "--out", "und"],
                  ["img.png", "cal.json"], ["und"], {}, None),
    "undistort-ecom": (["undistort", "img.png", "--calibration", "cal_ecom.json", "--e-com", "150", "--out", "und"],
                       ["img.png", "cal_ecom.json"], ["und"], {}, None),
    "diff": (["diff", "cal.json", "cal_paper.json", "--e-in", "150", "--t", "31", "--grid", "16x12", "--heatmap",
              "heat.png"], ["cal.json", "cal_paper.json"], ["heat.png"], {}, None),
    "diff-ecom": (["diff", "cal_ecom.json", "cal_ecom.json", "--e-com", "150", "--grid", "8x6"], ["cal_ecom.json"],
                  [], {}, None),
    "focus": (["focus", "--calibration", "cal.json", "--distance-mm", "80", "--t", "31"], ["cal.json"], [], {}, None),
    "board": (["board", "--board", "charuco_sim.json", "--out", "board.png", "--dpi", "300"], ["charuco_sim.json"],
              ["board.png"], {}, None),
    "board-svg": (["board", "--board", "charuco_sim.json", "--out", "board.svg"], ["charuco_sim.json"],
                  ["board.svg"], {}, None),
    "detect": (["detect", "img.png", "--pattern", "14x12"], ["img.png"], [], {}, None),
    "detect-checker": (["detect", "img.png", "--board", "checker.json"], ["img.png", "checker.json"], [], {}, None),
    "detect-board": (["detect", "rcharuco.png", "--board", "charuco_sim.json"], ["rcharuco.png", "charuco_sim.json"],
                     [], {}, None),
    "render": (["render", "--out", "r.png"], [], ["r.png", "r.png.corners.json"], {}, None),
    "render-board": (["render", "--out", "r.png", "--board", "charuco_sim.json"], ["charuco_sim.json"],
                     ["r.png", "r.png.corners.json"], {}, None),
    "sharpness": (["sharpness", "img.png", "--metric", "tenengrad"], ["img.png"], [], {}, None),
    "sharpness-cpbd": (["sharpness", "img.png"], ["img.png"], [], {}, None),
    "thermal-eval": (["thermal", "eval", "--e-in", "150", "--t", "31", "--thermal", "thermal.json"],
                     ["thermal.json"], [], {}, None),
    "thermal-eval-paper": (["thermal", "eval", "--e-in", "150", "--t", "31", "--thermal", "paper"], [], [], {}, None),
    "thermal-fit": (["thermal", "fit", "table.csv", "--out", "th_out.json"], ["table.csv"], ["th_out.json"], {}, None),
    "thermal-calibrate": (["thermal", "calibrate", "--virtual", "--quick", "--out", "tc.json", "--quiet"], [],
                          ["tc.json", "tc.csv"], {}, 60),
    "study": (["study", "fig5", "--out", "st"], [], ["st"], {}, None),
    "study-fig6": (["study", "fig6", "--trials", "1", "--out", "st", "--quiet"], [], ["st"], {}, 60),
    "model": (["model", "--from", "0", "--to", "250", "--step", "10"], [], [], {}, None),
    "model-fit": (["model", "--fit-degrees", "--from", "0", "--to", "250", "--step", "1"], [], [], {}, None),
    "lens-info": (["lens", "--virtual", "info"], [], [], {}, None),
    "lens-set": (["lens", "--virtual", "set-current", "100"], [], [], {}, None),
    "lens-get": (["lens", "--virtual", "get-current"], [], [], {}, None),
    "lens-temp": (["lens", "--virtual", "temperature"], [], [], {}, None),
    "lens-hold": (["lens", "--virtual", "hold", "--e-com", "120", "--thermal", "paper", "--duration", "0.3"],
                  [], [], {}, None),
    "lens-hold-file": (["lens", "--virtual", "hold", "--e-com", "120", "--thermal", "thermal.json", "--duration",
                        "0.3"], ["thermal.json"], [], {}, None),
    "demo": (["demo", "--no-images", "--out", "demo", "--quiet"], [], ["demo"], SDE, 60),
}
# the bases worth keeping in the CI subset's baselines
FAST_BASES = set(BASES) - {"simulate-images", "simulate-optics", "thermal-calibrate", "study-fig6"}


def copier(ctx: B.Ctx, files: List[str], extra: Optional[Callable[[str], None]] = None) -> Callable[[str], None]:
    def setup(d: str) -> None:
        for f in files:
            shutil.copy(ctx.fxp(f), os.path.join(d, f))
        if extra:
            extra(d)

    return setup


def chain(*fs: Optional[Callable[[str], None]]) -> Callable[[str], None]:
    def setup(d: str) -> None:
        for f in fs:
            if f:
                f(d)

    return setup


def set_flag(argv: List[str], flag: str, value, after: Optional[str] = None) -> List[str]:
    """argv with flag's value replaced (or the flag appended); '@N' is the N-th argv token."""
    argv = list(argv)
    if flag.startswith("@"):
        argv[int(flag[1:])] = value
        return argv
    if flag in argv:
        argv[argv.index(flag) + 1] = value
    else:
        argv += [flag, value]
    return argv


def replace_token(argv: List[str], old: str, new) -> List[str]:
    """argv with the token `old` replaced: the one that is a flag's value if there is one
    (a verb can share its name with its output folder: `demo --out demo`), else the first."""
    out = list(argv)
    idx = [i for i, a in enumerate(out) if a == old]
    flagged = [i for i in idx if i > 0 and out[i - 1].startswith("--")]
    out[(flagged or idx)[0]] = new
    return out


def crc(s: str) -> int:
    return zlib.crc32(s.encode())


# ---------------------------------------------------------------------------------------
# Bad numbers

VALUES = [("NaN", "NaN"), ("nan", "nan"), ("inf", "inf"), ("-inf", "-inf"), ("1e308", "1e308"),
          ("-1e308", "-1e308"), ("1e999", "1e999"), ("0", "0"), ("-0", "-0"), ("-1", "-1"), ("1e-320", "1e-320"),
          ("u64max", "18446744073709551615"), ("-2^64", "-18446744073709551616"), ("empty", ""), ("text", "text"),
          ("space5", " 5"), ("hex", "0x10"), ("comma", "1,5"), ("300digits", "1" + "0" * 300), ("1e20", "1e20")]
FAST_VALUES = {"NaN", "1e308", "empty", "-1", "u64max", "1e-320"}
SMALL = {"0", "-0", "-1", "1e-320", "space5"}
BAD_FOR = {
    # category: labels that must be refused
    "b": {l for l, _ in VALUES} - SMALL,
    "seed": {l for l, _ in VALUES} - {"0", "-0", "u64max"},
    "count": {l for l, _ in VALUES} - {"-0", "space5"},
    "clamp": {"NaN", "nan", "inf", "-inf", "1e999", "empty", "text", "hex", "comma"},
    # positive without a documented bound: large finite values may be taken
    "posu": {l for l, _ in VALUES} - {"space5", "1e-320", "1e20", "u64max", "300digits"},
    "posu-any": {l for l, _ in VALUES} - {"space5", "1e-320", "1e20", "u64max", "300digits", "1e308"},
    "pos": {l for l, _ in VALUES} - {"space5", "1e-320"},  # a positive quantity: 0 and -1 refused
}

# (base, flag, category); a few bases are slow: their values are cut to the fast ones
NUMERIC = [
    ("simulate", "--seed", "seed"), ("simulate", "--stage-noise-um", "b"), ("simulate", "--current-noise-ma", "b"),
    ("simulate", "--pixel-noise-px", "b"),
    ("simulate-optics", "--pixel-noise-px", "b"), ("simulate-optics", "--seed", "seed"),
    ("calibrate", "--sigma-z-um", "pos"), ("calibrate", "--sigma-z-mm", "pos"), ("calibrate", "--sigma-e-ma", "pos"),
    ("calibrate", "--sigma-px", "pos"), ("calibrate", "--huber-px", "pos"),
    ("calibrate+robust", "--robust-k-px", "pos"),
    ("zhang", "--square", "posu"), ("stereo", "--square", "posu"),
    ("export", "--e-in", "b"), ("export", "--t", "b"), ("export-ecom", "--e-com", "b"),
    ("measure", "--e-in", "b"), ("measure", "--t", "b"), ("measure", "--square", "posu"),
    ("undistort", "--e-in", "b"), ("undistort", "--t", "b"), ("undistort-ecom", "--e-com", "b"),
    ("diff", "--e-in", "b"), ("diff", "--t", "b"), ("diff-ecom", "--e-com", "b"),
    ("focus", "--distance-mm", "b"), ("focus", "--t", "b"),
    ("board", "--dpi", "pos"), ("board", "--margin-mm", "b"), ("board-svg", "--margin-mm", "b"),
    ("render", "--e-com", "b"), ("render", "--z-mm", "b"), ("render", "--square", "pos"),
    ("render", "--aperture-mm", "b"), ("render", "--blur-px", "b"), ("render", "--noise", "b"),
    ("render", "--bit-depth", "count"), ("render", "--seed", "seed"),
    ("thermal-eval", "--e-in", "b"), ("thermal-eval", "--t", "b"), ("thermal-eval-paper", "--e-in", "b"),
    ("thermal-eval-paper", "--t", "b"),
    ("thermal-calibrate", "--search-ma", "pos"),
    ("study-fig6", "--trials", "count"), ("study-fig6", "--seed", "seed"),
    ("model", "--from", "b"), ("model", "--to", "b"), ("model", "--step", "posu-any"),
    ("model-fit", "--step", "pos"),
    ("lens-set", "@3", "clamp"), ("lens-info", "--timeout-ms", "count"),
    ("lens-hold", "--e-com", "b"), ("lens-hold", "--rate", "b"), ("lens-hold", "--duration", "b"),
    ("lens-hold", "--warm", "b"), ("lens-hold", "--time-scale", "pos"),
    ("demo", "--seed", "seed"), ("demo", "--stage-noise-um", "b"),
]
SLOW_BASES = {"simulate-optics", "thermal-calibrate", "study-fig6", "simulate-images"}


def base_of(name: str):
    if name == "calibrate+robust":
        argv, files, outs, env, to = BASES["calibrate"]
        return argv + ["--robust", "huber"], files, outs, env, to
    return BASES[name]


def numeric_cases(ctx: B.Ctx) -> List[B.Case]:
    out = []
    for base, flag, cat in NUMERIC:
        argv, files, outs, env, to = base_of(base)
        for label, tok in VALUES:
            if base in SLOW_BASES and label not in FAST_VALUES | {"inf", "0"}:
                continue
            a = set_flag(argv, flag, tok)
            expect = "refuse" if label in BAD_FOR[cat] else "any"
            name = f"cli-num/{base}/{flag.lstrip('-') if not flag.startswith('@') else 'value'}={label}"
            out.append(B.Case(name, "cli-number", "cli", setup=copier(ctx, files), argv=a, env=dict(env),
                              expect=expect, outputs=list(outs), timeout=to,
                              fast=(label in FAST_VALUES and base not in SLOW_BASES and crc(name) % 3 == 0)))
    # Patterns, grids and degrees: numbers in a word
    patterns = ["0x0", "1x1", "2x2", "3x3", "999x999", "1000x1000", "14x", "x12", "14x12x1", "-3x4", "14X12",
                "1e1x12", "18446744073709551615x3", "4294967297x3", "\u0663x\u0664", " 14x12", "", "14 x 12"]
    ok_patterns = {"3x3", "999x999", "1000x1000", "14X12", " 14x12", "2x2", "14 x 12"}
    for base in ("detect", "measure", "zhang", "render"):
        argv, files, outs, env, to = BASES[base]
        for pat in patterns:
            if base == "render" and pat in ("999x999", "1000x1000"):
                continue  # a 1.5 m board in front of the rig: valid, only slow
            a = set_flag(argv, "--pattern", pat)
            name = f"cli-pattern/{base}/pattern={pat!r}"
            out.append(B.Case(name, "cli-number", "cli", setup=copier(ctx, files), argv=a, env=dict(env),
                              expect="any" if pat in ok_patterns else "refuse", outputs=list(outs), timeout=to,
                              fast=pat in ("0x0", "18446744073709551615x3")))
    grids = ["0x0", "1x1", "1000x1000", "1001x1", "-1x5", "x", "", "16x", "x12", "16x12x1", "1e3x2",
             "18446744073709551615x2", "16X12", "16*12", "NaNxNaN", "4294967296x1"]
    for g in grids:
        argv, files, outs, env, to = BASES["diff"]
        name = f"cli-grid/diff/grid={g!r}"
        out.append(B.Case(name, "cli-number", "cli", setup=copier(ctx, files), argv=set_flag(argv, "--grid", g),
                          expect="any" if g in ("1x1", "1000x1000", "16X12") else "refuse", outputs=list(outs),
                          fast=g in ("0x0", "4294967296x1")))
    for deg in ["0", "6", "-1", "auto", "AUTO", "1e308", "NaN", "", "3.0", "18446744073709551615", "text", "5"]:
        argv, files, outs, env, to = BASES["calibrate"]
        name = f"cli-num/calibrate/focal-degree={deg!r}"
        out.append(B.Case(name, "cli-number", "cli", setup=copier(ctx, files),
                          argv=set_flag(argv, "--focal-degree", deg),
                          expect="any" if deg in ("auto", "5", "AUTO") else "refuse", outputs=list(outs),
                          fast=deg == "18446744073709551615"))
    return out


# ---------------------------------------------------------------------------------------
# Bad input files

# (base, the token naming the file, its fixture, another format's fixture, file type)
INPUTS = [
    ("calibrate", "obs.json", "obs.json", "cal.json", "json"),
    ("calibrate-full", "a0.json", "a0.json", "thermal.json", "json"),
    ("calibrate-full", "thermal.json", "thermal.json", "a0.json", "json"),
    ("calibrate-dataset", "dataset.json", "dataset.json", "obs.json", "json"),
    ("simulate-config", "simconfig.json", "simconfig.json", "cal.json", "json"),
    ("simulate-optics", "optics.json", "optics.json", "a0.json", "json"),
    ("zhang", "z1.jpg", "z1.jpg", None, "image"),
    ("zhang-board", "checker96.json", "checker96.json", "thermal.json", "json"),
    ("report", "cal.json", "cal.json", "obs.json", "json"),
    ("report", "obs.json", "obs.json", "cal.json", "json"),
    ("report-thermal", "thermal.json", "thermal.json", "charuco_sim.json", "json"),
    ("export", "cal.json", "cal.json", "a0.json", "json"),
    ("measure", "cal.json", "cal.json", "truth.json", "json"),
    ("measure", "img.png", "img.png", None, "image"),
    ("measure-board", "charuco_sim.json", "charuco_sim.json", "checker.json", "json"),
    ("undistort", "img.png", "img.png", None, "image"),
    ("undistort", "cal.json", "cal.json", "thermal.json", "json"),
    ("diff", "cal.json", "cal.json", "a0.json", "json"),
    ("diff", "cal_paper.json", "cal_paper.json", "obs.json", "json"),
    ("focus", "cal.json", "cal.json", "cal_ecom.json", "json"),
    ("board", "charuco_sim.json", "charuco_sim.json", "thermal.json", "json"),
    ("detect", "img.png", "img.png", None, "image"),
    ("detect-board", "charuco_sim.json", "charuco_sim.json", "a0.json", "json"),
    ("detect-board", "rcharuco.png", "rcharuco.png", None, "image"),
    ("render-board", "charuco_sim.json", "charuco_sim.json", "obs.json", "json"),
    ("sharpness", "img.png", "img.png", None, "image"),
    ("sharpness-cpbd", "img.png", "img.png", None, "image"),
    ("thermal-eval", "thermal.json", "thermal.json", "charuco_sim.json", "json"),
    ("thermal-fit", "table.csv", "table.csv", "cal.json", "csv"),
    ("lens-hold-file", "thermal.json", "thermal.json", "cal.json", "json"),
]
KINDS = {"json": H.JSON_KINDS, "image": H.IMAGE_KINDS, "csv": H.CSV_KINDS}
# kinds too slow for a base that already takes seconds
SLOW_INPUT_OK = {"missing", "directory", "fifo", "/dev/zero", "truncated", "random", "wrong-format", "symlink-loop",
                 "sparse-1g", "deep-nest", "empty"}


def input_cases(ctx: B.Ctx) -> List[B.Case]:
    out = []
    seed = ctx.args.seed
    for base, tok, src, other, typ in INPUTS:
        argv, files, outs, env, to = BASES[base]
        for kind in KINDS[typ]:
            if base in SLOW_BASES and kind not in SLOW_INPUT_OK:
                continue
            if kind == "wrong-format" and other is None:
                continue
            if kind in ("png-bad-crc",) and not src.endswith(".png"):
                continue
            setup, arg = H.input_setup(kind, tok, src, other or src, seed, ctx.fx)
            a = replace_token(argv, tok, arg)
            expect = "any" if kind in H.MAY_SUCCEED else "refuse"
            if base == "diff" and kind == "wrong-format" and other == "obs.json":
                expect = "refuse"
            name = f"cli-input/{base}/{tok}={kind}"
            out.append(B.Case(name, "cli-input", "cli", setup=chain(copier(ctx, files), setup), argv=a,
                              env=dict(env), expect=expect, outputs=list(outs), timeout=to,
                              fast=kind in H.FAST_INPUT_KINDS and base not in SLOW_BASES and crc(name) % 2 == 0))
    # a dataset whose first image is hostile
    for kind in H.IMAGE_KINDS:
        if kind.startswith("/dev/") and kind != "/dev/zero":
            continue

        def setup(d: str, kind=kind) -> None:
            H.dataset_with_image(kind, d, ctx.fx, seed)

        argv, files, outs, env, to = BASES["calibrate-dataset"]
        name = f"cli-input/calibrate-dataset/view-image={kind}"
        # a view whose image cannot be read is skipped (named on stderr): success is fine
        out.append(B.Case(name, "cli-input", "cli", setup=setup, argv=argv, expect="any", outputs=list(outs),
                          timeout=to, fast=kind in ("fifo", "png-huge-header")))
    # lens ports
    for kind in ["missing", "directory", "fifo", "chardev", "empty", "random", "symlink-loop", "dangling",
                 "/dev/zero", "/dev/null", "/dev/stdin", "/dev/tty-nonexistent"]:
        for sub in (["info"], ["set-current", "100"], ["hold", "--e-com", "120", "--thermal", "paper", "--duration", "0.3"]):
            if kind.startswith("/dev/"):
                setup, arg = (lambda d: None), kind
            else:
                setup, arg = H.input_setup(kind, "port", "obs.json", "obs.json", seed, ctx.fx)
            name = f"cli-input/lens-{sub[0]}/port={kind}"
            out.append(B.Case(name, "cli-input", "cli", setup=setup,
                              argv=["lens", "--port", arg, "--timeout-ms", "200"] + sub, expect="refuse",
                              fast=kind in ("fifo", "/dev/zero") and sub[0] == "info"))
    return out


# ---------------------------------------------------------------------------------------
# Bad outputs

# (base, output token, file|dir, an input of the command, earlier set fixture)
OUTPUTS = [
    ("calibrate", "cal_out.json", "file", "obs.json", None),
    ("calibrate-dataset", "cal_out.json", "file", "dataset.json", None),
    ("calibrate-dataset", "obs_out.json", "file", "dataset.json", None),
    ("export", "cam.yaml", "file", "cal.json", None),
    ("export-mrcal", "cam.cameramodel", "file", "cal.json", None),
    ("diff", "heat.png", "file", "cal.json", None),
    ("board", "board.png", "file", "charuco_sim.json", None),
    ("board-svg", "board.svg", "file", "charuco_sim.json", None),
    ("render", "r.png", "file", None, None),
    ("render-board", "r.png", "file", "charuco_sim.json", None),
    ("thermal-fit", "th_out.json", "file", "table.csv", None),
    ("thermal-calibrate", "tc.json", "file", None, None),
    ("simulate", "out", "dir", None, "set_sim"),
    ("simulate-config", "out", "dir", "simconfig.json", "set_sim"),
    ("report", "rep", "dir", "cal.json", "set_rep"),
    ("undistort", "und", "dir", "img.png", "set_und"),
    ("study", "st", "dir", None, "set_study"),
    ("demo", "demo", "dir", None, "set_demo"),
]
SLOW_OUT_OK = {"same-as-input", "fifo", "directory", "readonly", "earlier", "new", "file", "foreign", "earlier-set"}


def output_cases(ctx: B.Ctx) -> List[B.Case]:
    out = []
    seed = ctx.args.seed
    for base, tok, typ, an_input, earlier in OUTPUTS:
        argv, files, outs, env, to = BASES[base]
        kinds = H.FILE_OUT_KINDS if typ == "file" else H.DIR_OUT_KINDS
        for kind in kinds:
            if base in SLOW_BASES and kind not in SLOW_OUT_OK:
                continue
            if kind in ("same-as-input", "same-as-input-dotted", "symlink-to-input", "hardlink-to-input",
                        "input-as-dir") and an_input is None:
                continue
            def setup(d: str, kind=kind, typ=typ, tok=tok, an_input=an_input, earlier=earlier) -> None:
                if typ == "file":
                    H.make_file_output(kind, d, tok, an_input, seed)
                else:
                    H.make_dir_output(kind, d, tok, an_input, ctx.fxp(earlier) if earlier else None, seed)

            # The argument and the allowed outputs depend only on the kind: compute them on a
            # scratch folder now, so that the case is fully known before it runs.
            arg, allowed, expect = _dry_output(kind, typ, tok, an_input, earlier, ctx, seed)
            a = replace_token(argv, tok, arg)
            others = [o for o in outs if o != tok and not (tok == "r.png" and o == "r.png.corners.json")]
            if tok == "r.png":
                # render's corners follow the image's name
                allowed = allowed + [x + ".corners.json" for x in allowed]
            protect = []
            if base == "undistort" and kind == "same-as-input-dir":
                expect = "refuse"  # und/ = . holds img.png: the output would be the input
            if typ == "dir" and base in ("undistort", "study") and kind == "member-name-no-marker":
                expect = "any"
            if typ == "dir" and base in ("undistort", "study") and kind in ("foreign", "only-foreign"):
                # not set folders: files are added beside the user's, which must stay
                expect = "any"
                allowed = [tok]
                protect = [os.path.join(tok, "my-notes.txt"), os.path.join(tok, "my-file.json")]
            name = f"cli-output/{base}/{tok}={kind}"
            out.append(B.Case(name, "cli-output", "cli", setup=chain(copier(ctx, files), setup), argv=a,
                              env=dict(env), expect=expect, outputs=allowed + others, timeout=to, protect=protect,
                              fast=(kind in H.FAST_OUT_KINDS or kind in H.FAST_DIR_KINDS) and base not in SLOW_BASES
                              and crc(name) % 2 == 0))
    # render: the corners file is the one that cannot be written
    for kind in ["directory", "fifo", "readonly", "chardev", "dangling", "symlink-loop"]:
        def setup(d: str, kind=kind) -> None:
            with open(os.path.join(d, "r.png"), "wb") as f:
                f.write(b"the earlier image\n")
            with open(os.path.join(d, "keep.json"), "w") as f:
                f.write("{}\n")
            H.make_file_output(kind, d, "r.png.corners.json", "keep.json", seed)

        name = f"cli-output/render/corners={kind}"
        out.append(B.Case(name, "cli-output", "cli", setup=setup, argv=["render", "--out", "r.png"],
                          expect="refuse", outputs=[], fast=kind in ("directory", "fifo")))
    # thermal calibrate: the table is the output that cannot be written
    for kind in ["directory", "fifo", "readonly"]:
        def setup(d: str, kind=kind) -> None:
            with open(os.path.join(d, "tc.json"), "w") as f:
                f.write('{"earlier": true}\n')
            H.make_file_output(kind, d, "tc.csv", None, seed)

        name = f"cli-output/thermal-calibrate/table={kind}"
        out.append(B.Case(name, "cli-output", "cli", setup=setup,
                          argv=["thermal", "calibrate", "--virtual", "--quick", "--out", "tc.json", "--quiet"],
                          expect="refuse", outputs=[], timeout=60))
    # undistort: two images of one name, and --out the folder of the image
    def two_names(d: str) -> None:
        shutil.copy(ctx.fxp("img.png"), os.path.join(d, "img.png"))
        os.makedirs(os.path.join(d, "sub"))
        shutil.copy(ctx.fxp("img2.png"), os.path.join(d, "sub", "img.png"))
        shutil.copy(ctx.fxp("cal.json"), os.path.join(d, "cal.json"))

    out.append(B.Case("cli-output/undistort/two-images-one-name", "cli-output", "cli", setup=two_names,
                      argv=["undistort", "img.png", "sub/img.png", "--calibration", "cal.json", "--e-in", "150",
                            "--t", "31", "--out", "und"], expect="refuse", outputs=["und"], fast=True))
    out.append(B.Case("cli-output/undistort/out-is-image-folder", "cli-output", "cli", setup=two_names,
                      argv=["undistort", "sub/img.png", "--calibration", "cal.json", "--e-in", "150",
                            "--t", "31", "--out", "sub"], expect="refuse", outputs=[], fast=True))
    return out


def _dry_output(kind, typ, tok, an_input, earlier, ctx, seed):
    import tempfile
    d = tempfile.mkdtemp(prefix="dry-", dir=ctx.logs)
    try:
        if an_input:
            with open(os.path.join(d, an_input), "wb") as f:
                f.write(b"x")
        with open(os.path.join(d, "sentinel.txt"), "wb") as f:
            f.write(b"x")
        if typ == "file":
            return H.make_file_output(kind, d, tok, an_input, seed)
        es = os.path.join(d, "_earlier")
        os.makedirs(es)
        return H.make_dir_output(kind, d, tok, an_input, es, seed)
    finally:
        B.cleanup(d)


# ---------------------------------------------------------------------------------------
# Mutated files: a valid file with one field made hostile, through a command that reads it

LEAF_VALUES = ["1e999", "-1e999", "1e308", "-1e308", "0", "-1", "5e-324", "1e20", '"text"', "null", "true", "[]",
               "{}", "18446744073709551616", "NaN", "-0"]


def leaves(obj, path=()):
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from leaves(v, path + (k,))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from leaves(v, path + (i,))
    else:
        yield path, obj


def containers(obj, path=()):
    if isinstance(obj, (dict, list)):
        yield path, obj
        items = obj.items() if isinstance(obj, dict) else enumerate(obj)
        for k, v in items:
            yield from containers(v, path + (k,))


def set_at(obj, path, value):
    for k in path[:-1]:
        obj = obj[k]
    obj[path[-1]] = value


def del_at(obj, path):
    for k in path[:-1]:
        obj = obj[k]
    del obj[path[-1]]


def mutated_text(base_obj, path, literal: str) -> str:
    obj = copy.deepcopy(base_obj)
    set_at(obj, path, "@@HOSTILE@@")
    return json.dumps(obj).replace('"@@HOSTILE@@"', literal)


def path_str(path) -> str:
    s = ""
    for k in path:
        s += f"[{k}]" if isinstance(k, int) else (("." if s else "") + str(k))
    return s or "<root>"


# (name, fixture, bases reading it, random leaf mutations, structural mutations)
MUTATE = [
    ("obs", "obs.json", ["calibrate"], 70, 25),
    ("cal", "cal.json", ["export", "focus", "undistort", "report", "diff"], 80, 30),
    ("cal-ecom", "cal_ecom.json", ["export-ecom"], 15, 5),
    ("a0", "a0.json", ["calibrate-full"], 20, 5),
    ("thermal", "thermal.json", ["thermal-eval", "calibrate-full"], 30, 8),
    ("board", "charuco_sim.json", ["board", "render-board", "detect-board", "board-svg"], 30, 8),
    ("checker", "checker.json", ["detect-checker"], 15, 5),
    ("simconfig", "simconfig.json", ["simulate-config"], 30, 10),
    ("dataset", "dataset.json", ["calibrate-dataset"], 12, 6),
    ("optics", "optics.json", ["simulate-optics"], 6, 2),
]

# Hand-picked values of the fields that size work or memory.
SPECIAL = {
    "obs": [("image_size", "[0, 0]"), ("image_size", "[1, 1]"), ("image_size", "[65536, 65536]"),
            ("image_size", "[65537, 1]"), ("image_size", "[-1, 5]"), ("image_size", "[1e308, 5]"),
            ("image_size", "[1.5, 2]"), ("image_size", "[18446744073709551616, 1]"), ("image_size", "[100000, 100000]"),
            ("views", "[]"), ("offstate_views", "[]"), ("views[0].points", "[]"), ("views[0].e_com_ma", "1e6"),
            ("views[0].temperature_c", "1e6"), ("views[0].points[0].world_mm", "[0, 0, 1e300]"),
            ("views[0].points[0].pixel", "[1e300, 0]"), ("offstate_views[0].points[0].world_mm", "[4, 4, 2]"),
            ("views[0].e_in_ma", "-1e6")],
    "cal": [("kf_x", "[]"), ("kf_x", "[" + ", ".join(["1e-9"] * 1000) + "]"), ("kf_x", "[0]"),
            ("kf_x[0]", "-5000"), ("principal_point", "[1e308, 0]"), ("image_size", "[65536, 65536]"),
            ("image_size", "[0, 0]"), ("e_com_range_ma", "[225, 80]"), ("e_com_range_ma", "[-1e308, 1e308]"),
            ("e_com_range_ma", "[150, 150]"), ("distortion_a", "[]"),
            ("distortion_a", "[" + ", ".join(["0"] * 1000) + "]"), ("rotation_rodrigues", "[1e308, 0, 0]"),
            ("translation_mm", "[0, 0, 0]"), ("thermal", "null"), ("focus_law.coefficients_ma", "[]"),
            ("focus_law.distance_range_mm", "[120, 49]"), ("focus_law.distance_range_mm", "[0, 1e308]"),
            ("covariance", "[[1]]"), ("views", "[]"), ("image_size", "[65536, 4096]")],
    "board": [("squares", "[1, 1]"), ("squares", "[2, 2]"), ("squares", "[1000, 1000]"), ("squares", "[1001, 2]"),
              ("squares", "[0, 5]"), ("squares", "[-3, 5]"), ("squares", "[1000000000, 1000000000]"),
              ("square_mm", "0"), ("square_mm", "-1"), ("square_mm", "1e306"), ("square_mm", "1e-320"),
              ("square_mm", "1000"), ("marker_mm", "2"), ("marker_mm", "1.5"), ("marker_mm", "0"),
              ("dictionary", '"DICT_4X4_50"'), ("dictionary", '"nope"'), ("dictionary", '""'),
              ("type", '"hexagon"'), ("type", '"checkerboard"')],
    "checker": [("inner_corners", "[999, 999]"), ("inner_corners", "[2, 2]"), ("inner_corners", "[3, 3]"),
                ("inner_corners", "[1000, 3]"), ("square_mm", "1e306"), ("inner_corners", "[4294967296, 3]")],
    "simconfig": [("seed", "-1"), ("seed", "18446744073709551616"), ("seed", "1e308"), ("rig", '"nope"'),
                  ("rig", '"strong"'), ("noise.px", "1e308"), ("noise.px", "-1"),
                  ("setting_rig.views_per_setting", "1000000000000"), ("setting_rig.views_per_setting", "0"),
                  ("setting_rig.e_com_ma", "[]"), ("setting_rig.e_com_ma", "[1e6]"),
                  ("setting_rig.e_com_ma", "[" + ", ".join(["100"] * 1001) + "]"),
                  ("setting_rig.blur_px", "1e308"), ("setting_rig.max_tilt_deg", "90"),
                  ("setting_rig.max_tilt_deg", "1e308"), ("setting_rig.aperture_mm", "-1")],
    "thermal": [("coefficients", "[]"), ("coefficients", "[1e308, 1e308, 1e308, 1e308, 1e308, 1e308, 1e308, 1e308, 1e308, 1e308]"),
                ("t_range_c", "[37, 27]"), ("e_in_range_ma", "[245, 40]"), ("t_range_c", "[-1e308, 1e308]"),
                ("e_in_range_ma", "[-1e308, 1e308]"), ("rms_ma", "-1")],
}


def parse_path(s: str):
    out = []
    for part in s.replace("]", "").split("."):
        bits = part.split("[")
        out.append(bits[0])
        out += [int(b) for b in bits[1:]]
    return tuple(out)


def mutation_cases(ctx: B.Ctx) -> List[B.Case]:
    out = []
    rng = random.Random(ctx.args.seed * 7919 + 1)
    for mname, fixture, bases, n_leaf, n_struct in MUTATE:
        with open(os.path.join(_fixture_source_dir(ctx), fixture)) as f:
            obj = json.load(f) if os.path.exists(os.path.join(_fixture_source_dir(ctx), fixture)) else None
        muts: List[Tuple[str, str, str]] = []  # (label, text, expect)
        for p, lit in SPECIAL.get(mname, []):
            path = parse_path(p)
            try:
                muts.append((f"{p}={lit[:30]}", mutated_text(obj, path, lit), "any"))
            except (KeyError, IndexError, TypeError):
                continue
        lv = [p for p, v in leaves(obj) if p and p[0] != "format"]
        # numbers first: the leaves that are numbers are most of a file and the likeliest to matter
        for _ in range(n_leaf):
            p = rng.choice(lv)
            lit = rng.choice(LEAF_VALUES)
            expect = "refuse" if lit in ("1e999", "-1e999", "NaN") else "any"
            muts.append((f"{path_str(p)}={lit}", mutated_text(obj, p, lit), expect))
        cs = [p for p, v in containers(obj) if p]
        for _ in range(n_struct if cs else 0):
            p = rng.choice(cs)
            op = rng.choice(["drop", "empty", "first-only", "null", "string", "triple"])
            o2 = copy.deepcopy(obj)
            parent = o2
            for k in p[:-1]:
                parent = parent[k]
            cur = parent[p[-1]]
            if op == "drop":
                del parent[p[-1]]
            elif op == "empty":
                parent[p[-1]] = type(cur)()
            elif op == "first-only":
                parent[p[-1]] = cur[:1] if isinstance(cur, list) else dict(list(cur.items())[:1])
            elif op == "null":
                parent[p[-1]] = None
            elif op == "string":
                parent[p[-1]] = "text"
            elif op == "triple":
                parent[p[-1]] = cur * 3 if isinstance(cur, list) else [cur, cur, cur]
            muts.append((f"{path_str(p)}:{op}", json.dumps(o2), "any"))
        # also: a key dropped at the top level, one by one
        if isinstance(obj, dict):
            for k in obj:
                o2 = dict(obj)
                del o2[k]
                muts.append((f"{k}:drop-top", json.dumps(o2), "any"))
        seen = set()
        for i, (label, text, expect) in enumerate(muts):
            base = bases[i % len(bases)]
            argv, files, outs, env, to = BASES[base]
            name = f"cli-json/{mname}/{base}/{label}"
            if name in seen:
                continue
            seen.add(name)

            def setup(d: str, text=text, fixture=fixture, files=files) -> None:
                for f in files:
                    if f != fixture:
                        shutil.copy(ctx.fxp(f), os.path.join(d, f))
                with open(os.path.join(d, fixture), "w") as f:
                    f.write(text)

            if fixture not in files and fixture != "cal.json":
                continue
            out.append(B.Case(name, "cli-json", "cli", setup=setup, argv=list(argv), env=dict(env), expect=expect,
                              outputs=list(outs), timeout=to,
                              fast=(crc(name) % 12 == 0) and base not in SLOW_BASES))
    return out


def _fixture_source_dir(ctx: B.Ctx) -> str:
    """The JSON fixtures must be known before the cases are built: they are built from
    build_fixtures, which runs before the cases are made."""
    return ctx.fx


# ---------------------------------------------------------------------------------------
# Environments, misuse, choices

def env_cases(ctx: B.Ctx) -> List[B.Case]:
    out = []
    argv, files, outs, env, to = BASES["report"]
    for v in ["NaN", "-1", "1e308", "253402300800", "253402300799", "", "text", "18446744073709551615", "1.5",
              "0x10", " 0", "-9223372036854775809", "1" + "0" * 300]:
        ok = v in ("253402300799",)
        for b in ("report", "demo"):
            argv, files, outs, env, to = BASES[b]

            def setup(d: str, b=b, files=files) -> None:
                copier(ctx, files)(d)
                shutil.copytree(ctx.fxp("set_rep" if b == "report" else "set_demo"),
                                os.path.join(d, "rep" if b == "report" else "demo"))

            name = f"cli-env/{b}/SOURCE_DATE_EPOCH={v[:24]!r}"
            out.append(B.Case(name, "cli-env", "cli", setup=setup, argv=list(argv), env={"SOURCE_DATE_EPOCH": v},
                              expect="ok" if ok else ("any" if v == "" else "refuse"), outputs=list(outs), timeout=to,
                              fast=v in ("1e308", "text")))
    refusals = [
        ("export-missing", ["export", "--calibration", "nope.json", "--e-in", "150", "--t", "31", "--format", "opencv",
                            "--out", "x.yaml"], []),
        ("calibrate-random", ["calibrate", "--observations", "sentinel.txt", "--out", "x.json"], []),
        ("render-nan", ["render", "--out", "r.png", "--e-com", "NaN"], []),
        ("lens-nan", ["lens", "--virtual", "set-current", "NaN"], []),
        ("study-zero", ["study", "fig6", "--trials", "0", "--out", "st"], []),
        ("thermal-fit-empty", ["thermal", "fit", "sentinel.txt", "--out", "t.json"], []),
        ("focus-far", ["focus", "--calibration", "cal.json", "--distance-mm", "1e6", "--t", "31"], ["cal.json"]),
        ("clap-unknown", ["calibrate", "--no-such-flag"], []),
    ]
    for name0, a, files in refusals:
        for var, val in [("RUST_BACKTRACE", "1"), ("RUST_BACKTRACE", "full"), ("RUST_LIB_BACKTRACE", "1"),
                         ("COLUMNS", "1"), ("TERM", "dumb"), ("LC_ALL", "tr_TR.UTF-8")]:
            name = f"cli-env/{name0}/{var}={val}"
            out.append(B.Case(name, "cli-env", "cli", setup=copier(ctx, files), argv=list(a), env={var: val},
                              expect="refuse", fast=var == "RUST_BACKTRACE" and val == "1"))
    for tmp in ["/nonexistent-tmp-dir", "sentinel.txt", "", "fifo-tmp", "long"]:
        for b in ("lens-info", "lens-hold", "thermal-eval-paper"):
            argv, files, outs, env, to = BASES[b]

            def setup(d: str, tmp=tmp) -> None:
                if tmp == "fifo-tmp":
                    os.mkfifo(os.path.join(d, "fifo-tmp"))

            tval = tmp
            if tmp == "long":
                tval = "/tmp/" + "t" * 300
            elif tmp in ("sentinel.txt", "fifo-tmp"):
                tval = "./" + tmp
            name = f"cli-env/{b}/TMPDIR={tmp}"
            out.append(B.Case(name, "cli-env", "cli", setup=setup, argv=list(argv), env={"TMPDIR": tval},
                              expect="any", fast=tmp == "sentinel.txt" and b == "lens-info"))
    for var, val in [("LC_ALL", "C"), ("LANG", "de_DE.UTF-8"), ("HOME", None), ("PATH", ""), ("COLUMNS", "100000"),
                     ("NO_COLOR", "1"), ("RAYON_NUM_THREADS", "0"), ("RAYON_NUM_THREADS", "1000"),
                     ("RAYON_NUM_THREADS", "text"), ("RAYON_NUM_THREADS", "-1")]:
        for b in ("calibrate", "model", "study"):
            argv, files, outs, env, to = BASES[b]
            name = f"cli-env/{b}/{var}={val!r}"
            out.append(B.Case(name, "cli-env", "cli", setup=copier(ctx, files), argv=list(argv), env={var: val},
                              expect="ok" if var != "RAYON_NUM_THREADS" else "any", outputs=list(outs),
                              fast=var == "RAYON_NUM_THREADS" and val == "1000" and b == "calibrate"))
    return out


def misuse_cases(ctx: B.Ctx) -> List[B.Case]:
    cal_in = ["cal.json"]
    obs = ["obs.json"]
    L: List[Tuple[str, list, list, str, list]] = [
        ("no-verb", [], [], "refuse", []),
        ("unknown-verb", ["nosuchverb"], [], "refuse", []),
        ("calibrate-nothing", ["calibrate"], [], "refuse", []),
        ("calibrate-no-out", ["calibrate", "--observations", "obs.json"], obs, "refuse", []),
        ("calibrate-both-inputs", ["calibrate", "--observations", "obs.json", "--dataset", "dataset.json", "--out",
                                   "x.json"], obs + ["dataset.json"], "refuse", ["x.json"]),
        ("calibrate-sigma-z-twice", ["calibrate", "--observations", "obs.json", "--out", "x.json", "--sigma-z-um", "10",
                                     "--sigma-z-mm", "0.01"], obs, "refuse", ["x.json"]),
        ("calibrate-huber-and-robust", ["calibrate", "--observations", "obs.json", "--out", "x.json", "--huber-px", "1",
                                        "--robust", "cauchy"], obs, "refuse", ["x.json"]),
        ("calibrate-per-setting-no-views", ["calibrate", "--observations", "obs.json", "--out", "x.json", "--method",
                                            "per-setting"], obs, "refuse", ["x.json"]),
        ("calibrate-per-setting-estimator", ["calibrate", "--observations", "obs.json", "--out", "x.json", "--method",
                                             "per-setting", "--estimator", "paper"], obs, "refuse", ["x.json"]),
        ("calibrate-fix-k3-paper", ["calibrate", "--observations", "obs.json", "--out", "x.json", "--fix-k3"], obs,
         "any", ["x.json"]),
        ("calibrate-out-twice", ["calibrate", "--observations", "obs.json", "--out", "x.json", "--out", "y.json"], obs,
         "refuse", ["x.json", "y.json"]),
        ("calibrate-same-two-outputs", ["calibrate", "--dataset", "dataset.json", "--out", "x.json",
                                        "--observations-out", "x.json"], ["dataset.json"], "refuse", []),
        ("calibrate-obs-out-without-dataset", ["calibrate", "--observations", "obs.json", "--out", "x.json",
                                               "--observations-out", "o.json"], obs, "refuse", ["x.json", "o.json"]),
        ("calibrate-all-auto", ["calibrate", "--observations", "obs.json", "--out", "x.json", "--distortion", "auto",
                                "--focal-degree", "auto", "--centre", "auto"], obs, "any", ["x.json"]),
        ("calibrate-thermal-PAPER", ["calibrate", "--observations", "obs.json", "--out", "x.json", "--thermal",
                                     "PAPER"], obs, "refuse", ["x.json"]),
        ("calibrate-thermal-empty", ["calibrate", "--observations", "obs.json", "--out", "x.json", "--thermal", ""],
         obs, "refuse", ["x.json"]),
        ("calibrate-estimator-bad", ["calibrate", "--observations", "obs.json", "--out", "x.json", "--estimator",
                                     "EIV"], obs, "refuse", []),
        ("calibrate-equals-form", ["calibrate", "--observations=obs.json", "--out=x.json"], obs, "ok", ["x.json"]),
        ("calibrate-obs2-a0-of-other", ["calibrate", "--observations", "obs.json", "--a0", "a0.json", "--hold-a0",
                                        "--out", "x.json"], obs + ["a0.json"], "ok", ["x.json"]),
        ("thermal-calibrate-same-out-table", ["thermal", "calibrate", "--virtual", "--quick", "--out", "t.json",
                                              "--table", "t.json"], [], "refuse", []),
        ("thermal-calibrate-no-virtual", ["thermal", "calibrate", "--out", "t.json"], [], "refuse", []),
        ("export-no-t", ["export", "--calibration", "cal.json", "--e-in", "150", "--format", "opencv", "--out",
                         "x.yaml"], cal_in, "refuse", []),
        ("export-both-settings", ["export", "--calibration", "cal.json", "--e-in", "150", "--t", "31", "--e-com", "150",
                                  "--format", "opencv", "--out", "x.yaml"], cal_in, "refuse", []),
        ("export-ecom-cal-with-e-in", ["export", "--calibration", "cal_ecom.json", "--e-in", "150", "--t", "31",
                                       "--format", "opencv", "--out", "x.yaml"], ["cal_ecom.json"], "refuse", []),
        ("export-format-bad", ["export", "--calibration", "cal.json", "--e-in", "150", "--t", "31", "--format", "yaml",
                               "--out", "x.yaml"], cal_in, "refuse", []),
        ("export-format-empty", ["export", "--calibration", "cal.json", "--e-in", "150", "--t", "31", "--format", "",
                                 "--out", "x.yaml"], cal_in, "refuse", []),
        ("export-extrapolate-driver-limit", ["export", "--calibration", "cal.json", "--e-in", "1000", "--t", "31",
                                             "--format", "opencv", "--out", "x.yaml", "--allow-extrapolation"], cal_in,
         "refuse", ["x.yaml"]),
        ("export-extrapolate-far", ["export", "--calibration", "cal.json", "--e-in", "290", "--t", "124",
                                    "--format", "opencv", "--out", "x.yaml", "--allow-extrapolation"], cal_in, "any",
         ["x.yaml"]),
        ("export-extrapolate-minus", ["export", "--calibration", "cal.json", "--e-in", "-290", "--t", "-40",
                                      "--format", "mrcal", "--out", "x.yaml", "--allow-extrapolation"], cal_in, "any",
         ["x.yaml"]),
        ("measure-one-image", ["measure", "--calibration", "cal.json", "--e-in", "150", "--t", "31", "img.png",
                               "--pattern", "14x12", "--square", "1.5"], cal_in + ["img.png"], "refuse", []),
        ("measure-board-and-pattern", ["measure", "--calibration", "cal.json", "--e-in", "150", "--t", "31", "img.png",
                                       "img.png", "--pattern", "14x12", "--square", "1.5", "--board",
                                       "charuco_sim.json"], cal_in + ["img.png", "charuco_sim.json"], "refuse", []),
        ("measure-wrong-pattern", ["measure", "--calibration", "cal.json", "--e-in", "150", "--t", "31", "img.png",
                                   "img.png", "--pattern", "9x6", "--square", "1.5"], cal_in + ["img.png"], "refuse", []),
        ("measure-no-square", ["measure", "--calibration", "cal.json", "--e-in", "150", "--t", "31", "img.png",
                               "img.png", "--pattern", "14x12"], cal_in + ["img.png"], "refuse", []),
        ("undistort-no-images", ["undistort", "--calibration", "cal.json", "--e-in", "150", "--t", "31", "--out", "u"],
         cal_in, "refuse", []),
        ("undistort-same-image-twice", ["undistort", "img.png", "img.png", "--calibration", "cal.json", "--e-in",
                                        "150", "--t", "31", "--out", "u"], cal_in + ["img.png"], "any", ["u"]),
        ("undistort-missing-images", ["undistort"] + [f"i{k}.png" for k in range(3)] + ["--calibration", "cal.json",
                                                                                    "--e-in", "150", "--t", "31", "--out", "u"],
         cal_in, "refuse", []),
        ("diff-one", ["diff", "cal.json", "--e-in", "150", "--t", "31"], cal_in, "refuse", []),
        ("diff-ecom-and-thermal-cal", ["diff", "cal.json", "cal_ecom.json", "--e-in", "150", "--t", "31"],
         cal_in + ["cal_ecom.json"], "refuse", []),
        ("diff-heatmap-bmp", ["diff", "cal.json", "cal.json", "--e-in", "150", "--t", "31", "--heatmap", "h.bmp"],
         cal_in, "any", ["h.bmp"]),
        ("detect-nothing", ["detect", "img.png"], ["img.png"], "refuse", []),
        ("detect-both", ["detect", "img.png", "--pattern", "14x12", "--board", "charuco_sim.json"],
         ["img.png", "charuco_sim.json"], "refuse", []),
        ("detect-wrong-pattern", ["detect", "img.png", "--pattern", "9x6"], ["img.png"], "refuse", []),
        ("detect-charuco-in-checker-image", ["detect", "img.png", "--board", "charuco_sim.json"],
         ["img.png", "charuco_sim.json"], "any", []),
        ("detect-5000-missing*", ["detect", "--pattern", "14x12"] + [f"m{k}.png" for k in range(5000)], [], "refuse", []),
        ("sharpness-200-images", ["sharpness", "--metric", "brenner"] + ["img.png"] * 200, ["img.png"], "ok", []),
        ("sharpness-metric-bad", ["sharpness", "img.png", "--metric", "CPBD2"], ["img.png"], "refuse", []),
        ("sharpness-metric-empty", ["sharpness", "img.png", "--metric", ""], ["img.png"], "refuse", []),
        ("sharpness-dashdash", ["sharpness", "--", "--metric"], [], "refuse", []),
        ("sharpness-16bit", ["sharpness", "img16.png", "--metric", "normvar"], ["img16.png"], "ok", []),
        ("sharpness-jpg-tif", ["sharpness", "img.jpg", "img.tif", "--metric", "laplacian"], ["img.jpg", "img.tif"],
         "ok", []),
        ("render-bmp", ["render", "--out", "r.bmp"], [], "refuse", []),
        ("render-no-ext", ["render", "--out", "r"], [], "refuse", []),
        ("render-upper-ext", ["render", "--out", "r.PNG"], [], "any", ["r.PNG", "r.PNG.corners.json"]),
        ("render-jpg-16", ["render", "--out", "r.jpg", "--bit-depth", "16"], [], "refuse", []),
        ("render-tiff-16", ["render", "--out", "r.tiff", "--bit-depth", "16"], [], "ok", ["r.tiff", "r.tiff.corners.json"]),
        ("render-pattern-and-board", ["render", "--out", "r.png", "--pattern", "14x12", "--board", "charuco_sim.json"],
         ["charuco_sim.json"], "refuse", []),
        ("render-square-and-board", ["render", "--out", "r.png", "--square", "2", "--board", "charuco_sim.json"],
         ["charuco_sim.json"], "refuse", []),
        ("render-far-e-com", ["render", "--out", "r.png", "--e-com", "-292"], [], "any", ["r.png", "r.png.corners.json"]),
        ("render-board-off-image", ["render", "--out", "r.png", "--z-mm", "-10000"], [], "any",
         ["r.png", "r.png.corners.json"]),
        ("board-svg-dpi", ["board", "--board", "charuco_sim.json", "--out", "b.svg", "--dpi", "300"],
         ["charuco_sim.json"], "refuse", []),
        ("board-pdf", ["board", "--board", "charuco_sim.json", "--out", "b.pdf"], ["charuco_sim.json"], "refuse", []),
        ("board-checker-png", ["board", "--board", "checker.json", "--out", "b.png", "--dpi", "50"], ["checker.json"],
         "ok", ["b.png"]),
        ("study-bad-name", ["study", "fig7", "--out", "st"], [], "refuse", []),
        ("study-empty-name", ["study", "", "--out", "st"], [], "refuse", []),
        ("study-fig5-strong", ["study", "fig5", "--rig", "strong", "--out", "st"], [], "refuse", []),
        ("study-crlb-strong-1", ["study", "crlb", "--rig", "strong", "--trials", "2", "--out", "st", "--quiet"], [],
         "ok", ["st"]),
        ("study-baseline-1", ["study", "baseline", "--trials", "1", "--out", "st", "--quiet"], [], "ok", ["st"]),
        ("study-subsets-1", ["study", "subsets", "--trials", "1", "--out", "st", "--quiet"], [], "ok", ["st"]),
        ("study-trials-100001", ["study", "crlb", "--trials", "100001", "--out", "st"], [], "refuse", []),
        ("model-reversed", ["model", "--from", "250", "--to", "0"], [], "any", []),
        ("model-negative-step", ["model", "--step", "-10"], [], "refuse", []),
        ("model-ten-million", ["model", "--from", "0", "--to", "1", "--step", "1e-7"], [], "any", []),
        ("model-fit-tiny-step", ["model", "--fit-degrees", "--step", "1e-300"], [], "refuse", []),
        ("model-fit-one-point", ["model", "--fit-degrees", "--from", "10", "--to", "10"], [], "refuse", []),
        ("lens-no-port", ["lens", "info"], [], "refuse", []),
        ("lens-port-and-virtual", ["lens", "--port", "x", "--virtual", "info"], [], "refuse", []),
        ("lens-set-missing", ["lens", "--virtual", "set-current"], [], "refuse", []),
        ("lens-hold-warm-out", ["lens", "--virtual", "hold", "--e-com", "120", "--thermal", "paper", "--duration",
                                "0.3", "--warm", "200"], [], "refuse", []),
        ("lens-hold-beyond", ["lens", "--virtual", "hold", "--e-com", "290", "--thermal", "paper", "--duration", "0.3"],
         [], "any", []),
        ("lens-hold-no-duration-rate0", ["lens", "--virtual", "hold", "--e-com", "120", "--thermal", "paper",
                                         "--duration", "0", "--rate", "0"], [], "any", []),
        ("lens-hold-thermal-bad", ["lens", "--virtual", "hold", "--e-com", "120", "--thermal", "nope", "--duration",
                                   "0.3"], [], "refuse", []),
        ("lens-hold-warm-virtual-port", ["lens", "--port", "/dev/null", "hold", "--e-com", "120", "--thermal", "paper",
                                         "--duration", "0.3", "--warm", "5"], [], "refuse", []),
        ("lens-set-clamped", ["lens", "--virtual", "set-current", "1e6"], [], "any", []),
        ("lens-handshake", ["lens", "--virtual", "--handshake", "info"], [], "ok", []),
        ("global-flags-first", ["--json", "--quiet", "model", "--from", "0", "--to", "10"], [], "ok", []),
        ("global-flags-twice", ["--json", "model", "--json"], [], "any", []),
        ("help-verb", ["help", "calibrate"], [], "ok", []),
        ("help-flag", ["calibrate", "--help"], [], "ok", []),
        ("version", ["--version"], [], "ok", []),
        ("huge-argument-file", ["sharpness", "x" * 100000], [], "refuse", []),
        ("huge-argument-number", ["model", "--from", "1" * 100000], [], "refuse", []),
        ("huge-argument-out", ["render", "--out", "a" * 100000 + ".png"], [], "refuse", []),
        ("many-slashes-out", ["render", "--out", "/" * 5000 + "nonexistent-root-dir/x.png"], [], "refuse", []),
        ("nonutf8-image", ["sharpness", b"\xff\xfe.png"], [], "refuse", []),
        ("nonutf8-format", ["export", "--calibration", "cal.json", "--e-in", "150", "--t", "31", "--format", b"\xff",
                            "--out", "x.yaml"], cal_in, "refuse", []),
        ("nonutf8-flag", ["calibrate", b"--\xff"], [], "refuse", []),
        ("nonutf8-number", ["model", "--from", b"1\xff"], [], "refuse", []),
        ("nonutf8-out", ["calibrate", "--observations", "obs.json", "--out", b"cal-\xff.json"], obs, "any",
         [os.fsdecode(b"cal-\xff.json")]),
        ("newline-in-path", ["sharpness", "a\nb.png"], [], "refuse", []),
        ("dash-path", ["sharpness", "-"], [], "refuse", []),
        ("zhang-two-images", ["zhang", "z1.jpg", "z2.jpg", "--pattern", "9x6", "--square", "1"], ["z1.jpg", "z2.jpg"],
         "refuse", []),
        ("zhang-same-image", ["zhang", "z1.jpg", "z1.jpg", "z1.jpg", "--pattern", "9x6", "--square", "1"], ["z1.jpg"],
         "refuse", []),
        ("zhang-fix-k3-paper", ["zhang", "z1.jpg", "z2.jpg", "z3.jpg", "--pattern", "9x6", "--square", "1", "--fix-k3"],
         ["z1.jpg", "z2.jpg", "z3.jpg"], "refuse", []),
        ("zhang-mixed-sizes", ["zhang", "z1.jpg", "z2.jpg", "img.png", "--pattern", "9x6", "--square", "1"],
         ["z1.jpg", "z2.jpg", "img.png"], "refuse", []),
        ("stereo-unequal-counts", ["stereo", "z1.jpg", "z2.jpg", "z3.jpg", "--right", "z1.jpg", "z2.jpg", "--pattern",
                                   "9x6", "--square", "1", "--model", "opencv"], ["z1.jpg", "z2.jpg", "z3.jpg"], "refuse", []),
        ("stereo-two-pairs", ["stereo", "z1.jpg", "z2.jpg", "--right", "z1.jpg", "z2.jpg", "--pattern", "9x6", "--square",
                              "1", "--model", "opencv"], ["z1.jpg", "z2.jpg"], "refuse", []),
        ("stereo-yaml-paper", ["stereo", "z1.jpg", "z2.jpg", "z3.jpg", "--right", "z1.jpg", "z2.jpg", "z3.jpg",
                               "--pattern", "9x6", "--square", "1", "--model", "paper", "--opencv-yaml", "p.yml"],
         ["z1.jpg", "z2.jpg", "z3.jpg"], "refuse", []),
        ("focus-ecom-calibration", ["focus", "--calibration", "cal_ecom.json", "--distance-mm", "80", "--t", "31"],
         ["cal_ecom.json"], "any", []),
        ("report-observations-other", ["report", "--calibration", "cal.json", "--observations", "obs2.json", "--out",
                                       "rep"], cal_in + ["obs2.json"], "any", ["rep"]),
        ("report-thermal-paper-word", ["report", "--calibration", "cal_ecom.json", "--thermal", "paper", "--out", "rep"],
         ["cal_ecom.json"], "any", ["rep"]),
        ("report-in-calibration-dir", ["report", "--calibration", "d/cal.json", "--out", "d"], [], "refuse", []),
        ("simulate-optics-and-config", ["simulate", "--optics", "optics.json", "--config", "simconfig.json", "--out",
                                        "o"], ["optics.json", "simconfig.json"], "refuse", []),
        ("simulate-setting-views", ["simulate", "--out", "o", "--observations-only", "--setting-views"], [], "ok", ["o"]),
        ("simulate-optics-current-noise", ["simulate", "--optics", "optics.json", "--out", "o", "--current-noise-ma",
                                           "1"], ["optics.json"], "refuse", []),
    ]
    out = []
    for name, argv, files, expect, outs in L:
        multiline = name.endswith("*")
        name = name.rstrip("*")
        extra = None
        if name == "report-in-calibration-dir":
            def extra(d: str) -> None:
                os.makedirs(os.path.join(d, "d"))
                shutil.copy(ctx.fxp("cal.json"), os.path.join(d, "d", "cal.json"))
        timeout = 60 if name.startswith(("study-", "thermal-calibrate", "simulate-optics")) else None
        n = f"cli-misuse/{name}"
        out.append(B.Case(n, "cli-misuse", "cli", setup=copier(ctx, files, extra), argv=argv,
                          expect=expect, outputs=outs, timeout=timeout,
                          echo=[a if isinstance(a, str) else os.fsdecode(a) for a in argv], multiline=multiline,
                          fast=crc(n) % 3 == 0 and timeout is None))
    return out


def baseline_cases(ctx: B.Ctx) -> List[B.Case]:
    out = []
    for name, (argv, files, outs, env, to) in BASES.items():
        out.append(B.Case(f"cli-baseline/{name}", "cli-baseline", "cli", setup=copier(ctx, files), argv=list(argv),
                          env=dict(env), expect="ok", outputs=list(outs), timeout=to, fast=name in FAST_BASES))
    return out


# ---------------------------------------------------------------------------------------
# Kills: a writer killed at a random moment leaves the earlier whole output or the new one


VOLATILE = [re.compile(rb'"seconds": [0-9.e+-]+'), re.compile(rb"\(\d+(?:\.\d+)? s\)")]


def normalized(path: str) -> tuple:
    """A file's digest with its run time taken out (a study writes how long it took)."""
    with open(path, "rb") as f:
        b = f.read()
    for r in VOLATILE:
        b = r.sub(b"<time>", b)
    import hashlib
    return ("file", hashlib.sha256(b).hexdigest())


def set_state(d: str, outputs: List[str]) -> Dict[str, tuple]:
    """The bytes of the named outputs (files, or every file of a folder), run times aside.

    A temporary inside an output folder (`.NAME.tmpPID`) is left out: a run killed before
    its commit leaves its temporaries as garbage, which the next writer removes (the leak
    check after the next run sees any that stay). Pending markers are kept: a set whose
    commit is written but whose renames are not is not the earlier set."""
    st: Dict[str, tuple] = {}
    for o in outputs:
        p = os.path.join(d, o)
        if os.path.isdir(p) and not os.path.islink(p):
            for k, v in B.snapshot(p).items():
                if B.is_temporary(k) and "etlcal-pending" not in k:
                    continue
                fp = os.path.join(p, k)
                st[os.path.join(o, k)] = normalized(fp) if v[0] == "file" else v
        elif os.path.isfile(p) and not os.path.islink(p):
            st[o] = normalized(p)
        elif os.path.lexists(p):
            st[o] = B.snapshot(os.path.dirname(p) or d).get(os.path.basename(p))
        else:
            st[o] = ("absent",)
    return st


KILLS = [
    # name, files, old argv, new argv, outputs, reader argv (completes a pending set), env, runs (full, fast)
    ("simulate-obs", [], ["simulate", "--out", "sim", "--observations-only", "--seed", "1"],
     ["simulate", "--out", "sim", "--observations-only", "--seed", "2"], ["sim"], None, {}, (12, 3)),
    ("simulate-images", [], ["simulate", "--out", "sim", "--seed", "1", "--quiet"],
     ["simulate", "--out", "sim", "--seed", "2", "--quiet"], ["sim"], None, {}, (4, 0)),
    ("report", ["cal.json", "cal_paper.json"], ["report", "--calibration", "cal_paper.json", "--out", "rep"],
     ["report", "--calibration", "cal.json", "--out", "rep"], ["rep"], None, SDE, (10, 2)),
    ("calibrate", ["obs.json"], ["calibrate", "--observations", "obs.json", "--estimator", "paper", "--out", "cal.json"],
     ["calibrate", "--observations", "obs.json", "--out", "cal.json"], ["cal.json"], None, {}, (12, 2)),
    ("calibrate-dataset-set", ["dataset.json"],
     ["calibrate", "--dataset", "dataset.json", "--estimator", "paper", "--out", "o1/cal.json", "--observations-out",
      "o2/obs.json", "--quiet"],
     ["calibrate", "--dataset", "dataset.json", "--out", "o1/cal.json", "--observations-out", "o2/obs.json", "--quiet"],
     ["o1/cal.json", "o2/obs.json"], ["calibrate", "--observations", "o2/obs.json", "--out", "check.json", "--quiet"],
     {}, (8, 1)),
    ("render-set", [], ["render", "--out", "r.png", "--e-com", "100"], ["render", "--out", "r.png", "--e-com", "150"],
     ["r.png", "r.png.corners.json"], ["sharpness", "r.png"], {}, (12, 2)),
    ("thermal-calibrate-set", [], ["thermal", "calibrate", "--virtual", "--quick", "--out", "t/t.json", "--table",
                                   "u/t.csv", "--search-ma", "15", "--quiet"],
     ["thermal", "calibrate", "--virtual", "--quick", "--out", "t/t.json", "--table", "u/t.csv", "--quiet"],
     ["t/t.json", "u/t.csv"], ["thermal", "eval", "--e-in", "150", "--t", "31", "--thermal", "t/t.json"], {}, (5, 0)),
    ("study", [], ["study", "fig6", "--trials", "1", "--seed", "1", "--out", "st", "--quiet"],
     ["study", "fig6", "--trials", "1", "--seed", "2", "--out", "st", "--quiet"], ["st"], None, {}, (8, 1)),
    ("export", ["cal.json", "cal_paper.json"], ["export", "--calibration", "cal_paper.json", "--e-in", "150", "--t",
                                                "31", "--format", "opencv", "--out", "cam.yaml"],
     ["export", "--calibration", "cal.json", "--e-in", "150", "--t", "31", "--format", "opencv", "--out", "cam.yaml"],
     ["cam.yaml"], None, {}, (6, 1)),
    ("board-png", ["charuco_sim.json", "checker.json"], ["board", "--board", "checker.json", "--out", "b.png"],
     ["board", "--board", "charuco_sim.json", "--out", "b.png"], ["b.png"], None, {}, (6, 1)),
    ("demo", [], ["demo", "--no-images", "--out", "demo", "--seed", "1", "--quiet"],
     ["demo", "--no-images", "--out", "demo", "--seed", "2", "--quiet"], ["demo"], None, SDE, (6, 1)),
    ("undistort", ["cal.json", "img.png", "img2.png"],
     ["undistort", "img2.png", "--calibration", "cal.json", "--e-in", "150", "--t", "31", "--out", "und"],
     ["undistort", "img.png", "img2.png", "--calibration", "cal.json", "--e-in", "150", "--t", "31", "--out", "und"],
     ["und"], None, {}, (5, 0)),
]


def kill_runner(spec, k: int):
    name, files, old, new, outputs, reader, env, _ = spec

    def run(case: B.Case, ctx: B.Ctx, d: str) -> B.Result:
        res = B.Result(case.name, case.family, case.kind)
        rng = random.Random(f"{ctx.args.seed}:{case.name}")
        ref = os.path.join(d, "ref")
        ref2 = os.path.join(d, "ref2")
        work = os.path.join(d, "work")
        for w in (ref, ref2, work):
            os.makedirs(w)
            for f in files:
                shutil.copy(ctx.fxp(f), os.path.join(w, f))
        t_new = 0.0
        for r in (ref, ref2):
            pr = B.run_proc(ctx, [ctx.binary] + new, r, env, 120)
            if pr.rc != 0:
                res.warn("baseline", f"the new writer failed: {B.first_error(pr.stderr)}")
                return res
            t_new = max(t_new, pr.seconds)
        new_state = set_state(ref, outputs)
        # files whose bytes differ between two identical runs (a run time in a table, a
        # clock): only their presence is compared
        other = set_state(ref2, outputs)
        volatile = {k2 for k2 in set(new_state) | set(other) if new_state.get(k2) != other.get(k2)}
        res.detail["volatile"] = sorted(volatile)

        def is_new(st) -> bool:
            if set(st) != set(new_state):
                return False
            return all(st[k2] == new_state[k2] or (k2 in volatile and st[k2][0] == new_state[k2][0]) for k2 in st)

        pr = B.run_proc(ctx, [ctx.binary] + old, work, env, 120)
        if pr.rc != 0:
            res.warn("baseline", f"the old writer failed: {B.first_error(pr.stderr)}")
            return res
        old_state = set_state(work, outputs)
        B.sentinel(work)
        inputs_before = {k2: v for k2, v in B.snapshot(work).items() if not B.covered(k2, outputs)}
        # the kill
        delay = rng.uniform(0.0, 1.2 * t_new)
        e = dict(os.environ)
        e.update(env)
        p = subprocess.Popen([ctx.binary] + new, cwd=work, env=e, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL, start_new_session=True, preexec_fn=B.limits(ctx.mem))
        with ctx.lock:
            ctx.children.append(p.pid)
        time.sleep(delay)
        killed = p.poll() is None
        if killed:
            os.killpg(p.pid, signal.SIGKILL)
        p.wait(30)
        res.detail.update(delay_s=round(delay, 4), t_new_s=round(t_new, 4), killed=killed)
        pending = [x for x in B.snapshot(work) if "etlcal-pending" in x]
        if pending and reader:
            pr = B.run_proc(ctx, [ctx.binary] + reader, work, env, 60)
            res.detail["reader_rc"] = pr.rc
            if pr.rc != 0 and "panicked" in pr.stderr:
                res.fail("uncatchable", f"the reader after the kill panicked: {pr.stderr[:300]}")
        after = set_state(work, outputs)
        if after != old_state and not is_new(after) and name == "thermal-calibrate-set" \
                and set(after) == set(new_state) and thermal_pair_consistent(ctx, work):
            # the procedure depends on timing under load: a new pair need not be byte-equal
            # to the reference, but its surface must be the fit of its table
            res.detail["thermal_pair"] = "consistent, not byte-equal to the reference run"
        elif after != old_state and not is_new(after):
            diff_old = sorted(k2 for k2 in set(after) | set(old_state) if after.get(k2) != old_state.get(k2))
            diff_new = sorted(k2 for k2 in set(after) | set(new_state) if after.get(k2) != new_state.get(k2)
                              and k2 not in volatile)
            res.fail("data-loss", f"killed after {delay:.3f} s (run takes {t_new:.3f} s): the outputs are neither the "
                                  f"earlier set nor the new one (vs earlier: {', '.join(diff_old[:4])}; vs new: "
                                  f"{', '.join(diff_new[:4])}); pending markers: {pending[:2]}")
        now = {k2: v for k2, v in B.snapshot(work).items() if not B.covered(k2, outputs)}
        for k2, v in inputs_before.items():
            if now.get(k2) != v and not B.is_temporary(k2) and k2 not in ("check.json",):
                res.fail("data-loss", f"an input changed by the killed run: {k2}")
        # the next run completes and leaves nothing behind
        pr = B.run_proc(ctx, [ctx.binary] + new, work, env, 120)
        B.judge_proc(res, pr, new, "ok", env)
        final = set_state(work, outputs)
        if pr.rc == 0 and not is_new(final) and not (name == "thermal-calibrate-set"
                                                     and thermal_pair_consistent(ctx, work)):
            diff_new = sorted(k2 for k2 in set(final) | set(new_state) if final.get(k2) != new_state.get(k2)
                              and k2 not in volatile)
            res.fail("data-loss", f"the run after the kill did not write the new set whole: {', '.join(diff_new[:4])}")
        if killed:
            left = B.vlens_dirs(p.pid, ["/tmp"])
            if left:
                res.fail("leak", f"the killed run's virtual-lens folder stays after the next run: {left[0]}")
                for x in left:
                    shutil.rmtree(x, ignore_errors=True)
        left = [x for x in B.snapshot(work) if B.is_temporary(x)]
        if left:
            res.fail("leak", f"after the next run: {', '.join(left[:5])}")
        res.detail["dir"] = d
        return res

    return run


def thermal_pair_consistent(ctx: B.Ctx, work: str) -> bool:
    """t/t.json is the fit of u/t.csv (the pair comes from one run)."""
    chk = os.path.join(work, "..", "chk")
    os.makedirs(chk, exist_ok=True)
    pr = B.run_proc(ctx, [ctx.binary, "thermal", "fit", os.path.join(work, "u", "t.csv"), "--out",
                          os.path.join(chk, "fit.json")], chk, {}, 60)
    if pr.rc != 0:
        return False
    try:
        with open(os.path.join(chk, "fit.json")) as f:
            a = json.load(f)["coefficients"]
        with open(os.path.join(work, "t", "t.json")) as f:
            b = json.load(f)["coefficients"]
    except (OSError, ValueError, KeyError):
        return False
    return len(a) == len(b) and all(abs(x - y) <= 1e-9 * max(1.0, abs(x)) for x, y in zip(a, b))


def concurrent_runner(kind: str):
    def run(case: B.Case, ctx: B.Ctx, d: str) -> B.Result:
        res = B.Result(case.name, case.family, case.kind)
        shutil.copy(ctx.fxp("obs.json"), d)
        shutil.copy(ctx.fxp("obs2.json"), d)
        if kind == "calibrate":
            cmds = [["calibrate", "--observations", "obs.json", "--out", "cal.json", "--quiet"],
                    ["calibrate", "--observations", "obs2.json", "--out", "cal.json", "--quiet"]]
            outputs = ["cal.json"]
        else:
            cmds = [["simulate", "--out", "sim", "--observations-only", "--seed", "1"],
                    ["simulate", "--out", "sim", "--observations-only", "--seed", "2"]]
            outputs = ["sim"]
        refs = []
        for i, c in enumerate(cmds):
            r = os.path.join(d, f"ref{i}")
            os.makedirs(r)
            shutil.copy(ctx.fxp("obs.json"), r)
            shutil.copy(ctx.fxp("obs2.json"), r)
            B.run_proc(ctx, [ctx.binary] + c, r, {}, 60)
            refs.append(set_state(r, outputs))
        procs: List[B.Proc] = []
        lock = __import__("threading").Lock()

        def go(c):
            pr = B.run_proc(ctx, [ctx.binary] + c, d, {}, 60)
            with lock:
                procs.append(pr)

        import threading
        ts = [threading.Thread(target=go, args=(c,)) for c in cmds * 2]
        for t in ts:
            t.start()
        for t in ts:
            t.join()
        for pr in procs:
            B.judge_proc(res, pr, [], "any", {})
        st = set_state(d, outputs)
        if st not in refs:
            res.fail("data-loss", "after two writers at once the output is neither run's whole output "
                                  "(documented as not covered: two runs writing the same outputs at once)")
        left = [x for x in B.snapshot(d) if B.is_temporary(x) and not x.startswith("ref")]
        if left:
            res.fail("leak", f"after concurrent runs: {', '.join(left[:5])}")
        return res

    return run


def lens_sim_runner(args: List[str], expect: str, connect: bool):
    def run(case: B.Case, ctx: B.Ctx, d: str) -> B.Result:
        res = B.Result(case.name, case.family, case.kind)
        e = dict(os.environ)
        p = subprocess.Popen([ctx.binary, "lens-sim"] + args, cwd=d, env=e, stdin=subprocess.DEVNULL,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
                             preexec_fn=B.limits(ctx.mem))
        with ctx.lock:
            ctx.children.append(p.pid)
        try:
            p.wait(3)
            served = False
        except subprocess.TimeoutExpired:
            served = True
        if not served:
            out, err = p.communicate()
            pr = B.Proc(p.returncode, out.decode(errors="replace"), err.decode(errors="replace"), False, 0, p.pid)
            B.judge_proc(res, pr, args, expect, {})
        else:
            if expect == "refuse":
                res.warn("accepted", f"lens-sim {' '.join(args)} serves")
            if connect:
                line = p.stdout.readline().decode().strip()
                pr = B.run_proc(ctx, [ctx.binary, "lens", "--port", line, "info"], d, {}, 20)
                B.judge_proc(res, pr, [], "ok", {})
                pr = B.run_proc(ctx, [ctx.binary, "lens", "--port", line, "set-current", "NaN"], d, {}, 20)
                B.judge_proc(res, pr, ["NaN"], "refuse", {})
            # Ctrl-C, the way a server in a terminal is stopped
            p.send_signal(signal.SIGINT)
            try:
                p.wait(5)
            except subprocess.TimeoutExpired:
                res.fail("hang", "lens-sim did not stop within 5 s of SIGINT")
                B.kill_group(p)
            left = B.vlens_dirs(p.pid, ["/tmp"])
            if left:
                res.fail("leak", f"lens-sim stopped by SIGINT (exit {p.returncode}) leaves its folder {left[0]}")
                for x in left:  # ours: removed, so that the next cases see a clean /tmp
                    shutil.rmtree(x, ignore_errors=True)
        return res

    return run


def custom_cases(ctx: B.Ctx) -> List[B.Case]:
    out = []
    for spec in KILLS:
        full, fast = spec[7]
        for k in range(full):
            n = f"cli-kill/{spec[0]}/{k}"
            out.append(B.Case(n, "cli-kill", "custom", runner=kill_runner(spec, k), fast=k < fast, timeout=300))
    for kind in ("calibrate", "simulate"):
        for k in range(2):
            out.append(B.Case(f"cli-concurrent/{kind}/{k}", "cli-concurrent", "custom",
                              runner=concurrent_runner(kind), fast=False))
    sims = [([], "any", True), (["--ambient", "NaN"], "refuse", False), (["--ambient", "1e308"], "refuse", False),
            (["--ambient", "-41"], "refuse", False), (["--time-scale", "0"], "refuse", False),
            (["--time-scale", "inf"], "refuse", False), (["--time-scale", "1e7"], "refuse", False),
            (["--upper-limit", "NaN"], "refuse", False), (["--upper-limit", "-300"], "refuse", False),
            (["--lower-limit", "300"], "refuse", False), (["--lower-limit", "1e308"], "refuse", False),
            (["--upper-limit", "10", "--lower-limit", "20"], "refuse", False),
            (["--upper-limit", "1e-320"], "any", False), (["--time-scale", "1e6"], "any", True),
            (["--ambient", ""], "refuse", False), (["--ambient", "text"], "refuse", False)]
    for args, expect, connect in sims:
        n = "cli-lens-sim/" + ("default" if not args else "_".join(a or "''" for a in args))
        out.append(B.Case(n, "cli-lens-sim", "custom", runner=lens_sim_runner(args, expect, connect),
                          fast=not args or args == ["--ambient", "NaN"], timeout=30))
    return out


def cases(ctx: B.Ctx) -> List[B.Case]:
    build_fixtures(ctx)
    return (baseline_cases(ctx) + numeric_cases(ctx) + input_cases(ctx) + output_cases(ctx) + mutation_cases(ctx)
            + env_cases(ctx) + misuse_cases(ctx) + custom_cases(ctx))
