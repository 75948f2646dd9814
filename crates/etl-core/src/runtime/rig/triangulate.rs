//! [`triangulate`]: a point from its pixels in K >= 2 cameras of a rig, by least squares
//! in pixels through each camera's full model, with the covariance the pixel noise gives.
//!
//! View k: the camera at its setting (`CameraAt`), its pose relative to camera 0 at these
//! settings (R_k, T_k: [`super::RigPose::at_settings`]; camera 0's is the identity) and
//! the observed pixel u_k. The point X, in camera 0's frame at its setting, minimises
//!
//! ```text
//! C(X) = sum_k |q_k(R_k X + T_k) - u_k|^2                                  (T1)
//! ```
//!
//! with q_k the camera's projection of a camera-frame point (Eq. 15, 17, distortion
//! included). The start is the midpoint of the rays: each pixel undistorted to its ray
//! (centre c_k = -R_k^T T_k, unit direction d_k = R_k^T (x_k, y_k, 1) / |.| in camera 0's
//! frame), and the point nearest to all of them in the least-squares sense,
//!
//! ```text
//! (sum_k (I - d_k d_k^T)) X = sum_k (I - d_k d_k^T) c_k                    (T2)
//! ```
//!
//! Then Gauss-Newton on (T1) with the analytic J_k = dq_k/dX_c R_k (2 x 3 per view),
//! halving a step that does not lower C. With independent pixel noise of sigma_px on each
//! coordinate, the point's covariance is (to first order)
//!
//! ```text
//! Cov(X) = sigma_px^2 (J^T J)^-1,   J^T J = sum_k J_k^T J_k                (T3)
//! ```
//!
//! Errors: fewer than 2 views ([`Error::TooFew`]); rays nearly parallel: the matrix of
//! (T2) or J^T J not certifiably positive definite ([`Error::Degenerate`], the point at
//! no finite depth); the point at or behind a camera ([`Error::BehindCamera`]); a
//! negative or non-finite sigma_px ([`Error::InvalidArgument`]); no convergence in
//! [`MAX_ITERATIONS`] ([`Error::NotConverged`]).

use super::pose::RigPose;
use crate::calib::jacobian::project_camera_point_jacobian;
use crate::error::{Error, Result};
use crate::linalg::cholesky::spd_inverse;
use crate::model::rotation::{mat_t_vec, Mat3};
use crate::runtime::CameraAt;

/// Gauss-Newton iterations at most.
pub const MAX_ITERATIONS: usize = 50;

/// The rank tolerance of the 3 x 3 inversions: rays closer to parallel than about 1e-6
/// rad (a 100 mm baseline at 100 km) are refused.
const RAYS_RANK_TOLERANCE: f64 = 1e-14;

/// One camera's observation of the point.
#[derive(Debug, Clone, Copy)]
pub struct TriangulationView<'a> {
    /// The camera at its setting.
    pub camera: &'a CameraAt,
    /// Its pose relative to camera 0 at these settings (camera 0: [`RigPose::IDENTITY`]).
    pub pose: RigPose,
    /// The observed (distorted) pixel, px.
    pub pixel: [f64; 2],
}

impl TriangulationView<'_> {
    /// The residual q(R X + T) - u of point `x0_mm` (camera 0's frame) and its derivative
    /// with respect to X (2 x 3, px / mm). Errors: X at or behind this camera.
    pub fn residual(&self, x0_mm: [f64; 3]) -> Result<([f64; 2], [[f64; 3]; 2])> {
        let (q, dq) =
            project_camera_point_jacobian(self.pose.apply(x0_mm), self.camera.intrinsics(), self.camera.distortion())?;
        let r = &self.pose.rotation;
        let j = dq.map(|row| core::array::from_fn(|c| (0..3).map(|k| row[k] * r[k][c]).sum()));
        Ok(([q[0] - self.pixel[0], q[1] - self.pixel[1]], j))
    }
}

/// A triangulated point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Triangulation {
    /// The point in camera 0's frame at its setting, mm.
    pub point_mm: [f64; 3],
    /// Its covariance from the pixel noise, sigma_px^2 (J^T J)^-1 (Eq. T3), mm^2.
    pub covariance_mm2: Mat3,
    /// (J^T J)^-1 at the point, mm^2 / px^2: what other error sources are propagated with.
    pub normal_inverse: Mat3,
    /// RMS reprojection distance over the views, px.
    pub rms_px: f64,
    /// Gauss-Newton iterations spent.
    pub iterations: usize,
}

