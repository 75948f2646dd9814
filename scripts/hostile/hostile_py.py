"""The Python package's cases: readers and from_json, numbers, arrays, threads, callbacks,
writers, interpreter exit and fork, and kills. Each case is a snippet run by pychild.py
with prelude.py's names (etlcal, np, cal(), obs(), img(), huge(), in_thread(), ...)."""
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time
import zlib
from typing import List, Optional

import battery as B
import hostile_files as H


def crc(s: str) -> int:
    return zlib.crc32(s.encode())


def case(name, family, code, expect="any", fast=None, setup=None, outputs=None, allowed=None, isolate=False,
         timeout=None, protect=None, no_message=False):
    return B.Case(name, family, "py", code=code, expect=expect, setup=setup, outputs=outputs or [],
                  allowed=allowed or [], isolate=isolate, timeout=timeout, protect=protect or [], no_message=no_message,
                  fast=(crc(name) % 9 == 0) if fast is None else fast)


# ---------------------------------------------------------------------------------------
# Readers and from_json

READERS = [
    ("Calibration.load", "etlcal.Calibration.load", "cal.json", "a0.json"),
    ("Observations.load", "etlcal.Observations.load", "obs.json", "cal.json"),
    ("Dataset.load", "etlcal.Dataset.load", "dataset.json", "obs.json"),
    ("Board.load", "etlcal.Board.load", "charuco_sim.json", "thermal.json"),
    ("ThermalCalibration.load", "etlcal.ThermalCalibration.load", "thermal.json", "charuco_sim.json"),
    ("A0.load", "etlcal.A0.load", "a0.json", "cal.json"),
]


def reader_cases(ctx: B.Ctx) -> List[B.Case]:
    out = []
    seed = ctx.args.seed
    for rname, fn, src, other in READERS:
        for kind in H.JSON_KINDS:
            setup, arg = H.input_setup(kind, "in.json", src, other, seed, ctx.fx)
            expect = "any" if kind in H.MAY_SUCCEED else "refuse"
            out.append(case(f"py-reader/{rname}/{kind}", "py-reader", f"RESULT = {fn}({arg!r})", expect=expect,
                            setup=setup, fast=kind in H.FAST_INPUT_KINDS and crc(rname + kind) % 2 == 0))
        for label, expr, exp in [("None", "None", "refuse"), ("int", "123", "refuse"), ("bytes", "b'in.json'", "any"),
                                 ("pathlib", "pathlib.Path('in.json')", "ok"), ("nul-in-str", "'in\\x00.json'", "refuse"),
                                 ("empty", "''", "refuse"), ("long", "'x' * 5000", "refuse"),
                                 ("surrogate", "'\\udcff.json'", "refuse"), ("list", "['in.json']", "refuse"),
                                 ("fd", "0", "refuse"), ("pathlike-raising", "BadPath()", "refuse")]:
            code = ("class BadPath:\n    def __fspath__(self):\n        raise Boom('fspath')\n" if label == "pathlike-raising"
                    else "") + f"RESULT = {fn}({expr})"
            out.append(case(f"py-reader/{rname}/path={label}", "py-reader", code, expect=exp,
                            setup=H.input_setup("symlink-valid", "in.json", src, other, seed, ctx.fx)[0],
                            allowed=["Boom"], no_message=label == "long"))
    # a dataset whose first image is hostile, read and detected from Python
    for kind in H.IMAGE_KINDS:
        if kind.startswith("/dev/") and kind != "/dev/zero":
            continue

        def setup(d, kind=kind):
            H.dataset_with_image(kind, d, ctx.fx, seed)

        out.append(case(f"py-reader/Dataset.detect/view-image={kind}", "py-reader",
                        "o, summary = etlcal.Dataset.load('dataset.json').detect()\nRESULT = (len(o), summary)",
                        setup=setup, timeout=60, fast=kind in ("fifo", "png-huge-header")))
    return out


FROM_JSON = [("Calibration", "cal.json"), ("Observations", "obs.json"), ("Dataset", "dataset.json"),
             ("Board", "charuco_sim.json"), ("ThermalCalibration", "thermal.json"), ("A0", "a0.json")]
BAD_TEXT = [("empty", "''"), ("null", "'null'"), ("array", "'[]'"), ("object", "'{}'"), ("nan", "'NaN'"),
            ("string", "'\"x\"'"), ("deep-array", "'[' * 100000 + ']' * 100000"),
            ("deep-object", "'{\"a\":' * 100000 + '1' + '}' * 100000"), ("nul", "'\\x00'"),
            ("surrogate", "'\\ud800'"), ("other-format", "open(fx({other!r})).read()"),
            ("garbage-after", "open(fx({src!r})).read() + '}{'"), ("huge-format", "json.dumps(dict(json.loads(open(fx({src!r})).read()), format='x' * 10_000_000))"),
            ("bytes", "b'{}'"), ("int", "123"), ("None", "None"), ("bom", "'\\ufeff' + open(fx({src!r})).read()"),
            ("valid", "open(fx({src!r})).read()"), ("1e999", "open(fx({src!r})).read().replace('1', '1e999', 1)"),
            ("utf8-lookalike", "open(fx({src!r})).read().replace('format', 'f\\u043ermat')")]


def from_json_cases(ctx: B.Ctx) -> List[B.Case]:
    out = []
    others = {"Calibration": "a0.json", "Observations": "cal.json", "Dataset": "obs.json", "Board": "thermal.json",
              "ThermalCalibration": "charuco_sim.json", "A0": "cal.json"}
    for cls, src in FROM_JSON:
        for label, expr in BAD_TEXT:
            e = expr.replace("{src!r}", repr(src)).replace("{other!r}", repr(others[cls]))
            code = f"import json\nRESULT = etlcal.{cls}.from_json({e})"
            exp = "ok" if label == "valid" else ("any" if label in ("bom",) else "refuse")
            out.append(case(f"py-fromjson/{cls}/{label}", "py-fromjson", code, expect=exp))
    dicts = ["{}", "{'type': 'charuco'}", "{'type': 'charuco', 'squares': [10**9, 10**9], 'square_mm': 1.0, "
             "'marker_mm': 0.5, 'dictionary': 'DICT_4X4_50'}", "{'type': 'checkerboard', 'inner_corners': [2**64, 3], "
             "'square_mm': 1.0}", "{'inner_corners': [14, 12], 'square_mm': float('nan')}",
             "{'type': 'checkerboard', 'inner_corners': [14, 12], 'square_mm': 1e306}", "[]", "None", "'charuco'",
             "{'type': 'charuco', 'squares': [7, 5], 'square_mm': 1.0, 'marker_mm': 0.5, 'dictionary': 5}",
             "{'type': 'checkerboard', 'inner_corners': (14, 12), 'square_mm': 1.5, 'extra': object()}",
             "{1: 2}", "{'type': 'checkerboard', 'inner_corners': [14, 12, 3], 'square_mm': 1.5}"]
    for k, dct in enumerate(dicts):
        out.append(case(f"py-fromjson/Board.from_dict/{k}", "py-fromjson", f"RESULT = etlcal.Board.from_dict({dct})",
                        expect="refuse" if k not in (5, 10) else "any"))
    return out


# ---------------------------------------------------------------------------------------
# Numbers

PYV = [("nan", "float('nan')"), ("inf", "float('inf')"), ("-inf", "float('-inf')"), ("1e308", "1e308"),
       ("-1e308", "-1e308"), ("0.0", "0.0"), ("-1.0", "-1.0"), ("denormal", "5e-324"), ("2^64", "2**64"),
       ("-2^63-1", "-2**63-1"), ("10^400", "10**400"), ("text", "'text'"), ("empty", "''"), ("None", "None"),
       ("True", "True"), ("complex", "1j"), ("np-nan", "np.float32('nan')"), ("list", "[1.0]"),
       ("str-num", "'150'"), ("object", "object()")]
PYV_INT_EXTRA = [("u64max", "2**64-1"), ("1.5", "1.5"), ("-1", "-1"), ("0", "0"), ("2^31", "2**31")]
FAST_PYV = {"nan", "1e308", "10^400", "text", "-1.0", "u64max"}
TYPE_BAD = {"text", "empty", "complex", "list", "str-num", "object"}
NONFINITE = {"nan", "inf", "-inf", "np-nan"}
HUGE = {"1e308", "-1e308", "10^400", "2^64", "-2^63-1"}
REFUSE = {
    "b": TYPE_BAD | NONFINITE | HUGE,
    "pos": TYPE_BAD | NONFINITE | HUGE | {"-1.0"},
    "math": TYPE_BAD,
    "int": TYPE_BAD | NONFINITE | HUGE | {"1.5", "-1", "u64max", "-1.0", "0.0", "denormal"},
    "count": TYPE_BAD | NONFINITE | HUGE | {"1.5", "-1", "u64max", "-1.0", "0.0", "denormal", "0"},
    "seed": TYPE_BAD | NONFINITE | {"1.5", "-1", "-1.0", "0.0", "denormal", "1e308", "-1e308", "10^400", "2^64",
                                    "-2^63-1"},
    "clamp": TYPE_BAD | NONFINITE,
}

