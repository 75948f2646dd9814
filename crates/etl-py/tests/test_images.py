"""Images from Python: render, detect_corners, sharpness, autofocus; the same numbers as
the Rust side, and each bad input as the right exception class."""
import json
import pathlib
from typing import Any, Dict, List, Tuple

import numpy as np
import numpy.typing as npt
import pytest

import etlcal
from etlcal.options import SharpnessMetric

# A rendered image and its true corners (N, 2) px.
Board = Tuple[npt.NDArray[Any], npt.NDArray[Any]]


@pytest.fixture(scope="module")
def board() -> Board:
    return etlcal.render(e_com_ma=150.0, seed=5)


def test_render_gives_an_image_and_its_true_corners(board: Board) -> None:
    image, corners = board
    assert image.shape == (1458, 1936) and image.dtype == np.uint8
    assert corners.shape == (168, 2)
    truth = etlcal.simulate.paper_rig(1).truth
    # The default stage position is the rig's focus position at the current (22 mm at
    # 150 mA); corner (i, j) is the model's projection of (1.5 i, 1.5 j, 22).
    want = truth.project(np.array([[0.0, 0.0, 22.0], [1.5 * 3, 1.5 * 2, 22.0]]), 150.0)
    assert np.allclose(corners[[0, 2 * 14 + 3]], want, atol=1e-9)


def test_detect_corners_finds_the_true_corners_to_hundredths_of_a_pixel(board: Board) -> None:
    image, corners = board
    found = etlcal.detect_corners(image, "14x12")
    assert found.shape == (168, 2)
    inside = (corners[:, 0] > 0) & (corners[:, 0] < 1935) & (corners[:, 1] > 0) & (corners[:, 1] < 1457)
    if inside.all():
        rms = np.sqrt(np.mean(np.sum((found - corners) ** 2, axis=1)))
        assert rms < 0.03
    # The same from a 16-bit image and from a non-contiguous view (copied once).
    wide = image.astype(np.uint16) * 257
    assert np.allclose(etlcal.detect_corners(wide, (14, 12)), found, atol=1e-3)
    assert np.allclose(etlcal.detect_corners(np.asfortranarray(image), "14x12"), found)


def test_detect_corners_bad_input(board: Board) -> None:
    image, _ = board
    with pytest.raises(etlcal.BoardNotFoundError):
        etlcal.detect_corners(image, "15x12")
    with pytest.raises(etlcal.BoardNotFoundError):
        etlcal.detect_corners(np.full((480, 640), 128, np.uint8), "9x6")
    with pytest.raises(etlcal.InputError):
        etlcal.detect_corners(image.astype(np.float32), "14x12")
    with pytest.raises(etlcal.InputError):
        etlcal.detect_corners(image, "14by12")
    with pytest.raises(etlcal.InputError):
        etlcal.detect_corners(image[None], "14x12")


def test_sharpness_measures_and_bad_input(board: Board) -> None:
    image, _ = board
    blurred, _ = etlcal.render(e_com_ma=150.0, blur_px=2.0, seed=5)
    metrics: List[SharpnessMetric] = ["cpbd", "tenengrad", "laplacian", "brenner", "normvar"]
    for metric in metrics:
        v = etlcal.sharpness(image, metric)
        assert np.isfinite(v)
        if metric != "cpbd":
            assert v > etlcal.sharpness(blurred, metric), metric
    assert 0.0 <= etlcal.sharpness(image) <= 1.0
    with pytest.raises(etlcal.InputError):
        etlcal.sharpness(image, "sharpest")  # type: ignore[arg-type]  # the run-time check under test
    with pytest.raises(etlcal.InputError):
        etlcal.sharpness(np.zeros((10, 10), np.uint8), "cpbd")


def test_autofocus_on_a_python_callable() -> None:
    calls: List[float] = []

    def peak(e: float) -> float:
        calls.append(e)
        return float(1.0 / np.sqrt(1.0 + ((e - 151.3) / 4.0) ** 2))

    r = etlcal.autofocus(peak)
    assert abs(r["best_ma"] - 151.3) < 0.5 and r["evaluations"] == len(calls) <= 15
    assert all(75.0 <= e <= 240.0 for e in calls)

    def broken(e: float) -> float:
        raise RuntimeError("camera unplugged")

    with pytest.raises(RuntimeError, match="camera unplugged"):
        etlcal.autofocus(broken)
    with pytest.raises(etlcal.InputError):
        etlcal.autofocus(peak, range_ma=(100.0, 50.0))
    with pytest.raises(etlcal.InputError):
        etlcal.autofocus(lambda e: float("nan"))


