//! Rotations as Rodrigues vectors (axis * angle, radians) and 3 x 3 matrices.
//!
//! The public API keeps plain arrays (row-major `[[f64; 3]; 3]`, `[f64; 3]`); the
//! arithmetic is nalgebra's fixed-size `Matrix3` / `Vector3` (no_std, no heap). Three
//! pieces stay hand-written (docs/PERFORMANCE-HISTORY.md, "nalgebra and faer"):
//! [`rodrigues_to_matrix`] (nalgebra's `Rotation3` moves the golden outputs),
//! [`matrix_to_rodrigues`] (nalgebra's `Rotation3::scaled_axis` takes the angle from
//! `acos`, losing half the digits near 0) and the SVD inside
//! [`nearest_rotation`] (nalgebra's SVD keeps panic paths the no-panic gate rejects).

use nalgebra::{Matrix3, Vector3};

use crate::linalg::svd::Svd;

/// A row-major 3 x 3 matrix: `m[row][col]`.
pub type Mat3 = [[f64; 3]; 3];

/// The nalgebra matrix of the row-major array `m` (nalgebra stores columns).
#[inline]
pub fn to_matrix3(m: &Mat3) -> Matrix3<f64> {
    let [r0, r1, r2] = *m;
    Matrix3::new(r0[0], r0[1], r0[2], r1[0], r1[1], r1[2], r2[0], r2[1], r2[2])
}

/// The row-major array of the nalgebra matrix `m` (the inverse of [`to_matrix3`]).
#[inline]
pub fn from_matrix3(m: &Matrix3<f64>) -> Mat3 {
    // `Into<[[f64; 3]; 3]>` gives the columns; the columns of m^T are the rows of m.
    m.transpose().into()
}

/// Rotation matrix of the Rodrigues vector `om` (axis times angle in radians).
///
/// `R = I + sin(t)/t [om]x + (1 - cos(t))/t^2 [om]x^2`, `t = |om|`; for t below 1e-8 the
/// series `I + [om]x + [om]x^2 / 2` is used (exact to double precision there).
///
/// Hand-written, not nalgebra's `Rotation3::from_scaled_axis` (which normalises the axis
/// first): that changes the last bits of R, and the PnP refinement of `etlcal demo`
/// amplifies them beyond the golden test's 1e-12 (docs/PERFORMANCE-HISTORY.md).
pub fn rodrigues_to_matrix(om: [f64; 3]) -> Mat3 {
    let t2 = om[0] * om[0] + om[1] * om[1] + om[2] * om[2];
    let t = libm::sqrt(t2);
    let (a, b) =
        if t < 1e-8 { (1.0 - t2 / 6.0, 0.5 - t2 / 24.0) } else { (libm::sin(t) / t, (1.0 - libm::cos(t)) / t2) };
    let [x, y, z] = om;
    // [om]x^2 = om om^T - t^2 I
    [
        [1.0 + b * (x * x - t2), -a * z + b * x * y, a * y + b * x * z],
        [a * z + b * x * y, 1.0 + b * (y * y - t2), -a * x + b * y * z],
        [-a * y + b * x * z, a * x + b * y * z, 1.0 + b * (z * z - t2)],
    ]
}

/// Rodrigues vector of a rotation matrix (the inverse of [`rodrigues_to_matrix`]).
///
/// Precondition: `r` is orthonormal with determinant +1 (not checked: a non-rotation gives
/// the Rodrigues vector of a nearby rotation). Angles near pi are handled through the
/// symmetric part of R, so the result is accurate over [0, pi].
pub fn matrix_to_rodrigues(r: &Mat3) -> [f64; 3] {
    let tr = r[0][0] + r[1][1] + r[2][2];
    let cos_t = ((tr - 1.0) * 0.5).clamp(-1.0, 1.0);
    // 2 sin(t) * axis
    let v = [r[2][1] - r[1][2], r[0][2] - r[2][0], r[1][0] - r[0][1]];
    let sin2 = libm::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    let t = libm::atan2(sin2 * 0.5, cos_t);
    if t < 1e-8 {
        return [v[0] * 0.5, v[1] * 0.5, v[2] * 0.5];
    }
    if cos_t > -0.9 {
        let k = t / sin2;
        return [v[0] * k, v[1] * k, v[2] * k];
    }
    // Near pi: the symmetric part of R is cos(t) I + (1 - cos(t)) a a^T; read the axis a
    // from the largest diagonal of a a^T (its sign from the antisymmetric part below).
    let c1 = 1.0 - cos_t;
    let s01 = (r[0][1] + r[1][0]) * 0.5 / c1;
    let s02 = (r[0][2] + r[2][0]) * 0.5 / c1;
    let s12 = (r[1][2] + r[2][1]) * 0.5 / c1;
    let b =
        [[(r[0][0] - cos_t) / c1, s01, s02], [s01, (r[1][1] - cos_t) / c1, s12], [s02, s12, (r[2][2] - cos_t) / c1]];
    let mut i = 0;
    if b[1][1] > b[i][i] {
        i = 1;
    }
    if b[2][2] > b[i][i] {
        i = 2;
    }
    let col = b[i];
    let n = libm::sqrt(col[0] * col[0] + col[1] * col[1] + col[2] * col[2]);
    if n == 0.0 {
        return [0.0; 3];
    }
    let mut axis = [col[0] / n, col[1] / n, col[2] / n];
    // Choose the sign that agrees with the antisymmetric part (meaningful when t < pi).
    if axis[0] * v[0] + axis[1] * v[1] + axis[2] * v[2] < 0.0 {
        axis = [-axis[0], -axis[1], -axis[2]];
    }
    [axis[0] * t, axis[1] * t, axis[2] * t]
}

