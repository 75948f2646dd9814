"""`etlcal stereo` against cv2.stereoCalibrate on the same corners, on a rendered pair with
known truth: two distorted 1280 x 960 cameras (OpenCV's model) 120 mm apart, turned 8
degrees towards each other, 13 synchronised views of a 9 x 6 checkerboard of 30 mm
squares at 550..700 mm, the last one out of the right camera's view (so that camera
misses it). The images are rendered here (exact ray-plane intersection through the
distortion, edges area-sampled, blur and noise), the corners are `etlcal detect`'s, and
cv2 is given those same corners:

* fixed intrinsics: cv2.calibrateCamera per camera on every view it saw, then
  cv2.stereoCalibrate with CALIB_FIX_INTRINSIC on the pairs seen by both;
* joint: cv2.stereoCalibrate with flags 0 on those pairs.

etlcal's R, T (and in the joint form both cameras' intrinsics) agree with OpenCV's to a
small fraction of etlcal's standard deviation of each, its RMS is OpenCV's, and R, T lie
within a few standard deviations of the truth.

Then a public real pair, fixtures/zhang (left) and fixtures/stereo (right), SOURCE.md there
(25 pairs of a 9x6 board, the square size unrecorded, 1 mm used: lengths in squares): on
etlcal's corners both modes reproduce OpenCV's R, T as above; end to end, each on its own
corners (OpenCV's: findChessboardCorners + cornerSubPix 11x11), etlcal's RMS is at most
OpenCV's and its baseline within 0.5 % of OpenCV's (0.5 mm of a 100 mm baseline).

Last, `--opencv-yaml`: cv2.FileStorage reads the file, its K1, D1, K2, D2, R, T are the
JSON's, and its rectification R1, R2, P1, P2, Q is cv2.stereoRectify's on those numbers
(its defaults: CALIB_ZERO_DISPARITY, alpha -1), on both pairs."""
import json
import os
import pathlib
import subprocess
from typing import Any, Dict, List, Tuple

import numpy as np
import numpy.typing as npt
import pytest

cv2: Any = pytest.importorskip("cv2")

ROOT = pathlib.Path(__file__).resolve().parents[3]
REAL = (sorted((ROOT / "fixtures" / "zhang").glob("left*.jpg")), sorted((ROOT / "fixtures" / "stereo").glob("right*.jpg")))
SIZE = (1280, 960)
PATTERN = (9, 6)
SQUARE_MM = 30.0
# The truth: each camera's K and OpenCV dist_coeffs, and R, T from the left camera's
# frame to the right's.
CAMERAS = [
    (np.array([[1010.0, 0, 645.0], [0, 1005.0, 478.0], [0, 0, 1]]), np.array([-0.21, 0.09, 4e-4, -3e-4, -0.01])),
    (np.array([[995.0, 0, 630.0], [0, 992.0, 486.0], [0, 0, 1]]), np.array([-0.18, 0.07, -2e-4, 5e-4, 0.0])),
]
OM_TRUE = np.array([0.01, -0.14, 0.005])
T_TRUE = np.array([-120.0, 1.5, 4.0])
CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 500, 1e-15)
Array = npt.NDArray[np.float64]


def board_poses() -> List[Tuple[Array, Array]]:
    """13 board poses in the left camera (Rodrigues, mm): 12 seen by both cameras, the
    last far to the left, out of the right camera's view."""
    centre = np.array([120.0, 75.0, 0.0])
    poses = []
    for k in range(12):
        phi = k * 2 * np.pi / 12
        tilt = [0.45, 0.3, 0.15][k % 3]
        om = np.array([tilt * np.cos(phi), tilt * np.sin(phi), 0.08 * (k - 5.5) / 5.5])
        c = cv2.Rodrigues(om)[0] @ centre
        aim = np.array([60.0 + 110.0 * np.sin(phi), 80.0 * np.cos(phi), 550.0 + 30.0 * (k % 6)])
        poses.append((om, aim - c))
    om = np.array([0.05, 0.25, 0.0])
    poses.append((om, np.array([-250.0, 0.0, 620.0]) - cv2.Rodrigues(om)[0] @ centre))
    return poses


def in_right(om: Array, t: Array) -> Tuple[Array, Array]:
    r = cv2.Rodrigues(OM_TRUE)[0]
    return cv2.Rodrigues(r @ cv2.Rodrigues(om)[0])[0].ravel(), r @ t + T_TRUE


