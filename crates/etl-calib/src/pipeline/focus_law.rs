//! The focus law of a calibration ([`FocusLaw`]): each ETL view is in focus at its current
//! and board plane by the way the data are taken (the board is moved until it is sharp, or
//! the lens is focused on it), so the views are samples of the law.

use etl_core::calib::View;
use etl_core::focus::{FocusLaw, FocusSample};
use etl_core::model::CameraModel;

/// The focus sample of each view under the calibrated `model`: its recorded E_com and the
/// depth in the camera frame of the centroid of its corners, i.e. the distance along the
/// optical axis from the camera's centre to the plane square to the axis through the middle
/// of what the view saw (a view is focused on the board as the image shows it, balanced
/// about its middle).
///
/// The recorded currents and stage positions are used as they are, not the
/// errors-in-variables corrections: the law maps what a caller commands to what is sharp,
/// and a run-time command has the same per-setting errors the corrections estimate. Views
/// without points are skipped.
pub fn focus_samples(model: &CameraModel, views: &[View<'_>]) -> Vec<FocusSample> {
    views
        .iter()
        .filter(|v| !v.points.is_empty())
        .map(|v| {
            let n = v.points.len() as f64;
            let mut c = [0.0; 3];
            for p in v.points {
                for (ci, wi) in c.iter_mut().zip(p.world_mm) {
                    *ci += wi / n;
                }
            }
            FocusSample { e_com_ma: v.e_com_ma, distance_mm: model.world_to_camera_at(c, v.e_com_ma)[2] }
        })
        .collect()
}

/// The focus law of `views` under `model`, or why there is none (one line: e.g. too few
/// distinct currents), which the calibration reports instead of leaving it out silently.
pub fn fit_focus_law(model: &CameraModel, views: &[View<'_>]) -> Result<FocusLaw, String> {
    FocusLaw::fit(&focus_samples(model, views)).map_err(|e| format!("no focus law: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use etl_core::calib::Point;

    #[test]
    fn samples_are_corner_centroid_depths_and_too_few_currents_are_said() {
        let model = CameraModel::paper_rig();
        let pts: Vec<Vec<Point>> = (0..4)
            .map(|k| {
                let z = 10.0 * k as f64;
                [[0.0, 0.0], [3.0, 0.0], [0.0, 6.0], [3.0, 6.0]]
                    .iter()
                    .map(|&[x, y]| Point { world_mm: [x, y, z], pixel: [0.0, 0.0] })
                    .collect()
            })
            .collect();
        let views: Vec<View<'_>> =
            pts.iter().enumerate().map(|(k, p)| View { e_com_ma: 200.0 - 30.0 * k as f64, points: p }).collect();
        let s = focus_samples(&model, &views);
        assert_eq!(s.len(), 4);
        for (k, x) in s.iter().enumerate() {
            let want = model.world_to_camera([1.5, 3.0, 10.0 * k as f64])[2];
            assert!((x.distance_mm - want).abs() < 1e-12 && x.e_com_ma == views[k].e_com_ma);
        }
        assert!(fit_focus_law(&model, &views).is_ok());
        let why = fit_focus_law(&model, &views[..3]).unwrap_err();
        assert!(why.starts_with("no focus law: too few calibration views at distinct currents"), "{why}");
        assert_eq!(why.lines().count(), 1);
    }
}
