//! Images: `detect_corners`, `sharpness` and `render`, numpy arrays in and out.
//!
//! Images are 2-D numpy arrays of dtype uint8 or uint16 (rows x columns, grey levels);
//! a C-contiguous uint8/uint16 array is read in place (detection and sharpness; CPBD of a
//! 16-bit image converts to 8 bits), anything else is copied once.

use etl_core::focus::{brenner, laplacian_variance, normalised_variance, tenengrad, ImageView, Pixel};
use etl_core::model::CameraModel;
use etl_image::board::detect_board_view;
use etl_image::checkerboard::{detect_view, Pattern};
use etl_image::grey::GrayView;
use etl_image::sharpness::cpbd::cpbd;
use etl_image::sharpness::{sharpness_u16, Gray16Image, Metric};
use etl_sim::render::{render as render_board, BitDepth, PaperRender, Scene};
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::points_out;
use crate::board::board_arg;
use crate::errors::{input_error, invalid, invalid_value, CoreResultExt};
use crate::results;

/// A grey image read from numpy: 8- or 16-bit samples, row-major.
enum Pixels {
    U8(Vec<u8>),
    U16(Vec<u16>),
}

/// Reads a 2-D uint8 or uint16 array as (width, height, samples); `f` gets a borrowed
/// view of C-contiguous arrays without a copy.
fn with_image<R>(obj: &Bound<'_, PyAny>, f: impl FnOnce(usize, usize, ImageRef<'_>) -> PyResult<R>) -> PyResult<R> {
    // The files' pixel limit, checked on the shape: before a copy, and before any detector
    // sizes its buffers by the image.
    crate::arrays::refuse_oversized(obj, "image", etl_formats::observations::MAX_IMAGE_PIXELS as usize)?;
    if let Ok(a) = obj.extract::<PyReadonlyArray2<'_, u8>>() {
        let (h, w) = (a.shape()[0], a.shape()[1]);
        return match a.as_slice() {
            Ok(s) if a.is_c_contiguous() => f(w, h, ImageRef::U8(s)),
            _ => {
                let owned = Pixels::U8(a.as_array().iter().copied().collect());
                call_owned(w, h, &owned, f)
            }
        };
    }
    if let Ok(a) = obj.extract::<PyReadonlyArray2<'_, u16>>() {
        let (h, w) = (a.shape()[0], a.shape()[1]);
        return match a.as_slice() {
            Ok(s) if a.is_c_contiguous() => f(w, h, ImageRef::U16(s)),
            _ => {
                let owned = Pixels::U16(a.as_array().iter().copied().collect());
                call_owned(w, h, &owned, f)
            }
        };
    }
    Err(invalid("image", "image must be a 2-D numpy array of dtype uint8 or uint16 (rows x columns)"))
}

