//! The projection difference of two calibrations at one lens setting (`etlcal diff`,
//! Python `etlcal.diff`), after mrcal's `mrcal-show-projection-diff`: how far apart, in
//! pixels, the two cameras put the same direction.
//!
//! Over a grid of pixels q_i covering the image (cell centres), each pixel is turned into
//! its viewing direction by camera A (undistorted, then through A's K: d_i = (x, y, 1) in
//! A's camera frame) and projected by camera B:
//!
//! ```text
//! intrinsics only:  e_i = |pi_B(d_i) - q_i|
//! best rotation:    e_i = |pi_B(R* d_i) - q_i|,  R* = argmin_R sum_i |pi_B(R d_i) - q_i|^2
//! ```
//!
//! The directions are taken at infinity: the two calibrations' frames are each camera's
//! own, and a rotation between them is all that a change of frame at infinity can do.
//! The first figure charges every difference to the intrinsics; the second forgives what
//! a rotation of the camera explains (a principal point and a small tilt trade against
//! each other), as mrcal's implied transformation does. A large gap between the two says
//! the calibrations disagree on where the camera points, a large best-rotation figure
//! that they disagree on its projection. Pixels that do not map through both models (a
//! direction behind B, an undistortion that does not converge) are counted apart.

use etl_core::model::projection::project_camera_point;
use etl_core::model::rotation::{mat_vec, rodrigues_to_matrix};
use etl_core::runtime::CameraAt;
use etl_formats::{Error, Result};

/// The grid of pixels compared by default: 64 x 48 cells.
pub const DEFAULT_GRID: [usize; 2] = [64, 48];

/// The largest grid side, cells.
pub const MAX_GRID_SIDE: usize = 1000;

/// The difference of two cameras over the image.
#[derive(Debug, Clone, PartialEq)]
pub struct ProjectionDiff {
    /// The grid, cells (columns, rows).
    pub grid: [usize; 2],
    /// RMS of the intrinsics-only differences, px.
    pub rms_px: f64,
    /// Their maximum, px.
    pub max_px: f64,
    /// RMS after the best rotation, px.
    pub rotated_rms_px: f64,
    /// Maximum after the best rotation, px.
    pub rotated_max_px: f64,
    /// The best rotation (Rodrigues, A's camera frame to B's), rad.
    pub rotation_rodrigues: [f64; 3],
    /// Each cell's intrinsics-only difference, row-major; NaN where a pixel did not map.
    pub diff_px: Vec<f64>,
    /// Each cell's difference after the best rotation, likewise.
    pub rotated_diff_px: Vec<f64>,
    /// Cells that did not map through both models (left out of every figure).
    pub unmapped: usize,
}

/// The directions of the grid's pixels through `a`, with the pixels (`None`: not mapped).
fn directions(a: &CameraAt, image_size: [u32; 2], grid: [usize; 2]) -> Vec<Option<([f64; 3], [f64; 2])>> {
    let k = *a.intrinsics();
    let [w, h] = image_size.map(f64::from);
    let mut out = Vec::with_capacity(grid[0] * grid[1]);
    for r in 0..grid[1] {
        for c in 0..grid[0] {
            let q = [(c as f64 + 0.5) * w / grid[0] as f64, (r as f64 + 0.5) * h / grid[1] as f64];
            let d = a.undistort_point(q).ok().map(|[x, y]| [(x - k.u0) / k.fx, (y - k.v0) / k.fy, 1.0]);
            out.push(d.map(|d| (d, q)));
        }
    }
    out
}

/// |pi_B(R d) - q| for each mapped direction (NaN where B cannot project it).
fn residuals(b: &CameraAt, rotation: [f64; 3], dirs: &[Option<([f64; 3], [f64; 2])>]) -> Vec<[f64; 2]> {
    let r = rodrigues_to_matrix(rotation);
    let (k, d) = (b.intrinsics(), b.distortion());
    dirs.iter()
        .map(|m| match m {
            Some((dir, q)) => match project_camera_point(mat_vec(&r, *dir), k, d) {
                Ok(p) => [p[0] - q[0], p[1] - q[1]],
                Err(_) => [f64::NAN; 2],
            },
            None => [f64::NAN; 2],
        })
        .collect()
}

/// Gauss-Newton on the three rotation numbers (central-difference Jacobian; the problem
/// is small and smooth), from the identity, over the cells that map at the identity.
fn best_rotation(b: &CameraAt, dirs: &[Option<([f64; 3], [f64; 2])>]) -> [f64; 3] {
    let mut om = [0.0; 3];
    let usable = |e: &[f64; 2]| e[0].is_finite() && e[1].is_finite();
    for _ in 0..20 {
        let e0 = residuals(b, om, dirs);
        let h = 1e-7;
        let cols: Vec<Vec<[f64; 2]>> = (0..3)
            .map(|j| {
                let (mut p, mut m) = (om, om);
                p[j] += h;
                m[j] -= h;
                let (ep, em) = (residuals(b, p, dirs), residuals(b, m, dirs));
                ep.iter().zip(&em).map(|(a, c)| [(a[0] - c[0]) / (2.0 * h), (a[1] - c[1]) / (2.0 * h)]).collect()
            })
            .collect();
        let (mut jtj, mut jte) = (nalgebra::Matrix3::<f64>::zeros(), nalgebra::Vector3::<f64>::zeros());
        for i in 0..e0.len() {
            let rows = [cols[0][i], cols[1][i], cols[2][i]];
            if !usable(&e0[i]) || !rows.iter().all(usable) {
                continue;
            }
            for axis in 0..2 {
                let g = nalgebra::Vector3::new(rows[0][axis], rows[1][axis], rows[2][axis]);
                jtj += g * g.transpose();
                jte += g * e0[i][axis];
            }
        }
        let Some(step) = jtj.lu().solve(&(-jte)) else { break };
        om = [om[0] + step[0], om[1] + step[1], om[2] + step[2]];
        if step.norm() < 1e-13 {
            break;
        }
    }
    om
}

