"""Calibration.undistort_maps / undistort_image against the model's own projection and
against OpenCV's cv2.remap through the same maps (opencv-python-headless)."""
from typing import Any, Callable, List, Tuple, Type

import numpy as np
import numpy.typing as npt
import pytest

import etlcal

_F64 = npt.NDArray[np.float64]

cv2 = pytest.importorskip("cv2")

W, H = 1936, 1458


def _rays_to_world(cal: etlcal.Calibration, xs: _F64, ys: _F64, k_out: _F64) -> _F64:
    """World points on the rays of output pixels (x, y) of the camera k_out, 300 mm deep."""
    fx, fy, cx, cy = k_out[0, 0], k_out[1, 1], k_out[0, 2], k_out[1, 2]
    z = 300.0
    pc = np.stack([z * (xs - cx) / fx, z * (ys - cy) / fy, np.full(xs.shape, z)], axis=-1)
    r, t = cal.rotation_matrix, cal.translation_mm
    return (pc - t) @ r  # R^T (pc - T), row by row


@pytest.mark.parametrize("e_com_ma", [80.0, 150.0, 225.0])
def test_maps_are_the_projection_of_each_output_ray(e_com_ma: float) -> None:
    cal = etlcal.Calibration.paper_rig()
    map_x, map_y = cal.undistort_maps(e_com_ma)
    assert map_x.dtype == np.float32 and map_y.dtype == np.float32
    assert map_x.shape == (H, W) and map_y.shape == (H, W)
    ys, xs = np.mgrid[0:H:7, 0:W:7].astype(np.float64)
    ys, xs = np.concatenate([ys.ravel(), [H - 1.0, 0.0]]), np.concatenate([xs.ravel(), [W - 1.0, 0.0]])
    px = cal.project(_rays_to_world(cal, xs, ys, cal.intrinsics(e_com_ma)), e_com_ma)
    iy, ix = ys.astype(int), xs.astype(int)
    err = max(np.abs(map_x[iy, ix] - px[:, 0]).max(), np.abs(map_y[iy, ix] - px[:, 1]).max())
    assert err < 1e-3, err


def test_a_new_camera_matrix_and_size() -> None:
    cal = etlcal.Calibration.paper_rig()
    k_new = np.array([[3900.0, 0.0, 500.0], [0.0, 3950.0, 400.0], [0.0, 0.0, 1.0]])
    map_x, map_y = cal.undistort_maps(120.0, new_camera_matrix=k_new, size=(1000, 800))
    assert map_x.shape == (800, 1000)
    ys, xs = np.mgrid[0:800:11, 0:1000:11].astype(np.float64)
    px = cal.project(_rays_to_world(cal, xs.ravel(), ys.ravel(), k_new), 120.0)
    iy, ix = ys.ravel().astype(int), xs.ravel().astype(int)
    assert np.abs(map_x[iy, ix] - px[:, 0]).max() < 1e-3
    assert np.abs(map_y[iy, ix] - px[:, 1]).max() < 1e-3
    # A nested list is a camera matrix too.
    lx, _ = cal.undistort_maps(120.0, k_new.tolist(), (1000, 800))
    assert np.array_equal(lx, map_x)


def _smooth_u8() -> npt.NDArray[np.uint8]:
    y, x = np.mgrid[0:H, 0:W]
    image: npt.NDArray[np.uint8] = (127.5 + 127.0 * np.sin(x / 13.0) * np.cos(y / 17.0)).astype(np.uint8)
    return image