fn call_owned<R>(
    w: usize,
    h: usize,
    owned: &Pixels,
    f: impl FnOnce(usize, usize, ImageRef<'_>) -> PyResult<R>,
) -> PyResult<R> {
    match owned {
        Pixels::U8(v) => f(w, h, ImageRef::U8(v)),
        Pixels::U16(v) => f(w, h, ImageRef::U16(v)),
    }
}

/// Borrowed samples.
#[derive(Clone, Copy)]
enum ImageRef<'a> {
    U8(&'a [u8]),
    U16(&'a [u16]),
}

fn pattern_of(obj: &Bound<'_, PyAny>) -> PyResult<Pattern> {
    if let Ok(s) = obj.extract::<String>() {
        return s.parse::<Pattern>().py();
    }
    let (c, r): (usize, usize) =
        obj.extract().map_err(|_| invalid("pattern", "pattern must be \"CxR\" (e.g. \"14x12\") or (cols, rows)"))?;
    Pattern::new(c, r).py()
}

/// Finds a board in an image: its corners refined to sub-pixel accuracy.
///
/// Args:
///     image: 2-D numpy array, dtype uint8 or uint16 (rows x columns).
///     board: the board. An `etlcal.Board` (or a dict of its fields): a ChArUco board
///         (the corners seen, each with its id: partial views need no hint) or a
///         checkerboard (the whole board). Or a checkerboard's inner corners as "CxR"
///         (e.g. "14x12") or (cols, rows), as before.
///     pattern: the same as a "CxR" or (cols, rows) `board` (the old keyword).
///
/// Returns: for an `etlcal.Board`, a `BoardDetection` (`etlcal.results`): `corners_px`
/// ((N, 2) float64, px, (0, 0) the centre of the top-left pixel), `ids` ((N,) int64,
/// increasing: OpenCV's ChArUco corner ids, a checkerboard's row-major index
/// `row * cols + col`), `board_mm` ((N, 2) float64, each corner on the board, mm),
/// `image_size` ((width, height)). For "CxR" or (cols, rows): the (cols * rows, 2) float64
/// array of pixels, row by row on the board (corner (i, j) at index j * cols + i; the
/// board square between corners (0, 0) and (1, 1) is the dark one).
///
/// Raises: BoardNotFoundError with the reason (no marker of the board's dictionary, none
/// confirmed by its neighbours; a checkerboard absent, partly outside the image or of
/// another size: never a wrong grid); InputError for a bad array, board or pattern.
#[pyfunction]
#[pyo3(signature = (image, board=None, *, pattern=None))]
pub fn detect_corners<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    board: Option<&Bound<'py, PyAny>>,
    pattern: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let target = match (board, pattern) {
        (Some(_), Some(_)) => return Err(invalid("board", "give the board once: board or pattern, not both")),
        (None, None) => return Err(invalid("board", "give the board: an etlcal.Board, or a pattern \"CxR\"")),
        (Some(b), None) if b.extract::<String>().is_err() && b.extract::<(usize, usize)>().is_err() => {
            Some(board_arg(b, "board")?)
        }
        _ => None,
    };
    let Some(target) = target else {
        let pattern = pattern_of(board.or(pattern).ok_or_else(|| invalid("pattern", "no pattern"))?)?;
        let corners = with_view(py, image, |v| detect_view(v, pattern), |v| detect_view(v, pattern))?;
        return points_out(py, corners.corners_px, false);
    };
    let d = with_view(py, image, |v| detect_board_view(v, &target), |v| detect_board_view(v, &target))?;
    let fields = PyDict::new(py);
    let board_mm: Vec<[f64; 2]> = d.ids.iter().filter_map(|&id| target.corner_mm(id)).collect();
    let ids: Vec<i64> = d.ids.iter().map(|&id| i64::from(id)).collect();
    fields.set_item("corners_px", points_out(py, d.corners_px, false)?)?;
    fields.set_item("ids", Array1::from(ids).into_pyarray(py))?;
    fields.set_item("board_mm", points_out(py, board_mm, false)?)?;
    fields.set_item("image_size", (d.image_size[0], d.image_size[1]))?;
    results::make(py, "BoardDetection", &fields)
}

/// Runs a detector on the image's grey view (8- or 16-bit), without the GIL.
fn with_view<'py, R: Send>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    at8: impl FnOnce(GrayView<'_, u8>) -> etl_formats::Result<R> + Send,
    at16: impl FnOnce(GrayView<'_, u16>) -> etl_formats::Result<R> + Send,
) -> PyResult<R> {
    with_image(image, |w, h, px| {
        let bad = || invalid("image", format!("image of {w} x {h} px has an inconsistent buffer"));
        crate::pool::detach(py, || match px {
            ImageRef::U8(s) => GrayView::new(w, h, s).map(at8),
            ImageRef::U16(s) => GrayView::new(w, h, s).map(at16),
        })
        .ok_or_else(bad)?
        .py()
    })
}

fn metric_of(name: &str) -> PyResult<Metric> {
    name.parse::<Metric>().py()
}

/// The sharpness of an image (larger is sharper).
///
/// Args:
///     image: 2-D numpy array, dtype uint8 or uint16.
///     metric: "cpbd" (the reference package's value exactly; 8-bit scale, a uint16 image
///         is divided by 257 first), "tenengrad", "laplacian", "brenner" or "normvar".
///
/// Returns: the value (float; CPBD in [0, 1]).
///
/// Raises: InputError for an unknown metric or an image too small (CPBD needs 64 x 64).
#[pyfunction]
#[pyo3(signature = (image, metric="cpbd"))]
pub fn sharpness(py: Python<'_>, image: &Bound<'_, PyAny>, metric: &str) -> PyResult<f64> {
    let metric = metric_of(metric)?;
    with_image(image, |w, h, px| match px {
        ImageRef::U8(s) if metric == Metric::Cpbd => crate::pool::detach(py, || cpbd(s, w, h)).py(),
        ImageRef::U8(s) => crate::pool::detach(py, || gradient_measure(s, w, h, metric)).py(),
        ImageRef::U16(s) if metric == Metric::Cpbd => {
            // CPBD reads 8-bit levels: etl-calib converts (a copy it makes anyway).
            let img = Gray16Image::from_raw(w as u32, h as u32, s.to_vec())
                .ok_or_else(|| invalid("image", format!("image of {w} x {h} px has an inconsistent buffer")))?;
            crate::pool::detach(py, || sharpness_u16(&img, metric)).py()
        }
        ImageRef::U16(s) => crate::pool::detach(py, || gradient_measure(s, w, h, metric)).py(),
    })
}