def test_zhang_on_rendered_lens_off_views_and_bad_input() -> None:
    sim = etlcal.simulate.paper_rig(1)
    obs = sim.observations
    views: List[Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]] = []
    for k in range(obs.offstate_count):
        v = obs.offstate_view(k)
        views.append((v["world_mm"][:, :2], v["pixels"]))
    r = etlcal.zhang(views, (1936, 1458))
    # The lens-off camera is the model at E = 0, outside the ETL views' 80..225 mA.
    truth = sim.truth.intrinsics(0.0, allow_extrapolation=True)
    assert abs(r["fx"] / truth[0, 0] - 1.0) < 2e-3 and abs(r["fy"] / truth[1, 1] - 1.0) < 2e-3
    assert abs(r["rms_px"] - 0.2 * np.sqrt(2.0)) < 0.05 and r["views_used"] == len(views)
    with pytest.raises(etlcal.InputError):
        etlcal.zhang(views[:2], (1936, 1458))
    with pytest.raises(etlcal.InputError):
        etlcal.zhang([(views[0][0], views[0][1][:-1])] * 3, (1936, 1458))


def test_render_16_bit_and_bad_input(board: Board) -> None:
    image, corners = board
    wide, same = etlcal.render(e_com_ma=150.0, seed=5, bit_depth=16)
    assert wide.dtype == np.uint16 and wide.shape == image.shape and np.array_equal(same, corners)
    # The same scene at 16 bits: 257 times the 8-bit grey levels, to the 8-bit rounding.
    assert abs(wide.astype(float).mean() / 257.0 - image.astype(float).mean()) < 1.0
    small, c = etlcal.render(pattern=(5, 4), square_mm=2.0, z_mm=40.0, aperture_mm=0.0, noise=0.0)
    assert c.shape == (20, 2)
    with pytest.raises(etlcal.InputError, match="bit_depth"):
        etlcal.render(bit_depth=12)
    # The CLI's ranges, by Python's names (a NaN aperture once rendered a sharp image).
    bad = {"aperture_mm": float("nan"), "blur_px": 100.0, "noise": 1e308, "e_com_ma": float("nan"), "z_mm": 1e308}
    for key, value in bad.items():
        with pytest.raises(etlcal.InputError, match=rf"^invalid input: {key} .* is outside \["):
            etlcal.render(**{key: value})  # type: ignore[arg-type]  # every keyword is a float
    with pytest.raises(etlcal.InputError):
        etlcal.render(square_mm=-1.5)
    with pytest.raises(etlcal.InputError):
        etlcal.render(pattern="0x3")
    with pytest.raises(etlcal.InputError):
        etlcal.render(pattern=3.5)  # type: ignore[arg-type]  # the run-time check under test


def test_sharpness_of_16_bit_images(board: Board) -> None:
    image, _ = board
    wide = image.astype(np.uint16) * 257
    # CPBD reads 16-bit images on the 8-bit scale (divided by 257): the same value.
    assert etlcal.sharpness(wide, "cpbd") == pytest.approx(etlcal.sharpness(image, "cpbd"), abs=1e-12)
    assert etlcal.sharpness(wide, "tenengrad") > 0.0
    with pytest.raises(etlcal.InputError, match="uint8 or uint16"):
        etlcal.sharpness(image.astype(np.int32), "tenengrad")


def test_autofocus_bad_options() -> None:
    def f(e: float) -> float:
        return -abs(e - 150.0)

    with pytest.raises(etlcal.InputError):
        etlcal.autofocus(f, coarse_points=2)
    with pytest.raises(etlcal.InputError):
        etlcal.autofocus(f, coarse_points=7, max_evaluations=5)
    with pytest.raises(etlcal.InputError):
        etlcal.autofocus(f, tolerance_ma=-1.0)
    # A callable that does not return a number: Python's own TypeError, as for float("x").
    with pytest.raises(TypeError):
        etlcal.autofocus(lambda e: "sharp")  # type: ignore[arg-type, return-value]  # the refusal under test