VL = "v = etlcal.VirtualLens()\n"
LENS = "v = etlcal.VirtualLens()\nwith etlcal.Lens(v.port) as lens:\n    "
THP = "etlcal.ThermalCalibration.paper()"
CAL_ARGS = "[0.2, 0.2, 0.2], [-11.0, -4.0, 48.0], [5400.0, -7.3, 0.021, -3.2e-5], [5445.0, -7.3, 0.021, -3.2e-5], [900.0, 550.0], [0.0] * 9"

# (name, template with {V}, category, outputs, timeout)
NUMERIC = [
    ("calibrate.robust_k_px", "RESULT = etlcal.calibrate(obs(), robust='huber', robust_k_px={V}).rms_px", "pos"),
    ("calibrate.sigma_z_mm", "RESULT = etlcal.calibrate(obs(), sigma_z_mm={V}).rms_px", "pos"),
    ("calibrate.sigma_z_um", "RESULT = etlcal.calibrate(obs(), sigma_z_um={V}).rms_px", "pos"),
    ("calibrate.sigma_e_ma", "RESULT = etlcal.calibrate(obs(), sigma_e_ma={V}).rms_px", "pos"),
    ("calibrate.sigma_px", "RESULT = etlcal.calibrate(obs(), sigma_px={V}).rms_px", "pos"),
    ("calibrate.focal_degree", "RESULT = etlcal.calibrate(obs(), focal_degree={V}).rms_px", "int"),
    ("render.e_com_ma", "RESULT = etlcal.render(e_com_ma={V})[1].shape", "b"),
    ("render.z_mm", "RESULT = etlcal.render(z_mm={V})[1].shape", "b"),
    ("render.square_mm", "RESULT = etlcal.render(square_mm={V})[1].shape", "pos"),
    ("render.aperture_mm", "RESULT = etlcal.render(aperture_mm={V})[1].shape", "b"),
    ("render.blur_px", "RESULT = etlcal.render(blur_px={V})[1].shape", "b"),
    ("render.noise", "RESULT = etlcal.render(noise={V})[1].shape", "b"),
    ("render.bit_depth", "RESULT = etlcal.render(bit_depth={V})[1].shape", "count"),
    ("render.seed", "RESULT = etlcal.render(seed={V})[1].shape", "seed"),
    ("render.pattern", "RESULT = etlcal.render(pattern=({V}, 12))[1].shape", "count"),
    ("paper_rig.seed", "RESULT = len(etlcal.simulate.paper_rig(seed={V}).observations)", "seed"),
    ("strong_rig.seed", "RESULT = len(etlcal.simulate.strong_rig(seed={V}).observations)", "seed"),
    ("study.trials", "RESULT = etlcal.study('fig6', trials={V}).keys()", "count", [], 60),
    ("study.seed", "RESULT = etlcal.study('fig5', seed={V}).keys()", "seed"),
    ("at.e_in", "RESULT = cal().at({V}, 31.0)", "b"),
    ("at.t", "RESULT = cal().at(150.0, {V})", "b"),
    ("at.e_in.extrapolate", "RESULT = cal().at({V}, 31.0, allow_extrapolation=True)", "b"),
    ("at.t.extrapolate", "RESULT = cal().at(150.0, {V}, allow_extrapolation=True)", "b"),
    ("at_e_com", "RESULT = cal_ecom().at_e_com({V})", "b"),
    ("at_e_com.extrapolate", "RESULT = cal_ecom().at_e_com({V}, allow_extrapolation=True)", "b"),
    ("e_com", "RESULT = cal().e_com({V}, 31.0)", "b"),
    ("e_in_for_e_com", "RESULT = cal().e_in_for_e_com({V}, 31.0)", "b"),
    ("focus_e_in", "RESULT = cal().focus_e_in({V}, 31.0)", "b"),
    ("focus_e_in.t", "RESULT = cal().focus_e_in(80.0, {V})", "b"),
    ("focus_distance_mm", "RESULT = cal().focus_distance_mm({V}, 31.0)", "b"),
    ("focal_lengths", "RESULT = cal().focal_lengths({V})", "b"),
    ("intrinsics", "RESULT = cal().intrinsics({V})", "b"),
    ("distortion", "RESULT = cal().distortion({V})", "b"),
    ("to_opencv", "RESULT = cal().to_opencv({V})", "b"),
    ("cal.undistort_maps.e", "RESULT = cal().undistort_maps({V}, size=(64, 48))[0].shape", "b"),
    ("cal.project.e", "RESULT = cal().project(world(), {V})", "b"),
    ("cal.ray.e", "RESULT = cal().ray((900.0, 700.0), {V})", "b"),
    ("cal.undistort.e", "RESULT = cal().undistort(corners(), {V})", "b"),
    ("cal.projection_std.e", "RESULT = cal().projection_std(world(), {V})", "b"),
    ("cal.undistort_image.e", "RESULT = cal().undistort_image(img(), {V}).shape", "b"),
    ("cal.export.e_in", "RESULT = cal().export('cam.yaml', {V}, 31.0, 'opencv')", "b", ["cam.yaml"]),
    ("cam.ray.u", "RESULT = cam().ray(({V}, 700.0))", "b"),
    ("cam.undistort_maps.width", "RESULT = cam().undistort_maps(size=({V}, 48))[0].shape", "count"),
    ("cam.undistort_maps.height", "RESULT = cam().undistort_maps(size=(64, {V}))[0].shape", "count"),
    ("cam.undistort_maps.K", "RESULT = cam().undistort_maps(new_camera_matrix=[[{V}, 0, 900], [0, 5000, 700], "
                             "[0, 0, 1]], size=(64, 48))[0].shape", "b"),
    ("cam.solve_pnp.sigma_px", "RESULT = cam().solve_pnp(board_mm(), corners(), sigma_px={V})", "pos"),
    ("surface.e_t", "RESULT = etlcal.ThermalSurface.paper().e_t({V}, 31.0)", "math"),
    ("surface.e_t.t", "RESULT = etlcal.ThermalSurface.paper().e_t(150.0, {V})", "math"),
    ("surface.e_com", "RESULT = etlcal.ThermalSurface.paper().e_com({V}, 31.0)", "math"),
    ("surface.e_in_for_e_com", "RESULT = etlcal.ThermalSurface.paper().e_in_for_e_com({V}, 31.0)", "math"),
    ("surface.new", "RESULT = etlcal.ThermalSurface([{V}] + [0.0] * 9).e_t(100.0, 30.0)", "b"),
    ("thcal.compensate", f"RESULT = {THP}.compensate({{V}}, 31.0)", "b"),
    ("thcal.compensate.t", f"RESULT = {THP}.compensate(150.0, {{V}})", "b"),
    ("thcal.e_in_for_e_com", f"RESULT = {THP}.e_in_for_e_com({{V}}, 31.0)", "b"),
    ("thcal.contains", f"RESULT = {THP}.contains({{V}}, 31.0)", "math"),
    ("thcal.new.e_in_range", "RESULT = etlcal.ThermalCalibration(etlcal.ThermalSurface.paper(), e_in_range_ma=({V}, "
                             "200.0), t_range_c=(27.0, 37.0))", "b"),
    ("thcal.new.t_range", "RESULT = etlcal.ThermalCalibration(etlcal.ThermalSurface.paper(), e_in_range_ma=(40.0, "
                          "200.0), t_range_c=(27.0, {V}))", "b"),
    ("thcal.new.rms", "RESULT = etlcal.ThermalCalibration(etlcal.ThermalSurface.paper(), e_in_range_ma=(40.0, 200.0),"
                      " t_range_c=(27.0, 37.0), rms_ma={V})", "b"),
    ("physics.f_com_mm", "RESULT = etlcal.LensPhysics.paper().f_com_mm({V})", "math"),
    ("physics.radius", "RESULT = etlcal.LensPhysics.paper().radius_of_curvature_mm({V})", "math"),
    ("physics.f_com_for_f_liq", "RESULT = etlcal.LensPhysics.paper().f_com_for_f_liq_mm({V})", "math"),
    ("physics.gravity_error", "RESULT = etlcal.LensPhysics.paper().gravity_error_mm(150.0, {V})", "math"),
    ("physics.gravity_coefficient", "RESULT = etlcal.LensPhysics.paper().gravity_coefficient(150.0, {V}, 1000.0)", "math"),
    ("physics.poly.step", "RESULT = etlcal.LensPhysics.paper().polynomial_fit_rmse_mm(step_ma={V})", "pos"),
    ("physics.poly.from", "RESULT = etlcal.LensPhysics.paper().polynomial_fit_rmse_mm(e_from_ma={V})", "b"),
    ("physics.poly.to", "RESULT = etlcal.LensPhysics.paper().polynomial_fit_rmse_mm(e_to_ma={V})", "b"),
    ("boardpose.rotation", "RESULT = etlcal.BoardPose(({V}, 0.0, 0.0), (0.0, 0.0, 50.0)).rotation_matrix", "b"),
    ("boardpose.translation", "RESULT = etlcal.BoardPose((0.0, 0.0, 0.0), (0.0, 0.0, {V})).translation_mm", "b"),
    ("boardpose.rms", "RESULT = etlcal.BoardPose((0.0, 0.0, 0.0), (0.0, 0.0, 50.0), rms_px={V})", "b"),
    ("boardpose.iterations", "RESULT = etlcal.BoardPose((0.0, 0.0, 0.0), (0.0, 0.0, 50.0), iterations={V})", "int"),
    ("a0.kf0x", "RESULT = etlcal.A0({V}, 5400.0, 900.0, 700.0).to_json()", "b"),
    ("a0.u0", "RESULT = etlcal.A0(5400.0, 5400.0, {V}, 700.0).to_json()", "b"),
    ("board.charuco.squares", "RESULT = etlcal.Board.charuco(({V}, 5), 1.5, 1.1, 'DICT_5X5_100').corner_count", "count"),
    ("board.charuco.square_mm", "RESULT = etlcal.Board.charuco((7, 5), {V}, 1.1, 'DICT_5X5_100')", "pos"),
    ("board.charuco.marker_mm", "RESULT = etlcal.Board.charuco((7, 5), 1.5, {V}, 'DICT_5X5_100')", "pos"),
    ("board.charuco.dictionary", "RESULT = etlcal.Board.charuco((7, 5), 1.5, 1.1, {V})", "b"),
    ("board.checker.inner", "RESULT = etlcal.Board.checkerboard(({V}, 5), 1.5).corner_count", "count"),
    ("board.checker.square", "RESULT = etlcal.Board.checkerboard((9, 6), {V})", "pos"),
    ("board.to_image.dpi", "RESULT = board().to_image({V}).shape", "pos"),
    ("board.to_image.margin", "RESULT = board().to_image(100, margin_mm={V}).shape", "b"),
    ("board.to_svg.margin", "RESULT = len(board().to_svg(margin_mm={V}))", "b"),
    ("obs.new.size", "RESULT = etlcal.Observations(({V}, 1458))", "count"),
    ("obs.add_view.e_in", "o = etlcal.Observations((1936, 1458))\no.add_view(board_mm()[:20] + [0, 0, 60], "
                          "corners()[:20], {V}, 31.0)", "b"),
    ("obs.add_view.t", "o = etlcal.Observations((1936, 1458))\no.add_view(board_mm()[:20] + [0, 0, 60], "
                       "corners()[:20], 150.0, {V})", "b"),
    ("obs.add_view.e_com", "o = etlcal.Observations((1936, 1458))\no.add_view(board_mm()[:20] + [0, 0, 60], "
                           "corners()[:20], 150.0, 31.0, {V})", "b"),
    ("obs.getitem", "RESULT = obs()[{V}]", "int"),
    ("obs.view", "RESULT = obs().view({V})", "int"),
    ("obs.offstate_view", "RESULT = obs().offstate_view({V})", "int"),
    ("dataset.new.square", "RESULT = etlcal.Dataset((1936, 1458), inner_corners=(14, 12), square_mm={V})", "pos"),
    ("dataset.new.size", "RESULT = etlcal.Dataset(({V}, 1458), inner_corners=(14, 12), square_mm=1.5)", "count"),
    ("dataset.add_view.e_in", "ds = etlcal.Dataset((1936, 1458), board=board())\n"
                              "ds.add_view(fx('img.png'), {V}, 31.0, 60.0)", "b"),
    ("dataset.add_view.z", "ds = etlcal.Dataset((1936, 1458), board=board())\n"
                           "ds.add_view(fx('img.png'), 150.0, 31.0, {V})", "b"),
    ("dataset.add_view.first_corner", "ds = etlcal.Dataset((1936, 1458), inner_corners=(14, 12), square_mm=1.5)\n"
                                      "ds.add_view(fx('img.png'), 150.0, 31.0, 60.0, first_corner=({V}, 0))", "int"),
    ("autofocus.range", "RESULT = etlcal.autofocus(lambda e: -(e - 150.0) ** 2, range_ma=({V}, 240.0))", "b"),
    ("autofocus.coarse", "RESULT = etlcal.autofocus(lambda e: -(e - 150.0) ** 2, coarse_points={V})", "count"),
    ("autofocus.max_evaluations", "RESULT = etlcal.autofocus(lambda e: -(e - 150.0) ** 2, max_evaluations={V})",
     "count"),
    ("autofocus.tolerance", "RESULT = etlcal.autofocus(lambda e: -(e - 150.0) ** 2, tolerance_ma={V})", "pos"),
    ("vlens.set_temperature_c", VL + "v.set_temperature_c({V})", "b"),
    ("vlens.set_ambient_c", VL + "v.set_ambient_c({V})", "b"),
    ("vlens.advance_s", VL + "v.advance_s({V})", "b"),
    ("vlens.faults.delay", VL + "v.inject_faults(reply_delay_ms={V})", "b"),
    ("vlens.faults.silence", VL + "v.inject_faults(silence_next={V})", "int"),
    ("vlens.faults.corrupt", VL + "v.inject_faults(corrupt_next={V})", "int"),
    ("vlens.faults.error_frame", VL + "v.inject_faults(error_frame_next={V})", "int"),
    ("vlens.faults.drop", VL + "v.inject_faults(drop_rx_bytes_next={V})", "int"),
    ("lens.timeout_ms", VL + "etlcal.Lens(v.port, timeout_ms={V}).close()", "count"),
    ("lens.set_current", LENS + "RESULT = lens.set_current_ma({V})", "clamp"),
    ("lens.hold.e_com", LENS + f"RESULT = lens.hold({THP}, {{V}}, steps=2)", "b"),
    ("lens.hold.steps", LENS + f"RESULT = lens.hold({THP}, 120.0, steps={{V}}, duration_s=0.5)", "count"),
    ("lens.hold.duration", LENS + f"RESULT = lens.hold({THP}, 120.0, duration_s={{V}}, steps=3)", "b"),
    ("lens.hold.rate", LENS + f"RESULT = lens.hold({THP}, 120.0, rate_hz={{V}}, steps=2)", "b"),
    ("diff.grid", "RESULT = etlcal.diff(cam(), cam(), grid=({V}, 48))", "count"),
    ("zhang.size", "RESULT = etlcal.zhang(zhang_views(), image_size=({V}, 512))", "count"),
    ("cramer_rao.sigma_px", "s = etlcal.simulate.paper_rig(seed=1)\n"
                            "RESULT = etlcal.cramer_rao_std(s.observations, s.truth, {V})", "pos"),
    ("cramer_rao.sigma_z_mm", "s = etlcal.simulate.paper_rig(seed=1)\n"
                              "RESULT = etlcal.cramer_rao_std(s.observations, s.truth, 0.2, sigma_z_mm={V})", "pos"),
    ("detect.pattern", "RESULT = etlcal.detect_corners(img(), ({V}, 12))", "count"),
    ("calibration.new.image_size", f"RESULT = etlcal.Calibration({CAL_ARGS}, image_size=({{V}}, 1458))", "count"),
    ("calibration.new.range", f"RESULT = etlcal.Calibration({CAL_ARGS}, e_com_range_ma=({{V}}, 225.0))", "b"),
    ("calibration.new.rms", f"RESULT = etlcal.Calibration({CAL_ARGS}, rms_px={{V}})", "b"),
]
for _p in ("young_modulus_pa", "membrane_radius_mm", "membrane_thickness_mm", "poisson_ratio", "prestrain", "n_liq",
           "p0_pa", "f_pri_mm", "d_lens_mm"):
    NUMERIC.append((f"physics.new.{_p}", f"RESULT = etlcal.LensPhysics({_p}={{V}}).f_com_mm(150.0)", "b"))

