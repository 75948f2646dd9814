//! `stereo(pairs, image_size, model="paper", ...)`: a fixed-focus camera pair from
//! synchronised views of a planar board (etl-calib's `stereo_calibrate`, as `etlcal
//! stereo`): each camera by Zhang's method, then R, T as `cv2.stereoCalibrate`. The
//! keywords parse into the same request as `etlcal stereo --model --fix-k3 --zero-tangent
//! --intrinsics`.

use etl_calib::stereo::{stereo_calibrate, StereoMode, StereoOptions, StereoPair};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{mat3_out, matrix_out, vec_out};
use crate::errors::{invalid_value, CoreResultExt};
use crate::pipeline::Keywords;
use crate::zhang::{planar_views, request};

/// One camera's view of a pair: (board_mm, pixels), or None.
type ViewArg<'py> = Option<(Bound<'py, PyAny>, Bound<'py, PyAny>)>;

/// A fixed-focus camera pair from synchronised views of a planar board: each camera's
/// intrinsics by Zhang's method (as `zhang`), then the relative pose R, T by
/// Levenberg-Marquardt, as cv2.stereoCalibrate: X_right = R X_left + T.
///
/// Args:
///     pairs: a list of (left, right), each camera's view of one pair: (board_mm, pixels)
///         as `zhang` takes them, or None where that camera did not see the board (its
///         other view still counts for the other camera's own calibration).
///     image_size: (width, height), px, of both cameras (`right_image_size` for another).
///     model, fix_k3, zero_tangent: as `zhang` (both cameras).
///     intrinsics: "fixed" (each camera's own Zhang calibration held while R, T are
///         fitted: cv2.stereoCalibrate's CALIB_FIX_INTRINSIC) or "joint" (both cameras'
///         intrinsics refined with R, T over the pairs seen by both; at least 3).
///     right_image_size: the right camera's (width, height) when it differs.
///
/// Returns: a StereoResult: "left", "right" (each a ZhangResult / ZhangOpenCvResult),
/// "rotation_rodrigues" (rad), "rotation_matrix", "translation_mm", "covariance" (6 x 6
/// over (om, T), rad and mm), "std" (its diagonal's square roots), "rms_px" (over both
/// cameras' points of the pairs used, cv2.stereoCalibrate's return value),
/// "per_view_rms_px" ((pairs, 2): left, right), "pairs_used", "baseline_mm",
/// "intrinsics".
///
/// Raises: InputError naming the unmet precondition (no pair seen by both cameras, too
/// few views, an unknown model or intrinsics, OpenCV flags with model="paper").
#[pyfunction]
#[pyo3(signature = (pairs, image_size, model="paper", fix_k3=false, zero_tangent=false, intrinsics="fixed", right_image_size=None))]
#[allow(clippy::too_many_arguments)]
pub fn stereo<'py>(
    py: Python<'py>,
    pairs: Vec<(ViewArg<'py>, ViewArg<'py>)>,
    image_size: (u32, u32),
    model: &str,
    fix_k3: bool,
    zero_tangent: bool,
    intrinsics: &str,
    right_image_size: Option<(u32, u32)>,
) -> PyResult<Bound<'py, PyAny>> {
    let request = request(model, fix_k3, zero_tangent)?;
    request.validate(&Keywords).py()?;
    let mode = match intrinsics {
        "fixed" => StereoMode::FixedIntrinsics,
        "joint" => StereoMode::Joint,
        other => {
            return Err(invalid_value(
                "intrinsics",
                other,
                format!("intrinsics must be \"fixed\" or \"joint\", got {other:?}"),
            ))
        }
    };
    let one = |v: &ViewArg<'py>| -> PyResult<_> {
        v.as_ref().map(|(b, p)| planar_views(&[(b.clone(), p.clone())]).map(|mut x| x.remove(0))).transpose()
    };
    let stereo_pairs =
        pairs.iter().map(|(l, r)| Ok(StereoPair { left: one(l)?, right: one(r)? })).collect::<PyResult<Vec<_>>>()?;
    let sizes = [[image_size.0, image_size.1], right_image_size.map_or([image_size.0, image_size.1], |s| [s.0, s.1])];
    let options = StereoOptions { zhang: request.options(), mode };
    let r = crate::pool::detach(py, || stereo_calibrate(&stereo_pairs, sizes, &options)).py()?;
    let d = PyDict::new(py);
    d.set_item("left", crate::zhang::result(py, &r.left)?)?;
    d.set_item("right", crate::zhang::result(py, &r.right)?)?;
    d.set_item("rotation_rodrigues", vec_out(py, &r.rotation_rodrigues))?;
    d.set_item("rotation_matrix", mat3_out(py, r.rotation_matrix()))?;
    d.set_item("translation_mm", vec_out(py, &r.translation_mm))?;
    d.set_item("covariance", matrix_out(py, &r.covariance))?;
    d.set_item("std", vec_out(py, &r.std()))?;
    d.set_item("rms_px", r.rms_px)?;
    d.set_item("per_view_rms_px", r.per_view_rms_px.iter().map(|p| p.to_vec()).collect::<Vec<_>>())?;
    d.set_item("pairs_used", r.pairs_used.clone())?;
    d.set_item("baseline_mm", r.baseline_mm())?;
    d.set_item("intrinsics", intrinsics)?;
    crate::results::make(py, "StereoResult", &d)
}
