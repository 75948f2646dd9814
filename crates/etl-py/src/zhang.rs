//! `zhang(views, image_size, model="paper", fix_k3=False, zero_tangent=False)`: Zhang's
//! monofocal calibration of a fixed-focus camera, e.g. the lens-off views that give A0, or
//! any camera in OpenCV's model. The keywords only parse into etl-calib's `ZhangRequest`,
//! as `etlcal zhang --model --fix-k3 --zero-tangent` does.

use etl_calib::request::ZhangRequest;
use etl_calib::zhang::{PlanarView, ZhangResult, ZhangUncertainty};
use etl_core::model::DistortionModel;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{mat3_out, points, points_out, vec_out};
use crate::errors::{invalid, invalid_value, CoreResultExt};
use crate::pipeline::Keywords;

/// The request of `model`, `fix_k3`, `zero_tangent` (an unknown model refused naming it).
pub(crate) fn request(model: &str, fix_k3: bool, zero_tangent: bool) -> PyResult<ZhangRequest> {
    let model = DistortionModel::from_name(model).ok_or_else(|| {
        invalid_value("model", model, format!("model must be \"paper\" or \"opencv\", got {model:?}"))
    })?;
    Ok(ZhangRequest { model, fix_k3, zero_tangent })
}

/// The (board_mm, pixels) pairs as planar views.
pub(crate) fn planar_views(views: &[(Bound<'_, PyAny>, Bound<'_, PyAny>)]) -> PyResult<Vec<PlanarView>> {
    let mut planar = Vec::with_capacity(views.len());
    for (k, (board, pixels)) in views.iter().enumerate() {
        let board_mm: Vec<[f64; 2]> = match crate::arrays::points::<2>(board, "board_mm") {
            Ok(p) => p.points,
            Err(_) => crate::arrays::points::<3>(board, &format!("views[{k}] board_mm"))?
                .points
                .into_iter()
                .map(|p| [p[0], p[1]])
                .collect(),
        };
        let pixels = crate::arrays::points::<2>(pixels, &format!("views[{k}] pixels"))?.points;
        if board_mm.len() != pixels.len() {
            return Err(invalid(
                &format!("views[{k}]"),
                format!("views[{k}]: {} board points but {} pixels", board_mm.len(), pixels.len()),
            ));
        }
        planar.push(PlanarView { board_mm, pixels });
    }
    Ok(planar)
}

/// Zhang's monofocal calibration of a fixed-focus camera from views of a planar board:
/// homographies, the closed form, then Levenberg-Marquardt over the intrinsics, the
/// distortion and every view's pose. Gives A0 from lens-off views. The keywords are those
/// of `etlcal zhang` (`--model`, `--fix-k3`, `--zero-tangent`): the same request gives the
/// same result through both.
///
/// Args:
///     views: a list of (board_mm, pixels) pairs: (N, 2) board coordinates, mm (or (N, 3)
///         with Z = 0), and the (N, 2) detected pixels, px (e.g. `detect_corners`).
///     image_size: (width, height), px.
///     model: "paper" (the paper's distortion k1, p1, p2 in centred pixels) or "opencv"
///         (OpenCV's k1, k2, p1, p2, k3 in normalised coordinates: the model and the
///         least-squares problem of cv2.calibrateCamera).
///     fix_k3: hold k3 = 0 (cv2.CALIB_FIX_K3); "opencv" only.
///     zero_tangent: hold p1 = p2 = 0 (cv2.CALIB_ZERO_TANGENT_DIST); "opencv" only.
///
/// Returns: "paper": a ZhangResult (attributes, also dict keys): "fx", "fy", "u0", "v0"
/// (px), "k1" (1/px^2), "p1", "p2" (1/px), "std" (one standard deviation of those seven,
/// same order), "rms_px", "iterations", "views_used", "poses" (list of (rodrigues,
/// translation_mm)). "opencv": a ZhangOpenCvResult, the same keys (k1, p1, p2 OpenCV's,
/// dimensionless) and "k2", "k3", "camera_matrix" (3 x 3), "dist_coeffs" ([k1, k2, p1, p2,
/// k3], cv2's order), "per_view_rms_px", "model"; "std" of fx, fy, u0, v0, k1, k2, p1, p2,
/// k3 as cv2.calibrateCameraExtended's stdDeviationsIntrinsics (0 for a held one).
///
/// Raises: InputError naming the unmet precondition (at least 3 views, 4 points each,
/// views not all parallel) or the flag given with model="paper".
#[pyfunction]
#[pyo3(signature = (views, image_size, model="paper", fix_k3=false, zero_tangent=false))]
pub fn zhang<'py>(
    py: Python<'py>,
    views: Vec<(Bound<'py, PyAny>, Bound<'py, PyAny>)>,
    image_size: (u32, u32),
    model: &str,
    fix_k3: bool,
    zero_tangent: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let request = request(model, fix_k3, zero_tangent)?;
    request.validate(&Keywords).py()?;
    let planar = planar_views(&views)?;
    let r = crate::pool::detach(py, || request.run(&planar, [image_size.0, image_size.1], &Keywords)).py()?;
    result(py, &r)
}