/// The rotation nearest to `m` in the Frobenius norm (the orthogonal polar factor):
/// R = U D V^T from m = U S V^T, D = diag(1, 1, det(U V^T)) on the smallest singular
/// value, so that det R = +1. The SVD is etl-core's one-sided Jacobi ([`Svd`]): nalgebra's
/// SVD has panic paths the no-panic gate rejects (docs/PERFORMANCE-HISTORY.md); the products are
/// nalgebra's.
///
/// Precondition: `m` finite (a non-finite `m` gives a non-finite matrix, which callers'
/// finiteness checks report).
pub fn nearest_rotation(m: &Mat3) -> Mat3 {
    let svd = Svd::of_rows(m);
    // `Svd` stores the singular vectors as arrays of columns, as nalgebra reads them.
    let (u, v) = (Matrix3::from(svd.u), Matrix3::from(svd.v));
    let r = u * v.transpose();
    if r.determinant() >= 0.0 {
        return from_matrix3(&r);
    }
    // Flip the direction of the smallest singular value (the first one on a tie):
    // R = U V^T - 2 u_k v_k^T.
    let k_min = Vector3::from(svd.s).imin();
    let (Some(&u_k), Some(&v_k)) = (svd.u.get(k_min), svd.v.get(k_min)) else { return from_matrix3(&r) };
    from_matrix3(&(r - Vector3::from(u_k) * 2.0 * Vector3::from(v_k).transpose()))
}

/// The rotation nearest to the matrix with columns `r1`, `r2`, `r1 x r2` (see
/// [`nearest_rotation`]): the rotation of a plane's pose whose first two columns a
/// homography gives (Zhang 2000, section 3.1).
pub fn rotation_from_two_columns(r1: [f64; 3], r2: [f64; 3]) -> Mat3 {
    let (a, b) = (Vector3::from(r1), Vector3::from(r2));
    // `From<[[f64; 3]; 3]>` reads columns (and, unlike `from_columns`, has no length check).
    nearest_rotation(&from_matrix3(&Matrix3::from([r1, r2, a.cross(&b).into()])))
}

/// `m * x`.
#[inline]
pub fn mat_vec(m: &Mat3, x: [f64; 3]) -> [f64; 3] {
    (to_matrix3(m) * Vector3::from(x)).into()
}

