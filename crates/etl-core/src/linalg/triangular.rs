//! Inverse of a small upper triangular matrix by back substitution, with a certificate of
//! full numerical rank.

/// The inverse of the upper triangular `b` when it is certified to have full numerical
/// rank: s_min(B) >= 1 / ||B^-1||_F and s_max(B) <= ||B||_F, so
/// 1 / ||B^-1||_F > 100 `rank_tolerance` ||B||_F guarantees that every singular value
/// clears the rank threshold (the factor 100 leaves room for rounding). `None` otherwise
/// (the caller then decides the rank by the SVD).
pub fn certified_upper_inverse<const N: usize>(b: &[[f64; N]; N], rank_tolerance: f64) -> Option<[[f64; N]; N]> {
    let mut inv = [[0.0; N]; N];
    // Column j of B^-1 by back substitution of B x = e_j (x_i = 0 for i > j).
    for j in 0..N {
        for i in (0..=j).rev() {
            let row = b.get(i)?;
            let bii = *row.get(i)?;
            if !(bii.abs() > 0.0) {
                return None;
            }
            let rhs = if i == j { 1.0 } else { 0.0 };
            let s: f64 = row
                .iter()
                .zip(inv.iter())
                .take(j + 1)
                .skip(i + 1)
                .map(|(bik, ik)| bik * ik.get(j).unwrap_or(&0.0))
                .sum();
            *inv.get_mut(i)?.get_mut(j)? = (rhs - s) / bii;
        }
    }
    let frob = |m: &[[f64; N]; N]| libm::sqrt(m.iter().flatten().map(|v| v * v).sum::<f64>());
    let (nb, ninv) = (frob(b), frob(&inv));
    (ninv.is_finite() && nb.is_finite() && 100.0 * rank_tolerance * nb * ninv < 1.0).then_some(inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverts_a_well_conditioned_triangle_exactly() {
        // [[2, 1], [0, 4]]^-1 = [[1/2, -1/8], [0, 1/4]] (all exact in binary).
        let inv = certified_upper_inverse(&[[2.0, 1.0], [0.0, 4.0]], 1e-13).unwrap();
        assert_eq!(inv, [[0.5, -0.125], [0.0, 0.25]]);
    }

    #[test]
    fn refuses_singular_and_nearly_singular_triangles() {
        assert!(certified_upper_inverse(&[[1.0, 1.0], [0.0, 0.0]], 1e-13).is_none());
        assert!(certified_upper_inverse(&[[1.0, 0.0], [0.0, 1e-15]], 1e-13).is_none());
        assert!(certified_upper_inverse(&[[f64::NAN, 0.0], [0.0, 1.0]], 1e-13).is_none());
    }
}