/// The result object of `r` (ZhangResult, or ZhangOpenCvResult for the opencv family).
pub(crate) fn result<'py>(py: Python<'py>, r: &ZhangResult) -> PyResult<Bound<'py, PyAny>> {
    let d = PyDict::new(py);
    let c = r.coefficients;
    let (k1, p1, p2) = match r.options.model {
        DistortionModel::Paper => (c[0], c[1], c[2]),
        DistortionModel::OpenCv => (c[0], c[2], c[3]),
    };
    for (name, v) in [("fx", r.fx), ("fy", r.fy), ("u0", r.u0), ("v0", r.v0), ("k1", k1), ("p1", p1), ("p2", p2)] {
        d.set_item(name, v)?;
    }
    d.set_item("std", r.std.clone())?;
    d.set_item("rms_px", r.rms_px)?;
    d.set_item("iterations", r.iterations)?;
    d.set_item("views_used", r.views_used)?;
    d.set_item("poses", r.poses.iter().map(|(om, t)| (om.to_vec(), t.to_vec())).collect::<Vec<_>>())?;
    let Some(dist) = r.dist_coeffs() else {
        return with_projection(py, crate::results::make(py, "ZhangResult", &d)?, r);
    };
    d.set_item("model", r.options.model.name())?;
    d.set_item("k2", dist[1])?;
    d.set_item("k3", dist[4])?;
    d.set_item("camera_matrix", mat3_out(py, r.camera_matrix()))?;
    d.set_item("dist_coeffs", vec_out(py, &dist))?;
    d.set_item("per_view_rms_px", r.per_view_rms_px.clone())?;
    with_projection(py, crate::results::make(py, "ZhangOpenCvResult", &d)?, r)
}

/// `obj` (a frozen result) with the Rust result behind its `projection_std`.
fn with_projection<'py>(py: Python<'py>, obj: Bound<'py, PyAny>, r: &ZhangResult) -> PyResult<Bound<'py, PyAny>> {
    let Some(inner) = r.uncertainty.clone() else { return Ok(obj) };
    let handle = Bound::new(py, ZhangProjection { inner })?;
    py.import("builtins")?.getattr("object")?.call_method1("__setattr__", (&obj, "_projection", handle))?;
    Ok(obj)
}

/// What `ZhangResult.projection_std` asks: the camera, poses and blocks of J^T J of the
/// Rust result it came from (private; the result object holds it, and pickles it as JSON).
#[pyclass(frozen, module = "etlcal", name = "_ZhangProjection")]
pub struct ZhangProjection {
    inner: ZhangUncertainty,
}

#[pymethods]
impl ZhangProjection {
    /// `ZhangResult.projection_std` (see there): the standard deviations of u and v, px,
    /// of the re-projection of the point seen at each pixel at `distance_mm` along its ray
    /// (None: the direction, a point at infinity); (N, 2), or (2,) for one pixel.
    #[pyo3(signature = (pixels, distance_mm=None))]
    fn projection_std<'py>(
        &self,
        py: Python<'py>,
        pixels: &Bound<'py, PyAny>,
        distance_mm: Option<f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let p = points::<2>(pixels, "pixels")?;
        let out = crate::pool::detach(py, || {
            p.points
                .iter()
                .map(|q| self.inner.projection_std(*q, distance_mm).map(|u| u.std_px))
                .collect::<etl_calib::Result<Vec<[f64; 2]>>>()
        })
        .py()?;
        points_out(py, out, p.single)
    }

    /// Rebuilds a pickled handle from its JSON (checked: lengths and finite numbers).
    #[staticmethod]
    fn _from_json(text: &str) -> PyResult<Self> {
        let inner: ZhangUncertainty =
            serde_json::from_str(text).map_err(|e| invalid("uncertainty", format!("not a Zhang uncertainty: {e}")))?;
        inner.validate().py()?;
        Ok(ZhangProjection { inner })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        crate::errors::guarded("_ZhangProjection.__reduce__", || {
            let text = serde_json::to_string(&slf.get().inner).map_err(|e| invalid("uncertainty", e.to_string()))?;
            Ok((slf.py().get_type::<ZhangProjection>().getattr("_from_json")?, (text,)))
        })
    }
}
