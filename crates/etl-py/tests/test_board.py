"""etlcal.Board: ChArUco and checkerboard targets, their etlcal.board/1 files, and the
print-ready target against OpenCV's own drawing (`cv2.aruco.CharucoBoard.generateImage`):
the raster of `Board.to_image`, the PNG of `etlcal board` and the SVG of `Board.to_svg`
(its rectangles filled at the same pixel size) equal OpenCV's image pixel for pixel; a
Dataset with ChArUco boards."""
import json
import pathlib
import pickle
import re
import subprocess
from typing import Any, Tuple

import numpy as np
import numpy.typing as npt
import pytest

import etlcal

cv2 = pytest.importorskip("cv2")

Squares = Tuple[int, int]

# (squares, square_mm, marker_mm, dictionary): at 254 dpi (10 px per mm) every square is
# 100 px and every marker cell 10 px, on the pixel grid, where OpenCV draws exactly.
BOARDS = [
    ((5, 4), 10.0, 6.0, "DICT_4X4_50"),  # 6 x 6 cells
    ((6, 5), 10.0, 7.0, "DICT_5X5_100"),  # 7 x 7 cells
    ((4, 6), 10.0, 8.0, "DICT_6X6_250"),  # 8 x 8 cells
    ((7, 5), 10.0, 8.0, "DICT_APRILTAG_36h11"),
    ((5, 5), 10.0, 6.0, "DICT_APRILTAG_16h5"),
]
MARGIN_MM = 5.0


def opencv_image(squares: Squares, square_mm: float, marker_mm: float, dictionary: str) -> Any:
    d = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary))
    b = cv2.aruco.CharucoBoard(squares, square_mm, marker_mm, d)
    size = (int(squares[0] * square_mm * 10 + 2 * MARGIN_MM * 10), int(squares[1] * square_mm * 10 + 2 * MARGIN_MM * 10))
    return b.generateImage(size, marginSize=int(MARGIN_MM * 10))


def svg_raster(svg: str, px_per_mm: float) -> npt.NDArray[np.uint8]:
    """The SVG's black rectangles (subpaths `M x y h w v h h -w z`) filled on a white page
    of the SVG's size, pixel (x, y) black when its centre is inside one."""
    width = re.search(r'width="([0-9.]+)mm"', svg)
    height = re.search(r'height="([0-9.]+)mm"', svg)
    assert width is not None and height is not None
    w, h = float(width.group(1)), float(height.group(1))
    img = np.full((round(h * px_per_mm), round(w * px_per_mm)), 255, np.uint8)
    for d in re.findall(r'<path id="[^"]+" fill="#000000" d="([^"]*)"', svg):
        for x, y, rw, rh in re.findall(r"M([-0-9.]+) ([-0-9.]+)h([-0-9.]+)v([-0-9.]+)h-[0-9.]+z", d):
            x0, y0 = round(float(x) * px_per_mm), round(float(y) * px_per_mm)
            x1, y1 = round((float(x) + float(rw)) * px_per_mm), round((float(y) + float(rh)) * px_per_mm)
            img[y0:y1, x0:x1] = 0
    return img


@pytest.mark.parametrize("squares,square_mm,marker_mm,dictionary", BOARDS)
def test_the_printed_board_is_opencvs(tmp_path: pathlib.Path, etlcal_binary: str, squares: Squares,
                                      square_mm: float, marker_mm: float, dictionary: str) -> None:
    ref = opencv_image(squares, square_mm, marker_mm, dictionary)
    board = etlcal.Board.charuco(squares, square_mm, marker_mm, dictionary)
    img = board.to_image(254.0, MARGIN_MM)
    assert img.dtype == np.uint8 and img.shape == ref.shape
    assert np.array_equal(img, ref), f"{(img != ref).sum()} pixels differ"
    svg = board.to_svg(MARGIN_MM)
    w, h = squares[0] * square_mm + 2 * MARGIN_MM, squares[1] * square_mm + 2 * MARGIN_MM
    assert f'width="{w:g}mm" height="{h:g}mm" viewBox="0 0 {w:g} {h:g}"' in svg
    assert np.array_equal(svg_raster(svg, 10.0), ref)
    # The command line writes the same PNG, and records its resolution.
    path = tmp_path / "b.json"
    board.save(path)
    png = tmp_path / "out" / "b.png"
    subprocess.run([etlcal_binary, "board", "--board", str(path), "--out", str(png), "--dpi", "254",
                    "--margin-mm", str(MARGIN_MM)], check=True, capture_output=True)
    assert np.array_equal(cv2.imread(str(png), cv2.IMREAD_GRAYSCALE), ref)
    data = png.read_bytes()
    at = data.index(b"pHYs")
    assert int.from_bytes(data[at + 4:at + 8], "big") == 10000 and data[at + 12] == 1
    svg_path = tmp_path / "b.svg"
    subprocess.run([etlcal_binary, "board", "--board", str(path), "--out", str(svg_path),
                    "--margin-mm", str(MARGIN_MM)], check=True, capture_output=True)
    assert svg_path.read_text() == svg