CHARUCO = pathlib.Path(__file__).resolve().parents[3] / "fixtures" / "charuco"

# An image drawn by OpenCV and its entry in fixtures/charuco/opencv.json.
Drawn = Tuple[npt.NDArray[np.uint8], Dict[str, Any]]


@pytest.fixture(scope="module")
def drawn_board() -> Drawn:
    """A board drawn by OpenCV (fixtures/charuco/SOURCE.md) and what OpenCV 5's
    CharucoDetector finds on it, with the true corners (fixtures/charuco/opencv.json)."""
    cv2: Any = pytest.importorskip("cv2")
    reference = json.loads((CHARUCO / "opencv.json").read_text())
    entry: Dict[str, Any] = next(e for e in reference["images"] if e["file"] == "opencv_DICT_5X5_100.png")
    image: npt.NDArray[np.uint8] = cv2.imread(str(CHARUCO / entry["file"]), cv2.IMREAD_GRAYSCALE)
    return image, entry


def test_detect_corners_of_a_charuco_board_gives_opencvs_ids(drawn_board: Drawn) -> None:
    image, entry = drawn_board
    b = entry["board"]
    board = etlcal.Board.charuco(tuple(b["squares"]), b["square_mm"], b["marker_mm"], b["dictionary"])
    found = etlcal.detect_corners(image, board)
    assert isinstance(found, etlcal.BoardDetection)
    assert found.ids.dtype == np.int64 and found.ids.tolist() == entry["ids"]
    assert found.corners_px.shape == (len(entry["ids"]), 2)
    assert np.allclose(found.board_mm, entry["board_mm"], atol=1e-6)
    assert found.image_size == (640, 480)
    truth = np.array(entry["truth_px"])[found.ids]
    rms = float(np.sqrt(np.mean(np.sum((found.corners_px - truth) ** 2, axis=1))))
    assert rms < 0.015, rms
    # The board as a dict of its fields, and a 16-bit image: the same corners.
    as_dict = dict(b, type="charuco")
    again = etlcal.detect_corners(image.astype(np.uint16) * 257, board=as_dict)
    assert again.ids.tolist() == entry["ids"]
    assert np.allclose(again.corners_px, found.corners_px, atol=1e-3)


def test_detect_corners_of_a_checkerboard_board_has_row_major_ids(board: Board) -> None:
    image, _ = board
    found = etlcal.detect_corners(image, etlcal.Board.checkerboard((14, 12), 1.5))
    assert found.ids.tolist() == list(range(168))
    assert np.array_equal(found.corners_px, etlcal.detect_corners(image, "14x12"))
    assert np.array_equal(etlcal.detect_corners(image, pattern="14x12"), found.corners_px)
    assert np.allclose(found.board_mm[15], [1.5, 1.5])


def test_detect_corners_of_a_charuco_board_bad_input(drawn_board: Drawn) -> None:
    image, entry = drawn_board
    b = entry["board"]
    other = etlcal.Board.charuco(tuple(b["squares"]), b["square_mm"], b["marker_mm"], "DICT_APRILTAG_36h11")
    with pytest.raises(etlcal.BoardNotFoundError, match="DICT_APRILTAG_36h11"):
        etlcal.detect_corners(image, other)
    with pytest.raises(etlcal.BoardNotFoundError):
        etlcal.detect_corners(np.full((480, 640), 128, np.uint8), etlcal.Board.charuco((8, 6), 25, 18, "DICT_5X5_100"))
    with pytest.raises(etlcal.InputError, match="dictionary"):
        etlcal.detect_corners(image, {"type": "charuco", "squares": [8, 6], "square_mm": 25, "marker_mm": 18,
                                      "dictionary": "DICT_5X5_99"})
    with pytest.raises(etlcal.InputError, match="not both") as e:
        etlcal.detect_corners(image, etlcal.Board.checkerboard((9, 6), 1.0), pattern="9x6")  # type: ignore[call-overload]
    assert e.value.what == "board"
    with pytest.raises(etlcal.InputError):
        etlcal.detect_corners(image)  # type: ignore[call-overload]
    with pytest.raises(etlcal.InputError):
        etlcal.detect_corners(image, 42)  # type: ignore[call-overload]