STRINGS = [("nope", "'nope'"), ("empty", "''"), ("None", "None"), ("int", "5"), ("bytes", "b'x'"), ("nul", "'\\x00'"),
           ("long", "'x' * 1000000"), ("upper", "{upper}"), ("surrogate", "'\\udcff'")]
STRING_ARGS = [
    ("sharpness.metric", "RESULT = etlcal.sharpness(img(), {S})", "'CPBD'"),
    ("study.name", "RESULT = etlcal.study({S}, trials=1)", "'FIG5'"),
    ("calibrate.estimator", "RESULT = etlcal.calibrate(obs(), estimator={S})", "'EIV'"),
    ("calibrate.method", "RESULT = etlcal.calibrate(obs(), method={S})", "'PROPOSED'"),
    ("calibrate.distortion", "RESULT = etlcal.calibrate(obs(), distortion={S})", "'PAPER'"),
    ("calibrate.robust", "RESULT = etlcal.calibrate(obs(), robust={S})", "'HUBER'"),
    ("calibrate.centre", "RESULT = etlcal.calibrate(obs(), centre={S})", "'FIXED'"),
    ("calibrate.thermal", "RESULT = etlcal.calibrate(obs(), thermal={S})", "'PAPER'"),
    ("paper_rig.noise", "RESULT = etlcal.simulate.paper_rig(noise={S})", "'PAPER'"),
    ("cam.export.format", "RESULT = cam().export('cam.yaml', {S})", "'OPENCV'"),
    ("board.charuco.dict", "RESULT = etlcal.Board.charuco((7, 5), 1.5, 1.1, {S})", "'dict_5x5_100'"),
    ("detect.board-string", "RESULT = etlcal.detect_corners(img(), {S})", "'14X12'"),
    ("obs.e_com_ma.thermal", "RESULT = obs().e_com_ma({S})", "'PAPER'"),
    ("zhang.model", "RESULT = etlcal.zhang(zhang_views(), (640, 512), model={S})", "'OPENCV'"),
    ("calibration.new.thermal", f"RESULT = etlcal.Calibration({CAL_ARGS}, thermal={{S}})", "'PAPER'"),
]