def test_opencv_reads_the_printed_board_with_its_ids() -> None:
    board = etlcal.Board.charuco((8, 6), 10.0, 7.0, "DICT_5X5_100")
    img = board.to_image(150.0)
    d = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_5X5_100)
    det = cv2.aruco.CharucoDetector(cv2.aruco.CharucoBoard((8, 6), 10.0, 7.0, d))
    corners, ids, _, marker_ids = det.detectBoard(img)
    assert sorted(marker_ids.ravel()) == list(range(24))
    assert sorted(ids.ravel()) == list(range(board.corner_count))
    # Corner id k is at corners_mm[k] + the margin (one square by default), in pixels.
    px_per_mm = 150.0 / 25.4
    want = (board.corners_mm[ids.ravel()] + 10.0) * px_per_mm - 0.5
    assert np.abs(corners.reshape(-1, 2) - want).max() < 0.1


def test_attributes_files_and_pickling(tmp_path: pathlib.Path) -> None:
    b = etlcal.Board.charuco((12, 9), 1.5, 1.1, "DICT_5X5_100")
    assert (b.type, b.squares, b.square_mm, b.marker_mm, b.dictionary) == ("charuco", (12, 9), 1.5, 1.1, "DICT_5X5_100")
    assert b.inner_corners == (11, 8) and b.corner_count == 88
    assert b.corners_mm.shape == (88, 2) and tuple(b.corners_mm[12]) == (3.0, 3.0)
    assert repr(b) == "Board(ChArUco 12 x 9 squares of 1.5 mm (markers 1.1 mm, DICT_5X5_100))"
    assert b.to_dict() == {"format": "etlcal.board/1", "type": "charuco", "squares": [12, 9], "square_mm": 1.5,
                           "marker_mm": 1.1, "dictionary": "DICT_5X5_100"}
    path = tmp_path / "b.json"
    b.save(path)
    assert etlcal.Board.load(path) == b
    assert json.loads(path.read_text())["type"] == "charuco"
    assert pickle.loads(pickle.dumps(b)) == b and etlcal.Board.from_json(b.to_json()) == b
    k = etlcal.Board.checkerboard((14, 12), 1.5)
    assert (k.type, k.squares, k.marker_mm, k.dictionary, k.inner_corners) == ("checkerboard", None, None, None, (14, 12))
    assert tuple(k.corners_mm[15]) == (1.5, 1.5) and k != b
    assert etlcal.Board.from_dict({"inner_corners": (14, 12), "square_mm": 1.5}) == k
    assert len({b, k, etlcal.Board.load(path)}) == 2


