//! A view's normal equations folded through its per-view variables: the hot loop of the
//! bundle adjustment.
//!
//! At one current a point's pixel depends on the model's numbers only through the
//! per-view variables (pose, fx, fy, u0, v0, the distortion coefficients: 13 or 15), so
//! J_view = J_reduced C_view and J_view^T J_view = C^T (J_reduced^T J_reduced) C: the
//! per-point work is a rank-2 update of the small reduced matrix, the fold through C is
//! once per view.

use crate::calib::params::{MAX_REDUCED, R_POSE, R_U0, R_V0};

/// The per-view variables other than u0, v0 (whose columns are the constants (1, 0) and
/// (0, 1) and are accumulated as plain sums): pose, fx, fy, the coefficients.
const OTHER: [usize; MAX_REDUCED - 2] = {
    let mut o = [0; MAX_REDUCED - 2];
    let mut k = 0;
    while k < R_POSE.len + 2 {
        o[k] = k; // om1..tz, fx, fy
        k += 1;
    }
    while k < MAX_REDUCED - 2 {
        o[k] = k + 2; // the coefficients, after u0, v0
        k += 1;
    }
    o
};

/// A view's reduced normal equations: the block of the `O` per-view variables other than
/// u0, v0 ([`OTHER`]'s first `O`: the layout's; upper triangle: row i holds columns i..,
/// padded to `P`, a multiple of 4, so that the accumulation vectorises), their cross terms
/// with u0 and v0 (column sums of the two rows), and the right-hand sides.
pub(super) struct ViewNormal<const O: usize, const P: usize> {
    a: [[f64; P]; O],
    g: [f64; P],
    /// sum f j_u and sum f j_v over the points (the u0 and v0 columns' cross terms).
    sum: [[f64; P]; 2],
    /// sum f^2 (the u0-u0 and v0-v0 terms, equal) and sum f r_u, sum f r_v.
    f2: f64,
    r_sum: [f64; 2],
}

impl<const O: usize, const P: usize> ViewNormal<O, P> {
    /// The per-view variables other than u0, v0 of the layout (a constant per `O`, so that
    /// the gather of a point's rows compiles to fixed loads).
    const OTHER: [usize; O] = {
        let mut o = [0; O];
        let mut k = 0;
        while k < O {
            o[k] = if k < OTHER.len() { OTHER[k] } else { 0 };
            k += 1;
        }
        o
    };

    /// Empty equations.
    pub(super) fn new() -> Self {
        ViewNormal { a: [[0.0; P]; O], g: [0.0; P], sum: [[0.0; P]; 2], f2: 0.0, r_sum: [0.0; 2] }
    }

    /// Adds a point's two rows f j (u and v) with residuals r.
    #[inline]
    pub(super) fn add_point(&mut self, j: &[[f64; MAX_REDUCED]; 2], f: f64, r: [f64; 2]) {
        let fj: [[f64; P]; 2] = core::array::from_fn(|row| {
            let mut v = [0.0; P];
            for (vk, &o) in v.iter_mut().zip(Self::OTHER.iter()) {
                *vk = f * j[row].get(o).copied().unwrap_or(0.0);
            }
            v
        });
        // The upper triangle only: the rank-2 update is the hot loop of the bundle
        // adjustment (half its instructions with the full square).
        for (i, (ai, (&u, &v))) in self.a.iter_mut().zip(fj[0].iter().zip(fj[1].iter())).enumerate() {
            let (Some(ai), Some(uk), Some(vk)) = (ai.get_mut(i..), fj[0].get(i..), fj[1].get(i..)) else { continue };
            for ((aik, &uk), &vk) in ai.iter_mut().zip(uk.iter()).zip(vk.iter()) {
                *aik += u * uk + v * vk;
            }
        }
        for row in 0..2 {
            for ((gk, sk), &jk) in self.g.iter_mut().zip(self.sum[row].iter_mut()).zip(fj[row].iter()) {
                *gk += jk * r[row];
                *sk += f * jk;
            }
            self.r_sum[row] += f * r[row];
        }
        self.f2 += f * f;
    }