def number_cases(ctx: B.Ctx) -> List[B.Case]:
    out = []
    for entry in NUMERIC:
        name, tpl, cat = entry[:3]
        outputs = entry[3] if len(entry) > 3 else []
        timeout = entry[4] if len(entry) > 4 else None
        values = PYV + (PYV_INT_EXTRA if cat in ("int", "count", "seed") else [])
        for label, expr in values:
            if name == "study.trials" and label in ("True",):
                continue  # one trial: valid, just slow enough to skip
            code = tpl.replace("{V}", expr)
            expect = "refuse" if label in REFUSE[cat] else "any"
            allowed = ["IndexError"] if name.startswith("obs.") and name != "obs.new.size" and \
                not name.startswith("obs.add_view") else []
            out.append(case(f"py-number/{name}={label}", "py-number", code, expect=expect, outputs=outputs,
                            allowed=allowed, timeout=timeout, fast=label in FAST_PYV and crc(name + label) % 4 == 0))
    for name, tpl, upper in STRING_ARGS:
        for label, expr in STRINGS:
            e = upper if label == "upper" else expr
            code = tpl.replace("{S}", e)
            expect = "any" if label in ("None", "upper") else "refuse"
            out.append(case(f"py-string/{name}={label}", "py-number", code, expect=expect,
                            outputs=["cam.yaml"] if "export" in name else [], timeout=60 if "study" in name else None,
                            fast=label == "long" and crc(name) % 3 == 0))
    return out


# ---------------------------------------------------------------------------------------
# Arrays

# target: (template with {A}, the valid array, kind of array)
ARRAY_TARGETS = [
    ("cam.project", "RESULT = cam().project({A})", "world()", "points3"),
    ("cam.projection_std", "RESULT = cam().projection_std({A})", "world()", "points3"),
    ("cal.project", "RESULT = cal().project({A}, 150.0)", "world()", "points3"),
    ("cam.undistort", "RESULT = cam().undistort({A})", "corners()", "points2"),
    ("cam.solve_pnp.pixels", "RESULT = cam().solve_pnp(board_mm(), {A})", "corners()", "points2"),
    ("cam.solve_pnp.board", "RESULT = cam().solve_pnp({A}, corners())", "board_mm()", "points3"),
    ("obs.add_view.pixels", "o = etlcal.Observations((1936, 1458))\no.add_view(board_mm() + [0, 0, 60], {A}, 150.0, 31.0)",
     "corners()", "points2"),
    ("obs.add_view.world", "o = etlcal.Observations((1936, 1458))\no.add_view({A}, corners(), 150.0, 31.0)",
     "board_mm() + [0, 0, 60]", "points3"),
    ("obs.from_arrays.world", "RESULT = etlcal.Observations.from_arrays((1936, 1458), [{A}], [corners()], [150.0], [31.0])",
     "board_mm() + [0, 0, 60]", "points3"),
    ("zhang.pixels", "v = zhang_views()\nv[0] = (v[0][0], {A})\nRESULT = etlcal.zhang(v, (640, 512))",
     "zhang_views()[0][1]", "points2"),
    ("sharpness.cpbd", "RESULT = etlcal.sharpness({A})", "img()", "image"),
    ("sharpness.tenengrad", "RESULT = etlcal.sharpness({A}, 'tenengrad')", "img()", "image"),
    ("detect.pattern", "RESULT = etlcal.detect_corners({A}, '14x12')", "img()", "image"),
    ("detect.board", "RESULT = etlcal.detect_corners({A}, board())", "img()", "image"),
    ("cam.undistort_image", "RESULT = cam().undistort_image({A}).shape", "img()", "image"),
    ("focal_lengths", "RESULT = cal().focal_lengths({A})", "np.array([100.0, 150.0, 200.0])", "currents"),
    ("intrinsics", "RESULT = cal().intrinsics({A})", "np.array([100.0, 150.0, 200.0])", "currents"),
    ("distortion", "RESULT = cal().distortion({A})", "np.array([100.0, 150.0, 200.0])", "currents"),
    ("to_opencv", "RESULT = cal().to_opencv({A})", "np.array([100.0, 150.0, 200.0])", "currents"),
    ("surface.e_com", "RESULT = etlcal.ThermalSurface.paper().e_com({A}, 31.0)", "np.array([100.0, 150.0, 200.0])",
     "currents"),
    ("thcal.compensate", f"RESULT = {THP}.compensate({{A}}, 31.0)", "np.array([100.0, 150.0, 200.0])", "currents"),
    ("thcal.compensate.broadcast", f"RESULT = {THP}.compensate({{A}}, np.array([30.0, 31.0]))",
     "np.array([100.0, 150.0, 200.0])", "currents"),
    ("cal.e_com", "RESULT = cal().e_com({A}, 31.0)", "np.array([100.0, 150.0, 200.0])", "currents"),
    ("physics.f_com_mm", "RESULT = etlcal.LensPhysics.paper().f_com_mm({A})", "np.array([100.0, 150.0, 200.0])",
     "currents"),
    ("surface.new", "RESULT = etlcal.ThermalSurface({A})", "etlcal.ThermalSurface.paper().coefficients", "coeffs"),
    ("surface.fit", "RESULT = etlcal.ThermalSurface.fit({A}, np.full(30, 30.0), np.full(30, 1.0))",
     "np.linspace(40.0, 240.0, 30)", "currents"),
    ("undistort_maps.K", "RESULT = cam().undistort_maps(new_camera_matrix={A}, size=(64, 48))[0].shape",
     "np.array([[5000.0, 0, 900], [0, 5000.0, 700], [0, 0, 1]])", "matrix"),
    ("calibration.new.kf_x", f"RESULT = etlcal.Calibration([0.2, 0.2, 0.2], [-11.0, -4.0, 48.0], {{A}}, "
                             "[5445.0, -7.3, 0.021, -3.2e-5], [900.0, 550.0], [0.0] * 9)",
     "np.array([5400.0, -7.3, 0.021, -3.2e-5])", "coeffs"),
]