@pytest.mark.parametrize("args,field,what,value", [
    (((12, 9), 1.5, 1.1, "DICT_5X5_99"), 'dictionary "DICT_5X5_99" is not one of OpenCV', "dictionary", "DICT_5X5_99"),
    (((12, 9), 1.5, 1.6, "DICT_5X5_100"), r"marker_mm must be smaller than square_mm \(square_mm 1.5, marker_mm 1.6\)",
     "marker_mm", "1.6"),
    (((12, 9), 1.5, 1.1, "DICT_4X4_50"), "DICT_4X4_50 has 50 markers, the board 54", "dictionary", "DICT_4X4_50"),
    (((12, 9), 0.0, 1.1, "DICT_5X5_100"), "square_mm must be positive", "square_mm", "0"),
    (((12, 9), -1.5, -2.0, "DICT_5X5_100"), "square_mm must be positive", "square_mm", "-1.5"),
    (((1, 9), 1.5, 1.1, "DICT_5X5_100"), r"squares: a ChArUco board has 2 to 1000 squares each way \(squares \[1, 9\]\)",
     "squares", "[1, 9]"),
])
def test_bad_boards_name_the_field_and_write_nothing(tmp_path: pathlib.Path, etlcal_binary: str,
                                                    args: Tuple[Squares, float, float, str], field: str, what: str,
                                                    value: str) -> None:
    with pytest.raises(etlcal.InputError, match=field) as e:
        etlcal.Board.charuco(*args)
    assert (e.value.what, e.value.value) == (what, value)
    # The same board as a file: refused by the reader and by `etlcal board`, nothing written.
    squares, square_mm, marker_mm, dictionary = args
    path = tmp_path / "bad.json"
    path.write_text(json.dumps({"format": "etlcal.board/1", "type": "charuco", "squares": list(squares),
                                "square_mm": square_mm, "marker_mm": marker_mm, "dictionary": dictionary}))
    with pytest.raises(etlcal.InputError, match=field):
        etlcal.Board.load(path)
    out = subprocess.run([etlcal_binary, "board", "--board", str(path), "--out", str(tmp_path / "o" / "b.svg")],
                         capture_output=True, text=True)
    assert out.returncode == 1 and len(out.stderr.strip().splitlines()) == 1
    assert re.search(field, out.stderr), out.stderr
    assert not (tmp_path / "o").exists()


def test_bad_print_sizes_and_checkerboards() -> None:
    b = etlcal.Board.charuco((5, 4), 10.0, 6.0, "DICT_4X4_50")
    with pytest.raises(etlcal.InputError, match="dpi 0 dpi is outside"):
        b.to_image(0.0)
    with pytest.raises(etlcal.InputError, match="margin_mm -1 mm is outside"):
        b.to_svg(-1.0)
    with pytest.raises(etlcal.InputError, match="a board needs at least 3 x 3 inner corners, got 2 x 12") as e:
        etlcal.Board.checkerboard((2, 12), 1.5)
    assert (e.value.what, e.value.value) == ("inner_corners", "[2, 12]")
    with pytest.raises(etlcal.InputError, match="board: unknown field `colour`"):
        etlcal.Board.from_dict({"inner_corners": (14, 12), "square_mm": 1.5, "colour": 1})


def test_a_dataset_with_charuco_boards(tmp_path: pathlib.Path) -> None:
    board = etlcal.Board.charuco((15, 13), 1.5, 1.1, "DICT_5X5_100")
    ds = etlcal.Dataset((1936, 1458), board=board, base_dir=tmp_path,
                        offstate_board=etlcal.Board.charuco((12, 9), 4.0, 3.0, "DICT_5X5_100"))
    ds.add_view("v0.png", 100.0, 30.0, 40.0)
    ds.add_offstate_view("o0.png")
    text = json.loads(ds.to_json())
    assert text["board"] == board.to_dict() and text["offstate_board"]["squares"] == [12, 9]
    assert ds.board == {"type": "charuco", "squares": (15, 13), "marker_mm": 1.1, "dictionary": "DICT_5X5_100",
                        "square_mm": 1.5}
    assert "ChArUco 15 x 13" in repr(ds)
    # A checkerboard hint means nothing for a ChArUco board: refused, nothing written.
    ds.add_view("v1.png", 110.0, 30.0, 35.0, first_corner=(1, 1))
    with pytest.raises(etlcal.InputError, match="first_corner \\[1, 1\\] applies to checkerboards only"):
        ds.save(tmp_path / "d.json")
    assert not (tmp_path / "d.json").exists()
    with pytest.raises(etlcal.InputError, match="give board=etlcal.Board"):
        etlcal.Dataset((1936, 1458), (14, 12), 1.5, board=board)
    with pytest.raises(etlcal.InputError, match="give board=etlcal.Board"):
        etlcal.Dataset((1936, 1458))