/// `m^T * x`.
#[inline]
pub fn mat_t_vec(m: &Mat3, x: [f64; 3]) -> [f64; 3] {
    to_matrix3(m).tr_mul(&Vector3::from(x)).into()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &Mat3, b: &Mat3, tol: f64) -> bool {
        (0..3).all(|i| (0..3).all(|j| (a[i][j] - b[i][j]).abs() < tol))
    }

    #[test]
    fn round_trip_over_angles_including_pi() {
        for &om in &[
            [0.2, 0.2, 0.2],
            [0.0, 0.0, 0.0],
            [1e-10, -2e-10, 0.0],
            [3.0, 0.1, -0.2],
            [0.0, core::f64::consts::PI, 0.0],
            [-2.0, 1.5, 0.7],
        ] {
            let r = rodrigues_to_matrix(om);
            let back = matrix_to_rodrigues(&r);
            assert!(close(&rodrigues_to_matrix(back), &r, 1e-12), "{om:?} -> {back:?}");
        }
    }

    #[test]
    fn ninety_degrees_about_z() {
        let r = rodrigues_to_matrix([0.0, 0.0, core::f64::consts::FRAC_PI_2]);
        let x = mat_vec(&r, [1.0, 0.0, 0.0]);
        assert!((x[0]).abs() < 1e-15 && (x[1] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn rodrigues_matches_the_series_of_the_matrix_exponential() {
        // R = exp([om]x) = sum_k [om]x^k / k!, summed to convergence (|om| <= 2.5).
        for &om in &[[0.2, 0.2, 0.2], [1e-9, 3e-9, -2e-9], [1.3, -0.4, 2.0], [0.0, 0.0, 0.0]] {
            let [x, y, z] = om;
            let k = [[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]];
            let (mut term, mut sum) = ([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], [[0.0; 3]; 3]);
            for n in 1..60 {
                for i in 0..3 {
                    for j in 0..3 {
                        sum[i][j] += term[i][j];
                    }
                }
                term = core::array::from_fn(|i| {
                    core::array::from_fn(|j| (0..3).map(|l| term[i][l] * k[l][j]).sum::<f64>() / n as f64)
                });
            }
            assert!(close(&rodrigues_to_matrix(om), &sum, 1e-15), "{om:?}");
        }
    }

    #[test]
    fn mat_vec_and_its_transpose_against_sums() {
        let m = [[1.0, 2.0, 3.0], [-4.0, 5.0, 0.5], [7.0, -8.0, 9.0]];
        assert_eq!(mat_vec(&m, [1.0, -1.0, 2.0]), [5.0, -8.0, 33.0]);
        assert_eq!(mat_t_vec(&m, [1.0, -1.0, 2.0]), [19.0, -19.0, 20.5]);
        assert_eq!(from_matrix3(&to_matrix3(&m)), m);
    }

    /// The polar factor of `m` by nalgebra's SVD, an independent reference (not the
    /// library's: nalgebra's SVD keeps panic paths): U diag(1, 1, det(U V^T)) V^T with the
    /// sign on the smallest singular value's direction.
    fn svd_nearest_rotation(m: &Mat3) -> Mat3 {
        let svd = to_matrix3(m).svd(true, true);
        let (u, v_t) = (svd.u.expect("U"), svd.v_t.expect("V^T"));
        let mut flip = Matrix3::identity();
        if (u * v_t).determinant() < 0.0 {
            // nalgebra does not sort the singular values.
            let k = svd.singular_values.imin();
            flip[(k, k)] = -1.0;
        }
        from_matrix3(&(u * flip * v_t))
    }

    #[test]
    fn nearest_rotation_agrees_with_an_svd_and_with_the_truth() {
        // Scaling the columns of a rotation keeps the polar factor symmetric-positive: the
        // truth is the rotation itself when the scale is uniform.
        let r0 = rodrigues_to_matrix([0.3, -1.1, 0.4]);
        assert!(close(&nearest_rotation(&r0.map(|row| row.map(|v| 2.5 * v))), &r0, 1e-15));
        for (k, om) in [[0.3, -1.1, 0.4], [2.9, 0.1, 0.2], [0.0, 0.0, 1e-3]].iter().enumerate() {
            let r = rodrigues_to_matrix(*om);
            let m = r.map(|row| [row[0] * 1.03, row[1] * 0.97 + 0.01 * k as f64, row[2] - 0.02]);
            let n = nearest_rotation(&m);
            assert!(close(&n, &svd_nearest_rotation(&m), 1e-14), "{om:?}");
            assert!((to_matrix3(&n).determinant() - 1.0).abs() < 1e-14);
        }
        // A reflection: det(m) < 0, the nearest rotation flips the smallest direction.
        let m = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -0.5]];
        assert!(close(&nearest_rotation(&m), &[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], 1e-15));
        assert!(close(&nearest_rotation(&m), &svd_nearest_rotation(&m), 1e-15));
    }

    #[test]
    fn rotation_from_two_columns_of_a_scaled_rotation() {
        let r = rodrigues_to_matrix([-0.7, 0.2, 1.9]);
        let col = |j: usize| [r[0][j] * 1.02, r[1][j] * 1.02, r[2][j] * 1.02];
        assert!(close(&rotation_from_two_columns(col(0), col(1)), &r, 1e-15));
    }

    #[test]
    fn nalgebra_scaled_axis_is_less_accurate_than_matrix_to_rodrigues() {
        // Why matrix_to_rodrigues stays hand-written: at 1e-7 rad nalgebra's acos of the
        // trace loses about half the digits (its axis at pi, from the antisymmetric part,
        // which is rounding noise there, is also undetermined; not exercised here).
        let om = [1e-7, -2e-7, 0.5e-7];
        let r = rodrigues_to_matrix(om);
        let err = |v: [f64; 3]| (0..3).map(|i| (v[i] - om[i]).abs() / 1e-7).fold(0.0, f64::max);
        let ours = err(matrix_to_rodrigues(&r));
        let theirs = err(nalgebra::Rotation3::from_matrix_unchecked(to_matrix3(&r)).scaled_axis().into());
        assert!(ours < 1e-14, "relative error {ours}");
        assert!(theirs > 1e-9, "relative error {theirs}");
    }
}