ARRAY_KINDS = {
    "common": [("f32", "{B}.astype(np.float32)"), ("i64", "{B}.astype(np.int64)"), ("u8", "{B}.astype(np.uint8)"),
               ("bool", "{B}.astype(bool)"), ("c128", "{B}.astype(complex)"), ("object", "{B}.astype(object)"),
               ("str", "{B}.astype(str)"), ("f16", "{B}.astype(np.float16)"), ("big-endian", "{B}.astype('>f8')"),
               ("empty", "np.zeros((0,) + {B}.shape[1:], {B}.dtype)"), ("flat", "{B}.ravel()"),
               ("0d", "np.float64(1.0)"), ("extra-dim", "{B}[None]"),
               ("nan", "np.full({B}.shape, np.nan)"), ("inf", "np.full({B}.shape, np.inf)"),
               ("1e308", "np.full({B}.shape, 1e308)"), ("every-other", "{B}[::2]"), ("reversed", "{B}[::-1]"),
               ("transposed", "{B}.T"), ("fortran", "np.asfortranarray({B})"), ("readonly", "readonly({B})"),
               ("zero-stride", "huge({B}.shape, {B}.dtype, {B}.ravel()[0] if {B}.size else 0)"),
               ("huge-2^31", "huge((2**31,) + {B}.shape[1:], {B}.dtype, {B}.ravel()[0])"),
               ("huge-2^40", "huge((2**40,) + {B}.shape[1:], {B}.dtype, {B}.ravel()[0])"),
               ("list", "{B}.tolist()"), ("ragged", "[[1.0, 2.0, 3.0], [1.0, 2.0]]"),
               ("masked", "np.ma.masked_array({B}, mask=np.zeros({B}.shape, bool))"),
               ("memoryview", "memoryview(np.ascontiguousarray({B}))"), ("None", "None"), ("str-scalar", "'points'"),
               ("void", "np.zeros({B}.shape, dtype='V8')"), ("datetime", "np.zeros({B}.shape, dtype='datetime64[s]')"),
               ("nested-deep", "[[[[[1.0]]]]]"), ("generator", "(x for x in {B})"), ("dict", "{{'a': 1}}")],
    "image": [("rgb", "np.dstack([{B}] * 3)"), ("rgba", "np.dstack([{B}] * 4)"), ("one-channel", "{B}[:, :, None]"),
              ("1x1", "{B}[:1, :1]"), ("1x100000", "np.zeros((1, 100000), np.uint8)"), ("0x0", "{B}[:0, :0]"),
              ("black", "np.zeros_like({B})"), ("white", "np.full_like({B}, 255)"), ("i8", "{B}.astype(np.int8)"),
              ("f64-unit", "{B} / 255.0"), ("f32-nan", "np.full({B}.shape, np.nan, np.float32)"),
              ("u16-max", "np.full({B}.shape, 65535, np.uint16)"), ("u32", "{B}.astype(np.uint32)"),
              ("huge-1gpx", "huge((2**15, 2**15), np.uint8, 128)"), ("huge-1tpx", "huge((2**20, 2**20), np.uint8, 128)"),
              ("huge-2^28+1", "huge((2**14 + 1, 2**14), np.uint8, 128)"), ("every-other-2d", "{B}[::2, ::2]"),
              ("u16-big-endian", "{B}.astype('>u2')"), ("tiny-3x3", "{B}[:3, :3]")],
}


def array_cases(ctx: B.Ctx) -> List[B.Case]:
    out = []
    for tname, tpl, base, kind in ARRAY_TARGETS:
        kinds = ARRAY_KINDS["common"] + (ARRAY_KINDS["image"] if kind == "image" else [])
        for label, aexpr in kinds:
            if kind == "image" and label in ("huge-2^31", "huge-2^40"):
                continue  # images have their own huge kinds
            a = aexpr.replace("{B}", f"_b").replace("{{", "{").replace("}}", "}")
            code = f"_b = {base}\n_a = {a}\ndel _b\n" + tpl.replace("{A}", "_a")
            expect = "refuse" if label in ("c128", "str", "object", "void", "datetime", "empty", "0d", "None",
                                           "str-scalar", "ragged", "nested-deep", "dict", "huge-2^40", "huge-1tpx",
                                           "0x0", "extra-dim") else "any"
            out.append(case(f"py-array/{tname}/{label}", "py-array", code, expect=expect, timeout=None,
                            fast=label in ("huge-2^31", "huge-1gpx", "nan", "object", "every-other") and
                            crc(tname + label) % 3 == 0))
    return out


# ---------------------------------------------------------------------------------------
# Threads and callbacks

THREADS = [
    ("cam.project-8-threads", "c = cam()\nRESULT = len(threads(lambda k: c.project(world()), 8))"),
    ("cal.at-8-threads", "c = cal()\nRESULT = len(threads(lambda k: c.at(150.0 + k, 31.0), 8))"),
    ("calibrate-4-threads-one-obs", "o = obs()\nRESULT = len(threads(lambda k: etlcal.calibrate(o), 4))"),
    ("obs.add_view-4-threads", "o = etlcal.Observations((1936, 1458))\n"
                               "RESULT = threads(lambda k: [o.add_view(board_mm() + [0, 0, 60], corners(), 150.0, 31.0)"
                               " for _ in range(50)], 4)\nRESULT = len(o)"),
    ("obs.add_view-while-calibrating", "o = obs()\nw, c = board_mm() + [0, 0, 60], corners()\n"
     "def add(k):\n    if k == 0:\n        return [etlcal.calibrate(o).rms_px for _ in range(5)]\n"
     "    for _ in range(300):\n        o.add_view(w, c, 150.0, 31.0)\n"
     "RESULT = threads(add, 3)"),
    ("obs.add_view-while-saving", "o = obs()\nw, c = board_mm() + [0, 0, 60], corners()\n"
     "def add(k):\n    if k == 0:\n        return [o.save('o.json') for _ in range(10)]\n"
     "    for _ in range(600):\n        o.add_view(w, c, 150.0, 31.0)\n"
     "RESULT = threads(add, 2)"),
    ("obs.to_json-while-adding", "o = obs()\nw, c = board_mm() + [0, 0, 60], corners()\n"
     "def add(k):\n    if k == 0:\n        return [len(o.to_json()) for _ in range(10)]\n"
     "    for _ in range(600):\n        o.add_view(w, c, 150.0, 31.0)\n"
     "RESULT = threads(add, 2)"),
    ("dataset.to_json-while-adding", "ds = etlcal.Dataset.load(fx('dataset.json'))\n"
     "def f(k):\n    if k == 0:\n        return [len(ds.to_json()) for _ in range(50)]\n"
     "    for _ in range(600):\n        ds.add_view(fx('img.png'), 150.0, 31.0, 60.0)\n"
     "RESULT = threads(f, 2)"),
    ("obs.iterate-while-adding", "o = obs()\n"
     "def f(k):\n    if k == 0:\n        return sum(1 for _ in o for _ in range(3))\n"
     "    for _ in range(100):\n        o.add_view(board_mm() + [0, 0, 60], corners(), 150.0, 31.0)\n"
     "RESULT = threads(f, 2)"),
    ("obs.save-while-adding-small", "o = obs()\n"
     "def f(k):\n    if k == 0:\n        for i in range(5):\n            o.save(f'o{i}.json')\n        return 1\n"
     "    for _ in range(100):\n        o.add_view(board_mm() + [0, 0, 60], corners(), 150.0, 31.0)\n"
     "RESULT = threads(f, 2)"),
    ("dataset.add_view-4-threads", "ds = etlcal.Dataset((1936, 1458), board=board())\n"
     "threads(lambda k: [ds.add_view(fx('img.png'), 150.0, 31.0, 60.0) for _ in range(100)], 4)\nRESULT = len(ds)"),
    ("dataset.detect-while-adding", "ds = etlcal.Dataset.load(fx('dataset.json'))\n"
     "def f(k):\n    if k == 0:\n        return ds.detect()[1]\n"
     "    for _ in range(50):\n        ds.add_view(fx('img.png'), 150.0, 31.0, 60.0)\n"
     "RESULT = threads(f, 2)"),
    ("vlens.from-thread", "v = etlcal.VirtualLens()\nRESULT = in_thread(v.state)"),
    ("vlens.created-in-thread-dropped-in-main", "v = in_thread(etlcal.VirtualLens)\nRESULT = v.state()\ndel v"),
    ("vlens.8-threads-state-and-faults", "v = etlcal.VirtualLens()\n"
     "RESULT = threads(lambda k: [v.state() if k % 2 else v.inject_faults(reply_delay_ms=1.0) for _ in range(200)], 8)"),
    ("vlens.advance-from-threads", "v = etlcal.VirtualLens()\nthreads(lambda k: [v.advance_s(0.5) for _ in range(100)], 4)\n"
     "RESULT = v.state()"),
    ("lens.8-threads", "v = etlcal.VirtualLens()\nwith etlcal.Lens(v.port) as lens:\n"
     "    RESULT = threads(lambda k: [lens.set_current_ma(100.0 + k) for _ in range(10)], 8)"),
    ("lens.call-during-hold", "v = etlcal.VirtualLens()\nseen = []\nwith etlcal.Lens(v.port) as lens:\n"
     "    def step(s):\n        try:\n            seen.append(in_thread(lens.current_ma))\n"
     "        except etlcal.Error as e:\n            seen.append(e)\n        return s.index < 3\n"
     f"    lens.hold({THP}, 120.0, on_step=step)\nRESULT = [type(x).__name__ for x in seen]"),
    ("lens.close-during-hold", "v = etlcal.VirtualLens()\nlens = etlcal.Lens(v.port)\n"
     "def step(s):\n    in_thread(lens.close)\n    return s.index < 3\n"
     f"RESULT = lens.hold({THP}, 120.0, on_step=step)"),
    ("lens.close-from-thread-during-calls", "v = etlcal.VirtualLens()\nlens = etlcal.Lens(v.port)\n"
     "def f(k):\n    if k == 0:\n        time.sleep(0.05)\n        return lens.close()\n"
     "    out = []\n    for _ in range(100):\n        try:\n            out.append(lens.current_ma())\n"
     "        except etlcal.Error as e:\n            out.append(type(e).__name__)\n    return out[-1]\n"
     "RESULT = threads(f, 3)"),
    ("vlens.disconnect-during-calls", "v = etlcal.VirtualLens()\nlens = etlcal.Lens(v.port, timeout_ms=100)\n"
     "def f(k):\n    if k == 0:\n        for _ in range(5):\n            v.disconnect(); time.sleep(0.01); v.reconnect()\n"
     "        return 0\n    out = []\n    for _ in range(30):\n        try:\n            out.append(lens.current_ma())\n"
     "        except etlcal.Error as e:\n            out.append(type(e).__name__)\n            try:\n"
     "                lens.reconnect()\n            except etlcal.Error:\n                pass\n    return out[-1]\n"
     "RESULT = threads(f, 3)\nlens.close()"),
    ("vlens.dropped-while-lens-in-use", "v = etlcal.VirtualLens()\nlens = etlcal.Lens(v.port, timeout_ms=100)\n"
     "def f(k):\n    global v\n    if k == 0:\n        time.sleep(0.02)\n        del v\n        gc.collect()\n        return 0\n"
     "    out = []\n    for _ in range(30):\n        try:\n            out.append(lens.current_ma())\n"
     "        except etlcal.Error as e:\n            out.append(type(e).__name__)\n    return out[-1]\n"
     "RESULT = threads(f, 2)\nlens.close()"),
    ("study-2-threads", "RESULT = threads(lambda k: etlcal.study('fig6', trials=1, seed=k).keys(), 2)"),
    ("render-and-sharpness-4-threads", "RESULT = threads(lambda k: etlcal.sharpness(etlcal.render(seed=k + 1)[0]), 4)"),
    ("autofocus-from-threads", "RESULT = threads(lambda k: etlcal.autofocus(lambda e: -(e - 100 - k) ** 2).best_ma, 4)"),
    ("sharpness-while-array-mutated", "a = img()\n"
     "def f(k):\n    if k == 0:\n        return [etlcal.sharpness(a, 'tenengrad') for _ in range(5)]\n"
     "    for i in range(200):\n        a[i % 1000] = 255 - a[i % 1000]\n"
     "RESULT = threads(f, 2)"),
    ("camera-shared-undistort-image", "c = cam()\nRESULT = threads(lambda k: c.undistort_image(img()).shape, 3)"),
]

