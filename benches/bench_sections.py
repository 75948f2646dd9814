"""The sections of docs/BENCHMARKS.md: what each runs and the tables it returns (benches/all.py).

A section takes the run's `Settings` and returns `{"tables": {NAME: {"header", "rows"}},
"values": {NAME: "figure with unit"}}`; the template (benches/BENCHMARKS.md.in) places them.
Formatting lives here, so the template holds no figure of its own.
"""
import json
import os
import pathlib
import resource
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
TARGET = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
ETLCAL = TARGET / "release" / "etlcal"
PY = sys.executable


class Settings:
    """The run's measurement lengths: `quick` to try the command, else the documented ones."""

    def __init__(self, quick: bool):
        self.quick = quick
        self.criterion = ["--warm-up-time", "0.2", "--measurement-time", "0.5"] if quick else [
            "--warm-up-time", "1", "--measurement-time", "3"]

    def pick(self, quick, full):
        return quick if self.quick else full


# ---------------------------------------------------------------------------------------
# Running and formatting


def sh(args, env=None) -> str:
    """stdout of a command run from the repository root; its stderr shown if it fails."""
    r = subprocess.run([str(a) for a in args], cwd=ROOT, capture_output=True, text=True,
                       env=None if env is None else {**os.environ, **env})
    if r.returncode != 0:
        sys.stderr.write(r.stderr[-4000:])
        raise RuntimeError(f"failed ({r.returncode}): {' '.join(str(a) for a in args)}")
    return r.stdout


def script(name: str, *args, env=None) -> dict:
    """One of benches/*.py with --json, in this interpreter's environment."""
    return json.loads(sh([PY, ROOT / "benches" / name, *args, "--json"], env=env))


def criterion(s: Settings, package: str, bench: str, ids, feature=True) -> dict:
    """Runs one criterion bench file; {id: (median, low, high)} in ns (95 % interval of the median)."""
    sh(["cargo", "bench", "-q", "-p", package, *(["--features", "bench"] if feature else []), "--bench", bench,
        "--", "--noplot", *s.criterion])
    out = {}
    for i in ids:
        est = json.loads((TARGET / "criterion" / i / "new" / "estimates.json").read_text())["median"]
        ci = est["confidence_interval"]
        out[i] = (est["point_estimate"], ci["lower_bound"], ci["upper_bound"])
    return out


def t(ns: float) -> str:
    """A time with three significant digits in the unit that suits it."""
    for unit, scale in (("s", 1e9), ("ms", 1e6), ("us", 1e3)):
        if abs(ns) >= scale:
            v = ns / scale
            return f"{v:.3g} {unit}" if v < 100 else f"{v:.0f} {unit}"
    return f"{ns:.3g} ns"


def ms(v: float) -> str:
    return t(v * 1e6)


def ci(e) -> str:
    return f"{t(e[0])} [{t(e[1])}, {t(e[2])}]"


def ratio(a: float, b: float) -> str:
    return f"{a / b:.2f}x" if a / b < 10 else f"{a / b:.0f}x"


def verdict(ok: bool) -> str:
    return "met" if ok else "**not met**"


def table(header, rows) -> dict:
    return {"header": list(header), "rows": [list(r) for r in rows]}


# ---------------------------------------------------------------------------------------
# The sections, in the document's order


def model(s):
    what = {
        "project_168_points": ("`CameraModel::project_many`, one paper-rig board view (168 corners) at 100 mA", 2e3),
        "undistort_168_points": ("`CameraModel::undistort` of the same 168 pixels (Newton, 1e-9 px)", None),
        "e_com_one": ("`ThermalSurface::e_com_ma` (domain checks + 10-term cubic)", 20.0),
        "e_com_1000": ("1000 distinct (E_in, T) per iteration", 20e3),
        "compensate_flagged_one": ("`ThermalCalibration::compensate` (validates the file's numbers, flags extrapolation)", None),
        "e_in_for_e_com_one": ("`ThermalSurface::e_in_for_e_com` (bracket scan + safeguarded Newton, 1e-9 mA)", None),
        "camera_at": ("`Camera::at(e_in_ma, temperature_c)`: range checks, E_com, K(E_com), distortion", 100.0),
    }
    r = criterion(s, "etl-core", "model", what)
    rows = []
    for i, (text, target) in what.items():
        goal = "-" if target is None else f"< {t(target)}: {verdict(r[i][0] < target)}"
        rows.append([f"`{i}`", text, ci(r[i]), goal])
    return {"tables": {"criterion": table(["benchmark", "what", "median [95 % interval]", "target"], rows)},
            "values": {}}