    /// The normal equations in the order of the per-view variables (full square, at
    /// capacity: zero past the layout's variables).
    pub(super) fn expand(&self) -> ([[f64; MAX_REDUCED]; MAX_REDUCED], [f64; MAX_REDUCED]) {
        let (iu, iv) = (R_U0, R_V0);
        let mut a = [[0.0; MAX_REDUCED]; MAX_REDUCED];
        let mut g = [0.0; MAX_REDUCED];
        for (p, &op) in Self::OTHER.iter().enumerate() {
            for (q, &oq) in Self::OTHER.iter().enumerate() {
                // Stored: the upper triangle (q >= p).
                let w =
                    if q >= p { self.a.get(p).and_then(|r| r.get(q)) } else { self.a.get(q).and_then(|r| r.get(p)) };
                if let (Some(v), Some(&w)) = (a.get_mut(op).and_then(|r| r.get_mut(oq)), w) {
                    *v = w;
                }
            }
            if let (Some(v), Some(&w)) = (g.get_mut(op), self.g.get(p)) {
                *v = w;
            }
            for (row, &i) in [iu, iv].iter().enumerate() {
                let w = self.sum[row].get(p).copied().unwrap_or(0.0);
                if let Some(v) = a.get_mut(op).and_then(|r| r.get_mut(i)) {
                    *v = w;
                }
                if let Some(v) = a.get_mut(i).and_then(|r| r.get_mut(op)) {
                    *v = w;
                }
            }
        }
        a[iu][iu] = self.f2;
        a[iv][iv] = self.f2;
        g[iu] = self.r_sum[0];
        g[iv] = self.r_sum[1];
        (a, g)
    }
}

/// out_a += C^T a C (upper triangle), out_g += C^T g, for a view's reduced normal
/// equations (a: the full square of its first `reduced` per-view variables, zero past
/// them) and its chain matrix C (per-view variables x N).
pub(super) fn fold_view<const N: usize>(
    reduced: usize,
    a: &[[f64; MAX_REDUCED]; MAX_REDUCED],
    g: &[f64; MAX_REDUCED],
    c: &[[f64; N]; MAX_REDUCED],
    out_a: &mut [[f64; N]; N],
    out_g: &mut [f64; N],
) {
    // t = a_sym C, row by row (rows past the layout's variables are zero in a and C).
    let mut t = [[0.0; N]; MAX_REDUCED];
    for (r, tr) in t.iter_mut().enumerate().take(reduced) {
        for (s, cs) in c.iter().enumerate().take(reduced) {
            let ars = a[r][s];
            if ars != 0.0 {
                for (trq, &csq) in tr.iter_mut().zip(cs.iter()) {
                    *trq += ars * csq;
                }
            }
        }
    }
    for (r, (cr, tr)) in c.iter().zip(t.iter()).enumerate().take(reduced) {
        for (p, ((&crp, outp), gp)) in cr.iter().zip(out_a.iter_mut()).zip(out_g.iter_mut()).enumerate() {
            if crp != 0.0 {
                *gp += crp * g[r];
                for (apq, &trq) in outp.iter_mut().zip(tr.iter()).skip(p) {
                    *apq += crp * trq;
                }
            }
        }
    }
}

/// A block's own columns folded in: out_w += C^T a C_y, out_v += C_y^T a C_y, out_gy +=
/// C_y^T g, for a view's reduced normal equations (a, g), its chain matrix C (per-view
/// variables x N) and its block's chain C_y (per-view variables x M: d(per-view
/// variables)/d(block parameters)).
pub(super) fn fold_block<const N: usize, const M: usize>(
    a: &[[f64; MAX_REDUCED]; MAX_REDUCED],
    g: &[f64; MAX_REDUCED],
    c: &[[f64; N]; MAX_REDUCED],
    cy: &[[f64; M]; MAX_REDUCED],
    out_w: &mut [[f64; M]; N],
    out_v: &mut [[f64; M]; M],
    out_gy: &mut [f64; M],
) {
    let mut acy = [[0.0; M]; MAX_REDUCED];
    for (ar, acyr) in a.iter().zip(acy.iter_mut()) {
        for (&ars, cys) in ar.iter().zip(cy.iter()) {
            for (o, &cysk) in acyr.iter_mut().zip(cys.iter()) {
                *o += ars * cysk;
            }
        }
    }
    for (cr, acyr) in c.iter().zip(acy.iter()) {
        for (&crp, wp) in cr.iter().zip(out_w.iter_mut()) {
            for (o, &acyk) in wp.iter_mut().zip(acyr.iter()) {
                *o += crp * acyk;
            }
        }
    }
    for (cyr, (acyr, &gr)) in cy.iter().zip(acy.iter().zip(g.iter())) {
        for (k, (gyk, vk)) in out_gy.iter_mut().zip(out_v.iter_mut()).enumerate() {
            let cyrk = cyr.get(k).copied().unwrap_or(0.0);
            *gyk += cyrk * gr;
            for (o, &acyl) in vk.iter_mut().zip(acyr.iter()) {
                *o += cyrk * acyl;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_other_variables_skip_the_principal_point() {
        use crate::calib::params::{Layout, R_K1};
        assert_eq!(ViewNormal::<11, 12>::OTHER, [0, 1, 2, 3, 4, 5, 6, 7, 10, 11, 12]);
        assert_eq!(ViewNormal::<13, 16>::OTHER, [0, 1, 2, 3, 4, 5, 6, 7, 10, 11, 12, 13, 14]);
        assert_eq!(Layout::PAPER.reduced_len() - 2, 11);
        assert_eq!(R_K1, 10);
    }
}