CALLBACKS = [
    ("autofocus.raises-own", "etlcal.autofocus(lambda e: (_ for _ in ()).throw(Boom('user')))", ["Boom"]),
    ("autofocus.raises-zero-division", "etlcal.autofocus(lambda e: 1 / 0)", ["ZeroDivisionError"]),
    ("autofocus.raises-keyboard-interrupt", "def f(e):\n    raise KeyboardInterrupt\netlcal.autofocus(f)",
     ["KeyboardInterrupt"]),
    ("autofocus.raises-system-exit", "def f(e):\n    raise SystemExit(3)\netlcal.autofocus(f)", ["SystemExit"]),
    ("autofocus.raises-memory-error", "def f(e):\n    raise MemoryError\netlcal.autofocus(f)", ["MemoryError"]),
    ("autofocus.raises-etlcal-error", "def f(e):\n    raise etlcal.InputError('mine')\netlcal.autofocus(f)", []),
    ("autofocus.returns-nan", "RESULT = etlcal.autofocus(lambda e: float('nan'))", []),
    ("autofocus.returns-inf", "RESULT = etlcal.autofocus(lambda e: float('inf'))", []),
    ("autofocus.returns-text", "RESULT = etlcal.autofocus(lambda e: 'sharp')", []),
    ("autofocus.returns-none", "RESULT = etlcal.autofocus(lambda e: None)", []),
    ("autofocus.returns-array", "RESULT = etlcal.autofocus(lambda e: np.array([1.0, 2.0]))", []),
    ("autofocus.returns-huge-int", "RESULT = etlcal.autofocus(lambda e: 10**400)", []),
    ("autofocus.returns-object-raising-float", "class X:\n    def __float__(self):\n        raise Boom('float')\n"
                                               "RESULT = etlcal.autofocus(lambda e: X())", ["Boom"]),
    ("autofocus.reentrant", "RESULT = etlcal.autofocus(lambda e: etlcal.autofocus(lambda f: -(f - e) ** 2).best_sharpness"
                            " - (e - 150) ** 2)", []),
    ("autofocus.not-callable", "RESULT = etlcal.autofocus(5)", []),
    ("autofocus.wrong-arity", "RESULT = etlcal.autofocus(lambda: 1.0)", []),
    ("autofocus.calls-gc-and-deletes", "def f(e):\n    gc.collect()\n    return -(e - 150.0) ** 2\n"
                                       "RESULT = etlcal.autofocus(f)", []),
    ("hold.on_step-raises", LENS + f"lens.hold({THP}, 120.0, on_step=lambda s: 1 / 0)", ["ZeroDivisionError"]),
    ("hold.on_step-keyboard-interrupt", "def st(s):\n    raise KeyboardInterrupt\n" + LENS +
     f"lens.hold({THP}, 120.0, on_step=st)", ["KeyboardInterrupt"]),
    ("hold.on_step-returns-text", LENS + f"RESULT = lens.hold({THP}, 120.0, steps=3, on_step=lambda s: 'go on')", []),
    ("hold.on_step-closes-lens", LENS + f"RESULT = lens.hold({THP}, 120.0, steps=3, on_step=lambda s: lens.close())", []),
    ("hold.on_step-holds-again", LENS + f"RESULT = lens.hold({THP}, 120.0, steps=3, on_step=lambda s: "
                                        f"lens.hold({THP}, 110.0, steps=1))", []),
    ("hold.on_step-uses-lens", LENS + f"RESULT = lens.hold({THP}, 120.0, steps=3, on_step=lambda s: lens.current_ma())",
     []),
    ("hold.on_step-disconnects", LENS + f"RESULT = lens.hold({THP}, 120.0, steps=3, on_step=lambda s: v.disconnect())",
     []),
    ("hold.thermal-wrong-type", LENS + "RESULT = lens.hold('paper', 120.0, steps=2)", []),
    ("thermal_calibration.capture-raises", "v = etlcal.VirtualLens()\nwith etlcal.Lens(v.port) as lens:\n"
     "    RESULT = etlcal.thermal_calibration(lens, lambda: 1 / 0, v.set_temperature_c, e_in_grid_ma=[100.0], "
     "temperatures_c=[30.0])", ["ZeroDivisionError"]),
    ("thermal_calibration.capture-none", "v = etlcal.VirtualLens()\nwith etlcal.Lens(v.port) as lens:\n"
     "    RESULT = etlcal.thermal_calibration(lens, lambda: None, v.set_temperature_c, e_in_grid_ma=[100.0], "
     "temperatures_c=[30.0])", []),
    ("thermal_calibration.capture-wrong-dtype", "v = etlcal.VirtualLens()\nwith etlcal.Lens(v.port) as lens:\n"
     "    RESULT = etlcal.thermal_calibration(lens, lambda: np.zeros((10, 10), complex), v.set_temperature_c, "
     "e_in_grid_ma=[100.0], temperatures_c=[30.0])", []),
    ("thermal_calibration.capture-huge", "v = etlcal.VirtualLens()\nwith etlcal.Lens(v.port) as lens:\n"
     "    RESULT = etlcal.thermal_calibration(lens, lambda: huge((2**20, 2**20), np.uint8), v.set_temperature_c, "
     "e_in_grid_ma=[100.0], temperatures_c=[30.0])", []),
    ("thermal_calibration.set_temperature-raises", "v = etlcal.VirtualLens()\nwith etlcal.Lens(v.port) as lens:\n"
     "    RESULT = etlcal.thermal_calibration(lens, img, lambda t: (_ for _ in ()).throw(Boom('t')), "
     "e_in_grid_ma=[100.0], temperatures_c=[30.0])", ["Boom"]),
    ("thermal_calibration.place_board-raises", "v = etlcal.VirtualLens()\nwith etlcal.Lens(v.port) as lens:\n"
     "    RESULT = etlcal.thermal_calibration(lens, img, v.set_temperature_c, place_board=lambda: 1 / 0, "
     "e_in_grid_ma=[100.0], temperatures_c=[30.0])", ["ZeroDivisionError"]),
    ("thermal_calibration.grid-empty", "v = etlcal.VirtualLens()\nwith etlcal.Lens(v.port) as lens:\n"
     "    RESULT = etlcal.thermal_calibration(lens, img, v.set_temperature_c, e_in_grid_ma=[], temperatures_c=[])", []),
    ("thermal_calibration.grid-nan", "v = etlcal.VirtualLens()\nwith etlcal.Lens(v.port) as lens:\n"
     "    RESULT = etlcal.thermal_calibration(lens, img, v.set_temperature_c, e_in_grid_ma=[float('nan')], "
     "temperatures_c=[30.0])", []),
    ("thermal_calibration.search-1e308", "v = etlcal.VirtualLens()\nwith etlcal.Lens(v.port) as lens:\n"
     "    RESULT = etlcal.thermal_calibration(lens, img, v.set_temperature_c, e_in_grid_ma=[100.0], "
     "temperatures_c=[30.0], search_ma=1e308)", []),
    ("thermal_calibration.temperature-200", "v = etlcal.VirtualLens()\nwith etlcal.Lens(v.port) as lens:\n"
     "    RESULT = etlcal.thermal_calibration(lens, img, v.set_temperature_c, e_in_grid_ma=[100.0], "
     "temperatures_c=[200.0])", []),
    ("thermal_calibration.lens-not-a-lens", "RESULT = etlcal.thermal_calibration('lens', img, print)", []),
]