def nist(s):
    res = script("nist_scipy.py")
    order, p = res["order"], res["problems"]
    rows = [[n] + [f"{v:.1f}" for k in ("etlcal", "lm", "trf") for v in p[n][k]] for n in order]
    counts = []
    for k, label in (("etlcal", "etlcal"), ("lm", "scipy lm"), ("trf", "scipy trf")):
        c6 = [sum(p[n][k][i] >= 6 for n in order) for i in (0, 1)]
        c4 = [sum(p[n][k][i] >= 4 for n in order) for i in (0, 1)]
        counts.append([label, f"{c6[0]} / 27", f"{c6[1]} / 27", f"{c4[0]} / 27", f"{c4[1]} / 27"])
    return {"tables": {
        "lre": table(["problem", "etlcal s1", "etlcal s2", "scipy lm s1", "scipy lm s2", "scipy trf s1", "scipy trf s2"], rows),
        "counts": table(["solver", "LRE >= 6, start 1", "LRE >= 6, start 2", "LRE >= 4, start 1", "LRE >= 4, start 2"], counts),
    }, "values": {}}


def bundle_adjust(s):
    ids = ["initialise_paper_rig", "bundle_adjust_paper_rig", "bundle_adjust_eiv_paper_rig"]
    r = criterion(s, "etl-core", "bundle_adjust", ids)
    targets = {"bundle_adjust_paper_rig": 2e6}
    rows = [[f"`{i}`", ci(r[i]), f"< {t(targets[i])}: {verdict(r[i][0] < targets[i])}" if i in targets else "-"]
            for i in ids]
    b = script("ba_scipy.py", "--rounds", s.pick(1, 5))
    et, cost = b["seconds"]["etlcal"], b["cost"]["etlcal"]
    peer = [["etlcal `bundle_adjust` (paper estimator)", ms(1e3 * et), "1", f"{cost:.9f}", "-"]]
    for m, label in (("lm", "scipy `least_squares` 'lm' (MINPACK)"), ("trf", "scipy `least_squares` 'trf', x_scale='jac'")):
        sec, c = b["seconds"][m], b["cost"][m]
        peer.append([label, ms(1e3 * sec), ratio(sec, et), f"{c:.9f}", f"{abs(c - cost) / cost:.1e}"])
    return {"tables": {
        "criterion": table(["benchmark", "median [95 % interval]", "target"], rows),
        "scipy": table(["solver (same start, same residuals)", f"time (median of {b['rounds']} rounds)", "time / etlcal's",
                        "final cost", "cost difference (relative)"], peer),
    }, "values": {"points": str(b["points"]), "iterations": str(b["etlcal_iterations"])}}


def pipeline(s):
    ids = ["observations_to_calibration_file_paper", "observations_to_calibration_file_eiv"]
    r = criterion(s, "etl-calib", "pipeline", ids)
    names = {ids[0]: "paper (Eq. 24)", ids[1]: "errors-in-variables (the default estimator)"}
    rows = [[names[i], ci(r[i]), f"< 10 ms: {verdict(r[i][0] < 10e6)}"] for i in ids]
    return {"tables": {"criterion": table(["estimator", "median [95 % interval]", "target"], rows)}, "values": {}}