/// The point seen by `views` (module docs: Eq. T1-T3), its covariance for a pixel noise
/// of `sigma_px` per coordinate.
pub fn triangulate(views: &[TriangulationView<'_>], sigma_px: f64) -> Result<Triangulation> {
    if views.len() < 2 {
        return Err(Error::TooFew { what: "cameras seeing the point", needed: 2, got: views.len() });
    }
    if !(sigma_px.is_finite() && sigma_px >= 0.0) {
        return Err(Error::InvalidArgument { what: "sigma_px must be finite and >= 0" });
    }
    let mut x = midpoint(views)?;
    let (mut cost, mut normal, mut gradient) = normal_equations(views, x)?;
    let mut iterations = 0;
    loop {
        let inverse = spd_inverse(&normal, RAYS_RANK_TOLERANCE)
            .ok_or(Error::Degenerate { what: "rays nearly parallel: the point is at no finite depth" })?;
        let step = core::array::from_fn::<f64, 3, _>(|i| -(0..3).map(|k| inverse[i][k] * gradient[k]).sum::<f64>());
        let size = libm::sqrt(step.iter().map(|s| s * s).sum::<f64>());
        let scale = 1.0 + libm::sqrt(x.iter().map(|s| s * s).sum::<f64>());
        let lower = if size <= 1e-12 * scale { None } else { descend(views, x, step, cost)? };
        let Some(next) = lower else {
            let n = views.len() as f64;
            let covariance_mm2 = inverse.map(|row| row.map(|v| v * sigma_px * sigma_px));
            let rms_px = libm::sqrt(cost / n);
            return Ok(Triangulation { point_mm: x, covariance_mm2, normal_inverse: inverse, rms_px, iterations });
        };
        if iterations == MAX_ITERATIONS {
            return Err(Error::NotConverged { what: "triangulation (Gauss-Newton)", iterations });
        }
        iterations += 1;
        (x, (cost, normal, gradient)) = next;
    }
}

/// The first of x + step, x + step / 2, ... (40 halvings at most) that lowers the cost,
/// with its normal equations; None when none does: x is the minimum to rounding.
fn descend(
    views: &[TriangulationView<'_>],
    x: [f64; 3],
    step: [f64; 3],
    cost: f64,
) -> Result<Option<([f64; 3], Normal)>> {
    let mut t = 1.0;
    for _ in 0..40 {
        let y = core::array::from_fn(|i| x[i] + t * step[i]);
        match normal_equations(views, y) {
            Ok(normal) if normal.0 < cost => return Ok(Some((y, normal))),
            Ok(_) | Err(Error::BehindCamera) => t *= 0.5,
            Err(e) => return Err(e),
        }
    }
    Ok(None)
}

/// C(X), J^T J and J^T r at a point.
type Normal = (f64, Mat3, [f64; 3]);

/// C(X), J^T J and J^T r at `x` (Eq. T1, T3).
fn normal_equations(views: &[TriangulationView<'_>], x: [f64; 3]) -> Result<Normal> {
    let (mut cost, mut normal, mut gradient) = (0.0, [[0.0; 3]; 3], [0.0; 3]);
    for v in views {
        let (r, j) = v.residual(x)?;
        cost += r[0] * r[0] + r[1] * r[1];
        for a in 0..3 {
            gradient[a] += j[0][a] * r[0] + j[1][a] * r[1];
            for b in 0..3 {
                normal[a][b] += j[0][a] * j[0][b] + j[1][a] * j[1][b];
            }
        }
    }
    Ok((cost, normal, gradient))
}

/// The midpoint of the views' rays (Eq. T2), checked to lie in front of every camera.
fn midpoint(views: &[TriangulationView<'_>]) -> Result<[f64; 3]> {
    let (mut a, mut b) = ([[0.0; 3]; 3], [0.0; 3]);
    for v in views {
        let d = mat_t_vec(&v.pose.rotation, v.camera.camera_ray(v.pixel)?);
        let c = v.pose.centre_mm();
        for i in 0..3 {
            for j in 0..3 {
                let p = if i == j { 1.0 } else { 0.0 } - d[i] * d[j];
                a[i][j] += p;
                b[i] += p * c[j];
            }
        }
    }
    let inverse = spd_inverse(&a, RAYS_RANK_TOLERANCE)
        .ok_or(Error::Degenerate { what: "rays nearly parallel: the point is at no finite depth" })?;
    let x: [f64; 3] = core::array::from_fn(|i| (0..3).map(|k| inverse[i][k] * b[k]).sum());
    if views.iter().any(|v| !(v.pose.apply(x)[2] > 0.0)) {
        return Err(Error::BehindCamera);
    }
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::CameraModel;
    use crate::runtime::{Camera, Trust};

    fn cameras() -> (CameraAt, CameraAt) {
        let paper = Camera::new(CameraModel::paper_rig(), None, [80.0, 225.0]).unwrap();
        let strong = Camera::new(CameraModel::strong_distortion_rig(), None, [80.0, 225.0]).unwrap();
        (paper.at_e_com(140.0, Trust::Refuse).unwrap(), strong.at_e_com(190.0, Trust::Refuse).unwrap())
    }

    /// Two different cameras (one per distortion family) and a third: noise-free pixels
    /// give the point back to 1e-6 mm; its covariance is sigma^2 (J^T J)^-1 at the point.
    #[test]
    fn noise_free_pixels_give_the_point_back() {
        let (a, b) = cameras();
        let poses = [
            RigPose::IDENTITY,
            RigPose::from_rodrigues([0.0, -0.06, 0.01], [-100.0, 1.0, 2.0]),
            RigPose::from_rodrigues([0.05, 0.02, 0.0], [3.0, -90.0, -4.0]),
        ];
        let cams = [&a, &b, &b];
        for x in [[15.0, -8.0, 600.0], [-120.0, 60.0, 1500.0], [0.0, 0.0, 250.0]] {
            let mut views = [TriangulationView { camera: &a, pose: RigPose::IDENTITY, pixel: [0.0; 2] }; 3];
            for k in 0..3 {
                let pixel = cams[k].project_camera_point(poses[k].apply(x)).unwrap();
                views[k] = TriangulationView { camera: cams[k], pose: poses[k], pixel };
            }
            for n in [2, 3] {
                let t = triangulate(&views[..n], 0.2).unwrap();
                assert!((0..3).all(|i| (t.point_mm[i] - x[i]).abs() < 1e-6), "{x:?}: {:?}", t.point_mm);
                assert!(t.rms_px < 1e-9);
                let (_, normal, _) = normal_equations(&views[..n], t.point_mm).unwrap();
                let inv = spd_inverse(&normal, 0.0).unwrap();
                for i in 0..3 {
                    for j in 0..3 {
                        assert!((t.covariance_mm2[i][j] - 0.04 * inv[i][j]).abs() <= 1e-9 * inv[i][i].abs());
                    }
                }
                // Depth is the worst-determined direction.
                assert!(t.covariance_mm2[2][2] > t.covariance_mm2[0][0]);
            }
        }
    }

    #[test]
    fn bad_inputs_are_named() {
        let (a, b) = cameras();
        let pose = RigPose::from_rodrigues([0.0, -0.06, 0.0], [-100.0, 0.0, 0.0]);
        let x = [10.0, 5.0, 700.0];
        let v0 = TriangulationView { camera: &a, pose: RigPose::IDENTITY, pixel: a.project_camera_point(x).unwrap() };
        let v1 = TriangulationView { camera: &b, pose, pixel: b.project_camera_point(pose.apply(x)).unwrap() };
        assert_eq!(triangulate(&[v0], 0.1), Err(Error::TooFew { what: "cameras seeing the point", needed: 2, got: 1 }));
        assert!(matches!(triangulate(&[v0, v1], f64::NAN), Err(Error::InvalidArgument { .. })));
        assert!(matches!(triangulate(&[v0, v1], -1.0), Err(Error::InvalidArgument { .. })));
        // The same camera twice at the same place: every ray is the same line.
        assert!(
            matches!(triangulate(&[v0, v0], 0.1), Err(Error::Degenerate { .. })),
            "{:?}",
            triangulate(&[v0, v0], 0.1)
        );
        // Rays that meet behind the cameras: camera 1's pixel of a point far to the left
        // of what camera 0 sees makes them diverge.
        let behind =
            TriangulationView { pixel: b.project_camera_point(pose.apply([900.0, 5.0, 700.0])).unwrap(), ..v1 };
        let shifted = TriangulationView { pixel: a.project_camera_point([-900.0, 5.0, 700.0]).unwrap(), ..v0 };
        assert_eq!(triangulate(&[shifted, behind], 0.1), Err(Error::BehindCamera));
    }
}
