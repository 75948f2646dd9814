//! `zhang(views, image_size)`: Zhang's monofocal calibration of a fixed-focus camera
//! (etl-calib's `zhang`), e.g. the lens-off views that give A0.

use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{invalid, CoreResultExt};

/// Zhang's monofocal calibration of a fixed-focus camera from views of a planar board:
/// homographies, the closed form, then Levenberg-Marquardt over the intrinsics, the paper's
/// distortion (k1, p1, p2) and every view's pose. Gives A0 from lens-off views.
///
/// Args:
///     views: a list of (board_mm, pixels) pairs: (N, 2) board coordinates, mm (or (N, 3)
///         with Z = 0), and the (N, 2) detected pixels, px (e.g. `detect_corners`).
///     image_size: (width, height), px.
///
/// Returns: a ZhangResult (attributes, also dict keys): "fx", "fy", "u0", "v0" (px), "k1" (1/px^2), "p1", "p2" (1/px),
/// "std" (one standard deviation of those seven, same order), "rms_px", "iterations",
/// "views_used", "poses" (list of (rodrigues, translation_mm)).
///
/// Raises: InputError naming the unmet precondition (at least 3 views, 4 points each,
/// views not all parallel).
#[pyfunction]
pub fn zhang<'py>(
    py: Python<'py>,
    views: Vec<(Bound<'py, PyAny>, Bound<'py, PyAny>)>,
    image_size: (u32, u32),
) -> PyResult<Bound<'py, PyAny>> {
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
        planar.push(etl_calib::zhang::PlanarView { board_mm, pixels });
    }
    let r = py.detach(|| etl_calib::zhang::zhang(&planar, [image_size.0, image_size.1])).py()?;
    let d = PyDict::new(py);
    for (name, v) in [("fx", r.fx), ("fy", r.fy), ("u0", r.u0), ("v0", r.v0), ("k1", r.k1), ("p1", r.p1), ("p2", r.p2)]
    {
        d.set_item(name, v)?;
    }
    d.set_item("std", r.std.to_vec())?;
    d.set_item("rms_px", r.rms_px)?;
    d.set_item("iterations", r.iterations)?;
    d.set_item("views_used", r.views_used)?;
    d.set_item("poses", r.poses.iter().map(|(om, t)| (om.to_vec(), t.to_vec())).collect::<Vec<_>>())?;
    crate::results::make(py, "ZhangResult", &d)
}