def rays(k: Array, dist: Array) -> Array:
    """The normalised ray (x, y, 1) through the centre of every pixel of the image."""
    u, v = np.meshgrid(np.arange(SIZE[0], dtype=np.float64), np.arange(SIZE[1], dtype=np.float64))
    pts = np.stack([u.ravel(), v.ravel()], -1).reshape(-1, 1, 2)
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-13)
    und = cv2.undistortPoints(pts, k, dist, criteria=crit).reshape(-1, 2)
    return np.column_stack([und, np.ones(len(und))])


def square_wave(c: Array, w: Array) -> Array:
    """+1 in even squares, -1 in odd ones along one board axis, ramped linearly over
    +-w mm at each edge (w: half a pixel's footprint, an area-sampling approximation)."""
    a = c / SQUARE_MM
    f = a - np.floor(a)
    d = np.minimum(f, 1.0 - f) * SQUARE_MM
    sign = np.where(np.floor(a) % 2 == 0, 1.0, -1.0)
    return np.asarray(sign * np.clip(d / np.maximum(w, 1e-9), 0.0, 1.0))


def shade(ray: Array, om: Array, t: Array, fx: float) -> Array:
    """The brightness (0 dark .. 1 white) seen along each ray of a board at pose (om, t):
    the square (0, 0) dark as etlcal's and OpenCV's detectors number it, a white margin
    of one square, a grey background."""
    r = cv2.Rodrigues(om)[0]
    n = r[:, 2]
    s = (n @ t) / (ray @ n)
    pb = (ray * s[:, None] - t) @ r
    x, y = pb[:, 0], pb[:, 1]
    w = 0.5 * np.abs(s) / fx
    value = 0.5 - 0.5 * square_wave(x, w) * square_wave(y, w)
    cols, rows = PATTERN
    inside = (x > -SQUARE_MM) & (x < cols * SQUARE_MM) & (y > -SQUARE_MM) & (y < rows * SQUARE_MM)
    margin = (x > -2 * SQUARE_MM) & (x < (cols + 1) * SQUARE_MM) & (y > -2 * SQUARE_MM) & (y < (rows + 1) * SQUARE_MM)
    out = np.where(inside, value, np.where(margin, 1.0, 0.35))
    return np.asarray(np.where(s > 0, out, 0.35))


def render_pair_set(out: pathlib.Path, seed: int) -> List[Tuple[pathlib.Path, pathlib.Path]]:
    """Renders every pose's left and right image into `out`; returns their paths."""
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    cams = [(k, rays(k, d)) for k, d in CAMERAS]
    paths = []
    for j, (om, t) in enumerate(board_poses()):
        pair = []
        for side, (pose, (k, ray)) in enumerate(zip([(om, t), in_right(om, t)], cams)):
            img = cv2.GaussianBlur(shade(ray, pose[0], pose[1], k[0, 0]).reshape(SIZE[1], SIZE[0]), (0, 0), 0.6)
            grey = np.clip(25.0 + 200.0 * img + rng.normal(0.0, 1.0, img.shape), 0, 255).astype(np.uint8)
            path = out / f"{['left', 'right'][side]}{j:02d}.png"
            cv2.imwrite(str(path), grey)
            pair.append(path)
        paths.append((pair[0], pair[1]))
    return paths


def run(binary: str, args: List[str], check: bool = True) -> Dict[str, Any]:
    out = subprocess.run([binary, *args], capture_output=True, text=True)
    if check:
        assert out.returncode == 0, out.stderr
    parsed: Dict[str, Any] = json.loads(out.stdout)
    return parsed


@pytest.fixture(scope="module")
def rig(tmp_path_factory: pytest.TempPathFactory, etlcal_binary: str) -> Dict[str, Any]:
    """The rendered pairs, etlcal's corners of every image (None where not found) and
    `etlcal stereo --json` in both modes."""
    pairs = render_pair_set(tmp_path_factory.mktemp("stereo"), seed=7)
    left, right = [str(p[0]) for p in pairs], [str(p[1]) for p in pairs]
    corners: Dict[str, Any] = {}
    for images in (left, right):
        found = run(etlcal_binary, ["detect", *images, "--pattern", "9x6", "--json"], check=False)
        for entry in found["images"]:
            corners[entry["path"]] = np.array(entry["corners_px"], np.float64) if entry["found"] else None
    common = [*left, "--right", *right, "--pattern", "9x6", "--square", str(SQUARE_MM), "--model", "opencv", "--json"]
    stereo = {mode: run(etlcal_binary, ["stereo", *common, "--intrinsics", mode]) for mode in ("fixed", "joint")}
    return {"left": left, "right": right, "corners": corners, "stereo": stereo}


