//! The starting relative pose of a pair from the per-view poses of each camera.

use etl_core::model::rotation::{mat_vec, matrix_to_rodrigues, rodrigues_to_matrix};

/// The median of `v` (the mean of the two middle values for an even count; 0 when empty).
fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => 0.0,
        _ if n % 2 == 1 => v[n / 2],
        _ => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// The relative pose (Rodrigues om, translation T mm) from each pair's board poses in the
/// left and right cameras ((Rodrigues, translation mm) each, pair by pair), as
/// `cv2.stereoCalibrate` starts it: per pair
///
/// ```text
/// R_j = R_r,j R_l,j^T,   T_j = t_r,j - R_j t_l,j
/// ```
///
/// then the median of each of the 6 components of (om_j, T_j) over the pairs. The median
/// keeps one bad pose from moving the start; it assumes the pairs' rotation vectors lie
/// together (a relative rotation near 180 degrees, whose vectors flip, does not occur
/// between two cameras that see the same board). Zero when there are no pairs.
///
/// ```
/// use etl_calib::stereo::relative_pose_median;
/// // The right camera 100 mm along the left's x axis, not rotated: a point at x in the
/// // left frame is at x - 100 in the right's.
/// let left = [([0.1, -0.2, 0.05], [10.0, 5.0, 500.0]), ([0.0, 0.3, 0.0], [-20.0, 0.0, 600.0])];
/// let right: Vec<_> = left.iter().map(|&(om, t)| (om, [t[0] - 100.0, t[1], t[2]])).collect();
/// let rt = relative_pose_median(&left, &right);
/// assert!(rt[..3].iter().all(|v| v.abs() < 1e-12));
/// assert!((rt[3] + 100.0).abs() < 1e-9 && rt[4].abs() < 1e-9 && rt[5].abs() < 1e-9);
/// ```
pub fn relative_pose_median(left: &[([f64; 3], [f64; 3])], right: &[([f64; 3], [f64; 3])]) -> [f64; 6] {
    let poses = relative_poses(left, right);
    core::array::from_fn(|k| median(&mut poses.iter().map(|p| p[k]).collect::<Vec<_>>()))
}

/// Each pair's relative pose (om_j, T_j) from its board poses in the left and right
/// cameras: R_j = R_r,j R_l,j^T, T_j = t_r,j - R_j t_l,j.
pub(super) fn relative_poses(left: &[([f64; 3], [f64; 3])], right: &[([f64; 3], [f64; 3])]) -> Vec<[f64; 6]> {
    left.iter()
        .zip(right)
        .map(|((oml, tl), (omr, tr))| {
            let (rl, rr) = (rodrigues_to_matrix(*oml), rodrigues_to_matrix(*omr));
            let r: [[f64; 3]; 3] =
                core::array::from_fn(|i| core::array::from_fn(|j| (0..3).map(|k| rr[i][k] * rl[j][k]).sum()));
            let om = matrix_to_rodrigues(&r);
            let rt = mat_vec(&r, *tl);
            [om[0], om[1], om[2], tr[0] - rt[0], tr[1] - rt[1], tr[2] - rt[2]]
        })
        .collect()
}

/// The angle between two rotations given as Rodrigues vectors, rad: |log(R(a) R(b)^T)|.
pub(super) fn rotation_angle_between(a: [f64; 3], b: [f64; 3]) -> f64 {
    let (ra, rb) = (rodrigues_to_matrix(a), rodrigues_to_matrix(b));
    let r: [[f64; 3]; 3] =
        core::array::from_fn(|i| core::array::from_fn(|j| (0..3).map(|k| ra[i][k] * rb[j][k]).sum()));
    let om = matrix_to_rodrigues(&r);
    (om[0] * om[0] + om[1] * om[1] + om[2] * om[2]).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_even_and_empty() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median(&mut []), 0.0);
    }
}