/// The gradient measures on the numpy buffer in place: the etl-core `focus` functions
/// etl-calib's `sharpness` calls on an image's raw buffer (same values, same errors).
fn gradient_measure<T: Pixel>(data: &[T], w: usize, h: usize, metric: Metric) -> etl_calib::Result<f64> {
    let view = ImageView::packed(data, w, h)?;
    Ok(match metric {
        Metric::Tenengrad => tenengrad(&view)?,
        Metric::Laplacian => laplacian_variance(&view)?,
        Metric::Brenner => brenner(&view)?,
        Metric::Normvar => normalised_variance(&view)?,
        Metric::Cpbd => {
            return Err(etl_calib::Error::invalid_value("metric", "cpbd", "CPBD is not a gradient measure"))
        }
    })
}

/// Renders a checkerboard on the paper rig's stage through the paper rig's camera (the
/// synthetic camera: exact anti-aliasing, distortion, thin-lens defocus, noise).
///
/// Args:
///     e_com_ma: compensated lens current, mA.
///     z_mm: stage position Z_W, mm (None: the rig's focus position at the current).
///     pattern: inner corners "CxR" or (cols, rows).
///     square_mm: square size, mm.
///     aperture_mm: aperture diameter for the defocus, mm (0: none).
///     blur_px: additional uniform Gaussian blur, px.
///     noise: read noise, grey levels (8-bit scale).
///     bit_depth: 8 or 16.
///     seed: noise seed.
///
/// Returns: (image, corners): a (1458, 1936) uint8/uint16 array and the (N, 2) true
/// pixels of the inner corners in `detect_corners`' order.
#[pyfunction]
#[pyo3(signature = (e_com_ma=150.0, z_mm=None, pattern=None, square_mm=1.5, aperture_mm=2.5, blur_px=0.0,
    noise=2.0, bit_depth=8, seed=1))]
#[allow(clippy::too_many_arguments)]
pub fn render<'py>(
    py: Python<'py>,
    e_com_ma: f64,
    z_mm: Option<f64>,
    pattern: Option<&Bound<'py, PyAny>>,
    square_mm: f64,
    aperture_mm: f64,
    blur_px: f64,
    noise: f64,
    bit_depth: u8,
    seed: u64,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let pattern = match pattern {
        Some(p) => pattern_of(p)?,
        None => Pattern::new(14, 12).py()?,
    };
    let depth = match bit_depth {
        8 => BitDepth::Eight,
        16 => BitDepth::Sixteen,
        b => return Err(invalid_value("bit_depth", b, format!("bit_depth must be 8 or 16, got {b}"))),
    };
    let truth = CameraModel::paper_rig();
    let request = PaperRender { e_com_ma, z_mm, aperture_mm, blur_px, noise, bit_depth: depth, seed };
    request.validate(str::to_owned).py()?;
    let board = etl_formats::Board::checkerboard([pattern.cols, pattern.rows], square_mm).py()?;
    let scene = Scene::new(truth, e_com_ma, board, request.stage_z_mm(), CameraModel::PAPER_IMAGE_SIZE);
    let opts = request.options(&truth);
    let r = crate::pool::detach(py, || render_board(&scene, &opts)).py()?;
    let (w, h) = (r.image.width as usize, r.image.height as usize);
    let image = match depth {
        BitDepth::Eight => {
            let a = Array2::from_shape_vec((h, w), r.image.data.iter().map(|&v| v.min(255) as u8).collect())
                .map_err(|e| input_error(e.to_string()))?;
            a.into_pyarray(py).into_any()
        }
        BitDepth::Sixteen => {
            let a = Array2::from_shape_vec((h, w), r.image.data).map_err(|e| input_error(e.to_string()))?;
            a.into_pyarray(py).into_any()
        }
    };
    Ok((image, points_out(py, r.corners_px, false)?))
}