def rig_reduced_system(s):
    cams = [2, 4, 8, 12, 16]
    ids = [f"rig_step_{k}_{n}_cameras" for n in cams for k in ("dense", "sparse")]
    r = criterion(s, "etl-calib", "rig_reduced_system", ids)
    rows = []
    for n in cams:
        d, sp = r[f"rig_step_dense_{n}_cameras"], r[f"rig_step_sparse_{n}_cameras"]
        rows.append([str(n), str(25 * n), str(25 * n + 200), ci(d), ci(sp), ratio(d[0], sp[0]),
                     "sparse" if sp[0] < d[0] else "dense"])
    return {"tables": {"criterion": table(["cameras", "dense system (sum p_k)", "sparse system (+ 200 dZ_j)",
                                            "dense (nalgebra) median [95 % interval]",
                                            "sparse (faer) median [95 % interval]", "dense / sparse", "faster"], rows)},
            "values": {}}


def timed_child(args) -> tuple:
    """Wall and CPU seconds (user + system, the child's threads included) of one command."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    sh(args)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def studies(s):
    plan = [("fig6", s.pick(5, 100), 30.0), ("fig5", None, None), ("subsets", s.pick(1, 5), None),
            ("baseline", s.pick(5, 200), None), ("crlb", s.pick(20, 300), None)]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, trials, target in plan:
            args = [ETLCAL, "study", name, "--quiet", "--out", pathlib.Path(tmp) / name]
            args += [] if trials is None else ["--trials", trials]
            wall, cpu = timed_child(args)
            goal = "-" if target is None else f"< {target:.0f} s: {verdict(wall < target)}"
            rows.append([f"`study {name}`", "-" if trials is None else str(trials), f"{wall:.1f} s", f"{cpu:.1f} s", goal])
    return {"tables": {"studies": table(["study", "trials", "wall", "CPU (user + system)", "target"], rows)}, "values": {}}


def checkerboard(s):
    blurs = ["0.5", "1.5", "3"]
    ids = [f"detect_1936x1458_14x12/blur_{b}" for b in blurs]
    r = criterion(s, "etl-image", "detect", ids)
    crit = [[f"{b} px", ci(r[i])] for b, i in zip(blurs, ids)]
    d = script("opencv_detect.py", "--etlcal", ETLCAL, *([] if s.quick else ["--sb"]))
    methods = list(next(iter(d["synthetic"].values())))
    acc = []
    for blur, m in d["synthetic"].items():
        acc.append([f"{blur} px"] + [f"{m[k]['found']} / {m[k]['images']}: {m[k]['rms_px']:.4f} / {m[k]['max_px']:.3f} px"
                                     for k in methods])
    real = [[x["pattern"], x["asked"] + f" ({x['label']})", f"{x['opencv_found']} / {x['images']}",
             f"{x['etlcal_found']} / {x['images']}"] for x in d["real"]]
    return {"tables": {
        "criterion": table(["blur sigma", "etlcal `detect_corners`, median [95 % interval]"], crit),
        "accuracy": table(["blur sigma"] + [f"{k}: found, RMS / max" for k in methods], acc),
        "real": table(["board", "asked for", "OpenCV found", "etlcal found"], real),
    }, "values": {}}


def python_bindings(s):
    d = script("py_overhead.py", "--no-bench")
    rows = [[x["call"], t(x["rust_ns"]), t(x["python_ns"]), f"{t(x['python_ns'] - x['rust_ns'])} "
             f"({100 * (x['python_ns'] - x['rust_ns']) / x['rust_ns']:+.1f} %)"] for x in d["rows"]]
    return {"tables": {"overhead": table(["call", "Rust", "Python (best of 7)", "difference"], rows)},
            "values": {"versions": f"Python {d['python']}, numpy {d['numpy']}"}}


def detection_sizes(s):
    d = script("detect_sizes.py", "--repeat", s.pick(3, 15), "--fresh", s.pick(3, 9))
    rows = []
    for g, x in d["sizes"].items():
        rows.append([g, x["images"], ms(x["etlcal_ms"]), ms(x["opencv_ms"]), f"{x['ratio']:.2f}",
                     len(x["images_where_etlcal_is_slower"])])
    corners = [f"{r['corners']['etlcal']} / {r['corners']['opencv']}" for g, x in d["sizes"].items()
               for r in x["per_image"] if "corners" in r]
    f = d["first_call_over_warm"]
    return {"tables": {"sizes": table(["size", "images", "etlcal (median)", "OpenCV (median)", "etlcal / OpenCV",
                                       "images where etlcal is slower"], rows)},
            "values": {"charuco_corners": ", ".join(corners), "first_call": f"{f['median']:.2f}",
                       "first_call_processes": str(len(f["all"])), "first_call_image": pathlib.Path(f["image"]).name,
                       "verdict_first_call": verdict(f["median"] <= 1.5),
                       "verdict_sizes": verdict(all(x["ratio"] <= 1.0 for x in d["sizes"].values()))}}


def charuco(s):
    views = TARGET / "charuco-views"
    d = script("charuco_opencv.py", "--etlcal", ETLCAL, "--out", views, "--repeat", s.pick(2, 7), "--phone")
    blurs = list(d["blurs"])
    crit_blur = {b: f"{float(b):.1f}" for b in blurs if b != "phone"}  # criterion names them 0.5, 1.5, 3.0
    ids = [f"charuco_1936x1458_12x9/pose{p}_blur{c}" for p in range(6) for c in crit_blur.values()]
    r = criterion(s, "etl-image", "charuco", ids, feature=True)
    acc, speed = [], []
    for blur, x in d["blurs"].items():
        o, e = x["opencv"], x["etlcal"]
        acc.append([blur if blur == "phone" else f"{blur} px",
                    f"{o['found']} / {o['in_frame']} = {100 * o['found'] / o['in_frame']:.1f} %",
                    f"{o['rms_px']:.4f} / {o['max_px']:.3f} px",
                    f"{e['found']} / {e['in_frame']} = {100 * e['found'] / e['in_frame']:.1f} %",
                    f"{e['rms_px']:.4f} / {e['max_px']:.3f} px", o["wrong_ids"] + e["wrong_ids"]])
        if blur == "phone":
            continue
        et = statistics.median(r[i][0] for i in ids if i.endswith(f"blur{crit_blur[blur]}"))
        oc = statistics.median(v["opencv_ms"] for k, v in d["views"].items() if k.endswith(f"_blur{blur}.png"))
        speed.append([f"{blur} px", ms(oc), t(et), ratio(oc * 1e6, et)])
    sm = script("charuco_photo_smoothness.py", "--etlcal", ETLCAL)
    smooth = [[x["photograph"], f"{x['difference_rms_px']:.3f} px", x["degree"], f"{x['etlcal_residual_px']:.4f} px",
               f"{x['opencv_residual_px']:.4f} px"] for x in sm["rows"]]
    return {"tables": {
        "accuracy": table(["blur sigma", "OpenCV found", "OpenCV RMS / max", "etlcal found", "etlcal RMS / max",
                           "wrong ids (both)"], acc),
        "speed": table(["blur sigma", "OpenCV `detectBoard` (median of the views)", "etlcal criterion (median of the views)",
                        "OpenCV / etlcal"], speed),
        "smoothness": table(["photograph", "etlcal - OpenCV (RMS, 2-D)", "degree", "etlcal residual", "OpenCV residual"], smooth),
    }, "values": {}}


def zhang_wide(s):
    names = ["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"]
    summary, values = [], []
    for flags in ([], ["--fix-k3"], ["--fix-k3", "--zero-tangent"]):
        d = json.loads(sh([PY, ROOT / "benches" / "zhang_opencv.py", "--wide", "--json", "--etlcal", ETLCAL, *flags]))
        for name, x in d.items():
            w, h = x["image_size"]
            summary.append([f"{name} ({w} x {h}, {x['pattern'][0]}x{x['pattern'][1]})", " ".join(flags) or "none",
                            f"{x['images']} ({x['opencv_found']} / {x['etlcal_found']})", f"{x['opencv']['rms_px']:.4f}",
                            f"{x['etlcal']['rms_px']:.4f}", f"{max(x['same_corners_in_std'].values()):.1e}",
                            "pass" if all(x["checks"].values()) else "**fail**"])
            if flags:
                continue
            k, dist = x["etlcal"]["camera_matrix"], x["etlcal"]["dist_coeffs"]
            et = [k[0][0], k[1][1], k[0][2], k[1][2], *dist]
            for label, v in (("OpenCV end to end", [x["opencv"]["values"][n] for n in names]), ("etlcal end to end", et),
                             ("OpenCV on etlcal's corners", [x["opencv_on_etlcal_corners"]["values"][n] for n in names])):
                values.append([name, label] + [f"{a:.4f}" for a in v])
    return {"tables": {
        "summary": table(["set", "held", "images (found: OpenCV / etlcal)", "RMS px, OpenCV end to end",
                          "RMS px, etlcal end to end", "same corners: largest |etlcal - cv| / cv's std", "acceptance"], summary),
        "values": table(["set", "solve"] + names, values),
    }, "values": {}}


def link(s):
    out = sh(["cargo", "bench", "-q", "-p", "etl-hw", "--bench", "link"]).strip().splitlines()[-1]
    d = json.loads(out)
    rows = [
        ["temperature query round trip (`TCA`, reply, CRC checks)", f"{d['temperature_round_trip_us']:.1f} us",
         f"{d['temperature_round_trip_wire_us']:.0f} us of wire time"],
        [f"current commands (`Aw`, confirmed by `Ar`: {d['current_command_bytes']:.0f} bytes)",
         f"{d['current_commands_per_s']:.0f} per s", f"{d['current_commands_per_s_at_115200_baud']:.0f} per s"],
        [f"compensation loop (`hold`: read T, solve E_in, send and confirm: {d['hold_step_bytes']:.0f} bytes)",
         f"{d['hold_steps_per_s']:.0f} steps per s", f"{d['hold_steps_per_s_at_115200_baud']:.0f} steps per s"],
    ]
    share = d["hold_steps_per_s_at_115200_baud"] / d["hold_steps_per_s"]
    return {"tables": {"link": table(["what", "measured", "115200 baud allows"], rows)},
            "values": {"software_share": f"{100 * share:.0f} %",
                       "verdict": verdict(d["hold_steps_per_s"] >= 0.9 * d["hold_steps_per_s_at_115200_baud"])}}


def rendering(s):
    what = {"render_1936x1458_defocus": ("checkerboard 14 x 12, defocus, noise", 100e6),
            "render_1936x1458_charuco_defocus": ("ChArUco 15 x 13 (DICT_5X5_100), same view", None),
            "sharpness_cpbd_1936x1458": ("CPBD of the checkerboard render", 20e6),
            "sharpness_cpbd_1936x1458_noise_free": ("CPBD, the same render without noise", 20e6),
            "sharpness_tenengrad_1936x1458": ("Tenengrad", None),
            "sharpness_laplacian_1936x1458": ("variance of the Laplacian", None)}
    r = criterion(s, "etl-sim", "images", what)
    rows = [[f"`{i}`", text, ci(r[i]), "-" if g is None else f"< {t(g)}: {verdict(r[i][0] < g)}"]
            for i, (text, g) in what.items()]
    return {"tables": {"criterion": table(["benchmark (1936 x 1458)", "what", "median [95 % interval]", "target"], rows)},
            "values": {}}


def service(s):
    rows = []
    for crate, purpose in (("etl-core", "the no_std core"), ("etl-formats", "read a calibration, E_com, K, project, undistort"),
                           ("etl-image", "detection and sharpness"), ("etl-calib", "the calibration library"),
                           ("etlcal", "the command line")):
        out = sh(["cargo", "tree", "-q", "-p", crate, "-e", "normal", "--prefix", "none"])
        n = len({line.split(" (")[0].strip() for line in out.splitlines() if line.strip()})
        rows.append([crate, n, purpose])
    return {"tables": {"crates": table(["crate", "crates compiled (itself included)", "what it is for"], rows)}, "values": {}}


def geometry(s):
    pairs = [("mat_vec_1000", "hand", "nalgebra"), ("nearest_rotation_100", "hand", "nalgebra_products"),
             ("rodrigues_to_matrix_1000", "hand", "nalgebra_rotation3")]
    # `bench_function("a/b")` is stored by criterion as a_b.
    ids = [f"{b}_{x}" for b, h, n in pairs for x in (h, n)] + [f"zhang_closed_form_{n}_views_hand" for n in (10, 50)]
    r = criterion(s, "etl-core", "geometry", ids)
    rows = [[f"`{b}`", ci(r[f"{b}_{h}"]), ci(r[f"{b}_{n}"]), f"{100 * (r[f'{b}_{n}'][0] / r[f'{b}_{h}'][0] - 1):+.0f} %"]
            for b, h, n in pairs]
    zhang = [[f"`zhang_closed_form_{n}_views`", ci(r[f"zhang_closed_form_{n}_views_hand"])] for n in (10, 50)]
    return {"tables": {"pairs": table(["bench", "hand-written", "nalgebra", "nalgebra against hand-written"], rows),
                       "zhang": table(["bench", "hand-written (Jacobi SVD of V^T V)"], zhang)}, "values": {}}


def undistortion(s):
    labels = {
        "opencv_maps_f32": "OpenCV maps (CV_32FC1)", "opencv_remap_f32_maps": "OpenCV remap (float maps given)",
        "opencv_maps_plus_remap_f32": "**OpenCV maps + remap (float)**",
        "opencv_maps_plus_remap_fixed": "OpenCV maps + remap (fixed-point CV_16SC2)",
        "etlcal_undistort_maps": "etlcal `Calibration.undistort_maps` (two float32 arrays)",
        "etlcal_undistort_image": "**etlcal `undistort_image` (maps + remap, band by band)**",
        "etlcal_maps_plus_image": "etlcal `undistort_maps` + `undistort_image` (maps twice)"}
    runs = [script("undistort_opencv.py", "--rounds", s.pick(2, 8), "--calls", s.pick(2, 5)),
            script("undistort_opencv.py", "--rounds", s.pick(2, 8), "--calls", s.pick(2, 5), "--threads", "1")]
    rows = []
    for k, label in labels.items():
        row = [label]
        for d in runs:
            w, c = d["wall_ms"][k], d["cpu_ms"][k]
            row += [f"{ms(w['median'])} [{w['min']:.2f}, {w['max']:.2f}]", ms(c["median"])]
        rows.append(row)
    a = runs[0]
    met = a["wall_ms"]["etlcal_undistort_image"]["median"] <= a["wall_ms"]["opencv_maps_plus_remap_f32"]["median"]
    ids = [f"undistort_1936x1458/{n}" for n in ("undistort_maps", "focus_maps_at_new_current", "remap_u8",
                                                 "maps_then_remap_u8", "undistort_image_u8_fused")]
    r = criterion(s, "etl-image", "undistort", ids)
    crit = [[f"`{i.split('/')[1]}`", ci(r[i])] for i in ids]
    maps_at = r["undistort_1936x1458/focus_maps_at_new_current"][0]
    interp = script("undistort_interpolation.py")["worst_px"]
    return {"tables": {
        "opencv": table(["case", "wall, all cores: median [min, max] ms", "CPU", "wall, one thread each", "CPU"], rows),
        "criterion": table(["benchmark", "median [95 % interval]"], crit),
        "interpolation": table(["cached currents"] + list(interp), [["worst error (px)"] + [f"{v:.4f}" for v in interp.values()]]),
    }, "values": {"verdict": verdict(met), "max_diff": str(a["max_abs_diff_levels_vs_cv2_remap_of_our_maps"]),
                  "maps_at": t(maps_at), "maps_at_verdict": f"< {t(5e6)}: {verdict(maps_at <= 5e6)}"}}


def python_project(s):
    d = script("python_project.py", "--repeat", s.pick(3, 15))
    base = d["ns_per_point"]["Calibration.project(world, e_com_ma)"]
    rows = [[f"`{n}`", f"{v:.1f} ns", f"{v / base:.2f}"] for n, v in d["ns_per_point"].items()]
    worst = max(d["ns_per_point"].values()) / base
    return {"tables": {"paths": table(["path", "per point", "against Calibration.project"], rows)},
            "values": {"verdict": verdict(worst <= 1.5), "points": str(d["points"])}}


SECTIONS = {f.__name__: f for f in (model, nist, bundle_adjust, pipeline, rig_reduced_system, studies, checkerboard, python_bindings,
                                    detection_sizes, charuco, zhang_wide, link, rendering, service, geometry,
                                    undistortion, python_project)}