/// RMS and maximum of the finite entries.
fn rms_max(v: &[f64]) -> (f64, f64) {
    let finite: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    let n = finite.len().max(1) as f64;
    let rms = (finite.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
    (rms, finite.iter().copied().fold(0.0, f64::max))
}

/// The projection difference of `b` against `a` over an image of `image_size` px on a
/// grid of `grid` cells (module doc). Errors: a grid side outside 1..=[`MAX_GRID_SIDE`];
/// an image size of zero; no cell that maps through both cameras.
pub fn projection_diff(a: &CameraAt, b: &CameraAt, image_size: [u32; 2], grid: [usize; 2]) -> Result<ProjectionDiff> {
    if grid.iter().any(|&g| !(1..=MAX_GRID_SIDE).contains(&g)) {
        return Err(Error::invalid_value(
            "grid",
            format!("{}x{}", grid[0], grid[1]),
            format!("grid {}x{}: each side must be 1..={MAX_GRID_SIDE} cells", grid[0], grid[1]),
        ));
    }
    etl_formats::check_image_size(image_size, "image_size")?;
    let dirs = directions(a, image_size, grid);
    let norm = |e: &[f64; 2]| (e[0] * e[0] + e[1] * e[1]).sqrt();
    let diff_px: Vec<f64> = residuals(b, [0.0; 3], &dirs).iter().map(norm).collect();
    let unmapped = diff_px.iter().filter(|x| !x.is_finite()).count();
    if unmapped == diff_px.len() {
        return Err(Error::invalid("grid", "no pixel of the image maps through both calibrations"));
    }
    let rotation_rodrigues = best_rotation(b, &dirs);
    let rotated_diff_px: Vec<f64> = residuals(b, rotation_rodrigues, &dirs).iter().map(norm).collect();
    let ((rms_px, max_px), (rotated_rms_px, rotated_max_px)) = (rms_max(&diff_px), rms_max(&rotated_diff_px));
    Ok(ProjectionDiff {
        grid,
        rms_px,
        max_px,
        rotated_rms_px,
        rotated_max_px,
        rotation_rodrigues,
        diff_px,
        rotated_diff_px,
        unmapped,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use etl_core::model::CameraModel;
    use etl_core::runtime::{Camera, Trust};

    fn at(model: CameraModel) -> CameraAt {
        Camera::new(model, None, [80.0, 225.0]).unwrap().at_e_com(150.0, Trust::Refuse).unwrap()
    }

    /// A camera against itself differs by nothing; a principal point moved by 3 px differs
    /// by 3 px everywhere before the rotation and by a small fraction after it (a rotation
    /// explains a shift up to the distortion's and the perspective's curvature).
    #[test]
    fn itself_is_zero_and_a_shifted_principal_point_is_its_shift() {
        let m = CameraModel::paper_rig();
        let size = CameraModel::PAPER_IMAGE_SIZE;
        let same = projection_diff(&at(m), &at(m), size, DEFAULT_GRID).unwrap();
        assert!(same.rms_px < 1e-9 && same.rotated_max_px < 1e-9 && same.unmapped == 0, "{same:?}");
        let mut shifted = m;
        shifted.principal_point[0] += 3.0;
        let d = projection_diff(&at(m), &at(shifted), size, [32, 24]).unwrap();
        assert!((d.rms_px - 3.0).abs() < 1e-6 && (d.max_px - 3.0).abs() < 1e-6, "{d:?}");
        assert!(d.rotated_rms_px < 0.1 * d.rms_px, "{d:?}");
        // The rotation is about y, by about 3 px / fx.
        let fx = m.kf_x.eval(150.0);
        assert!((d.rotation_rodrigues[1].abs() - 3.0 / fx).abs() < 0.1 * 3.0 / fx, "{:?}", d.rotation_rodrigues);
        assert_eq!(d.diff_px.len(), 32 * 24);
        // A focal length 0.1 % longer: no rotation explains a scale.
        let mut longer = m;
        longer.kf_x =
            etl_core::model::FocalPoly::new(&m.kf_x.coefficients().iter().map(|c| c * 1.001).collect::<Vec<_>>())
                .unwrap();
        let s = projection_diff(&at(m), &at(longer), size, [32, 24]).unwrap();
        assert!(s.rotated_max_px > 0.5 && s.rotated_rms_px <= s.rms_px + 1e-9, "{s:?}");
        assert!(projection_diff(&at(m), &at(m), size, [0, 24]).unwrap_err().to_string().contains("grid 0x24"));
    }
}
