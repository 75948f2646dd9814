//! The start of each free view's board pose, by relative PnP: the camera of the view with
//! the most points finds the board's pose in its own frame at its setting, (R_p, t_p),
//! with its own calibration ([`etl_core::pnp::solve_pnp`]); its pose to the world, x =
//! R_k w + t_k, carries it into the world:
//!
//! ```text
//! R_b = R_k' R_p,   t_b = R_k' (t_p - t_k)        (w = R_b X + t_b)
//! ```
//!
//! Both poses are in the model's convention: a moving centre shifts the camera frame at E
//! by -dz(E) e_z after either (Eq. C2), so the shift cancels and t_k is the pose's own
//! translation, not T(E).

use etl_core::model::rotation::{mat_t_vec, matrix_to_rodrigues, rodrigues_to_matrix, Mat3};
use etl_core::pnp::solve_pnp;
use etl_formats::{Error, Result};

use super::cameras::JointCamera;
use super::normal::FREE_POSE_LEN;

/// The starting pose (om_b, t_b), board to world, of each of the `free_views` free views
/// (rig views `stage_views..`). Errors: a free view no camera kept, or whose best camera's
/// points give no pose (fewer than 4, on one line), naming it.
pub(super) fn free_view_starts(
    cameras: &[JointCamera],
    stage_views: usize,
    free_views: usize,
) -> Result<Vec<[f64; FREE_POSE_LEN]>> {
    (0..free_views)
        .map(|f| {
            let j = stage_views + f;
            let seen =
                cameras.iter().enumerate().filter_map(|(k, c)| c.views.iter().find(|v| v.view == j).map(|v| (k, c, v)));
            let Some((k, cam, view)) = seen.max_by_key(|(_, _, v)| v.points.len()) else {
                return Err(Error::invalid(format!("free_views[{f}]"), format!("free_views[{f}]: no camera saw it")));
            };
            let board: Vec<[f64; 3]> = view.points.iter().map(|p| p.world_mm).collect();
            let pixels: Vec<[f64; 2]> = view.points.iter().map(|p| p.pixel).collect();
            let pose = solve_pnp(&cam.start, view.e, &board, &pixels).map_err(|e| {
                let message =
                    format!("free_views[{f}]: the board's pose cannot be found from camera {k}'s points ({e})");
                Error::invalid(format!("free_views[{f}]"), message)
            })?;
            let r_k = rodrigues_to_matrix(cam.start.rotation_rodrigues);
            let r_p = rodrigues_to_matrix(pose.rotation_rodrigues);
            let r_b: Mat3 =
                core::array::from_fn(|i| core::array::from_fn(|c| (0..3).map(|m| r_k[m][i] * r_p[m][c]).sum()));
            let t_k = cam.start.translation_mm;
            let t_b = mat_t_vec(&r_k, core::array::from_fn(|i| pose.translation_mm[i] - t_k[i]));
            let om_b = matrix_to_rodrigues(&r_b);
            Ok([om_b[0], om_b[1], om_b[2], t_b[0], t_b[1], t_b[2]])
        })
        .collect()
}