def thread_cases(ctx: B.Ctx) -> List[B.Case]:
    out = []
    for name, code in THREADS:
        out.append(case(f"py-thread/{name}", "py-thread", code, timeout=60, fast=crc(name) % 3 == 0))
    for name, code, allowed in CALLBACKS:
        out.append(case(f"py-callback/{name}", "py-callback", code, allowed=allowed, timeout=60,
                        fast=crc(name) % 3 == 0))
    return out


# ---------------------------------------------------------------------------------------
# Writers

WRITERS = [
    ("Calibration.save", "cal().save({P})", "file"),
    ("Observations.save", "obs().save({P})", "file"),
    ("A0.save", "a0().save({P})", "file"),
    ("ThermalCalibration.save", "thermal().save({P})", "file"),
    ("Board.save", "board().save({P})", "file"),
    ("Dataset.save", "etlcal.Dataset.load(fx('dataset.json')).save({P})", "file"),
    ("CameraAt.export", "cam().export({P}, 'opencv')", "file"),
    ("Calibration.export", "cal().export({P}, 150.0, 31.0, 'ros')", "file"),
    ("study.out", "etlcal.study('fig5', out={P})", "dir"),
]
PY_FILE_KINDS = ["new", "earlier", "earlier-0600", "symlink-to-earlier", "dangling", "symlink-loop", "directory",
                 "fifo", "chardev", "readonly", "in-missing-dir", "in-readonly-dir", "long-component", "long-path",
                 "file-as-parent", "empty", "trailing-slash", "dot", "stale-temp", "absolute", "hardlink-to-input",
                 "symlink-to-input"]
PY_DIR_KINDS = ["new", "empty-dir", "foreign", "file", "fifo", "chardev", "symlink-loop", "long-component",
                "file-as-parent", "empty", "in-missing-dir", "dangling"]


def writer_cases(ctx: B.Ctx) -> List[B.Case]:
    out = []
    seed = ctx.args.seed
    earlier = ctx.fxp("set_study")
    for wname, tpl, typ in WRITERS:
        kinds = PY_FILE_KINDS if typ == "file" else PY_DIR_KINDS
        for kind in kinds:
            tok = "out.json" if typ == "file" else "st"

            def setup(d, kind=kind, typ=typ, tok=tok):
                with open(os.path.join(d, "keep.json"), "w") as f:
                    f.write('{"a file of the user": true}\n')
                if typ == "file":
                    H.make_file_output(kind, d, tok, "keep.json", seed)
                else:
                    H.make_dir_output(kind, d, tok, "keep.json", earlier, seed)

            import tempfile
            dd = tempfile.mkdtemp(dir=ctx.logs)
            try:
                with open(os.path.join(dd, "keep.json"), "w") as f:
                    f.write("x")
                with open(os.path.join(dd, "sentinel.txt"), "w") as f:
                    f.write("x")
                if typ == "file":
                    arg, allowed, expect = H.make_file_output(kind, dd, tok, "keep.json", seed)
                else:
                    arg, allowed, expect = H.make_dir_output(kind, dd, tok, "keep.json", earlier, seed)
            finally:
                B.cleanup(dd)
            protect = []
            if typ == "dir" and kind == "foreign":
                expect, allowed, protect = "any", [tok], [os.path.join(tok, "my-notes.txt")]
            if typ == "dir" and kind == "dangling":
                expect = "refuse"
            if kind in ("symlink-to-input", "hardlink-to-input"):
                # keep.json is no input of a save: written through a link is the policy
                expect, allowed = "any", [tok, "keep.json"]
            code = tpl.replace("{P}", repr(arg).replace("'{CASE}/", "os.getcwd() + '/"))
            if kind in ("in-missing-dir", "long-path") or (typ == "dir" and kind == "new"):
                expect = "any"  # Python's writers need the folder to exist
            out.append(case(f"py-writer/{wname}/{kind}", "py-writer", code, expect=expect, setup=setup,
                            outputs=allowed, protect=protect,
                            fast=kind in ("fifo", "directory", "readonly", "chardev") and crc(wname) % 2 == 0))
        for label, expr, exp in [("None", "None", "refuse"), ("int", "5", "refuse"), ("bytes", "b'o.json'", "any"),
                                 ("nul", "'o\\x00.json'", "refuse"), ("surrogate", "'o\\udcff.json'", "any"),
                                 ("pathlib", "pathlib.Path('o.json')", "ok")]:
            if typ == "dir":
                continue
            code = tpl.replace("{P}", expr)
            out.append(case(f"py-writer/{wname}/path={label}", "py-writer", code, expect=exp,
                            outputs=["o.json", "o\udcff.json"]))
    return out


# ---------------------------------------------------------------------------------------
# Interpreter exit, fork, signals: each in its own interpreter

EXITS = [
    ("vlens-global-at-exit", "V = etlcal.VirtualLens()\nRESULT = V.port", "any"),
    ("lens-open-at-exit", "V = etlcal.VirtualLens()\nL = etlcal.Lens(V.port)\nL.set_current_ma(100.0)", "any"),
    ("vlens-in-a-cycle-at-exit", "class Holder:\n    pass\nh = Holder()\nh.me = h\nh.v = etlcal.VirtualLens()\n"
                                 "h.lens = etlcal.Lens(h.v.port)\nRESULT = h.lens.current_ma()", "any"),
    ("daemon-thread-projecting-at-exit", "c = cam()\nw = world()\n"
     "t = threading.Thread(target=lambda: [c.project(w) for _ in iter(int, 1)], daemon=True)\nt.start()\n"
     "time.sleep(0.2)", "any"),
    ("daemon-thread-calibrating-at-exit", "o = obs()\n"
     "t = threading.Thread(target=lambda: [etlcal.calibrate(o) for _ in iter(int, 1)], daemon=True)\nt.start()\n"
     "time.sleep(0.3)", "any"),
    ("daemon-thread-in-study-at-exit", "t = threading.Thread(target=lambda: etlcal.study('fig6', trials=20), daemon=True)\n"
     "t.start()\ntime.sleep(0.3)", "any"),
    ("daemon-thread-holding-lens-at-exit", "V = etlcal.VirtualLens()\nL = etlcal.Lens(V.port)\n"
     f"t = threading.Thread(target=lambda: L.hold({THP}, 120.0, duration_s=100.0), daemon=True)\nt.start()\n"
     "time.sleep(0.3)", "any"),
    ("vlens-made-in-finished-thread", "t = threading.Thread(target=lambda: globals().__setitem__('V', etlcal.VirtualLens()))\n"
     "t.start()\nt.join()\nRESULT = V.state()", "any"),
    ("fork-after-calibrate", "o = obs()\netlcal.calibrate(o)\npid = os.fork()\nif pid == 0:\n"
     "    try:\n        etlcal.calibrate(o)\n        etlcal.study('fig6', trials=1)\n        os._exit(0)\n"
     "    except BaseException:\n        os._exit(3)\n"
     "RESULT = wait_child(pid)\nif RESULT:\n    raise Boom(f'the forked child failed: exit {RESULT}')", "any"),
    ("fork-after-render", "etlcal.render()\npid = os.fork()\nif pid == 0:\n"
     "    try:\n        etlcal.render(seed=2)\n        etlcal.sharpness(img())\n        os._exit(0)\n"
     "    except BaseException:\n        os._exit(3)\n"
     "RESULT = wait_child(pid)\nif RESULT:\n    raise Boom(f'the forked child failed: exit {RESULT}')", "any"),
    ("fork-with-vlens", "V = etlcal.VirtualLens()\npid = os.fork()\nif pid == 0:\n"
     "    try:\n        V.state()\n        os._exit(0)\n    except BaseException:\n        os._exit(3)\n"
     "RESULT = wait_child(pid)", "any"),
    ("multiprocessing-fork-processes", "import multiprocessing as mp\netlcal.render()\no = obs()\n"
     "etlcal.calibrate(o)\nctx = mp.get_context('fork')\n"
     "ps = [ctx.Process(target=lambda: etlcal.calibrate(o)) for _ in range(2)]\n"
     "[p.start() for p in ps]\n[p.join(20) for p in ps]\nalive = [p for p in ps if p.is_alive()]\n"
     "[p.kill() for p in alive]\nif alive:\n    raise HostileHang('a forked multiprocessing child hangs in calibrate')\n"
     "RESULT = [p.exitcode for p in ps]", "any"),
    ("sigint-during-study", "import _thread\nthreading.Timer(0.2, _thread.interrupt_main).start()\n"
     "try:\n    etlcal.study('fig6', trials=5)\nexcept KeyboardInterrupt:\n    RESULT = 'interrupted'", "any"),
    ("sigint-handler-raises-during-calibrate", "signal.signal(signal.SIGALRM, lambda *a: (_ for _ in ()).throw(Boom('alarm')))\n"
     "signal.setitimer(signal.ITIMER_REAL, 0.01)\no = obs()\n"
     "try:\n    for _ in range(20):\n        etlcal.calibrate(o)\nexcept Boom:\n    RESULT = 'boom'", "any"),
    ("sys-exit-in-autofocus", "def f(e):\n    sys.exit(0)\netlcal.autofocus(f)", "any"),
]


