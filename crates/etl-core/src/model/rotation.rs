//! Rotations as Rodrigues vectors (axis * angle, radians) and 3 x 3 matrices.

/// A row-major 3 x 3 matrix: `m[row][col]`.
pub type Mat3 = [[f64; 3]; 3];

/// Rotation matrix of the Rodrigues vector `om` (axis times angle in radians).
///
/// R = I + sin(t)/t [om]x + (1 - cos(t))/t^2 [om]x^2, t = |om|; for t below 1e-8 the
/// series I + [om]x + [om]x^2 / 2 is used (exact to double precision there).
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

/// `m * x`.
#[inline]
pub fn mat_vec(m: &Mat3, x: [f64; 3]) -> [f64; 3] {
    [
        m[0][0] * x[0] + m[0][1] * x[1] + m[0][2] * x[2],
        m[1][0] * x[0] + m[1][1] * x[1] + m[1][2] * x[2],
        m[2][0] * x[0] + m[2][1] * x[1] + m[2][2] * x[2],
    ]
}

/// `m^T * x`.
#[inline]
pub fn mat_t_vec(m: &Mat3, x: [f64; 3]) -> [f64; 3] {
    [
        m[0][0] * x[0] + m[1][0] * x[1] + m[2][0] * x[2],
        m[0][1] * x[0] + m[1][1] * x[1] + m[2][1] * x[2],
        m[0][2] * x[0] + m[1][2] * x[1] + m[2][2] * x[2],
    ]
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
}
