//! The viewing ray of a pixel.

use super::projection::CameraModel;
use nalgebra::Vector3;

use super::rotation::to_matrix3;
use crate::error::{all_finite, Result};

/// A ray in world coordinates: the points `origin_mm + s * direction`, s > 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Centre of projection in world coordinates, mm: -R^T T.
    pub origin_mm: [f64; 3],
    /// Unit direction in world coordinates.
    pub direction: [f64; 3],
}

impl Ray {
    /// The point at distance `s_mm` from the origin along the ray.
    pub fn at(&self, s_mm: f64) -> [f64; 3] {
        [
            self.origin_mm[0] + s_mm * self.direction[0],
            self.origin_mm[1] + s_mm * self.direction[1],
            self.origin_mm[2] + s_mm * self.direction[2],
        ]
    }
}

impl CameraModel {
    /// The ray of world points that project to `pixel` at current `e_com_ma`.
    ///
    /// Undistorts the pixel (Eq. 17 inverted), back-projects through A(E) (Eq. 15) and
    /// rotates into the world frame. Errors as [`CameraModel::undistort`], and
    /// [`crate::Error::NotFinite`] when the pose holds NaN or overflows.
    pub fn ray(&self, pixel: [f64; 2], e_com_ma: f64) -> Result<Ray> {
        let k = self.intrinsics(e_com_ma)?;
        let [x, y] = self.undistort(pixel, e_com_ma)?;
        let dc = Vector3::new((x - k.u0) / k.fx, (y - k.v0) / k.fy, 1.0);
        // World = R^T (camera - T(E)): the direction R^T dc / |dc|, the origin -R^T T(E)
        // (Eq. C2: the centre where the lens puts it).
        let r = to_matrix3(&self.rotation_matrix());
        let dir: [f64; 3] = r.tr_mul(&(dc / dc.norm())).into();
        let o: [f64; 3] = r.tr_mul(&-Vector3::from(self.translation_at(e_com_ma))).into();
        // A NaN rotation or translation (or an overflow) must not come back as a ray.
        all_finite(&o, "ray origin (check rotation_rodrigues and translation_mm)")?;
        all_finite(&dir, "ray direction (check rotation_rodrigues)")?;
        Ok(Ray { origin_mm: o, direction: dir })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_along_the_ray_keep_their_pixel() {
        let cam = CameraModel::paper_rig();
        for &e in &[80.0, 150.0, 225.0] {
            let px = cam.project([4.5, 7.5, 31.0], e).unwrap();
            let ray = cam.ray(px, e).unwrap();
            for &s in &[10.0, 50.0, 80.0, 500.0] {
                let q = cam.project(ray.at(s), e).unwrap();
                assert!((q[0] - px[0]).abs() < 1e-7 && (q[1] - px[1]).abs() < 1e-7, "{q:?} {px:?}");
            }
        }
    }
}