@pytest.mark.parametrize("channels", [1, 3])
def test_cv2_remap_with_our_maps_is_our_undistort_image_u8(channels: int) -> None:
    cal = etlcal.Calibration.paper_rig()
    img = _smooth_u8()
    if channels == 3:
        img = np.ascontiguousarray(np.dstack([img, 255 - img, img // 2]))
    map_x, map_y = cal.undistort_maps(150.0)
    ours = cal.undistort_image(img, 150.0)
    theirs = cv2.remap(img, map_x, map_y, cv2.INTER_LINEAR)  # BORDER_CONSTANT, 0
    assert ours.dtype == np.uint8 and ours.shape == img.shape
    # OpenCV quantises the sub-pixel position to 1/32 px: within 1 grey level.
    assert np.abs(ours.astype(int) - theirs.astype(int)).max() <= 1


def test_cv2_remap_with_our_maps_is_our_undistort_image_u16_f32() -> None:
    cal = etlcal.Calibration.paper_rig()
    y, x = np.mgrid[0:H, 0:W]
    ramp = (3.0 * x + 5.0 * y).astype(np.float32)
    map_x, map_y = cal.undistort_maps(200.0)
    ours = cal.undistort_image(ramp, 200.0)
    theirs = cv2.remap(ramp, map_x, map_y, cv2.INTER_LINEAR)
    inside = (map_x >= 0) & (map_y >= 0) & (map_x <= W - 1) & (map_y <= H - 1)
    # Bilinear interpolation of a ramp is exact: both are the ramp at the map, to f32.
    truth = 3.0 * map_x.astype(np.float64) + 5.0 * map_y.astype(np.float64)
    assert np.abs(ours[inside] - truth[inside]).max() < 2e-3
    assert np.abs(ours - theirs).max() < 2e-3
    # Fortran order is read as the same image.
    assert np.array_equal(cal.undistort_image(np.asfortranarray(ramp), 200.0), ours)
    img16 = (_smooth_u8().astype(np.uint16) * 257)
    o16 = cal.undistort_image(img16, 200.0)
    assert o16.dtype == np.uint16
    assert np.abs(o16.astype(int) - cv2.remap(img16, map_x, map_y, cv2.INTER_LINEAR).astype(int)).max() <= 257


def test_bad_inputs_raise_one_line_errors() -> None:
    cal = etlcal.Calibration.paper_rig()
    cases: List[Tuple[Callable[[], object], Type[etlcal.Error], str]] = [
        (lambda: cal.undistort_maps(150.0, size=(0, 10)), etlcal.InputError, "output width_px"),
        (lambda: cal.undistort_maps(150.0, size=(10, 0)), etlcal.InputError, "output height_px"),
        (lambda: cal.undistort_maps(150.0, size=(-1, 10)), etlcal.InputError, "negative"),
        (lambda: cal.undistort_maps(150.0, size="big"), etlcal.InputError, "size must be"),  # type: ignore[arg-type]
        (lambda: cal.undistort_maps(150.0, np.eye(2)), etlcal.InputError, "3 x 3"),
        (lambda: cal.undistort_maps(150.0, [[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), etlcal.InputError,
         "no skew"),
        (lambda: cal.undistort_maps(150.0, [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), etlcal.InputError,
         "camera matrix"),
        (lambda: cal.undistort_maps(400.0), etlcal.InputError, "e_com_ma = 400 is outside [75, 230]"),
        # The run-time checks of what the types already refuse.
        (lambda: cal.undistort_image(np.zeros((H, W), np.float64), 150.0), etlcal.InputError,  # type: ignore[arg-type]
         "dtype float64"),
        (lambda: cal.undistort_image([[1, 2], [3, 4]], 150.0), etlcal.InputError, "numpy array"),  # type: ignore[arg-type]
        (lambda: cal.undistort_image(np.zeros((H, W, 4), np.uint8), 150.0), etlcal.InputError, "shape"),
        (lambda: cal.undistort_image(np.zeros((10, 10), np.uint8), 150.0), etlcal.InputError, "10 x 10 px"),
        (lambda: cal.undistort_image(np.zeros((H, W), np.uint8), 70.0), etlcal.InputError, "e_com_ma = 70 is outside [75, 230]"),
    ]
    for call, cls, words in cases:
        with pytest.raises(cls) as info:
            call()
        msg = str(info.value)
        assert words in msg and "\n" not in msg, msg