def object_points() -> npt.NDArray[np.float32]:
    cols, rows = PATTERN
    obj = np.zeros((rows * cols, 3), np.float32)
    obj[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * SQUARE_MM
    return obj


def cv_inputs(rig: Dict[str, Any]) -> Dict[str, Any]:
    """etlcal's corners as cv2 takes them (float32, once): every view of each camera, and
    the pairs seen by both."""
    c = rig["corners"]

    def f32(path: str) -> npt.NDArray[np.float32]:
        return np.asarray(c[path], np.float32).reshape(-1, 1, 2)

    views = [[f32(p) for p in rig[side] if c[p] is not None] for side in ("left", "right")]
    both = [j for j, (a, b) in enumerate(zip(rig["left"], rig["right"])) if c[a] is not None and c[b] is not None]
    pairs = ([f32(rig["left"][j]) for j in both], [f32(rig["right"][j]) for j in both])
    return {"views": views, "both": both, "pairs": pairs}


def rt_in_std(r: Array, t: Array, result: Dict[str, Any]) -> Array:
    """(om, T) of cv2 minus etlcal's, in units of etlcal's standard deviations."""
    om = cv2.Rodrigues(r)[0].ravel()
    est = np.array(result["rotation_rodrigues"] + result["translation_mm"])
    std = np.array(result["std"]["rotation_rodrigues"] + result["std"]["translation_mm"])
    return np.asarray((np.concatenate([om, t.ravel()]) - est) / std)


def test_rendered_pair_has_one_view_missed_by_the_right_camera(rig: Dict[str, Any]) -> None:
    c = rig["corners"]
    assert all(c[p] is not None for p in rig["left"])
    assert [c[p] is None for p in rig["right"]] == [False] * 12 + [True]
    for mode in ("fixed", "joint"):
        s = rig["stereo"][mode]
        assert s["views_used"] == 12 and s["pairs_used"] == list(range(12))
    assert rig["stereo"]["fixed"]["left"]["views_used"] == 13
    assert rig["stereo"]["fixed"]["right"]["views_used"] == 12


def test_fixed_intrinsics_reproduce_cv2_stereo_calibrate(rig: Dict[str, Any]) -> None:
    cv = cv_inputs(rig)
    obj = object_points()
    ks = []
    for side, views in zip(("left", "right"), cv["views"]):
        rms, k, d, _, _ = cv2.calibrateCamera([obj] * len(views), views, SIZE, None, None, flags=0,
                                              criteria=CRITERIA)
        # The intrinsics each camera holds are cv2.calibrateCamera's.
        e = rig["stereo"]["fixed"][side]
        zi = [(a - e[n]) / e["std"][n] for a, n in zip([k[0, 0], k[1, 1], k[0, 2], k[1, 2]], ["fx", "fy", "u0", "v0"])]
        zi += [(a - b) / e["std"][n] for a, b, n in zip(d.ravel(), e["dist_coeffs"], ["k1", "k2", "p1", "p2", "k3"])]
        assert np.max(np.abs(zi)) < 0.01, (side, zi)
        ks.append((k, d))
    (k1, d1), (k2, d2) = ks
    rms, _, _, _, _, r, t, _, _ = cv2.stereoCalibrate([obj] * len(cv["both"]), *cv["pairs"], k1, d1, k2, d2, SIZE,
                                                      flags=cv2.CALIB_FIX_INTRINSIC, criteria=CRITERIA)
    s = rig["stereo"]["fixed"]
    z = rt_in_std(r, t, s)
    print(f"fixed intrinsics: cv2 - etlcal in etlcal's std: {np.array2string(z, precision=5)}; "
          f"rms {rms:.6f} / {s['rms_px']:.6f} px")
    assert np.max(np.abs(z)) < 0.01, z
    assert abs(rms - s["rms_px"]) < 1e-4 * rms


def test_joint_reproduces_cv2_stereo_calibrate(rig: Dict[str, Any]) -> None:
    cv = cv_inputs(rig)
    obj = object_points()
    rms, k1, d1, k2, d2, r, t, _, _ = cv2.stereoCalibrate([obj] * len(cv["both"]), *cv["pairs"], None, None, None,
                                                          None, SIZE, flags=0, criteria=CRITERIA)
    s = rig["stereo"]["joint"]
    z = rt_in_std(r, t, s)
    names = ["fx", "fy", "u0", "v0", "k1", "k2", "p1", "p2", "k3"]
    zi = []
    for side, k, d in (("left", k1, d1), ("right", k2, d2)):
        e = s[side]
        cv_numbers = [k[0, 0], k[1, 1], k[0, 2], k[1, 2], *d.ravel()[:5]]
        ours = [e["fx"], e["fy"], e["u0"], e["v0"], *e["dist_coeffs"]]
        zi += [(a - b) / e["std"][n] for a, b, n in zip(cv_numbers, ours, names)]
    print(f"joint: cv2 - etlcal in etlcal's std: R, T {np.array2string(z, precision=5)}, intrinsics max "
          f"{np.max(np.abs(zi)):.5f}; rms {rms:.6f} / {s['rms_px']:.6f} px")
    assert np.max(np.abs(z)) < 0.01, z
    assert np.max(np.abs(zi)) < 0.01, zi
    assert abs(rms - s["rms_px"]) < 1e-4 * rms


def test_stereo_recovers_the_truth_within_its_standard_deviations(rig: Dict[str, Any]) -> None:
    truth = np.concatenate([OM_TRUE, T_TRUE])
    for mode in ("fixed", "joint"):
        s = rig["stereo"][mode]
        est = np.array(s["rotation_rodrigues"] + s["translation_mm"])
        std = np.array(s["std"]["rotation_rodrigues"] + s["std"]["translation_mm"])
        z = (est - truth) / std
        print(f"{mode}: etlcal - truth in std {np.array2string(z, precision=2)}; T off by "
              f"{np.array2string(est[3:] - truth[3:], precision=4)} mm, baseline {s['baseline_mm']:.4f} mm")
        assert np.max(np.abs(z)) < 5.0, (mode, z)
        assert abs(s["baseline_mm"] - np.linalg.norm(T_TRUE)) < 0.5


def cv_stereo(pairs: Tuple[List[Any], List[Any]], size: Tuple[int, int], fixed: bool,
              views: Tuple[List[Any], List[Any]]) -> Tuple[float, Array, Array]:
    """cv2's (rms, R, T): with `fixed`, calibrateCamera on each camera's `views` then
    stereoCalibrate with CALIB_FIX_INTRINSIC on `pairs`; else stereoCalibrate with flags 0."""
    obj = object_points() / SQUARE_MM
    if not fixed:
        rms, _, _, _, _, r, t, _, _ = cv2.stereoCalibrate([obj] * len(pairs[0]), *pairs, None, None, None, None,
                                                          size, flags=0, criteria=CRITERIA)
        return rms, r, t
    ks = [cv2.calibrateCamera([obj] * len(v), v, size, None, None, criteria=CRITERIA)[1:3] for v in views]
    rms, _, _, _, _, r, t, _, _ = cv2.stereoCalibrate([obj] * len(pairs[0]), *pairs, *ks[0], *ks[1], size,
                                                      flags=cv2.CALIB_FIX_INTRINSIC, criteria=CRITERIA)
    return rms, r, t


@pytest.fixture(scope="module")
def real(etlcal_binary: str) -> Dict[str, Any]:
    """The real pair: `etlcal stereo --json` in both modes, etlcal's corners and OpenCV's."""
    left, right = [str(p) for p in REAL[0]], [str(p) for p in REAL[1]]
    assert len(left) == len(right) == 25
    common = [*left, "--right", *right, "--pattern", "9x6", "--square", "1", "--model", "opencv", "--json"]
    stereo = {mode: run(etlcal_binary, ["stereo", *common, "--intrinsics", mode]) for mode in ("fixed", "joint")}
    ours: List[List[Any]] = []
    for images in (left, right):
        found = run(etlcal_binary, ["detect", *images, "--pattern", "9x6", "--json"])
        ours.append([np.array(e["corners_px"], np.float32).reshape(-1, 1, 2) for e in found["images"]])
    theirs: List[List[Any]] = [[], []]
    for side, images in enumerate((left, right)):
        for p in images:
            g = cv2.imread(p, cv2.IMREAD_GRAYSCALE)
            ok, c = cv2.findChessboardCorners(g, PATTERN)
            assert ok, p
            theirs[side].append(cv2.cornerSubPix(g, c, (11, 11), (-1, -1),
                                                 (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 100, 1e-4)))
    size = (g.shape[1], g.shape[0])
    return {"stereo": stereo, "ours": (ours[0], ours[1]), "theirs": (theirs[0], theirs[1]), "size": size}


@pytest.mark.parametrize("mode", ["fixed", "joint"])
def test_real_pair_same_corners_reproduce_cv2_stereo_calibrate(real: Dict[str, Any], mode: str) -> None:
    corners = real["ours"]
    rms, r, t = cv_stereo(corners, real["size"], mode == "fixed", corners)
    s = real["stereo"][mode]
    z = rt_in_std(r, t, s)
    print(f"real pair, {mode}, etlcal's corners: cv2 - etlcal in etlcal's std {np.array2string(z, precision=5)}; "
          f"rms {rms:.6f} / {s['rms_px']:.6f} px")
    assert s["views_used"] == 25
    assert np.max(np.abs(z)) < 0.01, z
    assert abs(rms - s["rms_px"]) < 1e-4 * rms


@pytest.mark.parametrize("mode", ["fixed", "joint"])
def test_real_pair_end_to_end_rms_at_most_cv2_and_same_baseline(real: Dict[str, Any], mode: str) -> None:
    corners = real["theirs"]
    rms, _, t = cv_stereo(corners, real["size"], mode == "fixed", corners)
    s = real["stereo"][mode]
    baseline = float(np.linalg.norm(t))
    print(f"real pair, {mode}, each its own corners: rms etlcal {s['rms_px']:.4f} px, cv2 {rms:.4f} px; baseline "
          f"etlcal {s['baseline_mm']:.5f}, cv2 {baseline:.5f} squares")
    assert s["rms_px"] <= rms
    assert abs(s["baseline_mm"] - baseline) < 0.005 * baseline


def read_yaml(path: pathlib.Path) -> Dict[str, Any]:
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    out: Dict[str, Any] = {k: fs.getNode(k).mat() for k in ("K1", "D1", "K2", "D2", "R", "T", "R1", "R2", "P1", "P2", "Q")}
    out["size"] = (int(fs.getNode("image_width").real()), int(fs.getNode("image_height").real()))
    fs.release()
    return out


@pytest.mark.parametrize("pair", ["rendered", "real"])
def test_opencv_yaml_rectification_is_cv2_stereo_rectify(tmp_path: pathlib.Path, etlcal_binary: str,
                                                           pair: str) -> None:
    if int(cv2.__version__.split(".")[0]) < 5:
        pytest.skip("OpenCV 4's stereoRectify takes the smaller focal length, reduced by k1; etlcal follows OpenCV 5")
    if pair == "rendered":
        images = render_pair_set(tmp_path / "images", seed=3)
        left, right, square = [str(p[0]) for p in images[:8]], [str(p[1]) for p in images[:8]], str(SQUARE_MM)
    else:
        left, right, square = [str(p) for p in REAL[0]], [str(p) for p in REAL[1]], "1"
    out = tmp_path / "sub" / "stereo.yml"
    s = run(etlcal_binary, ["stereo", *left, "--right", *right, "--pattern", "9x6", "--square", square, "--model",
                            "opencv", "--opencv-yaml", str(out), "--json"])
    assert s["opencv_yaml"] == str(out)
    y = read_yaml(out)
    assert np.array_equal(cv2.Rodrigues(y["R"])[0].ravel(), np.array(s["rotation_rodrigues"])) or \
        np.allclose(cv2.Rodrigues(y["R"])[0].ravel(), s["rotation_rodrigues"], rtol=0, atol=1e-13)
    assert np.array_equal(y["T"].ravel(), np.array(s["translation_mm"]))
    assert np.array_equal(y["K1"], np.array(s["left"]["camera_matrix"]))
    assert np.array_equal(y["D2"].ravel(), np.array(s["right"]["dist_coeffs"]))
    r1, r2, p1, p2, q, _, _ = cv2.stereoRectify(y["K1"], y["D1"], y["K2"], y["D2"], y["size"], y["R"], y["T"])
    diffs = {n: float(np.max(np.abs(a - b))) for n, a, b in
             (("R1", r1, y["R1"]), ("R2", r2, y["R2"]), ("P1", p1, y["P1"]), ("P2", p2, y["P2"]), ("Q", q, y["Q"]))}
    print(f"{pair}: |cv2.stereoRectify - etlcal| {diffs}")
    assert diffs["R1"] < 1e-12 and diffs["R2"] < 1e-12, diffs
    # P, Q (pixels; P2's baseline in px mm): OpenCV's float32 corner points and its
    # 5-iteration undistortion are reproduced, so they agree to rounding.
    assert diffs["P1"] < 1e-9 and diffs["P2"] < 1e-9 * max(1.0, abs(p2[0, 3])) and diffs["Q"] < 1e-9, diffs
