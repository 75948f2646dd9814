//! Each view's own focal lengths, for the report's fx(E), fy(E) plot (the points around
//! the curve): fx, fy refitted to one view's points with R, T, the principal point and
//! the distortion of the calibration held.

use etl_core::calib::jacobian::Projector;
use etl_core::calib::params::{R_FX, R_FY};
use etl_core::calib::View;
use etl_core::lm::{solve, Options, Problem, RowSink};
use etl_core::model::{CameraModel, FocalPoly};

use etl_formats::Result;

struct OneView<'a> {
    model: CameraModel,
    view: &'a View<'a>,
    dz_mm: f64,
}

impl OneView<'_> {
    fn at(&self, x: &[f64; 2]) -> CameraModel {
        // A constant cubic: the current no longer matters, the distortion's w = 1 / f_mean
        // follows the view's own focal lengths.
        CameraModel {
            kf_x: FocalPoly::cubic([x[0], 0.0, 0.0, 0.0]),
            kf_y: FocalPoly::cubic([x[1], 0.0, 0.0, 0.0]),
            ..self.model
        }
    }
}

impl Problem<2> for OneView<'_> {
    fn eval(&mut self, x: &[f64; 2], jacobian: bool, sink: &mut dyn RowSink<2>) -> etl_core::Result<()> {
        let proj = Projector::new(&self.at(x));
        for p in self.view.points {
            let w = [p.world_mm[0], p.world_mm[1], p.world_mm[2] + self.dz_mm];
            // With a constant cubic, d pixel / d kf0x is the per-view d pixel / d fx (the
            // chain's only entry in that column is 1), so the 13 per-view derivatives
            // suffice: the same numbers as the full 25-number Jacobian at a fifth of the cost.
            let q = proj.project_reduced(w, self.view.e_com_ma, jacobian)?;
            for row in 0..2 {
                sink.push(q.pixel[row] - p.pixel[row], &[q.d_reduced[row][R_FX], q.d_reduced[row][R_FY]]);
            }
        }
        Ok(())
    }
}

/// The focal lengths (fx, fy) that fit `view` best with every other number of `model`
/// held, the view's stage position corrected by `dz_mm` (errors-in-variables; else 0).
///
/// Errors: those of the LM (e.g. a point behind the camera).
pub fn view_focal(model: &CameraModel, view: &View<'_>, dz_mm: f64) -> Result<(f64, f64)> {
    let start = model.focal_lengths(view.e_com_ma);
    let mut p = OneView { model: *model, view, dz_mm };
    let r = solve(&mut p, [start.0, start.1], &Options::default())?;
    Ok((r.x[0], r.x[1]))
}