def exit_cases(ctx: B.Ctx) -> List[B.Case]:
    out = []
    for name, code, expect in EXITS:
        allowed = ["SystemExit", "Boom", "KeyboardInterrupt"]
        out.append(case(f"py-exit/{name}", "py-exit", code, expect=expect, isolate=True, allowed=allowed, timeout=60,
                        fast=name in ("vlens-global-at-exit", "fork-after-calibrate", "daemon-thread-projecting-at-exit")))
    return out


# ---------------------------------------------------------------------------------------
# Kills from Python: a save or a study(out=) killed at a random moment

KILL_SCRIPT = r"""
import os, sys
import etlcal
what, path = sys.argv[1], sys.argv[2]
fx = os.environ["HOSTILE_FX"]
if what == "cal":
    obj = etlcal.Calibration.load(os.path.join(fx, "cal.json"))
elif what == "obs":
    obj = etlcal.Observations.load(os.path.join(fx, "obs2.json"))
elif what == "vlens":
    obj = etlcal.VirtualLens()
sys.stdout.write("ready\n")
sys.stdout.flush()
sys.stdin.readline()
import time
t0 = time.perf_counter()
if what == "study":
    etlcal.study("fig6", trials=1, seed=2, out=path)
elif what == "vlens":
    time.sleep(30)
else:
    obj.save(path)
sys.stdout.write(f"done {time.perf_counter() - t0:.6f}\n")
sys.stdout.flush()
"""


def py_kill_runner(what: str):
    def run(c: B.Case, ctx: B.Ctx, d: str) -> B.Result:
        res = B.Result(c.name, c.family, c.kind)
        rng = random.Random(f"{ctx.args.seed}:{c.name}")
        env = dict(os.environ)
        env["HOSTILE_FX"] = ctx.fx
        target = {"cal": "cal.json", "obs": "obs.json", "study": "st", "vlens": "-"}[what]
        p_target = os.path.join(d, target)
        # the earlier output
        if what == "cal":
            shutil.copy(ctx.fxp("cal_paper.json"), p_target)
        elif what == "obs":
            shutil.copy(ctx.fxp("obs.json"), p_target)
        elif what == "study":
            os.makedirs(p_target)
            r0 = subprocess.run([ctx.python, "-c", "import etlcal,sys; etlcal.study('fig6', trials=1, seed=1, "
                                 "out=sys.argv[1])", p_target], capture_output=True, timeout=120)
            if r0.returncode != 0:
                res.warn("baseline", f"the earlier study failed: {r0.stderr[-300:]!r}")
                return res
        import hostile_cli as HC
        old = HC.set_state(d, [target]) if what != "vlens" else {}
        # the new output, written once whole elsewhere
        ref = os.path.join(d, "ref")
        os.makedirs(ref)
        if what == "study":
            os.makedirs(os.path.join(ref, "st"))
        t0 = time.monotonic()
        if what != "vlens":
            pr = subprocess.run([ctx.python, "-c", KILL_SCRIPT, what, os.path.join(ref, target)], input=b"go\n",
                                capture_output=True, env=env, timeout=120)
            if pr.returncode != 0:
                res.warn("baseline", f"the reference writer failed: {pr.stderr[-300:]!r}")
                return res
        t_ref = 0.05
        if what != "vlens":
            try:
                t_ref = float(pr.stdout.split()[-1])
            except (ValueError, IndexError):
                pass
        new = HC.set_state(ref, [target]) if what != "vlens" else {}
        p = subprocess.Popen([ctx.python, "-c", KILL_SCRIPT, what, p_target], stdin=subprocess.PIPE,
                             stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=env, start_new_session=True,
                             preexec_fn=B.limits(ctx.mem))
        with ctx.lock:
            ctx.children.append(p.pid)
        line = p.stdout.readline()
        if line.strip() != b"ready":
            res.warn("baseline", "the child did not start")
            B.kill_group(p)
            return res
        p.stdin.write(b"go\n")
        p.stdin.flush()
        delay = rng.uniform(0.0, t_ref * 1.5)
        time.sleep(delay)
        os.killpg(p.pid, signal.SIGKILL)
        p.wait(30)
        res.detail.update(delay_s=round(delay, 4))
        if what == "vlens":
            left = B.vlens_dirs(p.pid, ["/tmp"])
            # a later interpreter's VirtualLens: does it sweep the folders of dead processes?
            subprocess.run([ctx.python, "-c", "import etlcal; v = etlcal.VirtualLens(); del v"], timeout=60, env=env)
            still = B.vlens_dirs(p.pid, ["/tmp"])
            if still:
                res.fail("leak", f"a SIGKILLed interpreter's VirtualLens folder {still[0]} stays, also after a later "
                                 f"VirtualLens in another process")
            for x in still:
                shutil.rmtree(x, ignore_errors=True)
            res.detail["left_after_kill"] = left
            return res
        after = HC.set_state(d, [target])
        if after != old and after != new:
            res.fail("data-loss", f"killed after {delay:.3f} s: {target} is neither the earlier whole output nor the new")
        # the next write leaves nothing behind
        pr = subprocess.run([ctx.python, "-c", KILL_SCRIPT, what, p_target], input=b"go\n", capture_output=True,
                            env=env, timeout=120)
        if pr.returncode != 0:
            res.fail("uncatchable" if b"PanicException" in pr.stderr else "data-loss",
                     f"the write after the kill failed: {pr.stderr[-300:]!r}")
        elif HC.set_state(d, [target]) != new:
            res.fail("data-loss", "the write after the kill is not the new output")
        left = [x for x in B.snapshot(d) if B.is_temporary(x) and not x.startswith("ref")]
        if left:
            res.fail("leak", f"after the next write: {', '.join(left[:5])}")
        res.detail["t"] = round(time.monotonic() - t0, 3)
        return res

    return run


def kill_cases(ctx: B.Ctx) -> List[B.Case]:
    out = []
    for what, n, nfast in [("cal", 8, 1), ("obs", 8, 1), ("study", 5, 1), ("vlens", 2, 1)]:
        for k in range(n):
            out.append(B.Case(f"py-kill/{what}/{k}", "py-kill", "custom", runner=py_kill_runner(what), fast=k < nfast,
                              timeout=300))
    return out


def cases(ctx: B.Ctx) -> List[B.Case]:
    return (reader_cases(ctx) + from_json_cases(ctx) + number_cases(ctx) + array_cases(ctx) + thread_cases(ctx)
            + writer_cases(ctx) + exit_cases(ctx) + kill_cases(ctx))
